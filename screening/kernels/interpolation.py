"""Cubic Hermite interpolation: piecewise-cubic tables read by the compiled coefficient functions
(:mod:`screening.condensation.uplift_integrals`, :mod:`screening.condensation.quadrature`), and the
Hermite basis of the Monte Carlo input between its grid points (:mod:`screening.solvers.mcs_kernels`).

A table is built once, in Python, from node values and exact slopes (cubic Hermite interpolation)
and stored as ready per-interval cubic coefficients, so a compiled lookup is one index computation
and one Horner evaluation per column (no basis weights, no row views).

Octave grids.  A table over many decades of a positive variable ``x`` can be read without a
logarithm: its nodes are the doubles whose mantissa has only ``bits`` leading bits,
``x_j = 2^e (1 + m 2^-bits)`` for ``e`` from ``e_lo`` to ``e_hi`` (:func:`octave_grid`), so the
interval of ``x`` and the fraction ``s`` in it are the upper and lower bits of ``x``'s own
binary representation (:func:`octave_position_jit`: a shift and a mask, exact).  The spacing
``dx / x`` lies between ``2^-(bits+1)`` and ``2^-bits``, like a grid uniform in ``ln x``.
"""

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

__all__ = ["SIGNIFICAND_BITS", "cubic_coefficients", "octave_grid", "octave_position", "octave_first",
           "octave_position_jit", "cubic", "hermite_weights", "hermite", "hermite_rate"]

#: Bits of a double's significand.
SIGNIFICAND_BITS = 52


def cubic_coefficients(values, slopes, step):
    """Per-interval cubic coefficients of the Hermite interpolant of ``values`` with ``slopes``.

    ``values``, ``slopes``: ``(n_nodes, n_columns)``, the slopes being derivatives with respect to
    the grid variable; ``step``: the interval lengths, one number (uniform grid) or
    ``(n_nodes - 1,)``.  Returns ``(n_nodes, 4 n_columns)``:
    row ``i < n_nodes - 1`` holds, per column ``c``, ``(a0, a1, a2, a3)`` with
    ``f = a0 + s (a1 + s (a2 + s a3))`` at fraction ``s`` of interval ``i``; the last row holds the
    last node value as a constant (``a1 = a2 = a3 = 0``), read where a table is held beyond its end.
    """
    v = np.asarray(values, dtype=float)
    d = np.asarray(slopes, dtype=float)
    n, cols = v.shape
    step = np.broadcast_to(np.asarray(step, dtype=float), (n - 1,))[:, None]
    out = np.zeros((n, cols, 4))
    v0, v1, d0, d1 = v[:-1], v[1:], d[:-1] * step, d[1:] * step
    out[:-1, :, 0] = v0
    out[:-1, :, 1] = d0
    out[:-1, :, 2] = 3.0 * (v1 - v0) - 2.0 * d0 - d1
    out[:-1, :, 3] = 2.0 * (v0 - v1) + d0 + d1
    out[-1, :, 0] = v[-1]
    return np.ascontiguousarray(out.reshape(n, 4 * cols))


def octave_grid(e_lo, e_hi, bits):
    """Nodes ``2^e (1 + m 2^-bits)``, ``e_lo <= e < e_hi``, ``0 <= m < 2^bits``, and ``2^e_hi`` (ascending;
    ``(e_hi - e_lo) 2^bits + 1`` nodes, module docstring)."""
    m = np.arange(2**bits) / 2.0**bits
    e = np.arange(e_lo, e_hi)
    return np.append((np.ldexp(1.0, e)[:, None] * (1.0 + m[None, :])).ravel(), np.ldexp(1.0, e_hi))


def octave_position(x, e_lo, bits):
    """Interval index ``j`` and fraction ``s`` of ``x > 0`` on the :func:`octave_grid` starting at ``2^e_lo``.

    ``x = x_j + s (x_(j+1) - x_j)``, ``0 <= s < 1``; ``j < 0`` below the grid.  Numpy reference of
    :func:`octave_position_jit` (array ``x`` allowed).
    """
    mantissa, exponent = np.frexp(np.asarray(x, dtype=float))      # x = mantissa 2^exponent, mantissa in [0.5, 1)
    u = (2.0 * mantissa - 1.0) * 2.0**bits
    m = np.floor(u)
    return ((exponent - 1 - e_lo) * 2**bits + m.astype(np.int64))[()], (u - m)[()]


def octave_first(e_lo, bits):
    """The argument ``first`` of :func:`octave_position_jit` for a grid starting at ``2^e_lo``."""
    return int(np.float64(np.ldexp(1.0, e_lo)).view(np.int64)) >> (SIGNIFICAND_BITS - bits)


@intrinsic
def _float_bits(typingctx, x):
    """The IEEE 754 bits of the double ``x`` as an int64 (a bit cast, no conversion)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))
    return types.int64(types.float64), codegen


@numba.njit(cache=True, inline="always")
def octave_position_jit(x, first, bits):
    """Compiled twin of :func:`octave_position` from the bits of ``x`` (``first``: :func:`octave_first`).

    Exact (no rounding).  Any ``x <= 0`` (``-0.0`` included) gives ``j < 0``; ``+inf`` and NaN give
    ``j`` beyond every grid.
    """
    shift = SIGNIFICAND_BITS - bits
    b = _float_bits(x)
    return (b >> shift) - first, (b & ((1 << shift) - 1)) * (1.0 / (1 << shift))


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


@numba.njit(cache=True, inline="always")
def hermite_rate(v0, v1, d0, d1, s, step):
    """Time derivative of :func:`hermite` at fraction ``s`` (units of the values per unit of ``step``)."""
    s2 = s * s
    return (6.0 * (s - s2) * (v1 - v0) / step + (3.0 * s2 - 4.0 * s + 1.0) * d0
            + (3.0 * s2 - 2.0 * s) * d1)
