"""arbvis from Python: scenes in, numpy arrays out.

>>> import arbvis
>>> scene = arbvis.Scene.demo("v3o2-sum")
>>> scene.zoom = 1.4
>>> with arbvis.Renderer(scene) as renderer:
...     image = renderer.render()          # (height, width, 4) uint8
...     scene["technique.opacity3d.primary.coefficients"] = [0.2, 0.2, 0.2, 0.9]
...     again = renderer.render()          # a frame, not a new process

`Scene` reads and edits scenes (dotted keys, validated as scene files are); `Volume`,
`Cloud` and `Mesh` hand a survey (numpy, xarray), a point cloud (numpy, laspy) or an
unstructured mesh (numpy, meshio) over from memory, wherever a scene names a file;
`Renderer` keeps its GL context, data and programs between frames; `table(colors)` makes a
colour table of an array or a matplotlib colormap; `info()` reports the driver; `inspect(path)` and `convert(src, dst, progress=...)` are the command line's
`inspect` and `convert`; `read_png`, `write_png`, `compare` and `diff_image` read, write and compare pictures
as the Rust tests do. Errors are `ArbvisError` and its subclasses `SceneError`, `InputError`,
`GLError`, `RenderError`. The pytest plugin (`arbvis.pytest_plugin`, loaded by pytest)
adds the `arbvis_image` fixture; `arbvis.dask` renders many views on a Dask cluster;
`arbvis.notebook.View(scene)` shows a scene in a notebook and turns it with the mouse
(anywidget).
"""

from ._arbvis import (  # noqa: F401
    ArbvisError,
    Cancelled,
    Cloud,
    GLError,
    InputError,
    Mesh,
    Renderer,
    RenderError,
    Scene,
    SceneError,
    Surface,
    Volume,
    __version__,
    compare,
    convert,
    diff_image,
    info,
    inspect,
    fetch_stats,
    read_png,
    write_png,
)

from .tables import table  # noqa: E402

__all__ = [
    "ArbvisError",
    "Cancelled",
    "Cloud",
    "GLError",
    "InputError",
    "Mesh",
    "RenderError",
    "Renderer",
    "Scene",
    "SceneError",
    "Surface",
    "Volume",
    "compare",
    "convert",
    "diff_image",
    "info",
    "inspect",
    "fetch_stats",
    "read_png",
    "table",
    "write_png",
    "__version__",
]
