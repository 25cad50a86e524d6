#!/usr/bin/env python3
"""VTK's GPU ray caster as a peer of arbvis's 3D opacity, on the same work.

    pip install vtk numpy
    cargo build --release --no-default-features
    python3 benches/peers/vtk_volume.py scenes/bench/cube256-amplitude.toml \\
        --precise 128,256,512 --raycast 0.5,1,2 --faithful 128,256 \\
        --sample-distances 2,1,0.5,0.25 --types float32,uint8 --rounds 3

1. `arbvis bench SCENE --score --export DIR` prepares the data, computes the f64
   reference (cached in DIR) and writes what VTK needs: the quantized levels of each
   attribute, its 256-entry table, the camera and the box (see src/study/export.rs).
2. VTK gets the same levels as cell scalars on an (n+1)^3-point grid spanning the same box
   [-half, half] (point scalars would shrink the box by half a voxel), as uint8 and/or
   float32; colour and opacity transfer functions with one point per level (the table
   times the coefficients, times 1/3 in a sum, as arbvis's precise programs compute);
   scalar opacity unit distance = arbvis's reference spacing (one voxel along the longest
   axis: table alpha is the opacity of that length in both); linear interpolation, no
   shading, no jittering, no automatic sample distances; the same camera, size and
   background. Several attributes become independent components (VTK then combines them
   its own way, which is not arbvis's sum or product: its error includes that).
3. Both are scored as RGB against the one reference (RMSE over the three channels of
   every pixel), and timed per frame (clear + draw + finish; VTK: Render then
   WaitForCompletion), first frame apart, alternating arbvis and VTK round by round.
4. Matching (`--match FROM:TO:STEP`, default 0.2:2:0.025; `off` to skip): before the
   timed rounds, the ray caster is scored once at every steps-per-voxel on that ladder,
   and for each VTK setting the fewest steps at or below its RMSE join the timed
   settings. The error is not monotonic in the steps (a step that is a simple fraction
   of the voxel spacing aliases the data: on the 256³ cube 0.4 step/voxel is three times
   further from the reference than 0.425), so a coarse sweep such as 0.5,1,2 can miss the
   cheapest matching setting by a factor of two.
5. It prints, for each VTK setting, the fastest arbvis setting with equal or lower RMSE
   and the ratio of their median frame times.

Offscreen: VTK 9.4+ wheels pick their window class at run time; this script sets
VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow (the same Mesa EGL path as arbvis), and
vtkOSOpenGLRenderWindow works too (set the variable before running to choose it).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_common import (load_export, mapper_config, offscreen_window, rgb_error,  # noqa: E402
                         timed_frame, window_config, window_rgb)


def arbvis_bench(args, extra, score):
    """Run `arbvis bench` once and return its JSON report."""
    cmd = [args.arbvis, "bench", args.scene, "--json", "--frames", str(args.frames),
           "--export", args.export, "--oversample", str(args.oversample),
           "--view", args.view] + extra
    if score:
        cmd.append("--score")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def ladder(spec):
    """The steps per voxel of FROM:TO:STEP, rounded to 4 decimals."""
    lo, hi, step = (float(x) for x in spec.split(":"))
    if not (0 < lo <= hi and step > 0):
        raise SystemExit(f"--match {spec}: expected FROM:TO:STEP with 0 < FROM <= TO, STEP > 0")
    n = int(round((hi - lo) / step))
    return [round(lo + k * step, 4) for k in range(n + 1)]


def raycast_extra(extra, steps):
    """`extra` with its --raycast list replaced by `steps`."""
    out, skip = [], False
    for x in extra:
        if skip:
            skip = False
        elif x == "--raycast":
            skip = True
        else:
            out.append(x)
    return out + ["--raycast", steps]


def match_raycast(args, peers, arb):
    """For each VTK setting, the fewest steps per voxel on the --match ladder at which the
    ray caster's RMSE is at or below the setting's. The error is not monotonic in the steps
    (a step that is a simple fraction of the voxel spacing aliases the data), so a coarse
    sweep can miss the cheapest matching setting by a factor of two; the time is monotonic,
    so the first match on a fine ladder is the fastest. Its scores join `arb`."""
    steps = ladder(args.match)
    scan = dict(args.__dict__)
    scan["frames"] = 1
    only = (["--size", args.size] if args.size else []) + [
        "--raycast", ",".join(f"{v:g}" for v in steps)]
    scored = arbvis_bench(argparse.Namespace(**scan), only, score=True)["settings"]
    matched = {}
    for key, v in peers.items():
        fit = [step for step, m in zip(steps, scored)
               if m["rmse"] is not None and m["rmse"] <= v["rmse"]]
        if fit:
            matched[key] = fit[0]
    for step, m in zip(steps, scored):
        if step in matched.values() and m["name"] not in arb:
            arb[m["name"]] = {"rmse": m["rmse"], "max_abs": m["max_abs"], "frames_ms": []}
    print("matched on the ladder " + args.match + ": " + ", ".join(
        f"{t} sd {sd} -> {matched[(t, sd)]:g} step/voxel" if (t, sd) in matched
        else f"{t} sd {sd} -> none" for (t, sd) in peers), flush=True)
    return matched


def transfer_functions(scene, attribute):
    """Colour and opacity of each level, as arbvis's precise programs compute them."""
    table = np.fromfile(os.path.join(scene["folder"], attribute["table"]), dtype=np.uint8)
    table = table.reshape(256, 4).astype(np.float64) / 255.0
    c = np.array(attribute["coefficients"], dtype=np.float64)
    scale = 1.0 / 3.0 if scene["combine"] == "sum" else 1.0
    rgba = np.clip(table * c * scale, 0.0, 1.0)
    colour = vtk.vtkColorTransferFunction()
    opacity = vtk.vtkPiecewiseFunction()
    for k in range(256):
        colour.AddRGBPoint(float(k), *rgba[k, :3])
        opacity.AddPoint(float(k), rgba[k, 3])
    return colour, opacity


