#!/usr/bin/env python3
"""An outcrop-like point cloud of any size, written as uncompressed LAS 1.4 point format 7.

    python3 benches/points/outcrop.py POINTS OUT.las [--seed S]

A cliff face 2 km long and 150 m high (70 % of the points), the plateau behind it (25 %)
and vegetation over the plateau (5 %). The face bends, is cut by three faults that shift it
and its strata, and has holes (caves, missing scans) with no points; strata dip along x
and are coloured and given intensities by layer; 5 cm of noise on every point. The points
come in scan order (strips along x), as a scanner writes them, not sorted. Classification:
1 face, 2 plateau (ground), 5 vegetation. Written in chunks of 4 million points (about
150 MB of memory whatever the size). numpy only.
"""

import argparse
import struct
import sys

import numpy as np

SCALE = 0.001
FAULTS = [(400.0, 10.0, 3.0), (1100.0, -6.0, -2.0), (1600.0, 15.0, 4.0)]  # x, throw, heave
LENGTH, HEIGHT, DEPTH = 2000.0, 150.0, 300.0
PALETTE = np.array(
    [[176, 140, 96], [140, 98, 60], [204, 180, 130], [112, 84, 64], [190, 160, 110],
     [150, 120, 90], [220, 200, 160], [120, 100, 80]], dtype=np.uint16) * 257


def throw_and_heave(x):
    """Summed throw (m, vertical) and heave (m, into the face) of the faults left of x."""
    t = np.zeros_like(x)
    h = np.zeros_like(x)
    for fx, throw, heave in FAULTS:
        t += np.where(x > fx, throw, 0.0)
        h += np.where(x > fx, heave, 0.0)
    return t, h


def face_y(x, z):
    t, h = throw_and_heave(x)
    return 20.0 * np.sin(x / 300.0) + 4.0 * np.sin(x / 37.0 + z / 23.0) + 0.02 * z + h


def chunk(rng, n, holes):
    kind = rng.random(n)
    x = np.sort(rng.random(n)) * LENGTH  # strips along x: scan order
    z = rng.random(n) * HEIGHT
    y = face_y(x, z)
    cls = np.ones(n, dtype=np.uint8)
    plateau = (kind >= 0.70) & (kind < 0.95)
    veg = kind >= 0.95
    top = plateau | veg
    y[top] = face_y(x[top], np.full(top.sum(), HEIGHT)) + rng.random(top.sum()) * DEPTH
    z[top] = HEIGHT + 3.0 * np.sin(x[top] / 90.0) * np.cos(y[top] / 70.0)
    z[veg] += rng.random(veg.sum()) * 15.0
    cls[plateau] = 2
    cls[veg] = 5
    # Holes in the face: no points.
    keep = np.ones(n, dtype=bool)
    face = ~top
    for hx, hz, r in holes:
        keep &= ~(face & ((x - hx) ** 2 + (z - hz) ** 2 < r * r))
    x, y, z, cls = x[keep], y[keep], z[keep], cls[keep]
    m = x.size
    x += rng.normal(0, 0.05, m)
    y += rng.normal(0, 0.05, m)
    z += rng.normal(0, 0.05, m)
    t, _ = throw_and_heave(x)
    layer = np.floor((z + 0.05 * x - t) / 8.0).astype(np.int64) % len(PALETTE)
    rgb = PALETTE[layer]
    rgb[cls == 5] = [60 * 257, 140 * 257, 60 * 257]
    intensity = (layer * 4000 + rng.integers(0, 2000, m)).astype(np.uint16)
    return x, y, z, cls, rgb, intensity


def header(count, bounds):
    h = bytearray(375)
    h[0:4] = b"LASF"
    h[24], h[25] = 1, 4
    h[26:32] = b"arbvis"
    h[58:68] = b"outcrop.py"
    struct.pack_into("<HIIBH", h, 94, 375, 375, 0, 7, 36)
    struct.pack_into("<3d3d", h, 131, SCALE, SCALE, SCALE, 0.0, 0.0, 0.0)
    (lo, hi) = bounds
    struct.pack_into("<6d", h, 179, hi[0], lo[0], hi[1], lo[1], hi[2], lo[2])
    struct.pack_into("<Q", h, 247, count)
    struct.pack_into("<Q", h, 255, count)  # all first returns
    return bytes(h)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("points", type=int)
    p.add_argument("out")
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()
    rng = np.random.default_rng(a.seed)
    holes = [(rng.random() * LENGTH, rng.random() * HEIGHT, 2 + rng.random() * 12) for _ in range(60)]
    dtype = np.dtype([("X", "<i4"), ("Y", "<i4"), ("Z", "<i4"), ("intensity", "<u2"),
                      ("returns", "u1"), ("flags", "u1"), ("classification", "u1"),
                      ("user", "u1"), ("angle", "<i2"), ("source", "<u2"), ("gps", "<f8"),
                      ("red", "<u2"), ("green", "<u2"), ("blue", "<u2")])
    assert dtype.itemsize == 36
    count, lo, hi = 0, np.full(3, np.inf), np.full(3, -np.inf)
    with open(a.out, "wb") as f:
        f.write(bytes(375))
        while count < a.points:
            want = min(4_000_000, a.points - count)
            x, y, z, cls, rgb, intensity = chunk(rng, want, holes)
            n = x.size
            r = np.zeros(n, dtype=dtype)
            q = [np.round(v / SCALE).astype(np.int32) for v in (x, y, z)]
            r["X"], r["Y"], r["Z"] = q
            for k in range(3):
                lo[k] = min(lo[k], q[k].min() * SCALE)
                hi[k] = max(hi[k], q[k].max() * SCALE)
            r["intensity"] = intensity
            r["returns"] = 0x11
            r["classification"] = cls
            r["gps"] = (count + np.arange(n)) * 1e-6
            r["red"], r["green"], r["blue"] = rgb[:, 0], rgb[:, 1], rgb[:, 2]
            f.write(r.tobytes())
            count += n
            print(f"\r{count:,} of {a.points:,} points", end="", file=sys.stderr)
        f.seek(0)
        f.write(header(count, (lo, hi)))
    print(f"\n{a.out}: {count:,} points, bounds {lo.round(3)} .. {hi.round(3)}", file=sys.stderr)


if __name__ == "__main__":
    main()
