"""Equivalent linear coefficients of any condensation by Gaussian quadrature, tabulated per point.

A condensation whose ``C(theta)``, ``K(theta)`` have no closed-form Gaussian expectations (the
``"cubic"`` one, :mod:`screening.core.condensation.cubic`, or one registered from outside) gets the
coefficients of eq. (31) by quadrature; this is the default of
:meth:`screening.core.condensation.Condensation.equivalent_coefficients` and of its moment kernel.  For zero-mean Gaussian ``(theta, theta')`` with ``sigma = sigma_theta`` and
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
the same formulas reproduce the closed forms of :mod:`screening.core.condensation.paper`.

Quadrature (``E[f] = 2 int_0^inf f(theta) phi_sigma(theta) dtheta``, ``C``, ``K`` even): one node
set in ``theta`` per parameter point, Gauss–Legendre (:data:`GAUSS_ORDER` nodes) on panels

* ``[0, theta_ul]``: geometric panels ``[theta_ul 2^-(j+1), theta_ul 2^-j]`` down to
  ``2^-J_INNER theta_ul``, so every ``sigma`` of the table finds panels of its own size;
* ``[theta_ul, theta_top]``: geometric panels from ``theta_ul`` (``C``, ``K`` are analytic there
  with their nearest singularity at ``theta = 0``, one panel length away);
* softening beds: the panel ``[3/4 theta_cap, theta_cap]`` in ``s = sqrt(theta_cap - theta)``
  (``dz/da ~ (theta_cap - a)^(-1/2)`` becomes analytic in ``s``), and geometric panels above
  ``theta_cap``.

``C``, ``K`` are evaluated once per point; each ``sigma`` only reweights, its nodes up to
``SIGMA_SPAN sigma`` one by one and those below ``0.1 sigma`` through prefix moments.

Table: ``t = ln(sigma / theta_ul)`` on ``[T_LO, t_hi]`` with :data:`STEPS_PER_UNIT` nodes per
unit, values and their exact ``t``-derivatives (same quadrature)::

    d e_c / dt = E[(C - C0) (x^2 - 1)],   d e_k / dt = E[(K - K0) x^2 (x^2 - 3)],
    d d_c / dt = E[(C - C0) (x^4 - 6 x^2 + 3)] / sigma^2

read back by cubic Hermite interpolation, stored as per-interval cubic coefficients
(:func:`coefficient_table`, :func:`table_lookup`; largest error against the direct quadrature
3e-7 of ``k_eq``, 3e-9 of ``c_eq`` for the test beds; ~1200 nodes for the paper's block).  Below ``T_LO``
(``sigma < 6e-6 theta_ul``) ``e_c``, ``e_k`` follow ``f0 + (f(T_LO) - f0) (sigma/sigma_lo)^2`` and
``d_c`` is held (relative errors ``O(sigma^2)`` on terms that are themselves ``O(sigma^2)``);
above ``t_hi`` (4 x the slenderness angle, where the moment solver has long stopped the
point) the last values are held.

The moment solver reads the same interpolant without a logarithm (:func:`octave_table`,
:func:`octave_lookup_jit`): in ``q = (sigma / theta_ul)^2 = var_theta / theta_ul^2`` on an octave
grid of :data:`BUCKET_BITS` bits (:func:`screening.core.interpolation.octave_grid`; the bucket of
``q`` and the fraction in it come from the bits of ``q``), each bucket holds at most one node of
the ``t`` grid, and each of its two pieces is the interpolant re-expressed as a polynomial of
degree :data:`FIT_DEGREE` in the bucket fraction (Chebyshev-Lobatto interpolation: within 1e-13 of
``K(0)`` of the cubic in ``t``, the rounding of its logarithm).
A table costs ~3-4 ms per distinct point (the sums, ``C``, ``K`` at the nodes, the octave form), and a process keeps its :data:`TABLE_CACHE_SIZE` most recent ones, so a point met again (the
next chunk of a batch, the next call) does not rebuild its table.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict

import numba
import numpy as np

from screening.core.interpolation import cubic, cubic_coefficients, octave_first, octave_grid, octave_position_jit
from screening.core.signatures import FMA, MomentKernel, moment_coefficients_signature
from screening.core.model.points import flatten, point_key, select, numeric_fields

__all__ = []

#: Table grid in t = ln(sigma_theta / theta_ul).
T_LO = -12.0
STEPS_PER_UNIT = 64
#: Gauss–Legendre nodes per panel and number of geometric panels below theta_ul.
GAUSS_ORDER = 16
J_INNER = 22
#: The Gaussian weight is below 1e-31 of its peak beyond 12 sigma.
SIGMA_SPAN = 12.0
#: The solver's form of a table: buckets of an octave grid in q = (sigma / theta_ul)^2 from 2^Q_OCTAVE_LO
#: (below exp(2 T_LO)), BUCKET_BITS mantissa bits (a bucket is at most 2^-5 = 3.1 % of q wide, less than the
#: t grid's 3.2 %: at most one node per bucket), a polynomial of degree FIT_DEGREE per piece.
Q_OCTAVE_LO = -35
BUCKET_BITS = 5
FIT_DEGREE = 5
_FIRST = octave_first(Q_OCTAVE_LO, BUCKET_BITS)
_Q_LO = math.exp(2.0 * T_LO)
#: Tables a process keeps (the most recently used; ~0.6 MB each for the paper's block).
TABLE_CACHE_SIZE = 8

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
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] P. J. Davis and P. Rabinowitz, Methods of Numerical Integration, 2nd ed., Academic Press
       (1984), ch. 2 (Gauss-Legendre rules).
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
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [stein1981] in the bibliography, ``docs/bibliography.md``.
    """
    sigma = np.asarray(sigma, dtype=float).reshape(-1)
    theta = np.asarray(theta, dtype=float)
    order = np.argsort(theta, kind="stable")            # ascending: each sigma sums a leading run of nodes
    values = np.empty((sigma.size, 3))
    slopes = np.empty((sigma.size, 3))
    _expectation_sums_jit(sigma, theta[order], np.asarray(weight, dtype=float)[order],
                          np.asarray(c_values, dtype=float)[order], np.asarray(k_values, dtype=float)[order],
                          float(c0), float(k0), values, slopes)
    return values, slopes


