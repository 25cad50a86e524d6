"""Tracks a horizon on the F3 crop (data/seismic/f3.sgy) and writes it as GOCAD TSurf and
as an x y z grid: how data/seismic/f3-horizon.ts was made, for the layered scene
scenes/data/f3-horizon.toml.

    python3 scripts/track_horizon.py data/seismic/f3.sgy data/seismic/f3-horizon.ts

(and data/seismic/f3-horizon.xyz beside it).

The tracker is the simplest an interpreter uses: from a seed (the strongest peak within
SEED_WINDOW_MS of SEED_MS on the first trace), each trace's peak is the largest amplitude
within WINDOW_MS of its neighbour's already tracked (inline by inline, crossline by
crossline), refined to the vertex of the parabola through the peak sample and its two
neighbours; where the window holds no peak (its largest sample on an edge) the
neighbour's time is carried, so the tracker never slides onto another event. Times are
two-way in ms; the TSurf holds one vertex per trace at its CDP
coordinates, ZPOSITIVE Depth (time grows downwards), two triangles per grid cell; the x y z
grid the same nodes as OpendTect exports a horizon with X/Y and Inl/Crl and a header
(`"X" "Y" "Inline" "Crossline" "Z (ms)"`, tab-separated, time positive down). Plain
Python, no packages: the SEG-Y is read with struct (big-endian int16 samples, rev 1).
"""

import struct
import sys

SEED_MS = 130.0
SEED_WINDOW_MS = 12.0
WINDOW_MS = 6.0


def read_segy(path):
    """Traces as {(inline, crossline): (x, y, samples)} and the sample interval in ms."""
    data = open(path, "rb").read()
    interval_us, _, ns = struct.unpack(">hhh", data[3216:3222])
    fmt = struct.unpack(">h", data[3224:3226])[0]
    assert fmt == 3, "the F3 crop holds int16 samples"
    traces = {}
    at = 3600
    while at + 240 <= len(data):
        h = data[at : at + 240]
        scalar = struct.unpack(">h", h[70:72])[0]
        scale = -1.0 / scalar if scalar < 0 else (scalar if scalar > 0 else 1.0)
        x, y = (v * scale for v in struct.unpack(">ii", h[180:188]))
        inline, crossline = struct.unpack(">ii", h[188:196])
        samples = struct.unpack(f">{ns}h", data[at + 240 : at + 240 + 2 * ns])
        traces[(inline, crossline)] = (x, y, samples)
        at += 240 + 2 * ns
    return traces, interval_us / 1000.0


def peak(samples, dt, centre_ms, window_ms):
    """The time of the largest amplitude within window_ms of centre_ms, refined by a
    parabola through the peak sample and its neighbours."""
    lo = max(1, int((centre_ms - window_ms) / dt))
    hi = min(len(samples) - 2, int((centre_ms + window_ms) / dt))
    k = max(range(lo, hi + 1), key=lambda i: samples[i])
    if k in (lo, hi) and window_ms < SEED_WINDOW_MS:
        # No peak inside the window (the event fades or splits): carry the neighbour's
        # time rather than slide to another event.
        return centre_ms
    a, b, c = samples[k - 1], samples[k], samples[k + 1]
    denominator = a - 2 * b + c
    shift = 0.5 * (a - c) / denominator if denominator != 0 else 0.0
    return (k + max(-0.5, min(0.5, shift))) * dt


def track(traces, dt):
    inlines = sorted({il for il, _ in traces})
    crosslines = sorted({xl for _, xl in traces})
    times = {}
    first = (inlines[0], crosslines[0])
    times[first] = peak(traces[first][2], dt, SEED_MS, SEED_WINDOW_MS)
    for i, il in enumerate(inlines):
        for j, xl in enumerate(crosslines):
            if (il, xl) in times or (il, xl) not in traces:
                continue
            # The neighbour tracked before: along the crossline, else the inline before.
            near = (il, crosslines[j - 1]) if j > 0 else (inlines[i - 1], xl)
            times[(il, xl)] = peak(traces[(il, xl)][2], dt, times[near], WINDOW_MS)
    return inlines, crosslines, times


def write_tsurf(path, traces, inlines, crosslines, times):
    ids = {}
    lines = ["GOCAD TSurf 1", "HEADER {", "name:F3 crop, tracked peak near 130 ms", "}",
             "GOCAD_ORIGINAL_COORDINATE_SYSTEM", "NAME Default", 'AXIS_NAME "X" "Y" "Z"',
             'AXIS_UNIT "m" "m" "ms"', "ZPOSITIVE Depth", "END_ORIGINAL_COORDINATE_SYSTEM",
             "TFACE"]
    for il in inlines:
        for xl in crosslines:
            x, y, _ = traces[(il, xl)]
            ids[(il, xl)] = len(ids) + 1
            lines.append(f"VRTX {ids[(il, xl)]} {x:.2f} {y:.2f} {times[(il, xl)]:.3f}")
    for a, b in zip(inlines, inlines[1:]):
        for c, d in zip(crosslines, crosslines[1:]):
            p, q, r, s = ids[(a, c)], ids[(b, c)], ids[(b, d)], ids[(a, d)]
            lines += [f"TRGL {p} {q} {r}", f"TRGL {p} {r} {s}"]
    lines.append("END")
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def write_xyz(path, traces, inlines, crosslines, times):
    lines = ['"X"\t"Y"\t"Inline"\t"Crossline"\t"Z (ms)"']
    for il in inlines:
        for xl in crosslines:
            x, y, _ = traces[(il, xl)]
            lines.append(f"{x:.2f}\t{y:.2f}\t{il}\t{xl}\t{times[(il, xl)]:.3f}")
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def main(segy, target):
    traces, dt = read_segy(segy)
    inlines, crosslines, times = track(traces, dt)
    write_tsurf(target, traces, inlines, crosslines, times)
    write_xyz(target.rsplit(".", 1)[0] + ".xyz", traces, inlines, crosslines, times)
    print(f"{target}: {len(times)} traces, {min(times.values()):.1f}-{max(times.values()):.1f} ms")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
