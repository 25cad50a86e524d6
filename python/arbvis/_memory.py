"""The user's arrays as `arbvis.Volume` keeps them: a numpy array or an xarray DataArray
turned into float32 samples in C order, indexed [inline, crossline, sample], with the
map coordinates of the traces and the sample axis where a DataArray gives them. Every
refusal is an `InputError` naming the argument."""

import math

import numpy as np

from ._arbvis import InputError, check_budget

#: The sample types a volume takes (what SEG-Y, MDIO and raw files hold).
DTYPES = ("float32", "float64", "int8", "int16", "int32", "uint8", "uint16")
#: Dimension names, as mdio and segysak write them.
INLINE = ("inline", "iline", "il")
CROSSLINE = ("crossline", "xline", "xl")
SAMPLE = {"time": "time", "twt": "time", "depth": "depth", "sample": "sample", "samples": "sample"}


def _dim(dims, names, what):
    found = [d for d in dims if str(d).lower() in names]
    if len(found) != 1:
        raise InputError(
            f"volume: a DataArray with one {what} dimension ({', '.join(names)}), got dimensions {tuple(dims)}"
        )
    return found[0]


def _from_xarray(da):
    """The DataArray's samples [inline, crossline, sample], its traces' map coordinates
    (C order over inline, crossline) and its sample axis (domain, step)."""
    il = _dim(da.dims, INLINE, "inline")
    xl = _dim(da.dims, CROSSLINE, "crossline")
    sm = _dim(da.dims, tuple(SAMPLE), "sample")
    if da.ndim != 3:
        raise InputError(f"volume: a 3D DataArray, got dimensions {tuple(da.dims)}")
    da = da.transpose(il, xl, sm)
    axis = None
    if sm in da.coords and da.sizes[sm] > 1:
        t = np.asarray(da.coords[sm].values, dtype=np.float64)
        step = (t[-1] - t[0]) / (len(t) - 1)
        if math.isfinite(step) and step != 0:
            axis = (SAMPLE[str(sm).lower()], float(step))
    cdp = None
    if "cdp_x" in da.coords and "cdp_y" in da.coords:
        x = da.coords["cdp_x"].transpose(il, xl).values
        y = da.coords["cdp_y"].transpose(il, xl).values
        cdp = (
            np.asarray(x, dtype=np.float64).ravel().tolist(),
            np.asarray(y, dtype=np.float64).ravel().tolist(),
        )
    return da.values, cdp, axis


def _spacing(spacing):
    try:
        values = tuple(float(v) for v in spacing)
    except (TypeError, ValueError):
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) and v > 0 for v in values):
        raise InputError(
            f"volume: spacing is three positive numbers (inline, crossline, sample), got {spacing!r}"
        )
    return values


def volume_parts(data, spacing):
    """(float32 samples in C order [inline, crossline, sample], spacing or None, the
    traces' (x, y) or None, the sample axis (domain, step) or None)."""
    cdp = axis = None
    if hasattr(data, "dims") and hasattr(data, "coords") and hasattr(data, "transpose"):
        data, cdp, axis = _from_xarray(data)
    array = np.asarray(data)
    if array.ndim != 3:
        raise InputError(
            f"volume: a 3D array indexed [inline, crossline, sample], got shape {array.shape}"
        )
    if array.dtype.name not in DTYPES:
        raise InputError(f"volume: samples of {', '.join(DTYPES)}, got {array.dtype}")
    if 0 in array.shape:
        raise InputError(f"volume: shape {array.shape} holds no samples")
    # The copy (and any conversion before it) checked against the memory budget before it
    # is made: an array's shape may be declared by strides over a few bytes.
    check_budget(f"volume: {array.size} samples of {array.shape}", array.size * 8)
    if spacing is not None:
        spacing = _spacing(spacing)
    return np.ascontiguousarray(array, dtype=np.float32), spacing, cdp, axis


#: Integer attribute types kept as integers (as arbvis's LAS reader keeps extra bytes of
#: these types; 32-bit unsigned and 64-bit ones may not fit, and become floats).
INTEGRAL = ("int8", "int16", "int32", "uint8", "uint16")