#: Nodes beyond x^2 = (theta / sigma)^2 = SIGMA_SPAN^2 are left out of a sigma's sums: their Gaussian weight
#: exp(-x^2 / 2) is below 6e-32 of its peak, and below 2e-27 after the factor x^4 of the slopes.
_X2_CUT = SIGMA_SPAN ** 2
#: Nodes with x^2 <= _X2_SERIES enter a sigma's sums through their moments (prefix sums of ``w f theta^(2r)``),
#: with exp(-x^2 / 2) by its Taylor series to the power _SERIES_TERMS: remainder below 2e-17 of each term.
_X2_SERIES = 0.01
_SERIES_TERMS = 5


@numba.njit(cache=True, inline="always")
def _first_beyond(theta, s, x2):
    """The first index of ascending ``theta`` with ``(theta / s)^2 > x2`` (or NaN), by bisection."""
    lo, hi = 0, theta.size
    while lo < hi:
        mid = (lo + hi) // 2
        if (theta[mid] / s) ** 2 <= x2:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True)
def _expectation_sums_jit(sigma, theta, weight, c_values, k_values, c0, k0, values, slopes):
    """Compiled loop of :func:`gaussian_expectations` on nodes in ascending ``theta``: fills ``values`` and
    ``slopes`` in place.  A row sums its nodes with ``_X2_SERIES < x^2 <= _X2_CUT`` one by one and those below
    through prefix moments (a row's bits depend on its ``sigma`` alone)."""
    scale = 2.0 * _INV_SQRT_2PI
    n = theta.size
    powers = _SERIES_TERMS + 3
    q_norm = theta[n - 1] ** 2 if n > 0 else 1.0
    # prefix moments of w F q^r, q = theta^2 / q_norm, F = C, K, C - C0, K - K0 (columns 0-3)
    moments = np.zeros((n + 1, 4, powers))
    for j in range(n):
        q = theta[j] ** 2 / q_norm
        f0, f1, f2, f3 = weight[j] * c_values[j], weight[j] * k_values[j], weight[j] * (c_values[j] - c0), \
            weight[j] * (k_values[j] - k0)
        qr = 1.0
        for r in range(powers):
            moments[j + 1, 0, r] = moments[j, 0, r] + f0 * qr
            moments[j + 1, 1, r] = moments[j, 1, r] + f1 * qr
            moments[j + 1, 2, r] = moments[j, 2, r] + f2 * qr
            moments[j + 1, 3, r] = moments[j, 3, r] + f3 * qr
            qr *= q
    for i in range(sigma.size):
        s = sigma[i]
        hi = _first_beyond(theta, s, _X2_CUT)
        lo = _first_beyond(theta, s, _X2_SERIES)
        e_c = e_k = he2 = s_k = s_d = 0.0
        if lo > 0:              # sum_l w F q^p exp(-z q / 2) = sum_m (-z / 2)^m / m! z^m M_F[p + m], x^2 = z q
            z = q_norm / (s * s)
            sc0 = sk1 = sd0 = sd1 = sd2 = sq1 = sq2 = 0.0
            a = 1.0
            for m in range(_SERIES_TERMS + 1):
                sc0 += a * moments[lo, 0, m]
                sk1 += a * moments[lo, 1, m + 1]
                sd0 += a * moments[lo, 2, m]
                sd1 += a * moments[lo, 2, m + 1]
                sd2 += a * moments[lo, 2, m + 2]
                sq1 += a * moments[lo, 3, m + 1]
                sq2 += a * moments[lo, 3, m + 2]
                a *= -0.5 * z / (m + 1)
            f = scale / s
            e_c = f * sc0
            e_k = f * z * sk1
            he2 = f * (z * sd1 - sd0)
            s_k = f * z * (z * sq2 - 3.0 * sq1)
            s_d = f * (z * (z * sd2 - 6.0 * sd1) + 3.0 * sd0)
        for j in range(lo, hi):
            x2 = (theta[j] / s) ** 2
            phi = scale * weight[j] * math.exp(-0.5 * x2) / s
            dc = c_values[j] - c0
            phi_x2 = phi * x2
            e_c += phi * c_values[j]
            e_k += phi_x2 * k_values[j]
            he2 += phi * (x2 - 1.0) * dc
            s_k += phi_x2 * (x2 - 3.0) * (k_values[j] - k0)
            s_d += phi * (x2 * (x2 - 6.0) + 3.0) * dc
        if hi < n and not (theta[n - 1] / s) ** 2 < math.inf:          # a float-range scale: NaN, as the
            e_c = e_k = he2 = s_k = s_d = math.nan                        # point must
        inv_s2 = 1.0 / (s * s)
        values[i, 0] = e_c
        values[i, 1] = e_k
        values[i, 2] = he2 * inv_s2
        slopes[i, 0] = he2
        slopes[i, 1] = s_k
        slopes[i, 2] = s_d * inv_s2


