"""Equivalent linear coefficients of any condensation by Gaussian quadrature, tabulated per point.

A condensation without closed-form Gaussian expectations of ``C(theta)``, ``K(theta)`` (``"cubic"``, or one
registered from outside) gets the coefficients of eq. (31) of [mitseas2026] here: by Stein's lemma
[stein1981] ``c_eq = e_c`` and ``k_eq = e_k + cov d_c`` with three functions of ``sigma = sigma_theta``
alone (``x = theta / sigma``, ``C0 = C(0)``)::

    e_c = E[C]  [N m s/rad],   e_k = E[K x^2]  [N m/rad],   d_c = E[(C - C0) (x^2 - 1)] / sigma^2  [N m s/rad^3]

computed by Gauss–Legendre quadrature on geometric panels about ``theta_ul`` (and ``theta_cap``), tabulated
per point in ``t = ln(sigma / theta_ul)`` with exact ``t``-slopes and read back by cubic Hermite
interpolation; the moment solver reads the same interpolant on octave buckets of
``q = var_theta / theta_ul^2`` without a logarithm.  A process keeps its :data:`TABLE_CACHE_SIZE` most
recent tables.  The panels, the table, its accuracy and cost: ``docs/method.md#quadrature-tables``.
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
    """Nodes ``theta`` [rad] on ``(0, theta_top]`` and weights [rad] for Gaussian expectations.

    Notes
    -----
    :data:`GAUSS_ORDER`-point Gauss-Legendre rules [davis1984] on geometric panels below and above the uplift
    threshold ``theta_ul`` [rad] (``theta_top`` raised to ``2 theta_ul``), so that every ``sigma`` between
    ``2^-J_INNER theta_ul`` and ``theta_top / SIGMA_SPAN`` finds panels of its own size; below the capacity
    angle ``theta_cap`` [rad] (``inf``: none) ``theta = theta_cap - s^2`` removes the square-root singularity
    of ``dz/dtheta``.  ``E[f] = 2 sum(weight f(theta) phi_sigma(theta))`` for even ``f``.
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
    """``(values, slopes)``, each ``(len(sigma), 3)``: ``(e_c, e_k, d_c)`` (module docstring) and their d/d ln(sigma).

    Notes
    -----
    ``sigma`` [rad] > 0; ``theta``, ``weight`` of :func:`theta_quadrature`; ``c_values``, ``k_values``:
    ``C``, ``K`` at the nodes; ``c0``, ``k0``: ``C(0)``, ``K(0)``.  The slopes::

        d e_c / d ln(sigma) = E[(C - C0) (x^2 - 1)]
        d e_k / d ln(sigma) = E[(K - K0) x^2 (x^2 - 3)]
        d d_c / d ln(sigma) = E[(C - C0) (x^4 - 6 x^2 + 3)] / sigma^2
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
    """``(e_c, e_k, d_c)`` [SI, module docstring] at ``sigma_theta`` [rad] >= 0 by direct quadrature (no table) (``block``, ``foundation``: one scalar point; ``cond`` the condensation whose ``C``, ``K`` are averaged).

    Notes
    -----
    Below ``sigma_lo = theta_ul exp(T_LO)`` the same ``sigma^2`` extrapolation as the table; exact limits at
    ``sigma = 0``.
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
    """Number of table nodes per point: ``ceil((t_hi - T_LO) STEPS_PER_UNIT) + 1``, ``t_hi = max(ln(4 atan(b/h) / theta_ul), 2)``."""
    return _size(block.slenderness, cond.uplift_threshold(block, foundation))


def _size(slenderness, tu):
    """:func:`table_size` from the slenderness angle and ``theta_ul`` [rad]."""
    t_hi = np.maximum(np.log(4.0 * slenderness / tu), 2.0)
    return (np.ceil((t_hi - T_LO) * STEPS_PER_UNIT).astype(int) + 1)[()]


def node_values(block, foundation, cond):
    """``(values, slopes)``, each ``(table_size, 3)``, at ``t = T_LO + i / STEPS_PER_UNIT`` (``block``, ``foundation``: one scalar point; ``cond`` the condensation whose ``C``, ``K`` are averaged)."""
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
    """One scalar point's table ``(table_size, 12)``: per-interval cubic Hermite coefficients of :func:`node_values`.

    Notes
    -----
    Four coefficients [deboor1978] each of ``e_c`` (columns 0-3), ``e_k`` (4-7) and ``d_c`` (8-11); columns
    0, 4, 8 hold the node values (:func:`screening.core.interpolation.cubic_coefficients`).
    """
    values, slopes = node_values(block, foundation, cond)
    return cubic_coefficients(values, slopes, 1.0 / STEPS_PER_UNIT)


