"""Colour tables from Python: an (N, 3) or (N, 4) array, a matplotlib colormap, or a
colormap's name, as the table a scene takes (`{"colors": [[r, g, b, a], ...]}`, spread
evenly over the 256 entries and interpolated linearly; an `alpha` curve of `[position,
alpha]` points replaces the colours' own alpha)."""

import numpy as np

from ._arbvis import InputError


def table(colors, alpha=None):
    """The scene's table of `colors`: an (N, 3) or (N, 4) array (floats in 0..1, or uint8
    levels), a matplotlib colormap (anything called with positions that gives RGBA rows),
    or a colormap's name (matplotlib needed). Three columns are opaque unless `alpha` (a
    list of `[position, alpha]` points in 0..1) says otherwise.

    >>> scene["technique.opacity3d.primary.table"] = arbvis.table("viridis", alpha=[[0, 0], [1, 1]])
    """
    if isinstance(colors, str):
        try:
            import matplotlib
        except ImportError:
            raise InputError(
                f"table: the colormap {colors!r} is matplotlib's: install matplotlib, or give an (N, 3|4) array"
            ) from None
        try:
            colors = matplotlib.colormaps[colors]
        except KeyError:
            raise InputError(f"table: matplotlib has no colormap {colors!r}") from None
    if callable(colors):
        colors = np.asarray(colors(np.linspace(0.0, 1.0, 256)))
    array = np.asarray(colors)
    if array.ndim != 2 or array.shape[1] not in (3, 4) or not 2 <= array.shape[0] <= 4096:
        raise InputError(f"table: colours are an (N, 3) or (N, 4) array, 2 <= N <= 4096, got {array.shape}")
    if array.dtype == np.uint8:
        array = array / 255.0
    elif array.dtype.kind not in "f":
        raise InputError(f"table: colours are floats in 0..1 or uint8 levels, got {array.dtype}")
    array = np.asarray(array, dtype=np.float64)
    if not np.isfinite(array).all() or array.min() < 0 or array.max() > 1:
        raise InputError("table: colours are in 0..1")
    if array.shape[1] == 3:
        array = np.column_stack([array, np.ones(len(array))])
    spec = {"colors": array.tolist()}
    if alpha is not None:
        spec["alpha"] = np.asarray(alpha, dtype=np.float64).tolist()
    return spec