def _point_nodes(block, foundation, sigma_max, cond, tu=None):
    """Nodes, weights, ``C``, ``K`` at the nodes and ``C(0)``, ``K(0)`` for one (scalar) point (``tu``: its
    ``theta_ul`` [rad], if known)."""
    tu = float(cond.uplift_threshold(block, foundation)) if tu is None else tu
    cap = float(cond.capacity_angle(block, foundation))
    theta, weight = theta_quadrature(tu, cap, SIGMA_SPAN * sigma_max)
    c = cond.rocking_damping(theta, block, foundation)
    k = cond.rocking_stiffness(theta, block, foundation)
    return theta, weight, c, k, float(cond.damping_at_rest(block, foundation)), \
        float(cond.stiffness_at_rest(block, foundation))


def expectations(sigma_theta, block, foundation, cond):
    """``(e_c, e_k, d_c)`` [SI, module docstring] at ``sigma_theta`` [rad] >= 0 for one scalar point.

    Direct quadrature (no table); below ``sigma_lo = theta_ul exp(T_LO)`` the same ``sigma^2``
    extrapolation as the table, exact limits at ``sigma = 0``.

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.core.condensation.Condensation
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

    """
    s = np.asarray(sigma_theta, dtype=float)
    tu = float(cond.uplift_threshold(block, foundation))
    s_lo = tu * math.exp(T_LO)
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
    """Number of table nodes, from ``T_LO`` up to ``t_hi = ln(4 atan(b/h) / theta_ul)`` (at least 2).

    Vectorised over array model parameters (one size per point).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``b``, ``h`` [m]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed; fields may be arrays.
    cond : screening.core.condensation.Condensation
        The condensation (its ``uplift_threshold``).

    Returns
    -------
    int or numpy.ndarray of int
        ``ceil((t_hi - T_LO) STEPS_PER_UNIT) + 1`` nodes [-], with
        ``t_hi = max(ln(4 atan(b/h) / theta_ul), 2)``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".
    """
    return _size(block.slenderness, cond.uplift_threshold(block, foundation))


