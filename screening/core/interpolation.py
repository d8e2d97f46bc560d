"""Cubic Hermite interpolation: piecewise-cubic tables read by the compiled coefficient functions
(:mod:`screening.core.condensation.uplift_integrals`, :mod:`screening.core.condensation.quadrature`), and the
Hermite basis of the Monte Carlo input between its grid points (:mod:`screening.kernels.mcs_kernels`).

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

__all__ = []

#: Bits of a double's significand.
SIGNIFICAND_BITS = 52


def cubic_coefficients(values, slopes, step):
    """Per-interval cubic coefficients of the Hermite interpolant of node values with slopes.

    Parameters
    ----------
    values : array_like
        ``(n_nodes, n_columns)`` node values.
    slopes : array_like
        ``(n_nodes, n_columns)`` derivatives with respect to the grid variable.
    step : float or array_like
        Interval lengths, one number (uniform grid) or ``(n_nodes - 1,)``, in the grid variable's units.

    Returns
    -------
    numpy.ndarray
        ``(n_nodes, 4 n_columns)``: row ``i < n_nodes - 1`` holds, per column ``c``, ``(a0, a1, a2, a3)`` with
        ``f = a0 + s (a1 + s (a2 + s a3))`` at fraction ``s`` of interval ``i``; the last row holds the last
        node value as a constant (read where a table is held beyond its end).

    Notes
    -----
    ``a0 = v0``, ``a1 = h d0``, ``a2 = 3 (v1 - v0) - 2 h d0 - h d1``, ``a3 = 2 (v0 - v1) + h d0 + h d1``: the
    cubic Hermite basis [1] in power form (what :func:`cubic` evaluates).

    References
    ----------
    .. [1] [fritsch1980] in the bibliography, ``docs/bibliography.md``.
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
    """Nodes of an octave grid: ``2^bits`` equal steps in every octave.

    Parameters
    ----------
    e_lo : int
        Exponent of the first node ``2^e_lo``.
    e_hi : int
        Exponent of the last node ``2^e_hi``.
    bits : int
        Mantissa bits: ``2^bits`` intervals per octave.

    Returns
    -------
    numpy.ndarray
        ``2^e (1 + m 2^-bits)`` for ``e_lo <= e < e_hi``, ``0 <= m < 2^bits``, and ``2^e_hi``: ascending,
        ``(e_hi - e_lo) 2^bits + 1`` nodes.

    Notes
    -----
    The interval of a number on this grid is read from its binary64 exponent and leading significand
    bits [1] (:func:`octave_position_jit`): no logarithm.

    """
    m = np.arange(2**bits) / 2.0**bits
    e = np.arange(e_lo, e_hi)
    return np.append((np.ldexp(1.0, e)[:, None] * (1.0 + m[None, :])).ravel(), np.ldexp(1.0, e_hi))


def octave_position(x, e_lo, bits):
    """Interval index and fraction of ``x`` on an :func:`octave_grid` (numpy reference).

    Parameters
    ----------
    x : array_like
        Positive numbers (in the grid variable's units).
    e_lo : int
        Exponent of the grid's first node ``2^e_lo``.
    bits : int
        Mantissa bits of the grid.

    Returns
    -------
    j : numpy.ndarray or int
        Interval index; negative below the grid.
    s : numpy.ndarray or float
        Fraction [1] in [0, 1): ``x = x_j + s (x_(j+1) - x_j)``.

    Notes
    -----
    From ``frexp``; the numpy reference of :func:`octave_position_jit`, which reads the same from the bits [1].

    """
    mantissa, exponent = np.frexp(np.asarray(x, dtype=float))      # x = mantissa 2^exponent, mantissa in [0.5, 1)
    u = (2.0 * mantissa - 1.0) * 2.0**bits
    m = np.floor(u)
    return ((exponent - 1 - e_lo) * 2**bits + m.astype(np.int64))[()], (u - m)[()]


def octave_first(e_lo, bits):
    """The argument ``first`` of :func:`octave_position_jit` for a grid starting at ``2^e_lo``.

    Parameters
    ----------
    e_lo : int
        Exponent of the grid's first node.
    bits : int
        Mantissa bits of the grid.

    Returns
    -------
    int
        The bits of ``2^e_lo`` shifted right by ``52 - bits``.

    Notes
    -----
    The interval index of ``x`` is its bits shifted the same way minus this [1].

    """
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
    """Column ``column`` of a :func:`cubic_coefficients` table at fraction ``s`` of interval ``i``.

    Parameters
    ----------
    table : numpy.ndarray
        A table of :func:`cubic_coefficients`.
    i : int
        Interval index.
    column : int
        Column of the tabulated values.
    s : float
        Fraction [1] of the interval.

    Returns
    -------
    float
        ``a0 + s (a1 + s (a2 + s a3))``.

    Notes
    -----
    The cubic Hermite interpolant [1] in Horner form.

    References
    ----------
    .. [1] [fritsch1980] in the bibliography, ``docs/bibliography.md``.
    """
    c = 4 * column
    return table[i, c] + s * (table[i, c + 1] + s * (table[i, c + 2] + s * table[i, c + 3]))


@numba.njit(cache=True, inline="always")
def hermite_weights(s):
    """Cubic Hermite basis weights at fraction ``s`` of a node interval.

    Parameters
    ----------
    s : float
        Fraction [1] of the interval.

    Returns
    -------
    tuple of float
        ``(h00, h10, h01, h11)``: the interpolant is ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)``.

    Notes
    -----
    ``h00 = 2 s^3 - 3 s^2 + 1``, ``h10 = s^3 - 2 s^2 + s``, ``h01 = -2 s^3 + 3 s^2``, ``h11 = s^3 - s^2`` [1];
    the basis behind :func:`cubic_coefficients` too.

    References
    ----------
    .. [1] [fritsch1980] in the bibliography, ``docs/bibliography.md``.
    """
    s2 = s * s
    s3 = s2 * s
    return 2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2


@numba.njit(cache=True, inline="always")
def hermite(v0, v1, d0, d1, s, step):
    """Cubic Hermite interpolant at fraction ``s`` of an interval from node values and derivatives.

    Parameters
    ----------
    v0 : float
        Value at the interval's start.
    v1 : float
        Value at its end.
    d0 : float
        Derivative at the start (per unit of ``step``).
    d1 : float
        Derivative at the end.
    s : float
        Fraction [1] of the interval.
    step : float
        Interval length.

    Returns
    -------
    float
        ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)`` (:func:`hermite_weights`).

    Notes
    -----
    For data that change every call (the Monte Carlo input samples), evaluated on the fly [1].

    References
    ----------
    .. [1] [fritsch1980] in the bibliography, ``docs/bibliography.md``.
    """
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
