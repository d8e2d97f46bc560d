"""Cubic Hermite interpolation: piecewise-cubic tables read by the compiled coefficient functions
(:mod:`screening.condensation.uplift_integrals`, :mod:`screening.condensation.quadrature`), and the
Hermite basis of the Monte Carlo input between its grid points (:mod:`screening.solvers.mcs_kernels`).

A table is built once, in Python, from node values and exact slopes on a uniform grid (cubic
Hermite interpolation) and stored as ready per-interval cubic coefficients, so a compiled lookup
is one index computation and one Horner evaluation per column (no basis weights, no row views).
"""

import numba
import numpy as np


def cubic_coefficients(values, slopes, step):
    """Per-interval cubic coefficients of the Hermite interpolant of ``values`` with ``slopes``.

    ``values``, ``slopes``: ``(n_nodes, n_columns)`` on a uniform grid of spacing ``step`` (the
    slopes are derivatives with respect to the grid variable).  Returns ``(n_nodes, 4 n_columns)``:
    row ``i < n_nodes - 1`` holds, per column ``c``, ``(a0, a1, a2, a3)`` with
    ``f = a0 + s (a1 + s (a2 + s a3))`` at fraction ``s`` of interval ``i``; the last row holds the
    last node value as a constant (``a1 = a2 = a3 = 0``), read where a table is held beyond its end.
    """
    v = np.asarray(values, dtype=float)
    d = np.asarray(slopes, dtype=float) * step
    n, cols = v.shape
    out = np.zeros((n, cols, 4))
    v0, v1, d0, d1 = v[:-1], v[1:], d[:-1], d[1:]
    out[:-1, :, 0] = v0
    out[:-1, :, 1] = d0
    out[:-1, :, 2] = 3.0 * (v1 - v0) - 2.0 * d0 - d1
    out[:-1, :, 3] = 2.0 * (v0 - v1) + d0 + d1
    out[-1, :, 0] = v[-1]
    return np.ascontiguousarray(out.reshape(n, 4 * cols))


@numba.njit(cache=True, inline="always")
def cubic(table, i, column, s):
    """Column ``column`` of a :func:`cubic_coefficients` table at fraction ``s`` of interval ``i``."""
    c = 4 * column
    return table[i, c] + s * (table[i, c + 1] + s * (table[i, c + 2] + s * table[i, c + 3]))


@numba.njit(cache=True, inline="always")
def hermite_weights(s):
    """Cubic Hermite weights ``(h00, h10, h01, h11)`` at fraction ``s`` of a node interval: the interpolant
    is ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)`` (the basis behind :func:`cubic_coefficients` too)."""
    s2 = s * s
    s3 = s2 * s
    return 2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2


@numba.njit(cache=True, inline="always")
def hermite(v0, v1, d0, d1, s, step):
    """Cubic Hermite interpolant at fraction ``s`` of an interval of length ``step`` from node values and
    derivatives evaluated on the fly (for data that change every call, such as Monte Carlo samples)."""
    h00, h10, h01, h11 = hermite_weights(s)
    return h00 * v0 + h01 * v1 + step * (h10 * d0 + h11 * d1)