def _column(name, values, n):
    array = np.asarray(values)
    if array.shape != (n,):
        raise InputError(f"cloud: attribute {name!r} has shape {array.shape}, not ({n},)")
    if array.dtype.kind not in "iuf":
        raise InputError(f"cloud: attribute {name!r} holds {array.dtype}, not numbers")
    return (str(name), array.dtype.name in INTEGRAL, np.ascontiguousarray(array, dtype=np.float64))


def _colours(rgb, n):
    array = np.asarray(rgb)
    if array.shape != (n, 3) or array.dtype.name not in ("uint8", "uint16"):
        raise InputError(
            f"cloud: rgb is an ({n}, 3) array of uint8 or uint16, got {array.shape} {array.dtype}"
        )
    if array.dtype.name == "uint8":
        array = array.astype(np.uint16) * 257
    return np.ascontiguousarray(array, dtype=np.uint16)


def _from_laspy(las):
    """A LasData's points as arbvis reads its LAS file: positions scaled, intensity,
    classification, the returns, GPS time after the earliest point's, extra dimensions,
    colours."""
    names = set(las.point_format.dimension_names)
    positions = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])
    attributes = {}
    for name in ("intensity", "classification", "return_number", "number_of_returns"):
        attributes[name] = np.asarray(las[name]).astype(np.int32)
    if "gps_time" in names:
        t = np.asarray(las.gps_time, dtype=np.float64)
        attributes["gps_time"] = t - t.min() if len(t) else t
    for name in las.point_format.extra_dimension_names:
        label = name
        while label in attributes:
            label += "_extra"
        attributes[label] = np.asarray(las[name])
    rgb = None
    if {"red", "green", "blue"} <= names:
        rgb = np.column_stack([np.asarray(las[c]) for c in ("red", "green", "blue")]).astype(np.uint16)
    return positions, attributes, rgb


def cloud_parts(positions, attributes, rgb):
    """(positions N x 3 float64 in C order, [(name, integral, float64 values)], colours
    N x 3 uint16 or None) of numpy arrays or a laspy.LasData."""
    if hasattr(positions, "point_format") and hasattr(positions, "header"):
        if attributes is not None or rgb is not None:
            raise InputError("cloud: a LasData brings its own attributes and colours")
        positions, attributes, rgb = _from_laspy(positions)
    xyz = np.asarray(positions)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or xyz.dtype.kind not in "iuf":
        raise InputError(f"cloud: positions are an (N, 3) array of numbers, got {xyz.shape} {xyz.dtype}")
    n = xyz.shape[0]
    check_budget(f"cloud: {n} points", n * 64)
    if attributes is None:
        attributes = {}
    if not isinstance(attributes, dict):
        raise InputError(f"cloud: attributes are a dict of name to values, got {type(attributes).__name__}")
    columns = [_column(name, values, n) for name, values in attributes.items()]
    colours = None if rgb is None else _colours(rgb, n)
    return np.ascontiguousarray(xyz, dtype=np.float64), columns, colours


#: meshio's cell names and their VTK types (surface, line and vertex cells are skipped
#: as a file's are).
VTK_TYPES = {
    "vertex": 1,
    "line": 3,
    "triangle": 5,
    "quad": 9,
    "tetra": 10,
    "voxel": 11,
    "hexahedron": 12,
    "wedge": 13,
    "pyramid": 14,
}


def _array(name, values, n, where):
    a = np.asarray(values)
    if a.ndim not in (1, 2) or a.shape[0] != n or a.dtype.kind not in "iuf":
        raise InputError(
            f"mesh: {where} array {name!r} has shape {a.shape} {a.dtype}, not {n} numbers or rows of numbers"
        )
    components = 1 if a.ndim == 1 else a.shape[1]
    return (str(name), components, np.ascontiguousarray(a, dtype=np.float64).ravel())


