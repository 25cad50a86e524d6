#!/usr/bin/env python3
"""VTK's unstructured-grid volume mappers as peers of arbvis's cell-projection volume.

    pip install vtk numpy
    cargo build --release --no-default-features
    python3 benches/peers/vtk_unstructured.py scenes/bench/cellproj-seed-volume.toml \\
        --cellproj centroid:64,mpvonc:64,mpvonc:128,precise --rounds 3

1. `arbvis bench SCENE --cellproj ... --score --export DIR` prepares the mesh, computes the
   f64 reference and writes what VTK needs (src/study/export.rs, write_cellproj): the
   mesh's points in arbvis's object box (f64), its tetrahedra, the normalized point
   scalars, the transfer function's control points, the unit distance in those units, the
   camera (position, focal point, view up, parallel scale or view angle), size and
   background, and the reference's RGB.
2. VTK gets the same vtkUnstructuredGrid (VTK_TETRA cells, the scalars as point data), a
   vtkColorTransferFunction and vtkPiecewiseFunction with one point per control point
   (the same piecewise-linear function), SetScalarOpacityUnitDistance(unit) (VTK's
   unstructured mappers read the opacity value as attenuation per unit distance, as arbvis
   does), no shading, the same camera, size and background, and renders with
   vtkProjectedTetrahedraMapper (ParaView's default for unstructured volumes),
   vtkUnstructuredGridVolumeRayCastMapper and vtkUnstructuredGridVolumeZSweepMapper; and,
   as the peer of arbvis's precise `grid` (`--mappers resample:N` or `resample:N:F`), the
   grid resampled once by vtkResampleToImage (N points along the box's longest side, as
   arbvis's `grid:N`) and ray cast by vtkGPUVolumeRayCastMapper at F samples per spacing
   (default 2, arbvis's step), automatic sample distances and jittering off. The image
   ray caster reads an opacity value as opacity per unit distance, so its opacity function
   is 1 - exp(-a(s)) sampled at 257 points: the same attenuation per unit distance.
3. Every system is scored as RGB against the one reference (RMSE and the largest channel
   difference over every pixel) and timed per frame (VTK: Render then WaitForCompletion;
   arbvis: clear + draw + glFinish), first frame apart, arbvis and VTK alternating round
   by round. VTK's pictures are saved as PNG beside the export (ppm when no PIL).
4. It prints, for each VTK mapper, the fastest arbvis setting with equal or lower RMSE and
   the ratio of their median frame times.

Offscreen through EGL (VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow, the same Mesa path as
arbvis).
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

MAPPERS = {
    "projected-tetrahedra": "vtkProjectedTetrahedraMapper",
    "ray-cast": "vtkUnstructuredGridVolumeRayCastMapper",
    "zsweep": "vtkUnstructuredGridVolumeZSweepMapper",
}


def mapper_label(name):
    """The VTK class (and the grid) a `--mappers` name stands for."""
    if name.startswith("resample:"):
        return f"vtkResampleToImage {name[len('resample:'):]} + vtkGPUVolumeRayCastMapper"
    return MAPPERS[name]


def resampled(ug, spec):
    """`ug` on a grid of `N` points along its box's longest side (spec "resample:N[:F]"),
    and the sample distance of F samples per spacing."""
    parts = spec.split(":")
    n = int(parts[1])
    per_spacing = float(parts[2]) if len(parts) > 2 else 2.0
    b = ug.GetBounds()
    extent = np.array([b[1] - b[0], b[3] - b[2], b[5] - b[4]])
    spacing = extent.max() / (n - 1)
    dims = [int(np.ceil(e / spacing - 1e-9)) + 1 for e in extent]
    resample = vtk.vtkResampleToImage()
    resample.SetInputDataObject(ug)
    resample.SetUseInputBounds(True)
    resample.SetSamplingDimensions(*dims)
    resample.Update()
    image = resample.GetOutput()
    image.GetPointData().SetActiveScalars("scalars")
    return image, spacing / per_spacing


def arbvis_bench(args, score):
    cmd = [args.arbvis, "bench", args.scene, "--json", "--frames", str(args.frames),
           "--cellproj", args.cellproj, "--export", args.export]
    if args.size:
        cmd += ["--size", args.size]
    if score:
        cmd.append("--score")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def unstructured_grid(scene, folder):
    pts = np.fromfile(os.path.join(folder, scene["points_file"]), dtype="<f8").reshape(-1, 3)
    tets = np.fromfile(os.path.join(folder, scene["tets_file"]), dtype="<u4").reshape(-1, 4)
    s = np.fromfile(os.path.join(folder, scene["scalars_file"]), dtype="<f8")
    ug = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    p.SetData(numpy_support.numpy_to_vtk(pts, deep=True))
    ug.SetPoints(p)
    offsets = np.arange(0, 4 * len(tets) + 1, 4, dtype=np.int64)
    ca = vtk.vtkCellArray()
    ca.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
               numpy_support.numpy_to_vtkIdTypeArray(tets.astype(np.int64).ravel(), deep=True))
    ug.SetCells(vtk.VTK_TETRA, ca)
    arr = numpy_support.numpy_to_vtk(s.astype(np.float32), deep=True)
    arr.SetName("scalars")
    ug.GetPointData().SetScalars(arr)
    return ug


class VtkPeer:
    def __init__(self, scene, folder, mapper_name):
        self.scene = scene
        ug = unstructured_grid(scene, folder)
        colour = vtk.vtkColorTransferFunction()
        opacity = vtk.vtkPiecewiseFunction()
        for s, r, g, b, a in scene["transfer"]:
            colour.AddRGBPoint(s, r, g, b)
        image = mapper_name.startswith("resample:")
        if image:
            # Opacity per unit distance with the same attenuation: 1 - exp(-a(s)).
            tf = np.array(scene["transfer"])
            for s in np.linspace(0.0, 1.0, 257):
                opacity.AddPoint(s, 1.0 - np.exp(-np.interp(s, tf[:, 0], tf[:, 4])))
        else:
            for s, r, g, b, a in scene["transfer"]:
                opacity.AddPoint(s, a)
        prop = vtk.vtkVolumeProperty()
        prop.SetColor(colour)
        prop.SetScalarOpacity(opacity)
        prop.SetScalarOpacityUnitDistance(scene["unit_distance"])
        prop.ShadeOff()
        prop.SetInterpolationTypeToLinear()
        if image:
            grid, distance = resampled(ug, mapper_name)
            self.mapper = vtk.vtkGPUVolumeRayCastMapper()
            self.mapper.SetInputData(grid)
            self.mapper.SetAutoAdjustSampleDistances(0)
            self.mapper.SetSampleDistance(distance)
            self.mapper.SetUseJittering(0)
        else:
            self.mapper = getattr(vtk, MAPPERS[mapper_name])()
            self.mapper.SetInputData(ug)
        if hasattr(self.mapper, "SetAutoAdjustImageSampleDistances"):
            # Every pixel cast (no lower-resolution image when a frame runs long), as
            # arbvis draws every pixel: the ray caster's and the z-sweep's quality at its
            # fastest fixed setting.
            self.mapper.SetAutoAdjustImageSampleDistances(0)
            self.mapper.SetImageSampleDistance(1.0)
        volume = vtk.vtkVolume()
        volume.SetMapper(self.mapper)
        volume.SetProperty(prop)
        renderer = vtk.vtkRenderer()
        renderer.AddVolume(volume)
        self.window = offscreen_window(renderer, scene)
        self.config = (window_config(self.window) + "; " + mapper_config(self.mapper, [
            "AutoAdjustImageSampleDistances", "ImageSampleDistance", "MaxPixelListSize",
            "UseFloatingPointFrameBuffer", "AutoAdjustSampleDistances", "SampleDistance",
            "UseJittering"]))
        if image:
            self.config += f"; grid {list(grid.GetDimensions())}"


    def frame(self):
        return timed_frame(self.window)

    def rgb(self):
        return window_rgb(self.window)


def save_ppm(path, rgb):
    h, w, _ = rgb.shape
    with open(path, "wb") as f:
        f.write(f"P6 {w} {h} 255\n".encode())
        f.write((np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8).tobytes())


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", ".."))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--arbvis", default=os.path.join(root, "target", "release", "arbvis"))
    p.add_argument("--export", default=None)
    p.add_argument("--cellproj", default="centroid:64,mpvonc:64,mpvonc:128,precise")
    p.add_argument("--mappers", default="projected-tetrahedra,ray-cast,zsweep")
    p.add_argument("--frames", type=int, default=3)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--size", default=None)
    p.add_argument("--json", default=None)
    args = p.parse_args()
    name = os.path.splitext(os.path.basename(args.scene))[0]
    args.export = args.export or os.path.join(root, "target", f"peer-{name}")
    scored = arbvis_bench(args, score=True)
    scene, reference = load_export(args.export)
    print(f"arbvis: {scored['renderer']}, {scene['size']}, {scene['tets']} tetrahedra; "
          f"VTK {vtk.vtkVersion.GetVTKVersion()}", flush=True)
    arb = {m["name"]: {"rmse": m["rmse"], "max_abs": m["max_abs"], "frames_ms": []}
           for m in scored["settings"]}
    peers = {}
    for m in [x for x in args.mappers.split(",") if x]:
        peer = VtkPeer(scene, args.export, m)
        first = peer.frame()
        image = peer.rgb()
        err = rgb_error(image, reference)
        save_ppm(os.path.join(args.export, f"vtk-{m}.ppm"), image)
        peers[m] = {"peer": peer, "first_ms": first, "max_abs": err[0], "rmse": err[1],
                    "frames_ms": []}
        print(f"VTK {m}: first {first:.0f} ms, RMSE {err[1]:.5f}, max {err[0]:.3f}; "
              f"{peer.config}", flush=True)
    for r in range(args.rounds):
        report = arbvis_bench(args, score=False)
        for m in report["settings"]:
            arb[m["name"]]["frames_ms"] += m["frames_ms"]
        for m, v in peers.items():
            v["frames_ms"] += [v["peer"].frame() for _ in range(args.frames)]
        print(f"round {r + 1} of {args.rounds} done", flush=True)
    print("\n| system, setting | ms/frame (median) | RMSE | max |\n|---|---|---|---|")
    for n, v in arb.items():
        print(f"| arbvis {n} | {statistics.median(v['frames_ms']):.1f} | {v['rmse']:.5f} "
              f"| {v['max_abs']:.3f} |")
    for m, v in peers.items():
        print(f"| VTK {mapper_label(m)} | {statistics.median(v['frames_ms']):.1f} | {v['rmse']:.5f} "
              f"| {v['max_abs']:.3f} |")
    print("\n| VTK mapper | VTK ms | RMSE | fastest arbvis at equal or lower RMSE | ms | RMSE "
          "| speed-up |\n|---|---|---|---|---|---|---|")
    for m, v in peers.items():
        vt = statistics.median(v["frames_ms"])
        fit = [(statistics.median(a["frames_ms"]), n, a["rmse"]) for n, a in arb.items()
               if a["rmse"] is not None and a["rmse"] <= v["rmse"]]
        if fit:
            at, an, ae = min(fit)
            print(f"| {mapper_label(m)} | {vt:.1f} | {v['rmse']:.5f} | {an} | {at:.1f} | {ae:.5f} "
                  f"| {vt / at:.2f}x |")
        else:
            print(f"| {mapper_label(m)} | {vt:.1f} | {v['rmse']:.5f} | none | - | - | - |")
    if args.json:
        out = {"arbvis": scored, "arbvis_frames": arb,
               "vtk": [{"mapper": m, "first_ms": v["first_ms"], "frames_ms": v["frames_ms"],
                        "rmse": v["rmse"], "max_abs": v["max_abs"]} for m, v in peers.items()],
               "vtk_version": vtk.vtkVersion.GetVTKVersion(),
               "vtk_config": {m: v["peer"].config for m, v in peers.items()}}
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
