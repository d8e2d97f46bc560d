"""Input checks shared by the model objects: one clear ``ValueError`` per bad parameter."""

from __future__ import annotations

import numbers

import numpy as np
import xarray as xr


def as_checked_array(name, value, *, lower=None, lower_inclusive=False, upper=None,
                     upper_inclusive=False, range_text=None):
    """Return ``value`` as a float array after checking it is finite and inside the range.

    Raises ``ValueError`` naming ``name`` and the allowed range for strings, NaN/inf and
    out-of-range values (any element of an array).
    """
    if range_text is None:
        parts = []
        if lower is not None:
            parts.append(f"{'>=' if lower_inclusive else '>'} {lower:g}")
        if upper is not None:
            parts.append(f"{'<=' if upper_inclusive else '<'} {upper:g}")
        range_text = "a finite number" + (" " + " and ".join(parts) if parts else "")
    if isinstance(value, (str, bytes)) or isinstance(value, bool):
        raise ValueError(f"parameter '{name}' must be {range_text} (got {value!r})")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"parameter '{name}' must be {range_text} (got {value!r})") from None
    if arr.size == 0:
        raise ValueError(f"parameter '{name}' must be {range_text} (got an empty array)")
    bad = ~np.isfinite(arr)
    if lower is not None:
        bad |= (arr < lower) if lower_inclusive else (arr <= lower)
    if upper is not None:
        bad |= (arr > upper) if upper_inclusive else (arr >= upper)
    if np.any(bad):
        shown = arr[bad].flat[0] if arr.ndim else float(arr)
        raise ValueError(f"parameter '{name}' must be {range_text} (got {shown!r})")
    return arr


def checked(name, value, **kwargs):
    """Like :func:`as_checked_array` but give back a Python float for scalar input.

    An :class:`xarray.DataArray` is checked on its values and given back as a float DataArray
    (dims and coordinates kept): the model objects then carry labelled parameters, which
    :func:`screening.linearize` broadcasts by dimension name.
    """
    if isinstance(value, xr.DataArray):
        as_checked_array(name, value.values, **kwargs)
        return value if value.dtype == np.float64 else value.astype(np.float64)
    arr = as_checked_array(name, value, **kwargs)
    if arr.ndim == 0 and (isinstance(value, numbers.Number) or np.ndim(value) == 0):
        return float(arr)
    return arr