def _blocks(cells, n_points):
    if isinstance(cells, dict):
        items = list(cells.items())
    elif isinstance(cells, (list, tuple)) and all(
        isinstance(c, (list, tuple)) and len(c) == 2 and isinstance(c[0], str) for c in cells
    ) and cells:
        items = list(cells)  # [(kind, cells), ...], meshio's order
    else:
        items = [("tetra", cells)]
    blocks = []
    for kind, connectivity in items:
        if kind not in VTK_TYPES:
            raise InputError(f"mesh: cells of kind {kind!r}: arbvis takes {', '.join(VTK_TYPES)}")
        c = np.asarray(connectivity)
        if c.ndim != 2 or c.dtype.kind not in "iu" or c.shape[0] == 0:
            raise InputError(f"mesh: {kind} cells are an (M, k) array of point indices, got {c.shape} {c.dtype}")
        check_budget(f"mesh: {c.shape[0]} {kind} cells", c.size * 8)
        if c.min() < 0 or c.max() >= n_points:
            raise InputError(
                f"mesh: {kind} cells name point {int(c.min()) if c.min() < 0 else int(c.max())}; the mesh has {n_points} points"
            )
        blocks.append((VTK_TYPES[kind], c.shape[1], np.ascontiguousarray(c, dtype=np.uint32).ravel()))
    return blocks


def mesh_parts(points, cells, point_data, cell_data):
    """(points N x 3 float64 in C order, [(VTK type, points per cell, indices uint32)],
    [(name, components, float64 values)] per point, the same per cell) of numpy arrays or
    a meshio.Mesh (its cell_data: a list per block, joined in block order)."""
    if hasattr(points, "cells") and hasattr(points, "points") and hasattr(points, "point_data"):
        mesh = points
        if cells is not None or point_data is not None or cell_data is not None:
            raise InputError("mesh: a meshio.Mesh brings its own cells and data")
        points = mesh.points
        cells = [(block.type, block.data) for block in mesh.cells]
        point_data = dict(mesh.point_data)
        cell_data = {name: np.concatenate([np.asarray(b) for b in blocks]) for name, blocks in mesh.cell_data.items()}
    xyz = np.asarray(points)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or xyz.dtype.kind not in "iuf":
        raise InputError(f"mesh: points are an (N, 3) array of numbers, got {xyz.shape} {xyz.dtype}")
    check_budget(f"mesh: {xyz.shape[0]} points", xyz.shape[0] * 48)
    if not np.isfinite(xyz).all():
        bad = int(np.argwhere(~np.isfinite(xyz))[0][0])
        raise InputError(f"mesh: point {bad} has a non-finite coordinate {xyz[bad].tolist()}")
    if cells is None:
        raise InputError("mesh: cells are needed (an (M, 4) array of tetrahedra, or a dict of kind to cells)")
    blocks = _blocks(cells, xyz.shape[0])
    n_cells = sum(len(c) // k for _, k, c in blocks)
    for name, data in (("point_data", point_data), ("cell_data", cell_data)):
        if data is not None and not isinstance(data, dict):
            raise InputError(f"mesh: {name} is a dict of name to array, got {type(data).__name__}")
    points_arrays = [_array(k, v, xyz.shape[0], "point") for k, v in (point_data or {}).items()]
    cell_arrays = [_array(k, v, n_cells, "cell") for k, v in (cell_data or {}).items()]
    return np.ascontiguousarray(xyz, dtype=np.float64), blocks, points_arrays, cell_arrays


def json_default(value):
    """numpy's numbers and arrays as the Python numbers and lists a scene holds (json's
    `default`); an array's NaN as None (JSON has no NaN: a scene reads null where it takes
    a value of none, a log's or a line's, and refuses it elsewhere); anything else is
    json's TypeError."""
    if isinstance(value, np.ndarray) and value.dtype.kind == "f" and np.isnan(value).any():
        return np.where(np.isnan(value), None, value).tolist()
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"Object of type {type(value).__name__} is not a value a scene holds")