def coefficient_tables(block, foundation, cond):
    """``(tables, index)`` of flat model fields: one :func:`coefficient_table` per distinct point, zero-padded to the longest; point ``i``'s is ``tables[index[i]]``."""
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

    Notes
    -----
    ``(2 n_buckets, 3 + 3 (FIT_DEGREE + 1))``: rows ``2 j``, ``2 j + 1`` are the two pieces of bucket ``j`` of
    ``q = (sigma / theta_ul)^2`` (:func:`screening.core.interpolation.octave_grid`), split at the grid node
    inside it.  A row holds that node's ``q`` (``inf`` if none), ``A``, ``B`` with ``y = A s + B`` in
    ``[0, 1]`` (``s`` the bucket fraction) and the coefficients of ``e_c``, ``e_k``, ``d_c`` in powers of
    ``y``: the interpolant of :func:`table_lookup` at :data:`FIT_DEGREE` + 1 Chebyshev-Lobatto points of the
    piece [trefethen2013], within 1e-13 of ``K(0)``.
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
    """Compiled :func:`table_lookup` at ``q = (sigma_theta / theta_ul)^2`` from an :func:`octave_table`: ``(e_c, e_k, d_c)``.

    Notes
    -----
    ``q <= 0`` (and NaN) gives ``c0``, ``k0`` and ``d_c`` at rest.  Bucket and fraction from the bits of ``q``
    (:func:`screening.core.interpolation.octave_position_jit`), the piece by one comparison, then a polynomial
    in ``y``; below ``2^Q_OCTAVE_LO``, ``f0 + (f(T_LO) - f0) q / exp(2 T_LO)`` from the first node's values
    ``lo_*``; above the last node, ``hi_*`` held.
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

    Notes
    -----
    The default moment kernel of a condensation without closed forms: :func:`equivalent_coefficients_jit`,
    one :data:`RECORD` per point [SI] and the :func:`octave_table` of each distinct point.
    """
    first, index = _distinct_points(block, foundation)
    entries = [_solver_table(select(block, int(i)), select(foundation, int(i)), cond) for i in first]
    records = np.concatenate([e[1] for e in entries])
    return MomentKernel(equivalent_coefficients_jit, records[index], _stacked([e[0] for e in entries]), index)


def table_lookup(t, table, c0, k0):
    """``(e_c, e_k, d_c)`` at ``t = ln(sigma_theta / theta_ul)`` (``-inf`` allowed) from one point's table.

    Notes
    -----
    :func:`table_lookup_grid` on this module's grid: cubic Hermite interpolation [deboor1978]; below ``T_LO``
    ``e_c``, ``e_k`` go as ``f0 + (f(T_LO) - f0) (sigma / sigma_lo)^2`` to ``c0 = C(0)``, ``k0 = K(0)`` and
    ``d_c`` is held; above the last node its values are held.
    """
    return table_lookup_grid(t, table, c0, k0, T_LO, float(STEPS_PER_UNIT), table.shape[0])


@numba.njit(cache=True, inline="always")
def table_lookup_grid(t, table, c0, k0, t_lo, steps_per_unit, n):
    """Compiled :func:`table_lookup` on the grid ``t_lo + i / steps_per_unit`` of ``n`` nodes.

    Notes
    -----
    The grid is passed at run time so that numba-cached callers cannot disagree with the tables built in
    Python; rows beyond ``n`` (padding) are never read.  With ``u = (t - t_lo) steps_per_unit``,
    ``i = floor(u)``, ``s = u - i``, each quantity is the cubic ``a0 + a1 s + a2 s^2 + a3 s^3`` of row ``i``.
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
    """Compiled twin of :func:`equivalent_coefficients` from ``var_theta`` [rad2] and ``cov`` [rad2/s], read by :func:`octave_lookup_jit`."""
    e_c, e_k, d_c = octave_lookup_jit(var_theta * p.inv_theta_ul2, table, p.c_rest, p.k_rest, p.lo_c, p.lo_k,
                                      p.lo_d, p.hi_c, p.hi_k, p.hi_d, p.buckets)
    return e_c, e_k + cov * d_c


def equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation, cond):
    """``(c_eq [N m s/rad], k_eq [N m/rad])`` of the condensation ``cond`` by quadrature.

    Notes
    -----
    ``c_eq = e_c``, ``k_eq = e_k + cov d_c`` (:func:`expectations`; eq. (31) of [mitseas2026] by Stein's
    lemma [stein1981]) from ``sigma_theta`` [rad] and ``cov_over_sigma = rho sigma_theta_dot`` [rad s-1],
    broadcast with array model fields (one quadrature per distinct point).
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
