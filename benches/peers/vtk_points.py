#!/usr/bin/env python3
"""VTK's point Gaussian mapper as a peer of arbvis's splats (issue 12's frame-time goal).

    pip install vtk numpy
    cargo build --release
    python3 benches/peers/vtk_points.py --points 570000 --pixels 1.3 --rounds 3 --turn 1

1. A cloud of `--points` points shaped like the seed's section (8 folded layers in a
   4 x 1 x 1 box, a colour per layer, seeded) is written once as a binary little-endian PLY
   (x, y, z as float, red, green, blue as uchar) that both systems read.
2. arbvis draws it from two scenes (`cloud = { ply = ... }`, colour = "rgb", orthographic,
   looking down -y onto the section's face, splats of `--pixels` pixels: in orthographic
   views gl_PointSize = point_size x factor): `draw = "points"` (GL_POINTS sorted back to
   front by the radix sort) and `draw = "tiles"` (per-tile lists composited per pixel); VTK
   draws it with vtkPointGaussianMapper (the default Gaussian splat, opacity on, sorted by
   nothing), parallel projection, the same view direction, its scale factor set so a splat
   is `--pixels` pixels across at the window's size, and the same 1600x900 size.
3. All are timed per frame (arbvis: `arbvis bench SCENE --json`, clear + draw + finish;
   VTK: Render + WaitForCompletion), first frame apart, alternating round by round; the
   script prints the medians and their ratios. With `--turn DEG` the camera turns DEG
   degrees about the vertical axis before every frame in both (arbvis `bench --turn`, VTK
   `Azimuth`), so every arbvis frame pays for its order (the sort, or the tile lists);
   VTK's mapper does not sort, so turning costs it nothing. Without it the camera stays
   still and arbvis orders once.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import vtk  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_common import plain_window, window_config  # noqa: E402


MODES = {
    "opaque": "VTK's default: splats drawn opaque with the depth test, nothing blended",
    "unsorted": "translucent: blended in the points' order (no sort)",
    "peeled": "translucent, depth-peeled: blended in depth order (arbvis's work)",
}


def write_cloud(path, n, seed):
    """A layered section: 8 folded layers, a colour per layer, jittered."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 4.0, n)
    y = rng.uniform(0.0, 1.0, n)
    layer = rng.integers(0, 8, n)
    fold = 0.08 * np.sin(2.5 * x) + 0.04 * np.cos(7.0 * y)
    z = (layer + rng.uniform(0.0, 1.0, n)) / 8.0 + fold
    palette = np.array([[230, 140, 50], [200, 170, 110], [240, 210, 90], [110, 130, 80],
                        [150, 200, 170], [235, 205, 90], [100, 120, 70], [110, 160, 220]],
                       dtype=np.uint8)
    rec = np.zeros(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                             ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    rec["x"], rec["y"], rec["z"] = x, y, z
    c = palette[layer]
    rec["red"], rec["green"], rec["blue"] = c[:, 0], c[:, 1], c[:, 2]
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {n}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(rec.tobytes())


def arbvis_scene(path, ply, size, pixels, draw):
    # Looking along +y with z up (VTK's camera below): a quarter turn about x, the sign
    # checked by rendering both (--png).
    q = [-np.sin(np.pi / 4), 0.0, 0.0, np.cos(np.pi / 4)]
    with open(path, "w") as f:
        f.write(f"""size = [{size[0]}, {size[1]}]
fidelity = "precise"
programs = "glsl"
background = [0.0, 0.0, 0.0, 1.0]

[camera]
projection = "orthographic"
rotation = [{q[0]}, {q[1]}, {q[2]}, {q[3]}]
zoom = 1.0

[technique.splats]
cloud = {{ ply = "{ply}" }}
colour = "rgb"
point_size = {pixels}
factor = 1.0
kernel = "gaussian"
sort = "radix"
draw = "{draw}"
""")


def arbvis_frames(binary, scene, frames, turn):
    out = subprocess.run([binary, "bench", scene, "--json", "--frames", str(frames),
                          "--turn", str(turn)],
                         check=True, capture_output=True, text=True)
    j = json.loads(out.stdout)
    s = j["settings"][0]
    return s["frames_ms"], j["renderer"]


class VtkScene:
    def __init__(self, ply, size, pixels, mode):
        reader = vtk.vtkPLYReader()
        reader.SetFileName(ply)
        reader.Update()
        self.n = reader.GetOutput().GetNumberOfPoints()
        mapper = vtk.vtkPointGaussianMapper()
        mapper.SetInputConnection(reader.GetOutputPort())
        mapper.SetScalarModeToUsePointData()
        mapper.SetEmissive(0)
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        self.ren = vtk.vtkRenderer()
        self.ren.AddActor(actor)
        self.ren.SetBackground(0, 0, 0)
        self.win = plain_window(size)
        self.win.AddRenderer(self.ren)
        if mode != "opaque":
            # The actor translucent (opacity 0.999: VTK blends only translucent actors;
            # the Gaussian's alpha scaled by 0.999), so the splats are blended as arbvis's.
            actor.GetProperty().SetOpacity(0.999)
        if mode == "peeled":
            # Equal work: blended in depth order, as arbvis's are (the mapper itself sorts
            # nothing). Peels until nothing is left (no cap, occlusion ratio 0).
            self.win.SetAlphaBitPlanes(1)
            self.ren.SetUseDepthPeeling(1)
            self.ren.SetMaximumNumberOfPeels(0)
            self.ren.SetOcclusionRatio(0.0)
        self.mode = mode
        self.config = (f"{window_config(self.win)}; vtkPointGaussianMapper, {MODES[mode]}, "
                       f"opacity {actor.GetProperty().GetOpacity()}, depth peeling "
                       f"{self.ren.GetUseDepthPeeling()}")
        cam = self.ren.GetActiveCamera()
        cam.ParallelProjectionOn()
        b = reader.GetOutput().GetBounds()
        c = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
        cam.SetFocalPoint(*c)
        cam.SetPosition(c[0], c[1] - 10.0, c[2])
        cam.SetViewUp(0, 0, 1)
        self.ren.ResetCamera()
        # A splat `pixels` across: the Gaussian covers [-scale, scale] in world units.
        world_per_pixel = 2.0 * cam.GetParallelScale() / size[1]
        mapper.SetScaleFactor(0.5 * pixels * world_per_pixel)
        self.win.Render()
        self.win.WaitForCompletion()

    def save_png(self, path):
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(self.win)
        grab.Update()
        w = vtk.vtkPNGWriter()
        w.SetFileName(path)
        w.SetInputConnection(grab.GetOutputPort())
        w.Write()

    def frames(self, n, turn):
        out = []
        cam = self.ren.GetActiveCamera()
        for _ in range(n):
            if turn:
                cam.Azimuth(turn)
            t0 = time.perf_counter()
            self.win.Render()
            self.win.WaitForCompletion()
            out.append((time.perf_counter() - t0) * 1e3)
        return out


def main():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    p = argparse.ArgumentParser()
    p.add_argument("--arbvis", default=os.path.join(root, "target", "release", "arbvis"))
    p.add_argument("--points", type=int, default=570000)
    p.add_argument("--pixels", type=float, default=1.3)
    p.add_argument("--size", default="1600x900")
    p.add_argument("--frames", type=int, default=5)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--turn", type=float, default=0.0,
                   help="degrees the camera turns before every frame (both systems)")
    p.add_argument("--vtk-modes", default="opaque,unsorted,peeled",
                   help="how VTK draws: " + "; ".join(f"{k}: {v}" for k, v in MODES.items()))
    p.add_argument("--dir", default="/tmp/arbvis-vtk-points")
    p.add_argument("--json", default=None)
    p.add_argument("--png", default=None, help="write VTK's frame here (to compare coverage "
                   "with `arbvis render DIR/splats.toml`)")
    a = p.parse_args()
    size = [int(v) for v in a.size.lower().split("x")]
    os.makedirs(a.dir, exist_ok=True)
    ply = os.path.join(a.dir, f"section-{a.points}-{a.seed}.ply")
    if not os.path.exists(ply):
        write_cloud(ply, a.points, a.seed)
    scenes = {}
    for draw in ("points", "tiles"):
        scenes[draw] = os.path.join(a.dir, f"splats-{draw}.toml")
        arbvis_scene(scenes[draw], ply, size, a.pixels, draw)
    peers = [VtkScene(ply, size, a.pixels, m) for m in a.vtk_modes.split(",") if m]
    for v in peers:
        print(f"VTK {v.mode}: {v.config}", flush=True)
    if a.png:
        peers[0].save_png(a.png)
    arb = {draw: [] for draw in scenes}
    vtk_ms = {v.mode: [] for v in peers}
    renderer = ""
    for r in range(a.rounds):
        for draw, scene in scenes.items():
            ms, renderer = arbvis_frames(a.arbvis, scene, a.frames, a.turn)
            arb[draw] += ms
        for v in peers:
            vtk_ms[v.mode] += v.frames(a.frames, a.turn)
        print(f"round {r + 1} of {a.rounds} done", flush=True)
    print(f"{peers[0].n if peers else '?'} points at {size[0]}x{size[1]}, {a.pixels}-pixel splats, {renderer}; "
          f"VTK {vtk.vtkVersion.GetVTKVersion()}; camera turning {a.turn} degrees per frame")
    for draw, ms in arb.items():
        m = statistics.median(ms)
        against = ", ".join(f"{statistics.median(t) / m:.1f}x VTK {k}" for k, t in vtk_ms.items())
        print(f"arbvis splats, draw = {draw:<6} (Gaussian, in depth order): median {m:8.1f} "
              f"ms/frame; {against}")
    for v in peers:
        print(f"VTK {v.mode:<8} median {statistics.median(vtk_ms[v.mode]):8.1f} ms/frame: "
              f"{v.config}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"points": v.n, "size": size, "pixels": a.pixels, "turn": a.turn,
                       "renderer": renderer, "arbvis_ms": arb["points"],
                       "arbvis_tiles_ms": arb["tiles"], "vtk_ms": vtk_ms,
                       "vtk_config": {v.mode: v.config for v in peers}}, f, indent=1)


if __name__ == "__main__":
    main()