def surface_parts(vertices, triangles):
    """(vertices N x 3 float64 in C order, triangles M x 3 uint32 in C order) of numpy
    arrays, checked: finite vertices, indices below N."""
    xyz = np.asarray(vertices)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or xyz.dtype.kind not in "iuf":
        raise InputError(f"surface: vertices are an (N, 3) array of numbers, got {xyz.shape} {xyz.dtype}")
    tri = np.asarray(triangles)
    if tri.ndim != 2 or tri.shape[1] != 3 or tri.dtype.kind not in "iu":
        raise InputError(f"surface: triangles are an (M, 3) array of integers, got {tri.shape} {tri.dtype}")
    check_budget(f"surface: {xyz.shape[0]} vertices and {tri.shape[0]} triangles", xyz.shape[0] * 24 + tri.shape[0] * 12)
    if not np.isfinite(xyz).all():
        bad = int(np.argwhere(~np.isfinite(xyz))[0][0])
        raise InputError(f"surface: vertex {bad} has a non-finite coordinate {xyz[bad].tolist()}")
    if len(tri) == 0:
        raise InputError("surface: no triangles")
    if tri.min() < 0 or tri.max() >= len(xyz):
        bad = int(np.argwhere((tri < 0) | (tri >= len(xyz)))[0][0])
        raise InputError(f"surface: triangle {bad} is {tri[bad].tolist()}, but there are {len(xyz)} vertices")
    return np.ascontiguousarray(xyz, dtype=np.float64), np.ascontiguousarray(tri, dtype=np.uint32)


def surface_properties(properties, n, shape=None):
    """[(name, float64 array of n values)] of a dict of per-vertex values: each a 1D array
    of n numbers, or (for a grid, `shape` given) an array of the grid's shape, flattened
    as its nodes are; NaN (or inf) where a vertex has none."""
    if properties is None:
        return []
    if not isinstance(properties, dict):
        raise InputError(f"surface: properties are a dict of name to values, got {type(properties).__name__}")
    out = []
    for name, values in properties.items():
        if not isinstance(name, str) or not name:
            raise InputError(f"surface: a property's name is a non-empty string, got {name!r}")
        v = np.asarray(values)
        want = (n,) if shape is None else tuple(shape)
        if v.shape != want or v.dtype.kind not in "iuf":
            raise InputError(f"surface: property {name!r} is an array of {want} numbers, got {v.shape} {v.dtype}")
        out.append((name, np.ascontiguousarray(v.ravel(), dtype=np.float64)))
    return out


def grid_surface(z, x, y):
    """A 2D grid of heights (or times, downwards: pass -time) as vertices and triangles:
    node [i, j] at (x[i], y[j], z[i, j]); a cell's two triangles where its three corners
    are defined (NaN marks an undefined node, as interpretation tools leave holes)."""
    z = np.asarray(z, dtype=np.float64)
    if z.ndim != 2 or min(z.shape) < 2:
        raise InputError(f"surface: a grid is a 2D array of at least 2 x 2 heights, got {z.shape}")
    nx, ny = z.shape
    x = np.arange(nx, dtype=np.float64) if x is None else np.asarray(x, dtype=np.float64)
    y = np.arange(ny, dtype=np.float64) if y is None else np.asarray(y, dtype=np.float64)
    if x.shape != (nx,) or y.shape != (ny,):
        raise InputError(f"surface: x has {x.shape} and y {y.shape} values for a grid of {z.shape}")
    gx, gy = np.meshgrid(x, y, indexing="ij")
    vertices = np.stack([gx.ravel(), gy.ravel(), z.ravel()], axis=1)
    node = np.arange(nx * ny).reshape(nx, ny)
    a, b, c, d = node[:-1, :-1].ravel(), node[1:, :-1].ravel(), node[1:, 1:].ravel(), node[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    defined = np.isfinite(vertices[:, 2])
    triangles = triangles[defined[triangles].all(axis=1)]
    # Undefined nodes are left out and the rest renumbered.
    keep = np.flatnonzero(defined)
    index = np.full(len(vertices), -1)
    index[keep] = np.arange(len(keep))
    return vertices[keep], index[triangles], keep


def grid_properties(properties, z, keep):
    """`surface_properties` of a grid: arrays of `z`'s shape, at the nodes `keep` kept."""
    return [(name, v[keep]) for name, v in surface_properties(properties, None, np.shape(z))]
