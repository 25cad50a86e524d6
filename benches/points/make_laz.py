#!/usr/bin/env python3
"""Write an N-point LAZ (LAS 1.4, point format 7: GPS time + RGB) that looks like
airborne lidar: points along zig-zag scan lines over a smooth seeded terrain, in
acquisition order (gps_time increasing), so the LAZ predictors see coherent neighbours.

    python3 benches/points/make_laz.py OUT.laz [N=5000000] [--seed 1] [--extra 0] [--las]

Written 5 M points at a time, so any N fits in memory; --las writes the same points
uncompressed (the LAS side of benches/points/laz.sh).

Uses laspy + lazrs (pip install laspy lazrs). --extra K adds K bytes of extra bytes
(an undocumented u8 array) so the Byte14 layer is exercised too.
"""
import argparse
import time

import numpy as np
import laspy


def terrain(x, y, rng_phase):
    a, b, c = rng_phase
    return (
        30.0 * np.sin(x / 400.0 + a) * np.cos(y / 550.0 + b)
        + 8.0 * np.sin(x / 90.0 + c) * np.sin(y / 120.0)
        + 0.002 * x
        + 150.0
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("n", nargs="?", type=int, default=5_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--extra", type=int, default=0, help="extra bytes per point")
    ap.add_argument("--las", action="store_true", help="write LAS (uncompressed) instead")
    args = ap.parse_args()
    n = args.n
    rng = np.random.default_rng(args.seed)
    phase = rng.uniform(0, 6.28, 3)
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([500000.0, 4000000.0, 0.0])
    if args.extra:
        header.add_extra_dim(laspy.ExtraBytesParams(name="extra", type=f"{args.extra}u1"))
    t = time.perf_counter()
    block = 5_000_000  # points generated and written at a time: memory stays bounded
    with laspy.open(args.out, mode="w", header=header, do_compress=not args.las,
                    laz_backend=laspy.LazBackend.LazrsParallel) as w:
        for first in range(0, n, block):
            w.write_points(points(header, rng, phase, first, min(block, n - first), args.extra))
    dt = time.perf_counter() - t
    import os
    size = os.path.getsize(args.out)
    print(
        f"wrote {args.out}: {n} points, format 7, {header.point_format.size} B/record, "
        f"{size/1e6:.1f} MB ({size*8/n:.1f} bits/point), written in {dt:.1f} s"
    )


def points(header, rng, phase, first, n, extra):
    """Points `first..first + n` of the flight (lazrs: fixed-size chunks of 50,000)."""
    # Scan geometry: the aircraft flies along +y; the mirror sweeps across x.
    per_line = 800  # pulses per scan line
    index = first + np.arange(n)
    line = index // per_line
    k = index % per_line
    sweep = np.where(line % 2 == 0, k, per_line - 1 - k) / (per_line - 1)  # zig-zag
    x = 1000.0 * sweep + rng.normal(0, 0.05, n)
    y = 0.5 * line + 0.02 * sweep + rng.normal(0, 0.05, n)
    ground = terrain(x, y, phase)
    # Returns: ~85% single returns on ground; the rest 2-3 returns from vegetation.
    nret = np.where(rng.random(n) < 0.85, 1, rng.integers(2, 4, n)).astype(np.uint8)
    rnum = np.minimum(rng.integers(1, 4, n), nret).astype(np.uint8)
    canopy = rng.uniform(2.0, 20.0, n)
    z = ground + np.where(rnum < nret, canopy * (1.0 - (rnum - 1) / nret), 0.0)
    z += rng.normal(0, 0.02, n)
    cls = np.where(rnum < nret, 5, 2).astype(np.uint8)  # high vegetation / ground
    las = laspy.ScaleAwarePointRecord.zeros(n, header=header)
    las.x = x + 500000.0
    las.y = y + 4000000.0
    las.z = z
    las.intensity = np.clip(
        400 + 300 * np.sin(x / 50.0) + 60 * (cls == 5) + rng.normal(0, 25, n), 0, 65535
    ).astype(np.uint16)
    las.return_number = rnum
    las.number_of_returns = nret
    las.classification = cls
    las.scan_direction_flag = (line % 2).astype(np.uint8)
    las.scan_angle = ((sweep - 0.5) * 20.0 / 0.006).astype(np.int16)
    las.point_source_id = np.full(n, 7, np.uint16)
    las.gps_time = 3.0e8 + index * 2.0e-6
    shade = np.clip((ground - 100.0) / 100.0, 0.0, 1.0)
    veg = cls == 5
    las.red = np.clip(256 * (90 + 100 * shade - 40 * veg) + rng.normal(0, 300, n), 0, 65535).astype(np.uint16)
    las.green = np.clip(256 * (80 + 90 * shade + 60 * veg) + rng.normal(0, 300, n), 0, 65535).astype(np.uint16)
    las.blue = np.clip(256 * (60 + 70 * shade) + rng.normal(0, 300, n), 0, 65535).astype(np.uint16)
    if extra:
        las.extra = rng.integers(0, 4, (n, extra)).astype(np.uint8)
    return las


if __name__ == "__main__":
    main()
