"""arbvis from Python, timed in process (issue 44's figures):

- the import,
- a scene's first render (context, data loaded and prepared, programs, one frame) and the
  next ten (each after a turn of the camera: a frame each),
- the same frames with the array's buffer kept by numpy or copied (what the hand-over saves),
- two renderers in two threads against the same work one after the other (the overlap),
- an orbit on a Dask LocalCluster of one and of two worker processes (frames per second,
  the cluster's start left out).

Run with the package installed (a release wheel for figures: `maturin build --release`):
    python benches/python/bench.py --scene demo:v3o2-sum --scene scenes/store/f3.toml
Prints one JSON object per measurement. The command line's per-process time for the same
scenes is the yardstick; time it with any whole-process timer, e.g.
    /usr/bin/time -f %e target/release/arbvis render --demo v3o2-sum -o /tmp/a.png
"""

import argparse
import json
import math
import statistics
import sys
import threading
import time


def timed(f):
    t = time.perf_counter()
    value = f()
    return time.perf_counter() - t, value


def load(arbvis, spec):
    if spec.startswith("demo:"):
        return arbvis.Scene.demo(spec[5:])
    return arbvis.Scene.load(spec)


def turn(scene, k, n=10):
    half = math.pi * (k + 1) / (2 * n)
    scene.rotation = (0.1, math.sin(half), 0.0, math.cos(half))


def frames(arbvis, spec, runs):
    firsts, nexts = [], []
    for _ in range(runs):
        scene = load(arbvis, spec)
        t0 = time.perf_counter()
        renderer = arbvis.Renderer(scene)
        renderer.render()
        firsts.append(time.perf_counter() - t0)
        for k in range(10):
            turn(scene, k)
            nexts.append(timed(renderer.render)[0])
        renderer.close()
    return {
        "scene": spec,
        "size": list(scene.size),
        "first_render_s": statistics.median(firsts),
        "next_frame_s_median": statistics.median(nexts),
        "next_frame_s_min": min(nexts),
        "next_frame_s_max": max(nexts),
        "program_kind": renderer.program_kind,
        "driver": renderer.driver,
    }


def copies(arbvis, spec):
    scene = load(arbvis, spec)
    scene.fidelity = "precise"
    with arbvis.Renderer(scene) as r:
        r.render()
        handed = [timed(r.render)[0] for _ in range(10)]
        copied = [timed(lambda: r.render().copy())[0] for _ in range(10)]
        image = r.render()
    return {
        "scene": spec + " (precise, float32)",
        "owndata": bool(image.flags["OWNDATA"]),
        "bytes": image.nbytes,
        "render_s_median": statistics.median(handed),
        "render_and_copy_s_median": statistics.median(copied),
    }


def overlap(arbvis, spec, count=10):
    scenes = [load(arbvis, spec) for _ in range(2)]
    renderers = [arbvis.Renderer(s) for s in scenes]
    for r in renderers:
        r.render()

    def work(r, s):
        for k in range(count):
            turn(s, k)
            r.render()

    one_after, _ = timed(lambda: [work(r, s) for r, s in zip(renderers, scenes)])
    threads = [threading.Thread(target=work, args=(r, s)) for r, s in zip(renderers, scenes)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    together = time.perf_counter() - t0
    for r in renderers:
        r.close()
    return {
        "scene": spec,
        "frames": 2 * count,
        "one_after_the_other_s": one_after,
        "two_threads_s": together,
        "speedup": one_after / together,
    }


def dask_scaling(arbvis, spec, views):
    import arbvis.dask
    from dask.distributed import Client, LocalCluster

    scene = load(arbvis, spec)
    rotations = arbvis.dask.orbit(views)
    out = {"scene": spec, "views": views}
    for workers in (1, 2):
        with LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        ) as cluster, Client(cluster) as client:
            # The first orbit makes each worker's renderer; the second is timed.
            arbvis.dask.render_views(client, scene, rotations[:workers] * 2)
            seconds, _ = timed(lambda: arbvis.dask.render_views(client, scene, rotations))
        out[f"{workers}_workers_frames_per_s"] = views / seconds
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", action="append", required=True, help="demo:NAME or a scene file")
    p.add_argument("--runs", type=int, default=3, help="first renders per scene")
    p.add_argument("--views", type=int, default=24, help="views of the Dask orbit")
    a = p.parse_args()
    t0 = time.perf_counter()
    import arbvis

    print(json.dumps({"import_s": time.perf_counter() - t0}), flush=True)
    for spec in a.scene:
        print(json.dumps(frames(arbvis, spec, a.runs)), flush=True)
        print(json.dumps(copies(arbvis, spec)), flush=True)
        print(json.dumps(overlap(arbvis, spec)), flush=True)
        print(json.dumps(dask_scaling(arbvis, spec, a.views)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