def _size(slenderness, tu):
    """:func:`table_size` from the slenderness angle and ``theta_ul`` [rad]."""
    t_hi = np.maximum(np.log(4.0 * slenderness / tu), 2.0)
    return (np.ceil((t_hi - T_LO) * STEPS_PER_UNIT).astype(int) + 1)[()]


def node_values(block, foundation, cond):
    """``(values, slopes)`` of shape ``(table_size, 3)`` for one scalar point (module docstring).

    Nodes at ``t = T_LO + i / STEPS_PER_UNIT``; depends on the point alone.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.core.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    values : numpy.ndarray
        ``(table_size, 3)``: ``e_c`` [N m s/rad], ``e_k`` [N m/rad], ``d_c`` [N m s/rad^3] at
        ``sigma = theta_ul exp(t)``.
    slopes : numpy.ndarray
        ``(table_size, 3)``: their derivatives with respect to ``t`` (same units).

    Notes
    -----
    :func:`gaussian_expectations` at the table's ``sigma`` values, one node set for all of them.

    """
    return _node_values(block, foundation, cond)[:2]


def _node_values(block, foundation, cond):
    """``(values, slopes, theta_ul, C(0), K(0))`` of one scalar point (:func:`node_values`)."""
    tu = float(cond.uplift_threshold(block, foundation))
    n = int(_size(block.slenderness, tu))
    t = T_LO + np.arange(n) / STEPS_PER_UNIT
    sigma = tu * np.exp(t)
    theta, weight, c, k, c0, k0 = _point_nodes(block, foundation, float(sigma[-1]), cond, tu)
    return (*gaussian_expectations(sigma, theta, weight, c, k, c0, k0), tu, c0, k0)


def coefficient_table(block, foundation, cond):
    """One scalar point's table: per-interval cubic coefficients ``(table_size, 12)`` of
    :func:`node_values` (:func:`screening.core.interpolation.cubic_coefficients`).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    cond : screening.core.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    numpy.ndarray
        ``(table_size, 12)``: for each interval of ``t``, the four cubic Hermite coefficients of
        ``e_c`` (columns 0-3, [N m s/rad]), ``e_k`` (4-7, [N m/rad]) and ``d_c`` (8-11,
        [N m s/rad^3]); columns 0, 4, 8 hold the node values.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. IV (piecewise cubic Hermite
       interpolation).
    """
    values, slopes = node_values(block, foundation, cond)
    return cubic_coefficients(values, slopes, 1.0 / STEPS_PER_UNIT)


def coefficient_tables(block, foundation, cond):
    """Tables of the points of flat (1-d) model fields: ``(tables, index)``.

    ``tables``: ``(n_distinct, max size, 12)``, one :func:`coefficient_table` per distinct point,
    zero-padded to the longest (the padding is never read: :func:`table_lookup_grid` gets each
    point's :func:`table_size`); ``index[i]`` is point i's table.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); flat (1-d) fields, one entry per point.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); flat (1-d) fields, one entry per point.
    cond : screening.core.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    tables : numpy.ndarray
        ``(n_distinct, max table_size, 12)`` (units of :func:`coefficient_table`).
    index : numpy.ndarray of int64
        Point ``i``'s table is ``tables[index[i]]``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".
    """
    first, index = _distinct_points(block, foundation)
    return _stacked([coefficient_table(select(block, int(i)), select(foundation, int(i)), cond) for i in first]), index


