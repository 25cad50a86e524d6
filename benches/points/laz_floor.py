#!/usr/bin/env python3
"""Decode floor: time laspy + lazrs decompressing a whole LAZ file to raw point records.

    python3 benches/points/laz_floor.py IN.laz [--backend lazrs|parallel|both] [--repeat 3]
                                    [--threads N] [--chunked POINTS]

Each backend runs in a fresh child process so that its peak RSS (ru_maxrss) is its own.
Reported: best-of-repeat wall time (and that run's CPU time, user+sys) of the decode (file already in the page cache, one
warm-up read first), points/s, and the child's peak RSS. `--chunked P` reads P points at
a time (laspy's chunk_iterator: bounded memory, like arbvis's batches) instead of whole.
`--threads N` caps rayon's pool for the parallel backend (RAYON_NUM_THREADS).
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time


def child(path, backend, repeat, chunked):
    import laspy

    be = {"lazrs": laspy.LazBackend.Lazrs, "parallel": laspy.LazBackend.LazrsParallel}[backend]
    with open(path, "rb") as f:  # warm the page cache
        while f.read(1 << 24):
            pass
    best = None
    n = 0
    for _ in range(repeat):
        t = time.perf_counter()
        c0 = resource.getrusage(resource.RUSAGE_SELF)
        with laspy.open(path, laz_backend=be) as r:
            if chunked:
                n = 0
                for pts in r.chunk_iterator(chunked):
                    n += len(pts)
            else:
                pts = r.read_points(r.header.point_count)
                n = len(pts)
        dt = time.perf_counter() - t
        c1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu = c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime
        if best is None or dt < best:
            best, best_cpu = dt, cpu
        del pts
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    print(json.dumps({"backend": backend, "points": n, "seconds": best, "cpu": best_cpu, "rss_kib": rss}))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("path")
    ap.add_argument("--backend", default="both", choices=["lazrs", "parallel", "both"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--chunked", type=int, default=0)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        return child(a.path, a.backend, a.repeat, a.chunked)
    backends = ["lazrs", "parallel"] if a.backend == "both" else [a.backend]
    size = os.path.getsize(a.path)
    print(f"{a.path}: {size/1e6:.1f} MB, cores {os.cpu_count()}, load {os.getloadavg()[0]:.2f},"
          f" repeat {a.repeat}"
          + (f", chunk_iterator({a.chunked})" if a.chunked else ", read_points(all)"))
    for b in backends:
        env = dict(os.environ)
        if a.threads:
            env["RAYON_NUM_THREADS"] = str(a.threads)
        cmd = [sys.executable, __file__, a.path, "--backend", b, "--repeat", str(a.repeat),
               "--chunked", str(a.chunked), "--child"]
        out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
        r = json.loads(out.strip().splitlines()[-1])
        pps = r["points"] / r["seconds"]
        print(f"  {b:9s} {r['points']} points in {r['seconds']:.3f} s = {pps/1e6:.2f} M points/s"
              f" (CPU {r['cpu']:.2f} s: {r['points']/r['cpu']/1e6:.2f} M points per CPU-s)"
              f"  peak RSS {r['rss_kib']/1024:.0f} MiB")


if __name__ == "__main__":
    main()
