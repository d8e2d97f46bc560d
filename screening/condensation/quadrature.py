"""Equivalent linear coefficients of any condensation by Gaussian quadrature, tabulated per point.

A condensation whose ``C(theta)``, ``K(theta)`` have no closed-form Gaussian expectations (the
``"cubic"`` one, :mod:`screening.condensation.cubic`, or one registered from outside) gets the
coefficients of eq. (31) by quadrature; this is the default of
:meth:`screening.condensation.Condensation.equivalent_coefficients` and of its moment kernel.  For zero-mean Gaussian ``(theta, theta')`` with ``sigma = sigma_theta`` and
``cov = E[theta theta']``, Stein's lemma ``E[f'(theta)] = E[theta f(theta)] / sigma^2`` and
``E[theta' | theta] = cov theta / sigma^2`` turn ``g = C(theta) theta' + K(theta) theta`` into

    c_eq = E[dg/dtheta'] = E[C]                                             = e_c
    k_eq = E[dg/dtheta]  = E[(K theta)'] + E[C'(theta) theta']              = e_k + cov d_c

with three functions of ``sigma`` alone (``x = theta / sigma``, ``C0 = C(0)``)::

    e_c = E[C]                              [N m s/rad]
    e_k = E[K x^2]                          [N m/rad]
    d_c = E[(C - C0) (x^2 - 1)] / sigma^2   [N m s/rad^3]

(``E[x^2 - 1] = 0`` lets ``C0`` be subtracted, which keeps ``d_c`` accurate at small
``sigma``).  No derivative of the piecewise ``C``, ``K`` is taken: these are the regression
form ``Cov^-1 E[g y]`` of eq. (31), correct across the kinks at ``+-theta_ul``.  Limits at
``sigma -> 0``: ``e_c -> C(0)``, ``e_k -> K(0)`` (the no-uplift values) and
``d_c -> 2 C_2`` for ``C = C0 + C_2 theta^2 + ...``, all finite.  For the paper's ``C``, ``K``
the same formulas reproduce the closed forms of :mod:`screening.condensation.paper`.

Quadrature (``E[f] = 2 int_0^inf f(theta) phi_sigma(theta) dtheta``, ``C``, ``K`` even): one node
set in ``theta`` per parameter point, Gauss–Legendre (:data:`GAUSS_ORDER` nodes) on panels

* ``[0, theta_ul]``: geometric panels ``[theta_ul 2^-(j+1), theta_ul 2^-j]`` down to
  ``2^-J_INNER theta_ul``, so every ``sigma`` of the table finds panels of its own size;
* ``[theta_ul, theta_top]``: geometric panels from ``theta_ul`` (``C``, ``K`` are analytic there
  with their nearest singularity at ``theta = 0``, one panel length away);
* softening beds: the panel ``[3/4 theta_cap, theta_cap]`` in ``s = sqrt(theta_cap - theta)``
  (``dz/da ~ (theta_cap - a)^(-1/2)`` becomes analytic in ``s``), and geometric panels above
  ``theta_cap``.

``C``, ``K`` are evaluated once per point; each ``sigma`` only reweights.

Table: an octave grid in ``q = (sigma / theta_ul)^2 = var_theta / theta_ul^2``
(:func:`screening.kernels.interpolation.octave_grid`, :data:`TABLE_BITS` bits: ``2^TABLE_BITS``
intervals per octave of ``q``) from ``2^Q_OCTAVE_LO`` (``t = ln(sigma / theta_ul) = -12.1``) up to
the first octave above ``t_hi``; values and their exact first and second derivatives (same
quadrature; ``d/dq = (d/dt) / (2 q)``, ``d2/dq2 = (d2/dt2 - 2 d/dt) / (4 q^2)``)::

    d e_c / dt = E[(C - C0) (x^2 - 1)],        d2 e_c / dt2 = E[(C - C0) (x^4 - 4 x^2 + 1)]
    d e_k / dt = E[(K - K0) x^2 (x^2 - 3)],    d2 e_k / dt2 = E[(K - K0) x^2 (x^4 - 8 x^2 + 9)]
    d d_c / dt = E[(C - C0) (x^4 - 6 x^2 + 3)] / sigma^2
    d2 d_c / dt2 = E[(C - C0) (x^6 - 13 x^4 + 33 x^2 - 9)] / sigma^2

read back by quintic Hermite interpolation, stored as per-interval quintic coefficients
(:func:`table_lookup_jit`: the interval from the bits of ``q``, no logarithm per call; largest
error against the direct quadrature 3e-10 of ``c_eq`` and 1e-10 of ``K(0)`` in ``k_eq`` for the test
beds; a cubic in ``q`` would need 8x the nodes for that, the functions being power laws in ``q``).
The nodes' expectations are compiled sums (:func:`gaussian_expectations_jit`): a table of the
paper's block (865 nodes) costs 1.3-2 ms, of which 0.6-1.3 ms evaluate ``C``, ``K`` at the
quadrature nodes; a process keeps its :data:`TABLE_CACHE_SIZE` most recent tables, so a point met
again (the next chunk of a batch, the next call) does not rebuild its table.  Below the grid
(``sigma < 5.4e-6 theta_ul``) ``e_c``, ``e_k`` follow ``f0 + (f(q_lo) - f0) q / q_lo`` and ``d_c`` is
held (relative errors ``O(sigma^2)`` on terms that are themselves ``O(sigma^2)``); above ``t_hi``
(4 x the slenderness angle, where the moment solver has long stopped the point) the last values are
held.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from screening.kernels.interpolation import octave_first, octave_grid, octave_position_jit, quintic, quintic_coefficients
from screening.kernels.signatures import FMA, MomentKernel, moment_coefficients_signature
from screening.model.points import flatten, numeric_fields, point_key, select

__all__ = ["Q_OCTAVE_LO", "TABLE_BITS", "GAUSS_ORDER", "J_INNER", "SIGMA_SPAN", "TABLE_CACHE_SIZE",
           "theta_quadrature", "gaussian_expectations", "gaussian_expectations_jit", "expectations", "table_size",
           "node_values", "coefficient_table", "coefficient_tables", "RECORD", "moment_kernel", "table_lookup",
           "table_lookup_jit", "equivalent_coefficients_jit", "equivalent_coefficients"]

#: Table grid: an octave grid in q = (sigma_theta / theta_ul)^2 from 2^Q_OCTAVE_LO (sigma = 5.4e-6 theta_ul,
#: t = ln(sigma / theta_ul) = -12.1), TABLE_BITS mantissa bits (spacing in t 1/64 to 1/32).
Q_OCTAVE_LO = -35
TABLE_BITS = 4
#: The first node, and the interval index of q = 2^Q_OCTAVE_LO in the bits of q
#: (:func:`screening.kernels.interpolation.octave_first`).
Q_LO = 2.0 ** Q_OCTAVE_LO
_FIRST = octave_first(Q_OCTAVE_LO, TABLE_BITS)
#: Gauss–Legendre nodes per panel and number of geometric panels below theta_ul.
GAUSS_ORDER = 16
J_INNER = 22
#: The Gaussian weight is below 1e-31 of its peak beyond 12 sigma: nodes beyond are left out of the sums.
SIGMA_SPAN = 12.0
#: Tables a process keeps (the most recently used; ~125 kB each for the paper's block).
TABLE_CACHE_SIZE = 16

_GL_X, _GL_W = np.polynomial.legendre.leggauss(GAUSS_ORDER)
_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)


def _gauss_legendre(edges):
    """Nodes and weights of :data:`GAUSS_ORDER`-point Gauss–Legendre on the panels between ``edges``."""
    edges = np.asarray(edges, dtype=float)
    lo, hi = edges[:-1, None], edges[1:, None]
    nodes = 0.5 * (hi + lo) + 0.5 * (hi - lo) * _GL_X[None, :]
    weights = 0.5 * (hi - lo) * _GL_W[None, :]
    return nodes.ravel(), weights.ravel()


def _geometric_edges(start, stop):
    """``start, 2 start, 4 start, ...`` up to the first value >= ``stop`` (both > 0)."""
    n = max(int(math.ceil(math.log2(stop / start))), 1)
    return start * 2.0 ** np.arange(n + 1)


def theta_quadrature(theta_ul, theta_cap, theta_top):
    """Nodes ``theta_j`` [rad] and weights [rad] on ``(0, theta_top]`` for Gaussian expectations.

    ``theta_ul``: uplift threshold [rad]; ``theta_cap``: capacity angle [rad] (``inf`` if none);
    ``theta_top``: upper end [rad] (at least ``SIGMA_SPAN`` times the largest sigma).  Panels
    as in the module docstring.

    Parameters
    ----------
    theta_ul : float
        The uplift threshold [rad], > 0.
    theta_cap : float
        The capacity angle of a softening bed [rad]; ``math.inf`` for none.
    theta_top : float
        The upper end of the nodes [rad] (raised to ``2 theta_ul`` if below).

    Returns
    -------
    theta : numpy.ndarray
        The nodes [rad], in ``(0, theta_top]`` (up to the last geometric panel's end).
    weight : numpy.ndarray
        Their weights [rad]: ``sum(weight * f(theta))`` approximates ``int f dtheta``.

    Notes
    -----
    :data:`GAUSS_ORDER`-point Gauss-Legendre rules [2]_ on geometric panels
    ``[theta_ul 2^-(j+1), theta_ul 2^-j]`` (``j < J_INNER``) and ``[theta_ul 2^j, theta_ul 2^(j+1)]``,
    so that every ``sigma`` between ``2^-J_INNER theta_ul`` and ``theta_top / SIGMA_SPAN`` finds
    panels of its own size; below ``theta_cap`` the substitution ``theta = theta_cap - s^2`` removes
    the square-root singularity of ``dz/dtheta``.  The expectations of eq. (31) in [1]_ are
    ``E[f] = 2 sum(weight f(theta) phi_sigma(theta))`` for even ``f``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] P. J. Davis and P. Rabinowitz, Methods of Numerical Integration, 2nd ed., Academic Press
       (1984), ch. 2 (Gauss-Legendre rules).

    Examples
    --------
    The nodes integrate the Gaussian density of ``sigma = 1 mrad`` and its variance exactly:

    >>> import math
    >>> theta, weight = theta_quadrature(1.0372e-3, math.inf, 0.12)
    >>> sigma = 1e-3
    >>> phi = 2 * np.exp(-0.5 * (theta / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))
    >>> round(float(weight @ phi), 12), round(float(weight @ (phi * theta**2)) / sigma**2, 12)
    (1.0, 1.0)
    """
    inner = np.concatenate([[0.0], theta_ul * 2.0 ** -np.arange(J_INNER, -1, -1)])
    parts = [_gauss_legendre(inner)]
    top = max(theta_top, 2.0 * theta_ul)
    if theta_cap < top:
        bend = max(0.75 * theta_cap, theta_ul)
        if bend > theta_ul:
            edges = _geometric_edges(theta_ul, bend)
            parts.append(_gauss_legendre(np.append(edges[edges < bend], bend)))
        s, ws = _gauss_legendre(np.linspace(0.0, math.sqrt(theta_cap - bend), 4))
        parts.append((theta_cap - s * s, 2.0 * s * ws))        # theta = theta_cap - s^2
        parts.append(_gauss_legendre(_geometric_edges(theta_cap, top)))
    else:
        parts.append(_gauss_legendre(_geometric_edges(theta_ul, top)))
    nodes = np.concatenate([p[0] for p in parts])
    weights = np.concatenate([p[1] for p in parts])
    return nodes, weights


def gaussian_expectations(sigma, theta, weight, c_values, k_values, c0, k0):
    """``(values, slopes)``, each ``(len(sigma), 3)``: ``(e_c, e_k, d_c)`` and their d/d ln(sigma).

    ``sigma`` [rad] > 0; ``theta``, ``weight`` from :func:`theta_quadrature`; ``c_values``
    [N m s/rad], ``k_values`` [N m/rad] = ``C``, ``K`` at the nodes; ``c0``, ``k0`` = ``C(0)``, ``K(0)``.

    Parameters
    ----------
    sigma : array_like
        Standard deviations of the rotation [rad], > 0 (1-d).
    theta, weight : numpy.ndarray
        Nodes [rad] and weights [rad] (:func:`theta_quadrature`).
    c_values : numpy.ndarray
        The rocking damping ``C(theta)`` at the nodes [N m s/rad].
    k_values : numpy.ndarray
        The rocking stiffness ``K(theta)`` at the nodes [N m/rad].
    c0, k0 : float
        ``C(0)`` [N m s/rad] and ``K(0)`` [N m/rad].

    Returns
    -------
    values : numpy.ndarray
        ``(len(sigma), 3)``: ``e_c`` [N m s/rad], ``e_k`` [N m/rad], ``d_c`` [N m s/rad^3].
    slopes : numpy.ndarray
        ``(len(sigma), 3)``: their derivatives with respect to ``ln(sigma)`` (same units).

    Notes
    -----
    With ``x = theta / sigma``, the expectations of eq. (31) in [1]_ over the Gaussian density
    eq. (33), turned by Stein's lemma [2]_ into functions of ``sigma`` alone::

        e_c = E[C],   e_k = E[K x^2],   d_c = E[(C - C0) (x^2 - 1)] / sigma^2
        d e_c / d ln(sigma) = E[(C - C0) (x^2 - 1)]
        d e_k / d ln(sigma) = E[(K - K0) x^2 (x^2 - 3)]
        d d_c / d ln(sigma) = E[(C - C0) (x^4 - 6 x^2 + 3)] / sigma^2

    so that ``c_eq = e_c`` and ``k_eq = e_k + cov(theta, theta') d_c``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    For constant ``C`` and ``K`` the expectations are those constants, ``d_c = 0``, and nothing
    changes with ``sigma``:

    >>> import math
    >>> theta, weight = theta_quadrature(1e-3, math.inf, 0.12)
    >>> values, slopes = gaussian_expectations([1e-3], theta, weight, np.full(theta.shape, 2.0),
    ...                                        np.full(theta.shape, 500.0), 2.0, 500.0)
    >>> values.round(9).tolist(), slopes.round(9).tolist()
    ([[2.0, 500.0, 0.0]], [[0.0, 0.0, 0.0]])
    """
    sigma = np.asarray(sigma, dtype=float)[:, None]
    # at scales near the float range (k ~ 1e100) the products overflow: the table is then not finite and the
    # solver flags the point, as it did when these sums were a BLAS product (which raises no floating-point
    # warning); numpy's elementwise products would add a RuntimeWarning for the same outcome
    with np.errstate(over="ignore", invalid="ignore"):
        x2 = (theta[None, :] / sigma) ** 2
        phi = (2.0 * _INV_SQRT_2PI) * weight[None, :] * np.exp(-0.5 * x2) / sigma
        dc = c_values - c0
        dk = k_values - k0
        inv_s2 = 1.0 / sigma[:, 0] ** 2
        he2 = phi * (x2 - 1.0)
        values = np.stack([_row_sums(phi, c_values), _row_sums(phi * x2, k_values), _row_sums(he2, dc) * inv_s2],
                          axis=1)
        slopes = np.stack([_row_sums(he2, dc), _row_sums(phi * x2 * (x2 - 3.0), dk),
                           _row_sums(phi * (x2 * (x2 - 6.0) + 3.0), dc) * inv_s2], axis=1)
    return values, slopes


def _row_sums(weights, values):
    """``weights @ values`` by numpy's own pairwise summation: the same bits in every process (a BLAS
    product's last bits depend on its thread count, so a table built in a dask worker and one built
    in the main process would differ)."""
    return np.sum(weights * values[None, :], axis=1)


@intrinsic
def _float_from_bits(typingctx, bits):
    """The double whose IEEE 754 bits are the int64 ``bits`` (a bit cast, no conversion)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())
    return types.float64(types.int64), codegen


