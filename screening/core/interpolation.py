"""Cubic Hermite interpolation [fritsch1980]: tables built once in Python from node values and exact slopes,
stored as per-interval cubic coefficients (one index and one Horner evaluation per column in a
compiled lookup), and the Hermite basis of the Monte Carlo input between its grid points.

An octave grid (:func:`octave_grid`) has as nodes the doubles whose mantissa has only ``bits`` leading
bits, so the interval of ``x`` and its fraction are bits of ``x`` itself (:func:`octave_position_jit`):
a table over many decades read without a logarithm.
"""

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

__all__ = []

#: Bits of a double's significand.
SIGNIFICAND_BITS = 52


def cubic_coefficients(values, slopes, step):
    """Per-interval cubic coefficients ``(n_nodes, 4 n_columns)`` of the Hermite interpolant of node ``values`` with ``slopes``.

    Notes
    -----
    ``values``, ``slopes``: ``(n_nodes, n_columns)``; ``step``: one interval length or ``(n_nodes - 1,)``.  Row
    ``i`` holds per column ``a0 = v0``, ``a1 = h d0``, ``a2 = 3 (v1 - v0) - 2 h d0 - h d1``,
    ``a3 = 2 (v0 - v1) + h d0 + h d1`` (``f = a0 + s (a1 + s (a2 + s a3))``, :func:`cubic`); the last row holds
    the last node value as a constant, read where a table is held beyond its end.
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
    """Nodes ``2^e (1 + m 2^-bits)`` (``e_lo <= e < e_hi``, ``0 <= m < 2^bits``) and ``2^e_hi``: ``2^bits`` equal steps per octave, ascending."""
    m = np.arange(2**bits) / 2.0**bits
    e = np.arange(e_lo, e_hi)
    return np.append((np.ldexp(1.0, e)[:, None] * (1.0 + m[None, :])).ravel(), np.ldexp(1.0, e_hi))


def octave_position(x, e_lo, bits):
    """Interval index ``j`` (negative below the grid) and fraction ``s`` in [0, 1) of ``x`` on an :func:`octave_grid`, from ``frexp`` (numpy reference)."""
    mantissa, exponent = np.frexp(np.asarray(x, dtype=float))      # x = mantissa 2^exponent, mantissa in [0.5, 1)
    u = (2.0 * mantissa - 1.0) * 2.0**bits
    m = np.floor(u)
    return ((exponent - 1 - e_lo) * 2**bits + m.astype(np.int64))[()], (u - m)[()]


def octave_first(e_lo, bits):
    """The argument ``first`` of :func:`octave_position_jit`: the bits of ``2^e_lo`` shifted right by ``52 - bits``."""
    return int(np.float64(np.ldexp(1.0, e_lo)).view(np.int64)) >> (SIGNIFICAND_BITS - bits)


@intrinsic
def _float_bits(typingctx, x):
    """The IEEE 754 bits of the double ``x`` as an int64 (a bit cast, no conversion)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))
    return types.int64(types.float64), codegen


@numba.njit(cache=True, inline="always")
def octave_position_jit(x, first, bits):
    """Compiled twin of :func:`octave_position`, exact from the bits of ``x`` (a bit cast, a shift and a mask).

    ``j`` is negative for any ``x <= 0`` (``-0.0`` included) and beyond every grid for ``+inf`` and NaN.
    """
    shift = SIGNIFICAND_BITS - bits
    b = _float_bits(x)
    return (b >> shift) - first, (b & ((1 << shift) - 1)) * (1.0 / (1 << shift))


@numba.njit(cache=True, inline="always")
def cubic(table, i, column, s):
    """Column ``column`` of a :func:`cubic_coefficients` table at fraction ``s`` of interval ``i``, in Horner form."""
    c = 4 * column
    return table[i, c] + s * (table[i, c + 1] + s * (table[i, c + 2] + s * table[i, c + 3]))


@numba.njit(cache=True, inline="always")
def hermite_weights(s):
    """Cubic Hermite basis weights ``(h00, h10, h01, h11)`` at fraction ``s`` of an interval [fritsch1980].

    Notes
    -----
    ``h00 = 2 s^3 - 3 s^2 + 1``, ``h10 = s^3 - 2 s^2 + s``, ``h01 = -2 s^3 + 3 s^2``, ``h11 = s^3 - s^2``; the
    interpolant is ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)``.
    """
    s2 = s * s
    s3 = s2 * s
    return 2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2


@numba.njit(cache=True, inline="always")
def hermite(v0, v1, d0, d1, s, step):
    """Cubic Hermite interpolant ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)`` (:func:`hermite_weights`) at fraction ``s``, evaluated on the fly."""
    h00, h10, h01, h11 = hermite_weights(s)
    return h00 * v0 + h01 * v1 + step * (h10 * d0 + h11 * d1)


@numba.njit(cache=True, inline="always")
def hermite_rate(v0, v1, d0, d1, s, step):
    """Like :func:`hermite` (same arguments): its derivative with respect to the grid variable [values per
    unit of ``step``].

    Notes
    -----
    ``6 (s - s^2) (v1 - v0) / step + (3 s^2 - 4 s + 1) d0 + (3 s^2 - 2 s) d1``, the derivative of the
    Hermite basis ([fritsch1980] in the bibliography).
    """
    s2 = s * s
    return (6.0 * (s - s2) * (v1 - v0) / step + (3.0 * s2 - 4.0 * s + 1.0) * d0
            + (3.0 * s2 - 2.0 * s) * d1)