def _stacked(tables):
    """Tables zero-padded to the longest and stacked (the padding is never read)."""
    size = max(tb.shape[0] for tb in tables)
    out = np.zeros((len(tables), size, tables[0].shape[1]))
    for j, tb in enumerate(tables):
        out[j, :tb.shape[0]] = tb
    return out


def _distinct_points(block, foundation):
    """``(first, index)`` of flat model fields: the first point of each distinct parameter point (equal
    numeric fields, as :func:`screening.core.model.points.point_key` compares them), in order of appearance,
    and each point's distinct point (one ``numpy.unique`` over the points, not a key per point)."""
    n = np.size(block.m)
    columns = [np.broadcast_to(np.asarray(value, dtype=float).reshape(-1), (n,))
               for obj in (block, foundation) for value in numeric_fields(obj).values()]
    _, first, inverse = np.unique(np.stack(columns, axis=1), axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order], rank[inverse.reshape(-1)].astype(np.int64)


_LOBATTO = 0.5 - 0.5 * np.cos(np.pi * np.arange(FIT_DEGREE + 1) / FIT_DEGREE)
_TO_POWERS = np.linalg.inv(np.vander(_LOBATTO, FIT_DEGREE + 1, increasing=True))


@numba.njit(cache=True, inline="always")
def _interpolant_jit(q, table, c0, k0, out):
    """:func:`table_lookup` at ``q = (sigma / theta_ul)^2 > 0`` into ``out`` (``e_c``, ``e_k``, ``d_c``)."""
    t = 0.5 * math.log(q)
    n = table.shape[0]
    if t <= T_LO:
        f = math.exp(2.0 * (t - T_LO))
        out[0] = c0 + (table[0, 0] - c0) * f
        out[1] = k0 + (table[0, 4] - k0) * f
        out[2] = table[0, 8]
        return
    u = (t - T_LO) * STEPS_PER_UNIT
    if u >= n - 1:
        for column in range(3):
            out[column] = table[n - 1, 4 * column]
        return
    i = int(min(math.floor(u), n - 2.0))
    s = u - i
    for column in range(3):
        out[column] = cubic(table, i, column, s)


@numba.njit(cache=True)
def _octave_rows_jit(table, c0, k0, lo, hi, node, split, rows):
    """Fills the rows of :func:`octave_table` from the buckets ``[lo, hi)``, their nodes and splits."""
    values = np.empty((FIT_DEGREE + 1, 3))
    for b in range(lo.size):
        for piece in range(2):
            a, e = (0.0, split[b]) if piece == 0 else (split[b], 1.0)
            width = e - a if e > a else 1.0
            r = 2 * b + piece
            rows[r, 0] = node[b]
            rows[r, 1] = 1.0 / width
            rows[r, 2] = -a / width
            for j in range(FIT_DEGREE + 1):
                _interpolant_jit(lo[b] + (a + _LOBATTO[j] * width) * (hi[b] - lo[b]), table, c0, k0, values[j])
            for column in range(3):
                for i in range(FIT_DEGREE + 1):
                    acc = 0.0
                    for j in range(FIT_DEGREE + 1):
                        acc += _TO_POWERS[i, j] * values[j, column]
                    rows[r, 3 + (FIT_DEGREE + 1) * column + i] = acc


