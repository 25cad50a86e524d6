"""What the VTK peer scripts share: the Kuhn grid arbvis generates, the exported camera
applied to a VTK renderer in an offscreen window, and one timed frame.

Imported by vtk_volume.py, vtk_unstructured.py, vtk_contour.py and benches/meshes.py; it
imports vtk only inside the functions that need it, so meshes.py runs with numpy alone.
"""

import time

import numpy as np


def kuhn_tets(n):
    """The n^3-point Kuhn grid of src/mesh/grid.rs: points in [0, 1]^3 (point (i, j, k) is
    index i + n (j + n k)) and its 6 (n - 1)^3 tetrahedra, one per axis ordering of
    each cube."""
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    pts = np.stack([i, j, k], axis=-1).transpose(2, 1, 0, 3).reshape(-1, 3) / (n - 1.0)
    idx = lambda a, b, d: a + n * (b + n * d)  # noqa: E731
    ci, cj, ck = np.meshgrid(np.arange(n - 1), np.arange(n - 1), np.arange(n - 1), indexing="ij")
    ci, cj, ck = ci.ravel(), cj.ravel(), ck.ravel()
    tets = []
    for order in ([0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]):
        o = np.zeros(3, dtype=int)
        corners = [idx(ci, cj, ck)]
        for axis in order:
            o[axis] += 1
            corners.append(idx(ci + o[0], cj + o[1], ck + o[2]))
        tets.append(np.stack(corners, axis=1))
    return pts, np.concatenate(tets)


def offscreen_window(renderer, scene):
    """Point the renderer's camera as the exported scene says (focal point, position,
    view up, parallel scale or view angle, near and far around the object) and put it
    in an offscreen window of the scene's size and background."""
    import vtk

    renderer.SetBackground(*scene["background"][:3])
    cam = renderer.GetActiveCamera()
    c = scene["camera"]
    cam.SetFocalPoint(*c["focal_point"])
    cam.SetPosition(*c["position"])
    cam.SetViewUp(*c["view_up"])
    distance = float(np.linalg.norm(c["position"]))
    if c["projection"] == "orthographic":
        cam.ParallelProjectionOn()
        cam.SetParallelScale(c["parallel_scale"])
    else:
        cam.ParallelProjectionOff()
        cam.SetViewAngle(c["view_angle"])
    cam.SetClippingRange(max(distance - 2.0, 1e-3), distance + 2.0)
    window = plain_window(scene["size"])
    window.AddRenderer(renderer)
    return window


def plain_window(size):
    """An offscreen window of `size` as a careful user sets one up for a benchmark:
    multisampling off (VTK's EGL window multisamples 8x by default; arbvis renders
    without), so both draw one sample per pixel."""
    import vtk

    window = vtk.vtkRenderWindow()
    window.SetMultiSamples(0)
    window.SetOffScreenRendering(1)
    window.SetSize(*size)
    return window


def window_config(window):
    """The peer's window as the output states it beside every ratio."""
    import vtk

    w, h = window.GetSize()
    return (f"VTK {vtk.vtkVersion.GetVTKVersion()} {window.GetClassName()}, {w}x{h}, "
            f"multisamples {window.GetMultiSamples()}, offscreen {window.GetOffScreenRendering()}")


def mapper_config(mapper, names):
    """`Name=value` of each getter in `names` that `mapper` has (GetName)."""
    out = []
    for n in names:
        getter = getattr(mapper, "Get" + n, None)
        if getter is not None:
            out.append(f"{n}={getter()}")
    return f"{mapper.GetClassName()}(" + ", ".join(out) + ")"


def timed_frame(window):
    """One frame in milliseconds: Render, then WaitForCompletion (glFinish), as arbvis
    times clear + draw + glFinish."""
    t0 = time.perf_counter()
    window.Render()
    window.WaitForCompletion()
    return (time.perf_counter() - t0) * 1e3


def load_export(folder):
    """The scene an `arbvis bench --export FOLDER` wrote (scene.json) and its f64
    reference as an (h, w, 3) array; exits naming the folder if the sizes disagree."""
    import json
    import os
    import sys

    with open(os.path.join(folder, "scene.json")) as f:
        scene = json.load(f)
    w, h = scene["size"]
    ref = np.fromfile(os.path.join(folder, scene["reference"]), dtype="<f4")
    if ref.size != w * h * 3:
        sys.exit(f"{folder}: reference holds {ref.size} floats, expected {w * h * 3}")
    return scene, ref.reshape(h, w, 3)


def window_rgb(window):
    """The window's back buffer as RGB in [0, 1], top row first."""
    import vtk
    from vtk.util import numpy_support

    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    out = grab.GetOutput()
    w, h, _ = out.GetDimensions()
    pixels = numpy_support.vtk_to_numpy(out.GetPointData().GetScalars())
    return pixels.reshape(h, w, 3)[::-1].astype(np.float64) / 255.0


def rgb_error(image, reference):
    """Largest channel difference and RMSE of two RGB arrays."""
    d = image - reference
    return float(np.abs(d).max()), float(np.sqrt(np.mean(d * d)))
