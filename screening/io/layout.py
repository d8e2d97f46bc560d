"""The array layout of a sweep result, shared by the result formats and the sweep: where a flat range of points
sits in the grid's arrays, the chunks of a history, the model parameters as constants or per case."""

from __future__ import annotations

import math

import numpy as np

from screening.core.model import Block
from screening.solvers.schema import PARAMETERS

__all__ = []


def hyperslabs(lo, hi, shape):
    """Split the flat C-order range ``[lo, hi)`` of an array of ``shape`` into hyperslabs.

    Returns a list of ``(slices, a, b)``: ``array[slices]`` holds the flat points
    ``a <= i < b`` in order; the pieces cover ``[lo, hi)`` exactly.

    Parameters
    ----------
    lo, hi : int
        The flat range, ``0 <= lo <= hi <= prod(shape)``.
    shape : tuple of int
        The array's shape.

    Returns
    -------
    list of tuple
        ``(slices, a, b)`` per hyperslab, in C order.

    """
    if not shape:
        return [((), lo, hi)] if hi > lo else []
    inner = int(np.prod(shape[1:], dtype=np.int64))
    i0, r0 = divmod(lo, inner)
    i1, r1 = divmod(hi, inner)
    out = []
    if i0 == i1:
        for sub, a, b in hyperslabs(r0, r1, shape[1:]):
            out.append(((slice(i0, i0 + 1),) + sub, i0 * inner + a, i0 * inner + b))
        return out
    if r0:
        for sub, a, b in hyperslabs(r0, inner, shape[1:]):
            out.append(((slice(i0, i0 + 1),) + sub, i0 * inner + a, i0 * inner + b))
        i0 += 1
    if i1 > i0:
        out.append(((slice(i0, i1),) + tuple(slice(0, n) for n in shape[1:]), i0 * inner, i1 * inner))
    if r1:
        for sub, a, b in hyperslabs(0, r1, shape[1:]):
            out.append(((slice(i1, i1 + 1),) + sub, i1 * inner + a, i1 * inner + b))
    return out


def history_chunks(shape, nt):
    """netCDF chunks of a history on grid ``shape``: ``(1, ..., n_last, nt)`` (at most 2**18 values).

    Parameters
    ----------
    shape : tuple of int
        The grid's shape.
    nt : int
        Output instants.

    Returns
    -------
    tuple of int
        The chunk shape of a ``grid x t`` history.

    """
    if not shape:
        return (nt,)
    last = min(shape[-1], max(1, 2**18 // nt))
    return (1,) * (len(shape) - 1) + (last, nt)


def parameter_table(study):
    """Split the model parameters into constants and per-case values.

    Returns ``(constants, per_case, labels, case_labels)``: ``constants`` maps numeric
    parameter names to floats (same for every case, not swept), ``per_case`` maps the other
    non-swept numeric parameters to arrays over cases (NaN where one does not apply),
    ``labels``/``case_labels`` do the same for ``contact``, ``condensation``, ``excitation`` and
    ``envelope``.  Constants are in SI units (``I_cm`` [kg m2] computed when not given).
    """
    names = [n for n in PARAMETERS if n not in study.sweeps]
    values = {}
    for name in names:
        col = []
        for case in study.cases:
            if name == "I_cm" and "I_cm" not in case.params:
                p = case.params
                col.append(float(Block(m=p["m"], b=p["b"], h=p["h"]).I_cm))
            else:
                value = float(case.params.get(name, math.nan))
                col.append(math.nan if math.isinf(value) else value)       # band_limit_hz = "none": no band
        if not all(math.isnan(v) for v in col):
            values[name] = np.array(col)
    constants = {n: float(v[0]) for n, v in values.items() if np.all(v == v[0])}
    per_case = {n: v for n, v in values.items() if n not in constants}
    labels, case_labels = {}, {}
    for name in ("contact", "condensation", "excitation", "envelope"):
        col = [getattr(c, name) for c in study.cases]
        if len(set(col)) == 1:
            labels[name] = col[0]
        else:
            case_labels[name] = col
    return constants, per_case, labels, case_labels