def octave_table(table, c0, k0):
    """The solver's form of a :func:`coefficient_table`: its interpolant on the octave buckets of ``q``.

    Parameters
    ----------
    table : numpy.ndarray
        One point's :func:`coefficient_table` (on the grid ``t = T_LO + i / STEPS_PER_UNIT``).
    c0 : float
        ``C(0)`` [N m s/rad].
    k0 : float
        ``K(0)`` [N m/rad].

    Returns
    -------
    numpy.ndarray
        ``(2 n_buckets, 3 + 3 (FIT_DEGREE + 1))``: rows ``2 j`` and ``2 j + 1`` are the two pieces of
        bucket ``j`` of ``q = (sigma / theta_ul)^2`` (:func:`screening.core.interpolation.octave_grid`
        from ``2^Q_OCTAVE_LO``, :data:`BUCKET_BITS` bits), split at the grid node inside it (if any).  Each
        row holds that node's ``q`` (``inf`` if none), ``A``, ``B`` with ``y = A s + B`` in ``[0, 1]`` over
        the piece (``s`` the fraction of the bucket), and the coefficients of ``e_c`` [N m s/rad],
        ``e_k`` [N m/rad] and ``d_c`` [N m s/rad^3] in powers of ``y``.

    Notes
    -----
    Within a piece the interpolant of :func:`table_lookup` (a cubic in ``t = ln(q) / 2``, or the
    extrapolation below the grid) is analytic in ``q``; its interpolation at the :data:`FIT_DEGREE` + 1
    Chebyshev-Lobatto points of the piece [1]_ reproduces it within 1e-13 of ``K(0)`` (the rounding of its
    logarithm), and :func:`octave_lookup_jit` finds the piece from the bits of ``q``, without a logarithm.

    References
    ----------
    .. [1] L. N. Trefethen, Approximation Theory and Approximation Practice, SIAM (2013), ch. 8
       (convergence for analytic functions).
    """
    n = table.shape[0]
    q_nodes = np.exp(2.0 * (T_LO + np.arange(n) / STEPS_PER_UNIT))
    edges = octave_grid(Q_OCTAVE_LO, int(math.ceil(math.log2(q_nodes[-1]))), BUCKET_BITS)
    lo, hi = edges[:-1], edges[1:]
    k = np.minimum(np.searchsorted(q_nodes, lo), n - 1)           # the first node at or above each bucket
    inside = q_nodes[k] < hi
    node = np.where(inside, q_nodes[k], np.inf)
    split = np.where(inside, (node - lo) / (hi - lo), 1.0)
    rows = np.empty((2 * lo.size, 3 + 3 * (FIT_DEGREE + 1)))
    _octave_rows_jit(np.ascontiguousarray(table, dtype=float), float(c0), float(k0), lo, hi, node, split, rows)
    return rows


@numba.njit(cache=True, inline="always")
def _piece(table, r, column, y):
    """Column ``column`` (0 ``e_c``, 1 ``e_k``, 2 ``d_c``) of row ``r`` of an :func:`octave_table` at ``y``."""
    c = 3 + (FIT_DEGREE + 1) * column
    return table[r, c] + y * (table[r, c + 1] + y * (table[r, c + 2] + y * (table[r, c + 3] + y * (
        table[r, c + 4] + y * table[r, c + 5]))))


@numba.njit(cache=True, inline="always")
def octave_lookup_jit(q, table, c0, k0, lo_c, lo_k, lo_d, hi_c, hi_k, hi_d, buckets):
    """Compiled :func:`table_lookup` at ``q = (sigma_theta / theta_ul)^2`` from an :func:`octave_table`.

    Parameters
    ----------
    q : float
        ``(sigma_theta / theta_ul)^2`` [-]; any ``q <= 0`` (and NaN) gives the values at rest.
    table : numpy.ndarray
        The point's :func:`octave_table` (possibly zero-padded: rows beyond ``2 buckets`` are never read).
    c0 : float
        ``C(0)`` [N m s/rad].
    k0 : float
        ``K(0)`` [N m/rad].
    lo_c, lo_k, lo_d : float
        ``e_c``, ``e_k``, ``d_c`` at the first node of the :func:`coefficient_table` (``t = T_LO``) [SI].
    hi_c, hi_k, hi_d : float
        The same at its last node, held beyond [SI].
    buckets : int
        The table's number of buckets [-].

    Returns
    -------
    tuple of float
        ``(e_c [N m s/rad], e_k [N m/rad], d_c [N m s/rad^3])``.

    Notes
    -----
    The bucket and the fraction ``s`` in it from the bits of ``q``
    (:func:`screening.core.interpolation.octave_position_jit`), the piece by one comparison with the
    node in the bucket, then a polynomial of degree :data:`FIT_DEGREE` in ``y = A s + B``: the cubic
    Hermite interpolant [1]_ of :func:`table_lookup` without its logarithm.  Below ``2^Q_OCTAVE_LO`` the
    extrapolation ``f0 + (f(T_LO) - f0) q / exp(2 T_LO)``.

    References
    ----------
    .. [1] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. IV (piecewise cubic Hermite
       interpolation).
    """
    j, s = octave_position_jit(q, _FIRST, BUCKET_BITS)
    if j < 0:
        f = q * (1.0 / _Q_LO) if q > 0.0 else 0.0      # (sigma / sigma_lo)^2
        return c0 + (lo_c - c0) * f, k0 + (lo_k - k0) * f, lo_d
    if j >= buckets:
        return hi_c, hi_k, hi_d
    r = 2 * j + (1 if q >= table[2 * j, 0] else 0)
    y = s * table[r, 1] + table[r, 2]
    return _piece(table, r, 0, y), _piece(table, r, 1, y), _piece(table, r, 2, y)