_LOG2E = 1.0 / math.log(2.0)
_LN2_HI = 6.93147180369123816490e-01        # ln 2 in two parts (Cody and Waite): k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10


@numba.njit(cache=True, inline="always")
def _exp_nonpositive(y):
    """``exp(y)`` for ``-700 <= y <= 0`` in straight-line arithmetic, so that LLVM vectorises the loops
    that call it (libm's ``exp`` is a call): ``y = k ln 2 + r`` with ``|r| <= ln(2) / 2``, ``exp(r)`` by
    its Taylor series to ``r^13`` (truncation below 1e-17 relative), ``2^k`` from its bits; within
    2.3e-16 of ``math.exp`` (tests/unit/condensation/test_quadrature.py)."""
    k = math.floor(y * _LOG2E + 0.5)
    r = (y - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 / 6227020800.0
    p = 1.0 / 479001600.0 + r * p
    p = 1.0 / 39916800.0 + r * p
    p = 1.0 / 3628800.0 + r * p
    p = 1.0 / 362880.0 + r * p
    p = 1.0 / 40320.0 + r * p
    p = 1.0 / 5040.0 + r * p
    p = 1.0 / 720.0 + r * p
    p = 1.0 / 120.0 + r * p
    p = 1.0 / 24.0 + r * p
    p = 1.0 / 6.0 + r * p
    p = 0.5 + r * p
    p = 1.0 + r * p
    p = 1.0 + r * p
    return p * _float_from_bits((np.int64(k) + 1023) << 52)


@numba.njit(cache=True, fastmath={"reassoc", "contract"})
def gaussian_expectations_jit(sigma, theta, weight, c_values, k_values, c0, k0):
    """Compiled twin of :func:`gaussian_expectations` (what the tables are built with).

    Parameters
    ----------
    sigma : numpy.ndarray
        Standard deviations of the rotation [rad], > 0 (1-d, float64).
    theta, weight : numpy.ndarray
        Nodes [rad] and weights [rad] (:func:`theta_quadrature`).
    c_values : numpy.ndarray
        ``C(theta)`` at the nodes [N m s/rad].
    k_values : numpy.ndarray
        ``K(theta)`` at the nodes [N m/rad].
    c0, k0 : float
        ``C(0)`` [N m s/rad] and ``K(0)`` [N m/rad].

    Returns
    -------
    values : numpy.ndarray
        ``(len(sigma), 3)``: ``e_c`` [N m s/rad], ``e_k`` [N m/rad], ``d_c`` [N m s/rad^3].
    slopes : numpy.ndarray
        ``(len(sigma), 3)``: their derivatives with respect to ``ln(sigma)`` (same units).
    curvatures : numpy.ndarray
        ``(len(sigma), 3)``: their second derivatives with respect to ``ln(sigma)`` (module docstring).

    Notes
    -----
    The sums of eq. (31) in [1]_ over the Gaussian density, by Stein's lemma [2]_
    (:func:`gaussian_expectations`, plus the second derivatives), in one pass per ``sigma``; nodes beyond :data:`SIGMA_SPAN` ``sigma``
    (Gaussian weight below 1e-31) are left out.  The sums may be reassociated (vectorised): they agree
    with numpy's to ~1e-13 relative and are the same bits in every process on one machine.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    >>> theta, weight = theta_quadrature(1e-3, math.inf, 0.12)
    >>> c, k = 2.0 + 5e4 * theta**2, 500.0 - 3e7 * theta**2          # C = C0 + C2 theta^2, K likewise
    >>> sigma = np.array([1e-4, 1e-3])
    >>> values, slopes, curvatures = gaussian_expectations_jit(sigma, theta, weight, c, k, 2.0, 500.0)
    >>> ref = gaussian_expectations(sigma, theta, weight, c, k, 2.0, 500.0)
    >>> bool(np.allclose(values, ref[0], rtol=1e-12) and np.allclose(slopes, ref[1], rtol=1e-12, atol=1e-8))
    True
    >>> bool(np.allclose(curvatures[:, 0], 4 * 5e4 * sigma**2, rtol=1e-12))    # e_c = C0 + C2 sigma^2
    True
    """
    n = sigma.shape[0]
    m = theta.shape[0]
    theta2 = theta * theta
    dc = c_values - c0
    dk = k_values - k0
    span2 = SIGMA_SPAN * SIGMA_SPAN
    values = np.empty((n, 3))
    slopes = np.empty((n, 3))
    curvatures = np.empty((n, 3))
    for i in range(n):
        inv = 1.0 / sigma[i]
        inv2 = inv * inv
        e_c = 0.0
        e_k = 0.0
        s_c = 0.0
        s_k = 0.0
        s_d = 0.0
        r_c = 0.0
        r_k = 0.0
        r_d = 0.0
        for j in range(m):
            x2 = theta2[j] * inv2
            phi = weight[j] * _exp_nonpositive(max(-0.5 * x2, -700.0))
            phi = phi if x2 <= span2 else 0.0
            pc = phi * dc[j]
            pk = phi * x2 * dk[j]
            e_c += phi * c_values[j]
            e_k += phi * x2 * k_values[j]
            s_c += pc * (x2 - 1.0)
            s_k += pk * (x2 - 3.0)
            s_d += pc * (x2 * (x2 - 6.0) + 3.0)
            r_c += pc * (x2 * (x2 - 4.0) + 1.0)
            r_k += pk * (x2 * (x2 - 8.0) + 9.0)
            r_d += pc * (x2 * (x2 * (x2 - 13.0) + 33.0) - 9.0)
        f = 2.0 * _INV_SQRT_2PI * inv
        values[i, 0] = e_c * f
        values[i, 1] = e_k * f
        values[i, 2] = s_c * f * inv2
        slopes[i, 0] = s_c * f
        slopes[i, 1] = s_k * f
        slopes[i, 2] = s_d * f * inv2
        curvatures[i, 0] = r_c * f
        curvatures[i, 1] = r_k * f
        curvatures[i, 2] = r_d * f * inv2
    return values, slopes, curvatures


def _point_nodes(block, foundation, sigma_max, cond):
    """Nodes, weights, ``C``, ``K`` at the nodes and ``C(0)``, ``K(0)`` for one (scalar) point."""
    tu = float(cond.uplift_threshold(block, foundation))
    cap = float(cond.capacity_angle(block, foundation))
    theta, weight = theta_quadrature(tu, cap, SIGMA_SPAN * sigma_max)
    c = cond.rocking_damping(theta, block, foundation)
    k = cond.rocking_stiffness(theta, block, foundation)
    return theta, weight, c, k, float(cond.damping_at_rest(block, foundation)), \
        float(cond.stiffness_at_rest(block, foundation))


def expectations(sigma_theta, block, foundation, cond):
    """``(e_c, e_k, d_c)`` [SI, module docstring] at ``sigma_theta`` [rad] >= 0 for one scalar point.

    Direct quadrature (no table); below ``sigma_lo = theta_ul sqrt(Q_LO)`` the same ``sigma^2``
    extrapolation as the table, exact limits at ``sigma = 0``.

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    e_c : numpy.ndarray
        ``E[C]`` [N m s/rad], the shape of ``sigma_theta``.
    e_k : numpy.ndarray
        ``E[K x^2]`` [N m/rad].
    d_c : numpy.ndarray
        ``E[(C - C0) (x^2 - 1)] / sigma^2`` [N m s/rad^3].

    Notes
    -----
    :func:`gaussian_expectations` on the nodes of :func:`theta_quadrature`; the equivalent
    coefficients of eq. (31) in [1]_ are ``c_eq = e_c``, ``k_eq = e_k + cov d_c``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    The paper's condensation has closed forms (:mod:`screening.condensation.paper`): the
    quadrature reproduces them, and gives the no-uplift values at ``sigma = 0``:

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> paper = get("paper")
    >>> sigma = np.array([0.0, 1e-3, 3e-3])                                   # [rad]
    >>> e_c, e_k, d_c = expectations(sigma, block, bed, paper)
    >>> c_eq, k_eq = paper.equivalent_coefficients(sigma, 0.2, block, bed)    # cov / sigma = 0.2 rad/s
    >>> bool(np.allclose(e_c, c_eq, rtol=1e-9) and np.allclose(e_k + 0.2 * sigma * d_c, k_eq, rtol=1e-9))
    True
    >>> bool(e_c[0] == paper.damping_at_rest(block, bed)), [f"{v:.4g}" for v in e_c]
    (True, ['1.076', '1.041', '0.8289'])
    """
    s = np.asarray(sigma_theta, dtype=float)
    tu = float(cond.uplift_threshold(block, foundation))
    s_lo = tu * math.sqrt(Q_LO)
    theta, weight, c, k, c0, k0 = _point_nodes(block, foundation, max(float(np.max(s, initial=0.0)), s_lo), cond)
    flat = s.ravel()
    above = flat >= s_lo
    out = np.empty((flat.size, 3))
    if np.any(above):
        out[above] = gaussian_expectations(flat[above], theta, weight, c, k, c0, k0)[0]
    if not np.all(above):
        lo = gaussian_expectations(np.array([s_lo]), theta, weight, c, k, c0, k0)[0][0]
        f = (flat[~above] / s_lo) ** 2
        out[~above] = np.stack([c0 + (lo[0] - c0) * f, k0 + (lo[1] - k0) * f, np.full(f.shape, lo[2])], axis=1)
    out = out.reshape(s.shape + (3,))
    return out[..., 0], out[..., 1], out[..., 2]


def table_size(block, foundation, cond):
    """Number of table nodes: the octave grid in ``q`` from ``2^Q_OCTAVE_LO`` to the first power of 2 at or
    above ``exp(2 t_hi)``, ``t_hi = ln(4 atan(b/h) / theta_ul)`` (at least 2).

    Vectorised over array model parameters (one size per point).

    Parameters
    ----------
    block : screening.model.Block
        The rigid block (``b``, ``h`` [m]); fields may be arrays.
    foundation : screening.model.Foundation
        The bed; fields may be arrays.
    cond : screening.condensation.Condensation
        The condensation (its ``uplift_threshold``).

    Returns
    -------
    int or numpy.ndarray of int
        ``(e_hi - Q_OCTAVE_LO) 2^TABLE_BITS + 1`` nodes [-], with ``e_hi = ceil(2 t_hi / ln 2)`` and
        ``t_hi = max(ln(4 atan(b/h) / theta_ul), 2)``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> cubic = get("cubic")
    >>> theta_ul = float(cubic.uplift_threshold(block, bed))                  # [rad]
    >>> e_hi = math.ceil(2 * math.log(4 * math.atan(0.035 / 0.21) / theta_ul) / math.log(2))
    >>> int(table_size(block, bed, cubic)), (e_hi - Q_OCTAVE_LO) * 2**TABLE_BITS + 1
    (865, 865)
    """
    tu = cond.uplift_threshold(block, foundation)
    t_hi = np.maximum(np.log(4.0 * block.slenderness / tu), 2.0)
    e_hi = np.ceil(2.0 * t_hi / math.log(2.0)).astype(int)
    return (((e_hi - Q_OCTAVE_LO) << TABLE_BITS) + 1)[()]


def node_values(block, foundation, cond):
    """The table's nodes ``q`` and ``(values, slopes, curvatures)`` of shape ``(table_size, 3)`` for one scalar
    point.

    Nodes on the octave grid ``q = (sigma / theta_ul)^2`` of :func:`table_size`; depends on the point alone.

    Parameters
    ----------
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    q : numpy.ndarray
        The nodes ``(sigma / theta_ul)^2`` [1].
    values : numpy.ndarray
        ``(table_size, 3)``: ``e_c`` [N m s/rad], ``e_k`` [N m/rad], ``d_c`` [N m s/rad^3] at
        ``sigma = theta_ul sqrt(q)``.
    slopes : numpy.ndarray
        ``(table_size, 3)``: their derivatives with respect to ``q`` (units of the values).
    curvatures : numpy.ndarray
        ``(table_size, 3)``: their second derivatives with respect to ``q``.

    Notes
    -----
    :func:`gaussian_expectations_jit` at the table's ``sigma`` values, one node set for all of them;
    with ``t = ln(sigma / theta_ul) = ln(q) / 2``, ``d/dq = (d/dt) / (2 q)`` and
    ``d2/dq2 = (d2/dt2 - 2 d/dt) / (4 q^2)``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> cubic = get("cubic")
    >>> q, values, slopes, curvatures = node_values(block, bed, cubic)
    >>> values.shape, f"{values[0, 0]:.6f} {float(cubic.damping_at_rest(block, bed)):.6f}"   # e_c -> C(0)
    ((865, 3), '0.987309 0.987309')
    """
    n = int(table_size(block, foundation, cond))
    q = octave_grid(Q_OCTAVE_LO, Q_OCTAVE_LO + ((n - 1) >> TABLE_BITS), TABLE_BITS)
    tu = float(cond.uplift_threshold(block, foundation))
    sigma = tu * np.sqrt(q)
    theta, weight, c, k, c0, k0 = _point_nodes(block, foundation, float(sigma[-1]), cond)
    values, slopes, curvatures = gaussian_expectations_jit(sigma, theta, weight, c, k, c0, k0)
    q2 = q[:, None]
    return q, values, slopes / (2.0 * q2), (curvatures - 2.0 * slopes) / (4.0 * q2 * q2)


def coefficient_table(block, foundation, cond):
    """One scalar point's table: per-interval quintic coefficients ``(table_size, 18)`` of
    :func:`node_values` in ``q`` (:func:`screening.kernels.interpolation.quintic_coefficients`).

    Parameters
    ----------
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    numpy.ndarray
        ``(table_size, 18)``: for each interval of ``q``, the six quintic Hermite coefficients of
        ``e_c`` (columns 0-5, [N m s/rad]), ``e_k`` (6-11, [N m/rad]) and ``d_c`` (12-17,
        [N m s/rad^3]); columns 0, 6, 12 hold the node values.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. XII (osculatory interpolation:
       Hermite interpolation with derivatives at the nodes).

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> cubic = get("cubic")
    >>> table = coefficient_table(block, bed, cubic)
    >>> i = np.array([0, 400, 800])                                    # nodes 0, 400, 800 of the octave grid
    >>> q = np.ldexp(1.0 + i % 2**TABLE_BITS / 2**TABLE_BITS, Q_OCTAVE_LO + i // 2**TABLE_BITS)
    >>> sigma = float(cubic.uplift_threshold(block, bed)) * np.sqrt(q)
    >>> table.shape, bool(np.allclose(table[i][:, 0::6], np.stack(expectations(sigma, block, bed, cubic), axis=1),
    ...                               rtol=1e-9))
    ((865, 18), True)
    """
    q, values, slopes, curvatures = node_values(block, foundation, cond)
    return quintic_coefficients(values, slopes, curvatures, np.diff(q))


_TABLES = OrderedDict()
_TABLES_LOCK = threading.Lock()


def _table(block, foundation, cond):
    """:func:`coefficient_table` of one scalar point, from the process's cache of recent tables (read-only)."""
    key = (cond, point_key(block, foundation))
    with _TABLES_LOCK:
        table = _TABLES.get(key)
        if table is not None:
            _TABLES.move_to_end(key)
            return table
    table = coefficient_table(block, foundation, cond)
    table.flags.writeable = False
    with _TABLES_LOCK:
        _TABLES[key] = table
        while len(_TABLES) > TABLE_CACHE_SIZE:
            _TABLES.popitem(last=False)
    return table


def coefficient_tables(block, foundation, cond):
    """Tables of the points of flat (1-d) model fields: ``(tables, index)``.

    ``tables``: ``(n_distinct, max size, 18)``, one :func:`coefficient_table` per distinct point,
    zero-padded to the longest (the padding is never read: :func:`table_lookup_jit` gets each
    point's number of intervals); ``index[i]`` is point i's table.  The process keeps its
    :data:`TABLE_CACHE_SIZE` most recently used tables, so a point met again is not rebuilt.

    Parameters
    ----------
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); flat (1-d) fields, one entry per point.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); flat (1-d) fields, one entry per point.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    tables : numpy.ndarray
        ``(n_distinct, max table_size, 18)`` (units of :func:`coefficient_table`).
    index : numpy.ndarray of int64
        Point ``i``'s table is ``tables[index[i]]``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".

    Examples
    --------
    Two of three points are the same block and bed: they share a table.

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> from screening.model.points import flatten
    >>> (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=[0.21, 0.21, 0.3]),
    ...                           Foundation(k=2.89e7, lam=8.95e8, eps=6e7))
    >>> tables, index = coefficient_tables(block, bed, get("cubic"))
    >>> tables.shape, index.tolist()
    ((2, 865, 18), [0, 0, 1])
    """
    first, index = _distinct_points(block, foundation)
    return _stacked_tables(block, foundation, first, cond), index


def _stacked_tables(block, foundation, first, cond):
    """The tables of the points ``first`` of flat model fields, zero-padded to the longest and stacked."""
    tables = [_table(select(block, int(i)), select(foundation, int(i)), cond) for i in first]
    size = max(tb.shape[0] for tb in tables)
    out = np.zeros((len(tables), size, tables[0].shape[1]))
    for j, tb in enumerate(tables):
        out[j, :tb.shape[0]] = tb
    return out


def _distinct_points(block, foundation):
    """``(first, index)`` of flat model fields: the first point of each distinct parameter point (equal
    numeric fields, as :func:`screening.model.points.point_key` compares them), in order of appearance,
    and each point's distinct point (one ``numpy.unique`` over the points, not a key per point)."""
    n = np.size(block.m)
    columns = [np.broadcast_to(np.asarray(value, dtype=float).reshape(-1), (n,))
               for obj in (block, foundation) for value in numeric_fields(obj).values()]
    _, first, inverse = np.unique(np.stack(columns, axis=1), axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order], rank[inverse.reshape(-1)].astype(np.int64)


#: Per-point parameters of :func:`equivalent_coefficients_jit` (SI units; the table's last interval).
RECORD = np.dtype([("inv_theta_ul2", "f8"), ("c_rest", "f8"), ("k_rest", "f8"), ("table_intervals", "i8")])


def moment_kernel(block, foundation, cond):
    """:class:`~screening.condensation.base.MomentKernel` of ``cond`` for flat (1-d) model fields.

    The default moment kernel of a condensation without closed forms: the compiled
    :func:`equivalent_coefficients_jit`, one :data:`RECORD` per point and the tables of
    :func:`coefficient_tables`.

    Parameters
    ----------
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); flat (1-d) fields, one entry per point.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); flat (1-d) fields, one entry per point.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    screening.kernels.signatures.MomentKernel
        ``(coefficients, records, tables, table_index)``: records in SI units
        (``inv_theta_ul2`` = 1 / theta_ul^2 [rad-2], ``c_rest`` [N m s/rad], ``k_rest`` [N m/rad],
        ``table_intervals`` = table_size - 1).

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> from screening.model.points import flatten
    >>> (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=[0.21, 0.21]),
    ...                           Foundation(k=2.89e7, lam=8.95e8, eps=6e7))
    >>> kernel = moment_kernel(block, bed, get("cubic"))
    >>> kernel.tables.shape, kernel.table_index.tolist(), kernel.records["table_intervals"].tolist()
    ((1, 865, 18), [0, 0], [864, 864])
    """
    first, index = _distinct_points(block, foundation)
    tables = _stacked_tables(block, foundation, first, cond)
    blk, fnd = select(block, first), select(foundation, first)          # one entry per table
    fields = {"inv_theta_ul2": 1.0 / cond.uplift_threshold(blk, fnd) ** 2,
              "c_rest": cond.damping_at_rest(blk, fnd), "k_rest": cond.stiffness_at_rest(blk, fnd),
              "table_intervals": table_size(blk, fnd, cond) - 1}
    records = np.empty(first.size, dtype=RECORD)
    for name, value in fields.items():
        records[name] = np.broadcast_to(np.asarray(value, dtype=RECORD[name]), first.shape)
    return MomentKernel(equivalent_coefficients_jit, records[index], tables, index)


def table_lookup(q, table, c0, k0):
    """``(e_c, e_k, d_c)`` at ``q = (sigma_theta / theta_ul)^2`` (>= 0) from one point's table.

    ``c0``, ``k0``: ``C(0)`` [N m s/rad], ``K(0)`` [N m/rad], the limits at ``sigma = 0``.
    Python entry point of :func:`table_lookup_jit`.

    Parameters
    ----------
    q : float
        ``(sigma_theta / theta_ul)^2`` [-], >= 0.
    table : numpy.ndarray
        One point's :func:`coefficient_table`.
    c0 : float
        ``C(0)`` [N m s/rad].
    k0 : float
        ``K(0)`` [N m/rad].

    Returns
    -------
    tuple of float
        ``(e_c [N m s/rad], e_k [N m/rad], d_c [N m s/rad^3])``.

    Notes
    -----
    Quintic Hermite interpolation [2]_ of the node values and ``q``-derivatives on the octave grid; below
    ``Q_LO``, ``f0 + (f(Q_LO) - f0) q / Q_LO`` for ``e_c``, ``e_k`` and ``d_c`` held; above the last node
    its values held.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. XII (osculatory interpolation:
       Hermite interpolation with derivatives at the nodes).

    Examples
    --------
    Between two nodes the lookup agrees with the direct quadrature to 1e-8:

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> cubic = get("cubic")
    >>> table = coefficient_table(block, bed, cubic)
    >>> c0, k0 = float(cubic.damping_at_rest(block, bed)), float(cubic.stiffness_at_rest(block, bed))
    >>> q = 2.0**-3 * (1 + 8.5 / 2**TABLE_BITS)                       # halfway between two nodes
    >>> direct = expectations(float(cubic.uplift_threshold(block, bed)) * math.sqrt(q), block, bed, cubic)
    >>> looked_up = table_lookup(q, table, c0, k0)
    >>> all(abs(a / float(b) - 1) < 1e-8 for a, b in zip(looked_up, direct))
    True
    >>> table_lookup(0.0, table, c0, k0)[:2] == (c0, k0)              # sigma = 0: the values at rest
    True
    """
    return table_lookup_jit(q, table, c0, k0, table.shape[0] - 1)


@numba.njit(cache=True, inline="always")
def table_lookup_jit(q, table, c0, k0, intervals):
    """Compiled twin of :func:`table_lookup` on a table of ``intervals + 1`` nodes.

    Rows of ``table`` beyond ``intervals`` (padding of stacked tables) are never read.

    Parameters
    ----------
    q : float
        ``(sigma_theta / theta_ul)^2`` [-]; any ``q <= 0`` (and NaN) gives the values at rest.
    table : numpy.ndarray
        One point's :func:`coefficient_table` (possibly zero-padded).
    c0 : float
        ``C(0)`` [N m s/rad].
    k0 : float
        ``K(0)`` [N m/rad].
    intervals : int
        The point's number of table intervals [-] (:func:`table_size` - 1).

    Returns
    -------
    tuple of float
        ``(e_c [N m s/rad], e_k [N m/rad], d_c [N m s/rad^3])``.

    Notes
    -----
    The interval ``j`` and the fraction ``s`` in it are read from the bits of ``q``
    (:func:`screening.kernels.interpolation.octave_position_jit`), and each quantity is the quintic
    ``a0 + a1 s + ... + a5 s^5`` of row ``j`` (quintic Hermite interpolation [2]_); below ``Q_LO``,
    ``f0 + (f(Q_LO) - f0) q / Q_LO`` for ``e_c``, ``e_k`` and ``d_c`` held.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. XII (osculatory interpolation:
       Hermite interpolation with derivatives at the nodes).

    Examples
    --------
    At a node the lookup returns the node's values:

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> cubic = get("cubic")
    >>> table = coefficient_table(block, bed, cubic)
    >>> q = 2.0**-3 * (1 + 8 / 2**TABLE_BITS)                         # a node
    >>> got = table_lookup_jit(q, table, 1.0, 1.0, table.shape[0] - 1)
    >>> direct = expectations(float(cubic.uplift_threshold(block, bed)) * np.sqrt(q), block, bed, cubic)
    >>> bool(np.allclose(got, [float(v) for v in direct], rtol=1e-9))
    True
    """
    j, s = octave_position_jit(q, _FIRST, TABLE_BITS)
    if j < 0:
        f = q * (1.0 / Q_LO) if q > 0.0 else 0.0      # (sigma / sigma_lo)^2
        return c0 + (table[0, 0] - c0) * f, k0 + (table[0, 6] - k0) * f, table[0, 12]
    if j >= intervals:
        return table[intervals, 0], table[intervals, 6], table[intervals, 12]   # the last node, held
    return quintic(table, j, 0, s), quintic(table, j, 1, s), quintic(table, j, 2, s)


@numba.njit(moment_coefficients_signature(RECORD), cache=True, fastmath=FMA)
def equivalent_coefficients_jit(p, table, var_theta, cov):
    """Compiled twin of :func:`equivalent_coefficients`, from the moments ``var_theta`` [rad2] and
    ``cov`` [rad2/s], on one point's table: ``c_eq = e_c``, ``k_eq = e_k + cov d_c``.

    Parameters
    ----------
    p : numpy.void
        The point's :data:`RECORD` (:func:`moment_kernel`).
    table : numpy.ndarray
        The point's :func:`coefficient_table`.
    var_theta : float
        Variance of the rotation [rad2], >= 0.
    cov : float
        ``cov(theta, theta')`` [rad2/s].

    Returns
    -------
    c_eq : float
        Equivalent damping [N m s/rad].
    k_eq : float
        Equivalent stiffness [N m/rad].

    Notes
    -----
    Eq. (31) in [1]_ in the form ``c_eq = e_c``, ``k_eq = e_k + cov d_c`` (:func:`gaussian_expectations`),
    read from the table by :func:`table_lookup_jit` at ``q = var_theta / theta_ul^2``.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    The compiled kernel (compiled at import) against the direct quadrature:

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> from screening.model.points import flatten
    >>> (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7))
    >>> cubic = get("cubic")
    >>> kernel = moment_kernel(block, bed, cubic)
    >>> c_eq, k_eq = equivalent_coefficients_jit(kernel.records[0], kernel.tables[0], 2e-3 ** 2, 2e-3 * 0.05)
    >>> c_ref, k_ref = equivalent_coefficients(2e-3, 0.05, block, bed, cubic)
    >>> bool(abs(c_eq / c_ref - 1) < 1e-8 and abs(k_eq / k_ref - 1) < 1e-6)
    True
    """
    e_c, e_k, d_c = table_lookup_jit(var_theta * p.inv_theta_ul2, table, p.c_rest, p.k_rest, p.table_intervals)
    return e_c, e_k + cov * d_c


def equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation, cond):
    """``(c_eq [N m s/rad], k_eq [N m/rad])`` of the condensation ``cond`` by quadrature (module docstring).

    ``sigma_theta`` [rad] >= 0 and ``cov_over_sigma = cov(theta, theta') / sigma_theta``
    [rad/s] (``rho sigma_theta_dot``), broadcast with array model parameters (one quadrature
    per distinct parameter point).

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    cov_over_sigma : array_like
        ``cov(theta, theta') / sigma_theta = rho sigma_theta_dot`` [rad s-1].
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.
    cond : screening.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged.

    Returns
    -------
    c_eq : numpy.ndarray or float
        Equivalent damping [N m s/rad], the broadcast shape of the model fields and the moments.
    k_eq : numpy.ndarray or float
        Equivalent stiffness [N m/rad].

    Notes
    -----
    Eq. (31) in [1]_, ``c_eq = E[d g / d theta']``, ``k_eq = E[d g / d theta]`` for
    ``g = C(theta) theta' + K(theta) theta`` over the Gaussian density eq. (34), by Stein's
    lemma [2]_ ``c_eq = e_c``, ``k_eq = e_k + cov d_c`` (:func:`expectations`).

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733
    .. [2] C. M. Stein, "Estimation of the mean of a multivariate normal distribution", Annals of
       Statistics 9(6) (1981) 1135-1151.

    Examples
    --------
    By quadrature, the paper's condensation gives its closed forms, eqs. (35)-(36) in [1]_
    (:func:`screening.condensation.paper.equivalent_coefficients`):

    >>> from screening import Block, Foundation
    >>> from screening.condensation import get
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> paper = get("paper")
    >>> sigma = np.array([1e-4, 1e-3])                                         # [rad]
    >>> c_eq, k_eq = equivalent_coefficients(sigma, 0.5, block, bed, paper)
    >>> c_ref, k_ref = paper.equivalent_coefficients(sigma, 0.5, block, bed)
    >>> bool(np.allclose(c_eq, c_ref, rtol=1e-9) and np.allclose(k_eq, k_ref, rtol=1e-9))
    True
    >>> [f"{c:.4g}" for c in c_eq], [f"{k:.4g}" for k in k_eq]
    (['1.076', '1.041'], ['1072', '1026'])
    """
    s = np.asarray(sigma_theta, dtype=float)
    cs = np.asarray(cov_over_sigma, dtype=float)
    (blk_flat, fnd_flat), shape_p = flatten(block, foundation)
    shape = np.broadcast_shapes(shape_p, s.shape, cs.shape)
    s_b = np.broadcast_to(s, shape)
    cs_b = np.broadcast_to(cs, shape)
    c_eq = np.empty(shape)
    k_eq = np.empty(shape)
    p_index = np.broadcast_to(np.arange(int(np.prod(shape_p, dtype=int))).reshape(shape_p), shape)
    for j in range(int(np.prod(shape_p, dtype=int))):
        sel = p_index == j
        e_c, e_k, d_c = expectations(s_b[sel], select(blk_flat, j), select(fnd_flat, j), cond)
        c_eq[sel] = e_c
        k_eq[sel] = e_k + cs_b[sel] * s_b[sel] * d_c
    return c_eq[()], k_eq[()]
