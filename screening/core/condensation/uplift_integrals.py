"""The universal Gaussian uplift integrals of the paper's condensation, closed form and tabulated.

:func:`gaussian_uplift_integrals` evaluates them in closed form (numpy, the reference);
:func:`uplift_integrals` (from ``r``) and :func:`uplift_integrals_q` (from ``q = r^2``, what the moment solver
reads) are the compiled twins.

The sigma-dependent parts of ``c_eq`` and ``k_eq`` are universal functions of
``r = sigma_theta / theta_ul`` only (see :mod:`screening.core.condensation.paper`), so they are
tabulated once, for every block and foundation, in ``q = r^2 = var_theta / theta_ul^2`` with
their exact derivatives, and read back by cubic Hermite interpolation, stored as ready
per-interval cubic coefficients (error ~1e-13, tested against the closed forms).  The grid is an
octave grid (:func:`screening.core.interpolation.octave_grid`, :data:`MANTISSA_BITS` bits: the
spacing in ``ln q`` is 1/1024 to 1/512), so the compiled lookup finds its interval from the bits of
``q`` (no logarithm in the solver's right-hand side).  Below the grid (``x > 512``) every tail
is below 1e-220 and the limits are exact to double precision; above it the small-``x`` series
of the incomplete gamma functions is exact to rounding.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numba
import numpy as np
from scipy import special

from screening.core.interpolation import cubic, cubic_coefficients, octave_first, octave_grid, octave_position_jit

__all__ = []

#: Beyond this x = theta_ul^2/(2 sigma_theta^2) every tail is below 1e-300: use the limits.
X_LIMIT = 700.0

_C12 = 2.0**-0.25 / np.sqrt(np.pi)
_C32 = 2.0**-0.75 / np.sqrt(np.pi)


def _upper_gamma(a, x):
    """Non-regularised upper incomplete gamma ``Gamma(a, x)`` for ``a > 0``."""
    return special.gammaincc(a, x) * special.gamma(a)


def gaussian_uplift_integrals(r):
    """The dimensionless Gaussian uplift integrals at ``r = sigma_theta / theta_ul``, closed form.

    Parameters
    ----------
    r : array_like
        ``sigma_theta / theta_ul`` [1], >= 0.

    Returns
    -------
    dict
        Arrays [1] ``p_in`` (``P(|theta| <= theta_ul)``), ``p_out`` (its complement, eq. (58) in [1]),
        ``tail_m12``, ``tail_m32`` (the expectations of ``(|theta|/theta_ul)^(-1/2)`` and ``^(-3/2)`` over the
        uplift tails), ``inner_m2`` and the velocity-coupling versions ``tail_m12_r = tail_m12 / r`` and
        ``tail_m32_r = tail_m32 / r`` (finite, and zero, at ``r = 0``).

    Notes
    -----
    With ``x = 1 / (2 r^2)``: ``p_in = erf(sqrt(x))``, ``p_out = erfc(sqrt(x))`` and the tails through the
    upper incomplete gamma function ``Gamma(1/4, x)`` (eqs. (35)-(38) in [1]); exact limits where
    ``x > X_LIMIT``.  The compiled twins :func:`uplift_integrals` and :func:`uplift_integrals_q` read them from
    the table of :func:`coefficient_table`.

    """
    r = np.asarray(r, dtype=float)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        x = 0.5 / r**2
        tiny = ~(x <= X_LIMIT)  # includes r = 0 (x = inf)
        rs = np.where(tiny, 1.0, r)
        xs = np.where(tiny, 0.5, x)
        sx = np.sqrt(xs)
        g14 = _upper_gamma(0.25, xs)
        gm14 = 4.0 * (xs**-0.25 * np.exp(-xs) - _upper_gamma(0.75, xs))
        out = {
            "p_in": special.erf(sx),
            "p_out": special.erfc(sx),
            "tail_m12": _C12 * rs**-0.5 * g14,
            "tail_m32": _C32 * rs**-1.5 * gm14,
            "inner_m2": rs**2 * special.gammainc(1.5, xs),
            "tail_m12_r": _C12 * rs**-1.5 * g14,
            "tail_m32_r": _C32 * rs**-2.5 * gm14,
        }
    limits = {"p_in": 1.0, "p_out": 0.0, "tail_m12": 0.0, "tail_m32": 0.0,
              "tail_m12_r": 0.0, "tail_m32_r": 0.0}
    for name, value in limits.items():
        out[name] = np.where(tiny, value, out[name])
    out["inner_m2"] = np.where(tiny, np.where(np.isfinite(r), r, 0.0) ** 2, out["inner_m2"])
    return out


#: Octave grid in q = (sigma_theta / theta_ul)^2: 2^Q_OCTAVE_LO .. 2^Q_OCTAVE_HI (x = 1/(2 q) from 512
#: down to 1e-16), MANTISSA_BITS bits of mantissa per node.
Q_OCTAVE_LO = -10
Q_OCTAVE_HI = 52
MANTISSA_BITS = 9
#: Interval index of the first node (:func:`screening.core.interpolation.octave_first`) and
#: number of intervals.
FIRST = octave_first(Q_OCTAVE_LO, MANTISSA_BITS)
N_INTERVALS = (Q_OCTAVE_HI - Q_OCTAVE_LO) << MANTISSA_BITS
#: The grid's ends in r = sigma_theta / theta_ul.
R_LO = 2.0 ** (0.5 * Q_OCTAVE_LO)
R_HI = 2.0 ** (0.5 * Q_OCTAVE_HI)

# Columns of the table.
P_IN, TAIL_M12, TAIL_M32, P32 = 0, 1, 2, 3
N_FUNCS = 4

_G14 = math.gamma(0.25)
_G34 = math.gamma(0.75)
_G52 = math.gamma(2.5)


def _table_values_and_slopes(t):
    """Values and exact d/dt of the four tabulated functions at ``t = ln r``."""
    r = np.exp(t)
    x = 0.5 / r**2
    G = gaussian_uplift_integrals(r)
    ex = np.exp(-x)
    g14 = special.gammaincc(0.25, x) * _G14
    gm14 = 4.0 * (x**-0.25 * ex - special.gammaincc(0.75, x) * _G34)
    values = np.stack([G["p_in"], G["tail_m12"], G["tail_m32"], special.gammainc(1.5, x)], axis=1)
    slopes = np.stack([
        -2.0 / math.sqrt(math.pi) * np.sqrt(x) * ex,
        _C12 * np.exp(-0.5 * t) * (-0.5 * g14 + 2.0 * x**0.25 * ex),
        _C32 * np.exp(-1.5 * t) * (-1.5 * gm14 + 2.0 * x**-0.25 * ex),
        -2.0 * x**1.5 * ex / math.gamma(1.5),
    ], axis=1)
    return values, slopes


def node_values():
    """The tabulated functions and their slopes on the octave grid in ``q = r^2`` (fixed by
    :data:`Q_OCTAVE_LO`, :data:`Q_OCTAVE_HI` and :data:`MANTISSA_BITS`).

    Returns
    -------
    q : numpy.ndarray
        The nodes ``q = var_theta / theta_ul^2`` [1].
    values : numpy.ndarray
        ``(N_INTERVALS + 1, 4)``: ``p_in``, ``tail_m12``, ``tail_m32``, ``P(3/2, x)`` at the nodes [1].
    slopes : numpy.ndarray
        Their exact derivatives ``d/dq``, same shape.

    Notes
    -----
    The universal functions of eqs. (35)-(36) in [1] (:func:`gaussian_uplift_integrals`) and their exact
    derivatives, for the cubic Hermite table.

    """
    q = octave_grid(Q_OCTAVE_LO, Q_OCTAVE_HI, MANTISSA_BITS)
    values, slopes_t = _table_values_and_slopes(0.5 * np.log(q))
    return q, values, slopes_t / (2.0 * q[:, None])        # dt/dq = 1 / (2 q)


@lru_cache(maxsize=1)
def coefficient_table():
    """The universal table of the Gaussian uplift integrals: per-interval cubic coefficients.

    Returns
    -------
    numpy.ndarray
        ``(N_INTERVALS + 1, 16)``: the cubic coefficients of :func:`node_values` in ``q``
        (:func:`screening.core.interpolation.cubic_coefficients`).

    Notes
    -----
    The sigma-dependent parts of eqs. (35)-(36) in [1] depend on ``r = sigma_theta / theta_ul`` only, so one
    table serves every point (interpolation error ~1e-13).

    """
    q, values, slopes = node_values()
    return cubic_coefficients(values, slopes, np.diff(q))


@numba.njit(cache=True, inline="always")
def uplift_integrals(r, table):
    """Like :func:`uplift_integrals_q` at ``q = r^2``, from ``r = sigma_theta / theta_ul`` [1] (>= 0): the
    compiled twin of :func:`gaussian_uplift_integrals` (eqs. (35)-(38) in [mitseas2026])."""
    return uplift_integrals_q(r * r, table)


@numba.njit(cache=True, inline="always")
def uplift_integrals_q(q, table):
    """Compiled Gaussian uplift integrals from ``q = r^2 = var_theta / theta_ul^2``, what the moment solver reads.

    Parameters
    ----------
    q : float
        ``var_theta / theta_ul^2`` [1]; any ``q <= 0`` gives the limits.
    table : numpy.ndarray
        The table of :func:`coefficient_table`.

    Returns
    -------
    p_in : float
        ``P(|theta| <= theta_ul)`` [1].
    tail_m12 : float
        Uplift tail of ``(|theta|/theta_ul)^(-1/2)`` [1].
    tail_m32 : float
        Uplift tail of ``(|theta|/theta_ul)^(-3/2)`` [1].
    p32 : float
        ``P(3/2, x)``, the regularised lower incomplete gamma function at ``x = 1/(2 r^2)`` [1].

    Notes
    -----
    Cubic Hermite interpolation on the octave grid (the interval from the bits of ``q``, no logarithm);
    series beyond the grid.  The integrals of eqs. (35)-(38) in [1].

    """
    j, s = octave_position_jit(q, FIRST, MANTISSA_BITS)
    if j < 0:
        return 1.0, 0.0, 0.0, 1.0
    if j >= N_INTERVALS:
        r = math.sqrt(q)
        x = 0.5 / q
        sx = math.sqrt(x)
        return (2.0 / math.sqrt(math.pi) * sx * (1.0 - x / 3.0),
                _C12 * r**-0.5 * (_G14 - 4.0 * x**0.25 + 0.8 * x**1.25),
                _C32 * r**-1.5 * 4.0 * (x**-0.25 - _G34 + x**0.75 / 3.0),
                x * sx / _G52 * (1.0 - 0.6 * x))
    p_in = cubic(table, j, P_IN, s)
    tail_m12 = cubic(table, j, TAIL_M12, s)
    tail_m32 = cubic(table, j, TAIL_M32, s)
    p32 = cubic(table, j, P32, s)
    # keep the tails' interpolants non-negative near the grid's lower end
    return p_in, max(tail_m12, 0.0), max(tail_m32, 0.0), p32