_TABLES = OrderedDict()
_TABLES_LOCK = threading.Lock()


def _solver_table(block, foundation, cond):
    """``(octave table, its RECORD)`` of one scalar point, from the process's cache of recent tables
    (read-only)."""
    key = (cond, point_key(block, foundation))
    with _TABLES_LOCK:
        entry = _TABLES.get(key)
        if entry is not None:
            _TABLES.move_to_end(key)
            return entry
    values, slopes, tu, c0, k0 = _node_values(block, foundation, cond)
    table = cubic_coefficients(values, slopes, 1.0 / STEPS_PER_UNIT)
    solver_table = octave_table(table, c0, k0)
    solver_table.flags.writeable = False
    record = np.empty(1, dtype=RECORD)
    record[0] = (1.0 / tu ** 2, c0, k0, *table[0, 0::4][:3], *table[-1, 0::4][:3], solver_table.shape[0] // 2)
    record.flags.writeable = False
    entry = (solver_table, record)
    with _TABLES_LOCK:
        _TABLES[key] = entry
        while len(_TABLES) > TABLE_CACHE_SIZE:
            _TABLES.popitem(last=False)
    return entry


#: Per-point parameters of :func:`equivalent_coefficients_jit` (SI units): ``1 / theta_ul^2``, ``C(0)``,
#: ``K(0)``, the table's first and last node values and its number of buckets.
RECORD = np.dtype([("inv_theta_ul2", "f8"), ("c_rest", "f8"), ("k_rest", "f8"), ("lo_c", "f8"), ("lo_k", "f8"),
                   ("lo_d", "f8"), ("hi_c", "f8"), ("hi_k", "f8"), ("hi_d", "f8"), ("buckets", "i8")])


def moment_kernel(block, foundation, cond):
    """:class:`~screening.core.condensation.base.MomentKernel` of ``cond`` for flat (1-d) model fields.

    The default moment kernel of a condensation without closed forms: the compiled
    :func:`equivalent_coefficients_jit`, one :data:`RECORD` per point and the :func:`octave_table` of each
    distinct point (kept by the process for the next call).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); flat (1-d) fields, one entry per point.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); flat (1-d) fields, one entry per point.
    cond : screening.core.condensation.Condensation
        The condensation whose ``C(theta)``, ``K(theta)`` are averaged (``get("cubic")``).

    Returns
    -------
    screening.core.signatures.MomentKernel
        ``(coefficients, records, tables, table_index)``: records in SI units (:data:`RECORD`).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "Method", docs/method.md, section "Quadrature tables".
    """
    first, index = _distinct_points(block, foundation)
    entries = [_solver_table(select(block, int(i)), select(foundation, int(i)), cond) for i in first]
    records = np.concatenate([e[1] for e in entries])
    return MomentKernel(equivalent_coefficients_jit, records[index], _stacked([e[0] for e in entries]), index)


def table_lookup(t, table, c0, k0):
    """``(e_c, e_k, d_c)`` at ``t = ln(sigma_theta / theta_ul)`` (``-inf`` allowed) from one point's table.

    ``c0``, ``k0``: ``C(0)`` [N m s/rad], ``K(0)`` [N m/rad], the limits at ``sigma = 0``.
    Python entry point of :func:`table_lookup_grid` on the grid of this module.

    Parameters
    ----------
    t : float
        ``ln(sigma_theta / theta_ul)`` [-]; ``-inf`` for ``sigma_theta = 0``.
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
    Cubic Hermite interpolation [2]_ of the node values and ``t``-slopes; below ``T_LO``,
    ``f0 + (f(T_LO) - f0) (sigma / sigma_lo)^2`` for ``e_c``, ``e_k`` and ``d_c`` held; above the
    last node its values held.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. IV (piecewise cubic Hermite
       interpolation).
    """
    return table_lookup_grid(t, table, c0, k0, T_LO, float(STEPS_PER_UNIT), table.shape[0])


@numba.njit(cache=True, inline="always")
def table_lookup_grid(t, table, c0, k0, t_lo, steps_per_unit, n):
    """Compiled :func:`table_lookup` on the grid ``t_lo + i / steps_per_unit`` of ``n`` nodes.

    The grid is passed at run time (not read from module constants) so that compiled
    callers cached by numba can never disagree with the tables built in Python; rows of
    ``table`` beyond ``n`` (padding of stacked tables) are never read.

    Parameters
    ----------
    t : float
        ``ln(sigma_theta / theta_ul)`` [-]; ``-inf`` for ``sigma_theta = 0``.
    table : numpy.ndarray
        One point's :func:`coefficient_table` (possibly zero-padded).
    c0 : float
        ``C(0)`` [N m s/rad].
    k0 : float
        ``K(0)`` [N m/rad].
    t_lo : float
        ``t`` of the first node [-] (:data:`T_LO`).
    steps_per_unit : float
        Nodes per unit of ``t`` [-] (:data:`STEPS_PER_UNIT`).
    n : float or int
        The point's number of nodes [-] (:func:`table_size`).

    Returns
    -------
    tuple of float
        ``(e_c [N m s/rad], e_k [N m/rad], d_c [N m s/rad^3])``.

    Notes
    -----
    With ``u = (t - t_lo) steps_per_unit``, ``i = floor(u)``, ``s = u - i``, each quantity is the
    cubic ``a0 + a1 s + a2 s^2 + a3 s^3`` of row ``i`` (cubic Hermite interpolation [2]_); below
    ``t_lo``, ``f0 + (f(t_lo) - f0) exp(2 (t - t_lo))`` for ``e_c``, ``e_k`` and ``d_c`` held.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] C. de Boor, A Practical Guide to Splines, Springer (1978), ch. IV (piecewise cubic Hermite
       interpolation).
    """
    n = int(n)
    if t <= t_lo:
        f = math.exp(2.0 * (t - t_lo))                 # (sigma / sigma_lo)^2
        return c0 + (table[0, 0] - c0) * f, k0 + (table[0, 4] - k0) * f, table[0, 8]
    u = (t - t_lo) * steps_per_unit
    if u >= n - 1:
        return table[n - 1, 0], table[n - 1, 4], table[n - 1, 8]   # the last node, held
    i = int(u)
    s = u - i
    return cubic(table, i, 0, s), cubic(table, i, 1, s), cubic(table, i, 2, s)


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
    read from the :func:`octave_table` by :func:`octave_lookup_jit` at ``q = var_theta / theta_ul^2`` (the
    interpolant of :func:`table_lookup`, without a logarithm).

    """
    e_c, e_k, d_c = octave_lookup_jit(var_theta * p.inv_theta_ul2, table, p.c_rest, p.k_rest, p.lo_c, p.lo_k,
                                      p.lo_d, p.hi_c, p.hi_k, p.hi_d, p.buckets)
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
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.
    cond : screening.core.condensation.Condensation
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
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [stein1981] in the bibliography, ``docs/bibliography.md``.
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
