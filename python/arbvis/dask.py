"""Many views of one scene rendered on a Dask cluster, one renderer per worker.

Each worker process keeps one ``arbvis.Renderer`` per scene between tasks (its GL context,
the loaded data and the programs), so a view costs a frame, not a load; views are spread
over the workers with ``client.map`` and come back as numpy arrays (or PNG files)::

    from dask.distributed import Client, LocalCluster
    import arbvis, arbvis.dask

    scene = arbvis.Scene.load("scenes/store.toml")
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        images = arbvis.dask.render_views(client, scene, arbvis.dask.orbit(36))

A scene crosses to the workers as its TOML text and folder; its data paths must be
readable from every worker (a shared folder, or the same paths on each machine).
"""

import math
import os

import arbvis

# Per worker process: the scene's text and folder -> its renderer.
_RENDERERS = {}


def orbit(count, elevation_deg=20.0):
    """``count`` camera rotations (quaternions ``(x, y, z, w)``) turning once around the
    vertical axis, looked at from ``elevation_deg`` above."""
    tilt = math.radians(elevation_deg) / 2.0
    qx = (math.sin(tilt), 0.0, 0.0, math.cos(tilt))
    views = []
    for k in range(count):
        half = math.pi * k / count
        qy = (0.0, math.sin(half), 0.0, math.cos(half))
        views.append(_multiply(qx, qy))
    return views


def _multiply(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _renderer_for(text, base, backend):
    key = (text, base, backend)
    renderer = _RENDERERS.get(key)
    if renderer is None:
        # One scene at a time per worker: drop the others' contexts and data.
        for old in _RENDERERS.values():
            old.close()
        _RENDERERS.clear()
        renderer = arbvis.Renderer(arbvis.Scene.from_toml(text, base), backend=backend)
        _RENDERERS[key] = renderer
    return renderer


def render_view(text, base, rotation, backend="egl", png=None):
    """Render the scene given as TOML ``text`` (data read from ``base``) turned to
    ``rotation``, with this worker's renderer for it; the array, or the PNG's path when
    ``png`` names one (written atomically). The task ``render_views`` maps."""
    renderer = _renderer_for(text, base, backend)
    scene = arbvis.Scene.from_toml(text, base)
    scene.rotation = tuple(rotation)
    image = renderer.render(scene)
    if png is None:
        return image
    arbvis._arbvis.write_png(png, image)
    return png


def _names_memory(tree):
    """Whether a scene's tree names a volume in memory (`{"memory": NAME}`) anywhere."""
    if isinstance(tree, dict):
        return "memory" in tree or any(_names_memory(v) for v in tree.values())
    if isinstance(tree, list):
        return any(_names_memory(v) for v in tree)
    return False


def render_views(client, scene, rotations, backend="egl", out_dir=None):
    """Render ``scene`` turned to each of ``rotations`` on ``client``'s workers: the
    arrays in order, or with ``out_dir`` the PNG files written there
    (``view_0000.png``, ...)."""
    text = scene.to_toml()
    if _names_memory(scene.to_dict()):
        raise arbvis.InputError(
            "render_views: the scene holds an arbvis.Volume, which lives in this process "
            "only; the workers read files: write the survey to a SEG-Y file or a store "
            "(arbvis convert) and name it in the scene"
        )
    base = str(scene.base)
    pngs = [None] * len(rotations)
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
        pngs = [os.path.join(out_dir, f"view_{k:04d}.png") for k in range(len(rotations))]
    futures = client.map(
        render_view,
        [text] * len(rotations),
        [base] * len(rotations),
        list(rotations),
        [backend] * len(rotations),
        pngs,
        pure=False,
    )
    return client.gather(futures)
