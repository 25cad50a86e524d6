"""The user's arrays as `arbvis.Volume` keeps them: a numpy array or an xarray DataArray
turned into float32 samples in C order, indexed [inline, crossline, sample], with the
map coordinates of the traces and the sample axis where a DataArray gives them. Every
refusal is an `InputError` naming the argument."""

import math

import numpy as np

from ._arbvis import InputError

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
    if spacing is not None:
        spacing = _spacing(spacing)
    return np.ascontiguousarray(array, dtype=np.float32), spacing, cdp, axis
