#!/usr/bin/env python3
"""VTK's re-extract-and-draw as a peer of arbvis's cell projection (issue 10's latency).

    pip install vtk numpy
    python3 benches/peers/vtk_contour.py --grids 17,25,33,45,56 --edits 10

The same meshes arbvis generates (`mesh = { grid = { points = [n, n, n], field =
"spherical" } }`, src/mesh/grid.rs): n^3 points at integer steps scaled so the box spans
[0, 1], each cube split into 6 tetrahedra by the Kuhn rule, the field the distance from the
box centre normalized to [0, 1]. VTK extracts the seed's three isosurfaces (0.3, 0.5, 0.9)
with vtkContourFilter (the path ParaView takes for an unstructured grid), draws them at
320x240 offscreen, and after each isovalue edit (0.5 moved by a small step, as arbvis's study
does) re-extracts and draws again: the time from the edit to the finished frame
(Render + glFinish through vtkRenderWindow.WaitForCompletion) is the latency arbvis's
`isovalue edit -> frame` column is compared with. Prints one line per grid (median of
`--edits`), or JSON with --json.
"""

import argparse
import json
import os
import statistics
import sys
import time

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_common import kuhn_tets, plain_window, window_config  # noqa: E402


def grid_mesh(n):
    """The n^3-point Kuhn grid of src/mesh/grid.rs with its spherical field."""
    pts, tets = kuhn_tets(n)
    c = 0.5  # the box [0, 1]^3 has its centre at 0.5 on every axis
    f = np.linalg.norm(pts - c, axis=1)
    f = (f - f.min()) / (f.max() - f.min())
    ug = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    p.SetData(numpy_support.numpy_to_vtk(pts.astype(np.float64), deep=True))
    ug.SetPoints(p)
    offsets = np.arange(0, 4 * len(tets) + 1, 4, dtype=np.int64)
    ca = vtk.vtkCellArray()
    ca.SetData(
        numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
        numpy_support.numpy_to_vtkIdTypeArray(tets.astype(np.int64).ravel(), deep=True),
    )
    ug.SetCells(vtk.VTK_TETRA, ca)
    s = numpy_support.numpy_to_vtk(f.astype(np.float32), deep=True)
    s.SetName("spherical")
    ug.GetPointData().SetScalars(s)
    return ug, len(tets)


def measure(n, edits, size):
    ug, tets = grid_mesh(n)
    contour = vtk.vtkContourFilter()
    contour.SetInputData(ug)
    values = [0.3, 0.5, 0.9]
    for i, v in enumerate(values):
        contour.SetValue(i, v)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(contour.GetOutputPort())
    mapper.SetScalarRange(0.0, 1.0)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    ren = vtk.vtkRenderer()
    ren.AddActor(actor)
    ren.SetBackground(0, 0, 0)
    win = plain_window(size)
    win.AddRenderer(ren)
    ren.ResetCamera()
    win.Render()
    win.WaitForCompletion()
    times = []
    for e in range(edits):
        contour.SetValue(1, 0.5 + 0.001 * (e + 1))
        t0 = time.perf_counter()
        win.Render()
        win.WaitForCompletion()
        times.append((time.perf_counter() - t0) * 1e3)
    # The frame alone (no edit): what a camera move costs.
    frames = []
    for _ in range(edits):
        t0 = time.perf_counter()
        win.Render()
        win.WaitForCompletion()
        frames.append((time.perf_counter() - t0) * 1e3)
    return {
        "grid": n,
        "tets": tets,
        "edit_to_frame_ms": statistics.median(times),
        "frame_ms": statistics.median(frames),
        "triangles": contour.GetOutput().GetNumberOfCells(),
        "renderer": win.ReportCapabilities().split("OpenGL renderer string:")[-1].split("\n")[0].strip(),
        "config": window_config(win),
    }


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--grids", default="17,25,33,45,56")
    p.add_argument("--edits", type=int, default=10)
    p.add_argument("--size", default="320x240")
    p.add_argument("--json", default=None)
    a = p.parse_args()
    size = [int(v) for v in a.size.split("x")]
    rows = []
    for n in [int(g) for g in a.grids.split(",")]:
        r = measure(n, a.edits, size)
        rows.append(r)
        print(
            f"VTK {vtk.vtkVersion.GetVTKVersion()} grid {n}: {r['tets']:>9} tets, "
            f"{r['triangles']:>8} triangles, edit->frame {r['edit_to_frame_ms']:8.2f} ms, "
            f"frame {r['frame_ms']:7.2f} ms ({r['renderer']}; {r['config']})",
            flush=True,
        )
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
