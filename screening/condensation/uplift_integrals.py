"""The universal Gaussian uplift integrals of the paper's condensation, closed form and tabulated.

:func:`gaussian_uplift_integrals` evaluates them in closed form (numpy, the reference);
:func:`uplift_integrals_log` is the compiled twin the moment solver reads.

The sigma-dependent parts of ``c_eq`` and ``k_eq`` are universal functions of
``r = sigma_theta / theta_ul`` only (see :mod:`screening.condensation.paper_coefficients`), so they are
tabulated once, for every block and foundation, on a uniform grid in ``t = ln r`` with
their exact derivatives, and read back by cubic Hermite interpolation, stored as ready
per-interval cubic coefficients (error ~1e-12, tested against the closed forms).  Below the grid every tail is zero to double precision;
above it the small-``x`` series of the incomplete gamma functions is exact to rounding.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numba
import numpy as np
from scipy import special

from screening.kernels.interpolation import cubic, cubic_coefficients

#: Beyond this x = theta_ul^2/(2 sigma_theta^2) every tail is below 1e-300: use the limits.
X_LIMIT = 700.0

_C12 = 2.0**-0.25 / np.sqrt(np.pi)
_C32 = 2.0**-0.75 / np.sqrt(np.pi)


def _upper_gamma(a, x):
    """Non-regularised upper incomplete gamma ``Gamma(a, x)`` for ``a > 0``."""
    return special.gammaincc(a, x) * special.gamma(a)


def gaussian_uplift_integrals(r):
    """The dimensionless Gaussian integrals of the module table at ``r = sigma_theta/theta_ul``.

    Returns a dict of arrays ``p_in, p_out, tail_m12, tail_m32, inner_m2`` and the
    velocity-coupling versions ``tail_m12_r = tail_m12 / r`` and ``tail_m32_r = tail_m32 / r``
    (finite, and zero, at ``r = 0``).  Exact limits are used where ``x > X_LIMIT``.
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


#: Grid in t = ln(sigma_theta / theta_ul).
T_LO = -0.5 * math.log(2.0 * X_LIMIT)
T_HI = 18.0
STEPS_PER_UNIT = 512

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
    """``(values, slopes)``, each of shape ``(n_nodes, 4)``, on the grid ``T_LO + i / STEPS_PER_UNIT``."""
    n = int(round((T_HI - T_LO) * STEPS_PER_UNIT)) + 1
    t = T_LO + np.arange(n) / STEPS_PER_UNIT
    return _table_values_and_slopes(t)


@lru_cache(maxsize=1)
def coefficient_table():
    """The universal table: per-interval cubic coefficients ``(n_nodes, 16)`` of :func:`node_values`
    (:func:`screening.kernels.interpolation.cubic_coefficients`, slopes in ``t``)."""
    values, slopes = node_values()
    table = cubic_coefficients(values, slopes, 1.0 / STEPS_PER_UNIT)
    return table


@numba.njit(cache=True, inline="always")
def uplift_integrals(r, table):
    """``(p_in, tail_m12, tail_m32, P(3/2, x))`` at ``r = sigma_theta / theta_ul`` >= 0."""
    if not (r > 0.0):
        return 1.0, 0.0, 0.0, 1.0
    return uplift_integrals_log(math.log(r), table)


@numba.njit(cache=True, inline="always")
def uplift_integrals_log(t, table):
    """As :func:`uplift_integrals`, from ``t = ln(sigma_theta / theta_ul)`` (``-inf`` allowed)."""
    if t <= T_LO:
        return 1.0, 0.0, 0.0, 1.0
    if t >= T_HI:
        r = math.exp(t)
        x = 0.5 / (r * r)
        sx = math.sqrt(x)
        return (2.0 / math.sqrt(math.pi) * sx * (1.0 - x / 3.0),
                _C12 * r**-0.5 * (_G14 - 4.0 * x**0.25 + 0.8 * x**1.25),
                _C32 * r**-1.5 * 4.0 * (x**-0.25 - _G34 + x**0.75 / 3.0),
                x * sx / _G52 * (1.0 - 0.6 * x))
    u = (t - T_LO) * STEPS_PER_UNIT
    i = min(int(u), table.shape[0] - 2)
    s = u - i
    p_in = cubic(table, i, P_IN, s)
    tail_m12 = cubic(table, i, TAIL_M12, s)
    tail_m32 = cubic(table, i, TAIL_M32, s)
    p32 = cubic(table, i, P32, s)
    # the tails underflow smoothly to zero at T_LO: keep their interpolants non-negative
    return p_in, max(tail_m12, 0.0), max(tail_m32, 0.0), p32
