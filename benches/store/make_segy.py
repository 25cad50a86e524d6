"""A post-stack SEG-Y survey written with numpy alone (not arbvis's writer), for the MDIO
bench: layered reflectors that fold, two faults, a Ricker wavelet, noise, and a hole of
traces left out (dead traces in MDIO). SEG-Y rev 1, IEEE float big-endian (format 5),
4 ms; inline at bytes 189, crossline at 193, CDP x/y at 181/185 (scalar -100 at 71).

    python3 benches/store/make_segy.py OUT.sgy SAMPLES INLINES CROSSLINES
"""
import sys

import numpy as np


def main():
    out, ns, ni, nx = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    rng = np.random.default_rng(7)
    text = np.full(3200, 0x40, np.uint8)  # EBCDIC spaces
    binary = np.zeros(400, np.uint8)
    def put(buf, at, value, fmt):
        buf[at:at + np.dtype(fmt).itemsize] = np.frombuffer(np.array(value, fmt).tobytes(), np.uint8)
    put(binary, 16, 4000, ">i2")   # sample interval (us)
    put(binary, 20, ns, ">i2")     # samples per trace
    put(binary, 24, 5, ">i2")      # format: IEEE float
    put(binary, 300, 0x0100, ">i2")  # revision 1
    t = np.arange(ns, dtype=np.float64)
    # A Ricker wavelet of 25 Hz at 4 ms, as a kernel.
    tw = (np.arange(-32, 33) * 0.004)
    f = 25.0
    ricker = (1 - 2 * (np.pi * f * tw) ** 2) * np.exp(-((np.pi * f * tw) ** 2))
    layers = np.sort(rng.uniform(0.05, 0.95, 40)) * ns
    strength = rng.uniform(-1, 1, 40)
    header = np.zeros(240, np.uint8)
    with open(out, "wb") as f:
        f.write(text.tobytes())
        f.write(binary.tobytes())
        for il in range(ni):
            x = np.arange(nx)
            # Folded depth shift, with faults at a third and two thirds of the crosslines.
            shift = 25 * np.sin(2 * np.pi * (il / ni + x / nx * 1.5)) + 12 * (x > nx / 3) - 18 * (x > 2 * nx / 3)
            traces = np.zeros((nx, ns))
            for depth, s in zip(layers, strength):
                at = np.clip((depth + shift).astype(int), 0, ns - 1)
                traces[np.arange(nx), at] += s
            traces = np.apply_along_axis(lambda r: np.convolve(r, ricker, "same"), 1, traces)
            traces += rng.normal(0, 0.02, traces.shape)
            data = traces.astype(">f4")
            keep = ~((ni // 3 < il < ni // 3 + ni // 20) & (x > nx // 2) & (x < nx // 2 + nx // 20))
            recs = np.zeros((nx, 240 + 4 * ns), np.uint8)
            recs[:, 240:] = data.view(np.uint8).reshape(nx, 4 * ns)
            hdr = recs[:, :240]
            def col(at, values, fmt):
                b = np.asarray(values).astype(fmt).view(np.uint8).reshape(-1, np.dtype(fmt).itemsize)
                hdr[:, at:at + b.shape[1]] = b
            col(70, np.full(nx, -100), ">i2")
            col(114, np.full(nx, ns), ">i2")
            col(116, np.full(nx, 4000), ">i2")
            col(180, (400000 + 25 * x + 10 * il) * 100, ">i4")
            col(184, (6000000 + 25 * il - 5 * x) * 100, ">i4")
            col(188, np.full(nx, 1000 + il), ">i4")
            col(192, 2000 + x, ">i4")
            f.write(recs[keep].tobytes())


if __name__ == "__main__":
    main()
