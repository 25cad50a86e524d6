"""A survey's first picture from memory (arbvis.Volume of a numpy array) against the same
survey from a SEG-Y file, and a frame after it; the copy arbvis.Volume makes, per input
type. Usage: python benches/python/memory_vs_file.py [INLINES CROSSLINES SAMPLES]
(default 160 140 300: 27 MB of float32). Prints the median of three runs of each."""

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import arbvis

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python" / "tests"))
from test_memory import SCENE, write_segy  # noqa: E402  (the tests' SEG-Y writer)


def timed(f, runs=3):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def first_and_next(scene):
    t = time.perf_counter()
    with arbvis.Renderer(scene) as r:
        r.render()
        first = time.perf_counter() - t
        scene.zoom = scene.zoom * 1.1
        t = time.perf_counter()
        r.render()
        frame = time.perf_counter() - t
    return first, frame


def main():
    shape = tuple(int(v) for v in sys.argv[1:4]) or (160, 140, 300)
    cube = np.random.default_rng(1).standard_normal(shape).astype(np.float32)
    print(f"survey {shape} (inline, crossline, sample), {cube.nbytes / 1e6:.0f} MB of float32")
    for name, data in [
        ("float32, C order", cube),
        ("float32, Fortran order", np.asfortranarray(cube)),
        ("int16", (cube * 1000).astype(np.int16)),
        ("float64", cube.astype(np.float64)),
    ]:
        seconds, _ = timed(lambda: arbvis.Volume(data, spacing=(25.0, 12.5, 4.0)))
        print(f"arbvis.Volume({name}): {seconds * 1e3:.0f} ms (one copy into float32)")
    with tempfile.TemporaryDirectory() as d:
        write_segy(Path(d) / "cube.sgy", cube)
        memory = arbvis.Volume(cube, spacing=(25.0, 12.5, 4.0))
        for label, make in [
            ("SEG-Y file", lambda: arbvis.Scene.from_toml(SCENE, base=d)),
            ("numpy in memory", lambda: with_memory(SCENE, d, memory)),
        ]:
            runs = [first_and_next(make()) for _ in range(3)]
            first = statistics.median(r[0] for r in runs)
            frame = statistics.median(r[1] for r in runs)
            print(f"{label}: first picture {first * 1e3:.0f} ms, a frame after it {frame * 1e3:.0f} ms")


def with_memory(text, base, volume):
    scene = arbvis.Scene.from_toml(text, base=base)
    scene["technique.opacity3d.primary.volume"] = volume
    return scene


if __name__ == "__main__":
    main()