class VtkPeer:
    def __init__(self, scene, scalar_type):
        self.scene = scene
        ni, nj, nk = scene["dims"]
        half = np.array(scene["half"])
        image = vtk.vtkImageData()
        image.SetDimensions(ni + 1, nj + 1, nk + 1)
        image.SetSpacing(*(2.0 * half / np.array([ni, nj, nk])))
        image.SetOrigin(*(-half))
        levels = []
        for a in scene["attributes"]:
            v = np.fromfile(os.path.join(scene["folder"], a["levels"]), dtype=np.uint8)
            levels.append(v)
        data = np.stack(levels, axis=1) if len(levels) > 1 else levels[0]
        data = data.astype(np.float32 if scalar_type == "float32" else np.uint8)
        array = numpy_support.numpy_to_vtk(np.ascontiguousarray(data), deep=True)
        array.SetName("levels")
        image.GetCellData().SetScalars(array)
        self.image = image

        prop = vtk.vtkVolumeProperty()
        prop.SetInterpolationTypeToLinear()
        prop.ShadeOff()
        prop.IndependentComponentsOn()
        for i, a in enumerate(scene["attributes"]):
            colour, opacity = transfer_functions(scene, a)
            prop.SetColor(i, colour)
            prop.SetScalarOpacity(i, opacity)
            prop.SetScalarOpacityUnitDistance(i, scene["reference_spacing"])
            if len(levels) > 1:
                prop.SetComponentWeight(i, 1.0)
        self.mapper = vtk.vtkGPUVolumeRayCastMapper()
        self.mapper.SetInputData(image)
        self.mapper.SetScalarModeToUseCellData()
        self.mapper.SetBlendModeToComposite()
        self.mapper.SetAutoAdjustSampleDistances(0)
        self.mapper.SetUseJittering(0)
        volume = vtk.vtkVolume()
        volume.SetMapper(self.mapper)
        volume.SetProperty(prop)

        renderer = vtk.vtkRenderer()
        renderer.AddVolume(volume)
        self.window = offscreen_window(renderer, scene)
        self.renderer = renderer

    def frame(self):
        return timed_frame(self.window)

    def set_sample_distance(self, voxels):
        self.mapper.SetSampleDistance(voxels * self.scene["reference_spacing"])

    def rgb(self):
        return window_rgb(self.window)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", ".."))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--arbvis", default=os.path.join(root, "target", "release", "arbvis"))
    p.add_argument("--export", default=None, help="folder for the shared data (default: "
                   "target/peer-SCENE-NAME)")
    p.add_argument("--faithful", default="")
    p.add_argument("--precise", default="")
    p.add_argument("--raycast", default="")
    p.add_argument("--raycast-preint", default="")
    p.add_argument("--match", default="0.2:2:0.025", metavar="FROM:TO:STEP",
                   help="for each VTK setting, also time the ray caster at the fewest steps "
                   "per voxel on this ladder whose RMSE is at or below that setting's "
                   "(scored once, before the timed rounds); 'off' to time only the given "
                   "settings")
    p.add_argument("--view", default="file", help="file, axis, rotated or perspective "
                   "(arbvis bench --view)")
    p.add_argument("--only-vtk", default=None, metavar="TYPE:SD",
                   help="render only VTK at this setting (e.g. float32:2) from the export "
                   "folder, --frames frames, and print the median: for timing whole "
                   "processes")
    p.add_argument("--sample-distances", default="2,1,0.5,0.25",
                   help="VTK sample distances in voxels (reference spacings)")
    p.add_argument("--types", default="float32,uint8")
    p.add_argument("--frames", type=int, default=3)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--oversample", type=float, default=16.0)
    p.add_argument("--size", default=None, help="override the scene's size, e.g. 256x256")
    p.add_argument("--json", default=None, help="write every measurement here")
    args = p.parse_args()
    name = os.path.splitext(os.path.basename(args.scene))[0]
    args.export = args.export or os.path.join(root, "target", f"peer-{name}-{args.view}")
    if args.only_vtk:
        t, sd = args.only_vtk.split(":")
        scene, _ = load_export(args.export)
        scene["folder"] = args.export
        peer = VtkPeer(scene, t)
        peer.set_sample_distance(float(sd))
        peer.frame()
        times = [peer.frame() for _ in range(args.frames)]
        print(f"VTK {t} sd {sd}: median {statistics.median(times):.1f} ms")
        return

    extra = []
    for flag in ("faithful", "precise", "raycast", "raycast_preint"):
        if getattr(args, flag):
            extra += ["--" + flag.replace("_", "-"), getattr(args, flag)]
    if args.size:
        extra += ["--size", args.size]
    # The first run scores (and computes or reads the cached reference) and exports.
    scored = arbvis_bench(args, extra, score=True)
    scene, reference = load_export(args.export)
    scene["folder"] = args.export
    print(f"arbvis: {scored['renderer']} ({scored['version']}), {scene['size']}, "
          f"{len(scene['attributes'])} attribute(s); VTK {vtk.vtkVersion.GetVTKVersion()}",
          flush=True)

    arb = {m["name"]: {"rmse": m["rmse"], "max_abs": m["max_abs"], "frames_ms": []}
           for m in scored["settings"]}
    peers = {}
    distances = [float(x) for x in args.sample_distances.split(",") if x]
    for t in [x for x in args.types.split(",") if x]:
        peer = VtkPeer(scene, t)
        print(f"VTK {t}: {window_config(peer.window)}; " + mapper_config(peer.mapper, [
            "AutoAdjustSampleDistances", "UseJittering", "LockSampleDistanceToInputSpacing",
            "ImageSampleDistance"]), flush=True)
        for sd in distances:
            peer.set_sample_distance(sd)
            first = peer.frame()
            err = rgb_error(peer.rgb(), reference)
            peers[(t, sd)] = {"peer": peer, "first_ms": first, "max_abs": err[0],
                              "rmse": err[1], "frames_ms": []}
            print(f"VTK {t} sd {sd}: first {first:.0f} ms, RMSE {err[1]:.5f}", flush=True)

    matched = match_raycast(args, peers, arb) if args.match != "off" else {}
    if matched:
        steps = [x for x in args.raycast.split(",") if x] + sorted(
            {f"{v:g}" for v in matched.values()} - set(args.raycast.split(",")), key=float)
        extra = raycast_extra(extra, ",".join(steps))

    for r in range(args.rounds):
        report = arbvis_bench(args, extra, score=False)
        for m in report["settings"]:
            arb[m["name"]]["frames_ms"] += m["frames_ms"]
        for (t, sd), v in peers.items():
            v["peer"].set_sample_distance(sd)
            v["peer"].frame()  # the first frame after a change, apart
            v["frames_ms"] += [v["peer"].frame() for _ in range(args.frames)]
        print(f"round {r + 1} of {args.rounds} done", flush=True)

    print("\n| system, setting | ms/frame (median) | RMSE |\n|---|---|---|")
    for name, v in arb.items():
        print(f"| arbvis {name} | {statistics.median(v['frames_ms']):.0f} | {v['rmse']:.4f} |")
    for (t, sd), v in peers.items():
        print(f"| VTK {t}, sample distance {sd} voxel | "
              f"{statistics.median(v['frames_ms']):.0f} | {v['rmse']:.4f} |")
    print("\n| VTK setting | VTK ms | RMSE | fastest arbvis at equal or lower RMSE | ms | RMSE "
          "| speed-up |\n|---|---|---|---|---|---|---|")
    ratios = []
    for (t, sd), v in peers.items():
        vt = statistics.median(v["frames_ms"])
        fit = [(statistics.median(a["frames_ms"]), n, a["rmse"]) for n, a in arb.items()
               if a["rmse"] is not None and a["rmse"] <= v["rmse"]]
        if fit:
            at, an, ae = min(fit)
            ratios.append(vt / at)
            print(f"| {t} sd {sd} | {vt:.0f} | {v['rmse']:.4f} | {an} | {at:.0f} | {ae:.4f} "
                  f"| {vt / at:.2f}x |")
        else:
            print(f"| {t} sd {sd} | {vt:.0f} | {v['rmse']:.4f} | none | - | - | - |")
    if ratios:
        print(f"\nspeed-up at equal or lower error: {min(ratios):.2f}x to {max(ratios):.2f}x")
    if args.json:
        out = {"arbvis": scored, "arbvis_frames": arb,
               "vtk": [{"type": t, "sample_distance": sd, "first_ms": v["first_ms"],
                        "frames_ms": v["frames_ms"], "rmse": v["rmse"],
                        "max_abs": v["max_abs"]} for (t, sd), v in peers.items()],
               "vtk_version": vtk.vtkVersion.GetVTKVersion(),
               "vtk_config": window_config(next(iter(peers.values()))["peer"].window)
               if peers else None}
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
