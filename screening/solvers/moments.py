"""Lyapunov covariance propagation closed by stochastic linearization (paper, sections 2.5–2.6).

The moment equations ``dC/dt = P C + C P^T + D`` (eq. 45; eq. 51 with the Kanai–Tajimi
filter) have ``P`` built from ``c_eq`` and ``k_eq`` evaluated at the current moments, so
the whole system is one nonlinear ODE in the independent covariance entries: 3 for
modulated white noise (``var_theta, cov, var_theta_dot``), 10 for Kanai–Tajimi (the 4x4
symmetric covariance of ``theta, theta', u_g, u_g'``).  Only what the excitation needs is
integrated.

:func:`solve_moments` integrates a batch of parameter points in one compiled call:
an embedded Dormand–Prince 5(4) pair per point, with absolute tolerances scaled to the
linear stationary moments, dense output for the output grid, and the peak of
``var_theta`` located inside the step where ``cov`` changes sign.  A point whose ``k_eq``
turns negative, whose ``sigma_theta`` passes the slenderness angle, whose state is not
finite, or which exceeds the step budget stops there with a ``status`` code; the other
points of the batch are unaffected.

Condensation.  ``condensation="paper"`` (default) uses the closed forms of
:mod:`screening.condensation.paper_coefficients` through the universal table of :mod:`screening.condensation.paper_table`.
``condensation="cubic"`` (:mod:`screening.condensation.cubic`) has no closed form: each
distinct parameter point gets its own table of ``E[C]``, ``E[K x^2]`` and the
velocity-coupling term, built once by quadrature (:mod:`screening.condensation.quadrature`),
and the compiled solver reads it in place of the universal one (parameter ``I_COND``
selects the branch; the default path only pays that one comparison).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numba
import numpy as np

from screening.condensation import cubic as cubic_condensation, quadrature as cubic_linearization
from screening.condensation.paper import check_condensation, damping_inner, m_sdof, uplift_threshold
from screening.condensation.quadrature import table_lookup_grid
from screening.condensation.paper_table import coefficient_table, uplift_integrals_log

# ---------------------------------------------------------------- status codes
STATUS_OK = 0
STATUS_K_EQ_NEGATIVE = 1
STATUS_VARIANCE_UNBOUNDED = 2
STATUS_MAX_STEPS = 3
STATUS_NONFINITE = 4
STATUS_MEANINGS = {
    STATUS_OK: "ok",
    STATUS_K_EQ_NEGATIVE: "k_eq_negative",
    STATUS_VARIANCE_UNBOUNDED: "sigma_theta_beyond_slenderness",
    STATUS_MAX_STEPS: "step_budget_exhausted",
    STATUS_NONFINITE: "non_finite_moments",
}

# ---------------------------------------------------------------- parameter layout
(I_M, I_GAIN, I_TU, I_K0, I_MGH, I_E0, I_EPS, I_C1, I_DAMP, I_S0, I_WG, I_ZG,
 I_ENV, I_T1, I_T2, I_SIGMAX, I_LOG_TU, I_COND, I_K_REST, I_TAB_LO, I_TAB_RATE, I_TAB_N) = range(22)
N_PARAMS = 22

#: Value of ``params[:, I_COND]`` per condensation.
CONDENSATION_CODES = {"paper": 0.0, "cubic": 1.0}

#: Points per call of the compiled solver when per-point tables are built (``"cubic"``).
TABLE_CHUNK = 256

DEFAULT_RTOL = 1e-7
DEFAULT_MAX_STEPS = 200_000

#: Smallest absolute-tolerance scale [moment units]: below it the scale would underflow.
SCALE_FLOOR = 1e-300


def pack_parameters(block, foundation, excitation, condensation="paper"):
    """Broadcast the model objects to a ``(n_points, N_PARAMS)`` float array (SI units).

    Every field of ``block``, ``foundation`` and ``excitation`` may be an array; they are
    broadcast together and flattened.  Returns ``(params, shape)`` with the broadcast shape.
    With ``condensation="cubic"``, ``I_TU`` is the cubic threshold, ``I_C1`` is ``C(0)`` and
    ``I_E0`` is ``4 k b^3 z0^2`` so that ``K(0) = I_K0 - I_MGH + I_EPS I_E0 / 2`` still holds.
    """
    env = excitation.envelope
    kt = excitation.kind == "kanai_tajimi"
    cubic = check_condensation(condensation) == "cubic"
    if cubic:
        theta_ul = cubic_condensation.uplift_threshold(block, foundation)
        z0 = cubic_condensation.rest_indentation(block, foundation)
        e0 = 4.0 * foundation.k * block.b**3 * z0 * z0
        c_rest = cubic_condensation.damping_at_rest(block, foundation)
        k_rest = cubic_condensation.stiffness_at_rest(block, foundation)
        table_n = cubic_linearization.table_size(block, foundation)
    else:
        table_n = 0
        theta_ul = uplift_threshold(block, foundation)
        e0 = (block.m * block.g) ** 2 * block.b / foundation.k
        c_rest = damping_inner(block, foundation)
        k_rest = 2.0 / 3.0 * block.b**3 * foundation.k - block.m * block.g * block.h + 0.5 * foundation.eps * e0
    fields = {
        I_M: m_sdof(block),
        I_GAIN: block.m * block.h / m_sdof(block),
        I_TU: theta_ul,
        I_K0: 2.0 / 3.0 * block.b**3 * foundation.k,
        I_MGH: block.m * block.g * block.h,
        I_E0: e0,
        I_EPS: foundation.eps,
        I_C1: c_rest,
        I_DAMP: 0.0 if foundation.contact == "hunt_crossley" else 1.0,
        I_S0: excitation.S0,
        I_WG: excitation.omega_g if kt else 1.0,
        I_ZG: excitation.zeta_g if kt else 1.0,
        I_ENV: float(env.params[0]),
        I_T1: env.params[1],
        I_T2: env.params[2],
        I_SIGMAX: block.slenderness,
        I_LOG_TU: np.log(theta_ul),
        I_COND: CONDENSATION_CODES[condensation],
        I_K_REST: k_rest,
        I_TAB_LO: cubic_linearization.T_LO,                       # grid of the per-point tables
        I_TAB_RATE: float(cubic_linearization.STEPS_PER_UNIT),
        I_TAB_N: table_n,
    }
    arrays = np.broadcast_arrays(*[np.asarray(fields[i], dtype=float) for i in range(N_PARAMS)])
    shape = arrays[0].shape
    params = np.ascontiguousarray(np.stack([a.reshape(-1) for a in arrays], axis=1))
    return params, shape


# ---------------------------------------------------------------- compiled pieces
@numba.njit(cache=True, inline="always")
def _envelope(p, t):
    if p[I_ENV] == 1.0:
        return 1.0
    return 4.0 * (math.exp(-t / p[I_T1]) - math.exp(-t / p[I_T2]))


@numba.njit(cache=True, inline="always")
def _exp_minus(x):
    """``exp(-x)`` for ``0 <= x``; a 7-term series below 0.02 (error < 1e-16)."""
    if x < 0.02:
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x / 720.0)))))
    return math.exp(-x)


@numba.njit(cache=True)
def _stage_gains(p, t, h, gains):
    """``m h q(t + c_s h) / M`` at the 7 stage times of a Dormand–Prince step (2 exp per step)."""
    if p[I_ENV] == 1.0:
        for s in range(7):
            gains[s] = p[I_GAIN]
        return
    e1 = math.exp(-t / p[I_T1])
    e2 = math.exp(-t / p[I_T2])
    for s in range(7):
        c = _C7[s] * h
        gains[s] = p[I_GAIN] * 4.0 * (e1 * _exp_minus(c / p[I_T1]) - e2 * _exp_minus(c / p[I_T2]))


@numba.njit(cache=True, inline="always")
def _coefficients_tabulated(p, var_theta, cov, values, slopes):
    """``(c_eq, k_eq)`` from a per-point table (:mod:`screening.condensation.quadrature`):
    ``c_eq = E[C]``, ``k_eq = E[K x^2] + cov d_c``."""
    t = 0.5 * math.log(var_theta) - p[I_LOG_TU] if var_theta > 0.0 else -math.inf
    e_c, e_k, d_c = table_lookup_grid(t, values, slopes, p[I_C1], p[I_K_REST], p[I_TAB_LO], p[I_TAB_RATE],
                                      p[I_TAB_N])
    return e_c, e_k + cov * d_c


@numba.njit(cache=True, inline="always")
def _coefficients(p, var_theta, cov, values, slopes):
    """``(c_eq, k_eq)`` from the moments: the closed forms of :mod:`screening.condensation.paper_coefficients`.

    ``values``, ``slopes``: the universal table of :mod:`screening.condensation.paper_table` (``"paper"``), or
    the point's own table when ``p[I_COND] != 0`` (``"cubic"``).
    """
    if p[I_COND] != 0.0:
        return _coefficients_tabulated(p, var_theta, cov, values, slopes)
    if var_theta > 0.0:
        p_in, tail_m12, tail_m32, p32 = uplift_integrals_log(
            0.5 * math.log(var_theta) - p[I_LOG_TU], values, slopes)
    else:
        p_in, tail_m12, tail_m32, p32 = 1.0, 0.0, 0.0, 1.0
    r2 = var_theta / (p[I_TU] * p[I_TU])
    if p[I_DAMP] == 0.0:
        c_shape = tail_m12
        coupling = 0.5 * tail_m12
    else:
        c_shape = tail_m32
        coupling = 1.5 * tail_m32
    # D = C1 * coupling * cov / sigma^2, finite at sigma = 0 (coupling vanishes first)
    d_term = p[I_C1] * coupling * cov / var_theta if coupling > 0.0 else 0.0
    c_eq = p[I_C1] * (p_in + c_shape)
    k_eq = (p[I_K0] * (p_in + tail_m32) - p[I_MGH] - d_term
            + p[I_EPS] * p[I_E0] * (1.0 - 0.5 * p_in + 0.3 * r2 * p32 - 0.2 * tail_m12))
    return c_eq, k_eq


@numba.njit(cache=True, inline="always")
def _rhs(p, kt, alpha, y, dy, row, values, slopes):
    """Moment equations (45)/(51) into ``dy[row]``; returns ``(c_eq, k_eq)`` at ``y``.

    ``alpha = m h q(t) / M`` is the input gain at the stage time.
    """
    c_eq, k_eq = _coefficients(p, y[0], y[1], values, slopes)
    m = p[I_M]
    kap = k_eq / m
    gam = c_eq / m
    if not kt:
        dy[row, 0] = 2.0 * y[1]
        dy[row, 1] = y[2] - kap * y[0] - gam * y[1]
        dy[row, 2] = -2.0 * kap * y[1] - 2.0 * gam * y[2] + 2.0 * math.pi * p[I_S0] * alpha * alpha
        return c_eq, k_eq
    # 4x4 symmetric C stored as (00 01 02 03 11 12 13 22 23 33)
    wg = p[I_WG]
    zg = p[I_ZG]
    w2 = wg * wg
    b2 = alpha * w2
    b3 = 2.0 * alpha * zg * wg
    c00, c01, c02, c03, c11, c12, c13, c22, c23, c33 = (
        y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8], y[9])
    # A = Q C, rows of Q: [0 1 0 0], [-kap -gam -b2 -b3], [0 0 0 1], [0 0 -w2 -2 zg wg]
    a10 = -kap * c00 - gam * c01 - b2 * c02 - b3 * c03
    a11 = -kap * c01 - gam * c11 - b2 * c12 - b3 * c13
    a12 = -kap * c02 - gam * c12 - b2 * c22 - b3 * c23
    a13 = -kap * c03 - gam * c13 - b2 * c23 - b3 * c33
    two_zw = 2.0 * zg * wg
    a30 = -w2 * c02 - two_zw * c03
    a31 = -w2 * c12 - two_zw * c13
    a32 = -w2 * c22 - two_zw * c23
    a33 = -w2 * c23 - two_zw * c33
    # dC = A + A^T + D, rows 0 and 2 of A are rows 1 and 3 of C
    dy[row, 0] = 2.0 * c01
    dy[row, 1] = c11 + a10
    dy[row, 2] = c12 + c03
    dy[row, 3] = c13 + a30
    dy[row, 4] = 2.0 * a11
    dy[row, 5] = a12 + c13
    dy[row, 6] = a13 + a31
    dy[row, 7] = 2.0 * c23
    dy[row, 8] = c33 + a32
    dy[row, 9] = 2.0 * a33 + 2.0 * math.pi * p[I_S0]
    return c_eq, k_eq


# Dormand–Prince 5(4) tableau with its 4th-order dense output (Hairer; as in scipy's RK45)
_A = np.array([
    [0.0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
_C7 = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
_P = np.array([
    [1, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0, 0, 0, 0],
    [0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])


@numba.njit(cache=True, inline="always")
def _dense(y0, K, h, theta, j):
    """Component ``j`` of the dense-output polynomial at fraction ``theta`` of the step."""
    acc = 0.0
    for i in range(7):
        q = theta * (_P[i, 0] + theta * (_P[i, 1] + theta * (_P[i, 2] + theta * _P[i, 3])))
        acc += K[i, j] * q
    return y0[j] + h * acc


@numba.njit(cache=True)
def _linear_scales(p, kt, scale):
    """Diagonal moment scales from the linear no-uplift oscillator (for absolute tolerances)."""
    m = p[I_M]
    k1 = p[I_K0] - p[I_MGH] + 0.5 * p[I_EPS] * p[I_E0]
    w2 = abs(k1) / m
    if w2 <= 0.0:
        w2 = 1.0
    zw = max(0.5 * p[I_C1] / m, 0.05)  # floor: undamped points still get a finite scale
    s_eff = p[I_S0]
    if kt:
        wg = p[I_WG]
        zg = p[I_ZG]
        num = wg**4 + 4.0 * zg * zg * wg * wg * w2
        den = (w2 - wg * wg) ** 2 + 4.0 * zg * zg * wg * wg * w2
        s_eff = p[I_S0] * num / den
    g2 = p[I_GAIN] ** 2
    var_theta_dot = math.pi * s_eff * g2 / (2.0 * zw)
    diag = np.empty(4)
    diag[0] = var_theta_dot / w2
    diag[1] = var_theta_dot
    if kt:
        diag[2] = math.pi * p[I_S0] / (2.0 * p[I_ZG] * p[I_WG] ** 3)
        diag[3] = math.pi * p[I_S0] / (2.0 * p[I_ZG] * p[I_WG])
        idx = 0
        for i in range(4):
            for j in range(i, 4):
                scale[idx] = math.sqrt(diag[i]) * math.sqrt(diag[j])   # no S0^2 underflow
                idx += 1
    else:
        scale[0] = diag[0]
        scale[1] = math.sqrt(diag[0]) * math.sqrt(diag[1])
        scale[2] = diag[1]
    for i in range(scale.size):        # vanishing S0 (< ~1e-295): keep the error norm finite
        scale[i] = max(scale[i], SCALE_FLOOR)


@numba.njit(cache=True)
def _p_uplift(p, var_theta):
    if var_theta <= 0.0:
        return 0.0
    return math.erfc(p[I_TU] / math.sqrt(2.0 * var_theta))


@numba.njit(cache=True)
def _store(p, out_i, k, y, values, slopes, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o,
           p_upl):
    n = y.shape[0]
    var_theta[out_i, k] = y[0]
    cov[out_i, k] = y[1]
    var_theta_dot[out_i, k] = y[2] if n == 3 else y[4]
    c, kk = _coefficients(p, y[0], y[1], values, slopes)
    c_eq_o[out_i, k] = c
    k_eq_o[out_i, k] = kk
    p_upl[out_i, k] = _p_uplift(p, y[0])


@numba.njit(cache=True)
def _solve_point(p, kt, t_out, rtol, h_max, max_steps, values, slopes, i,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                 status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    n = 10 if kt else 3
    y = np.zeros(n)
    y_new = np.empty(n)
    y_stage = np.empty(n)
    K = np.empty((7, n))
    scale = np.empty(n)
    gains = np.empty(7)
    _linear_scales(p, kt, scale)
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    t = t_out[0]

    c0, k0 = _rhs(p, kt, p[I_GAIN] * _envelope(p, t), y, K, 0, values, slopes)
    _store(p, i, 0, y, values, slopes, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    next_out = 1
    best = 0.0
    best_t = t
    lowest_k = k0
    steps = 0
    rejected = 0
    err_old = 1e-4
    code = STATUS_OK
    if not (k0 > 0.0):
        code = STATUS_K_EQ_NEGATIVE
        t_end = t  # no step is taken
    else:
        h = min(h_max, 0.05 / math.sqrt(k0 / p[I_M]), t_end - t)
    while t < t_end:
        if steps >= max_steps:
            code = STATUS_MAX_STEPS
            break
        if t + h > t_end:
            h = t_end - t
        _stage_gains(p, t, h, gains)
        # stages 2..6
        for s in range(1, 6):
            for j in range(n):
                acc = 0.0
                for q in range(s):
                    acc += _A[s, q] * K[q, j]
                y_stage[j] = y[j] + h * acc
            _rhs(p, kt, gains[s], y_stage, K, s, values, slopes)
        for j in range(n):
            acc = 0.0
            for q in range(6):
                acc += _B[q] * K[q, j]
            y_new[j] = y[j] + h * acc
        c_new, k_new = _rhs(p, kt, gains[6], y_new, K, 6, values, slopes)
        err = 0.0
        finite = True
        for j in range(n):
            e = 0.0
            for q in range(7):
                e += _E[q] * K[q, j]
            e = abs(h * e) / (rtol * scale[j] + rtol * max(abs(y[j]), abs(y_new[j])))
            if not (e < 1e300):
                finite = False
            err = max(err, e)
        steps += 1
        if not finite:
            if h > 1e-12 * t_end:
                h *= 0.2
                continue
            code = STATUS_NONFINITE
            break
        if err > 1.0:
            h *= max(0.2, 0.9 * err**-0.2)
            rejected += 1
            continue
        # accepted step [t, t + h]
        t_new = t + h
        while next_out < nt and t_out[next_out] <= t_new * (1.0 + 1e-14):
            theta = (t_out[next_out] - t) / h
            for j in range(n):
                y_stage[j] = _dense(y, K, h, theta, j)
            _store(p, i, next_out, y_stage, values, slopes,
                   var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
            next_out += 1
        # peak of var_theta: d(var)/dt = 2 cov changes sign from + to -
        # (only where the step could hold a new maximum; 24 halvings ~ 6e-8 of a step)
        bound = max(y[0], y_new[0]) + h * max(abs(y[1]), abs(y_new[1])) * 2.0
        if y[1] > 0.0 and y_new[1] <= 0.0 and bound > best:
            lo = 0.0
            hi = 1.0
            for _ in range(24):
                mid = 0.5 * (lo + hi)
                if _dense(y, K, h, mid, 1) > 0.0:
                    lo = mid
                else:
                    hi = mid
            v = _dense(y, K, h, 0.5 * (lo + hi), 0)
            if v > best:
                best = v
                best_t = t + 0.5 * (lo + hi) * h
        if y_new[0] > best:
            best = y_new[0]
            best_t = t_new
        if k_new < lowest_k:
            lowest_k = k_new
        for j in range(n):
            y[j] = y_new[j]
            K[0, j] = K[6, j]
        t = t_new
        if not (k_new > 0.0):
            code = STATUS_K_EQ_NEGATIVE
            break
        if y[0] > p[I_SIGMAX] ** 2:
            code = STATUS_VARIANCE_UNBOUNDED
            break
        # PI step control (Hairer & Wanner's DOPRI5, beta = 0.04): smooth near the stability bound
        err = max(err, 1e-10)
        fac = min(5.0, max(0.2, 0.9 * err**-0.17 * err_old**0.04))
        err_old = err
        h = min(h * fac, h_max)
    status[i] = code
    t_stop[i] = t
    n_steps[i] = steps
    n_rejected[i] = rejected
    peak_var[i] = best
    t_peak[i] = best_t
    min_k_eq[i] = lowest_k


@numba.njit(cache=True)
def _solve_batch(params, kt, t_out, rtol, h_max, max_steps, values, slopes,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                 status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    for i in range(params.shape[0]):
        _solve_point(params[i], kt, t_out, rtol, h_max, max_steps, values, slopes, i,
                     var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                     status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq)


@numba.njit(cache=True)
def _solve_batch_tabulated(params, kt, t_out, rtol, h_max, max_steps, tables_v, tables_s,
                           var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                           status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    """:func:`_solve_batch` with one coefficient table per point (``tables_v[i]``, ``tables_s[i]``)."""
    for i in range(params.shape[0]):
        _solve_point(params[i], kt, t_out, rtol, h_max, max_steps, tables_v[i], tables_s[i], i,
                     var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                     status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq)


HISTORY_VARIABLES = ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq", "p_uplift")
SUMMARY_VARIABLES = ("status", "t_stop", "n_steps", "peak_var_theta", "t_peak_var_theta",
                     "peak_p_uplift", "min_k_eq")


def solve_moments(block, foundation, excitation, t_out, rtol=DEFAULT_RTOL, h_max=None,
                  max_steps=DEFAULT_MAX_STEPS, condensation="paper"):
    """Integrate the linearized moment equations for a batch of parameter points.

    Parameters
    ----------
    block, foundation, excitation : model objects whose fields may be arrays (broadcast).
    t_out : increasing output times [s], starting at the initial time (zero covariance).
    rtol : relative tolerance of the Dormand–Prince pair (absolute tolerances are ``rtol``
        times the linear stationary moments of each point).
    h_max : largest step [s]; default ``(t_out[-1] - t_out[0]) / 20``.
    max_steps : step budget per point (accepted + rejected).
    condensation : ``"paper"`` (eqs. 17–25, default) or ``"cubic"``
        (:mod:`screening.condensation.cubic`; raises ``ValueError`` for a softening bed that
        cannot carry the block through the onset of uplift).

    Returns
    -------
    dict of numpy arrays: the time histories ``var_theta`` [rad^2], ``var_theta_dot``
    [rad^2/s^2], ``cov_theta_theta_dot`` [rad^2/s], ``c_eq`` [N m s/rad], ``k_eq`` [N m/rad],
    ``p_uplift`` [1] of shape ``shape + (len(t_out),)`` (NaN after a point stopped), and per
    point ``status`` (see ``STATUS_MEANINGS``), ``t_stop`` [s], ``n_steps``,
    ``peak_var_theta`` [rad^2] with ``t_peak_var_theta`` [s], ``peak_p_uplift`` [1] and
    ``min_k_eq`` [N m/rad] (over the integrated span).
    """
    t_out = np.ascontiguousarray(t_out, dtype=float)
    if t_out.ndim != 1 or t_out.size < 2 or np.any(np.diff(t_out) <= 0):
        raise ValueError("parameter 't_out' must be an increasing 1-d array of at least 2 times")
    params, shape = pack_parameters(block, foundation, excitation, condensation)
    kt = excitation.kind == "kanai_tajimi"
    n, nt = params.shape[0], t_out.size
    if h_max is None:
        h_max = (t_out[-1] - t_out[0]) / 20.0
    values, slopes = coefficient_table()
    hist = {name: np.full((n, nt), np.nan) for name in HISTORY_VARIABLES}
    status = np.zeros(n, dtype=np.int8)
    t_stop = np.full(n, np.nan)
    n_steps = np.zeros(n, dtype=np.int64)
    n_rejected = np.zeros(n, dtype=np.int64)
    peak = np.full(n, np.nan)
    t_peak = np.full(n, np.nan)
    min_k = np.full(n, np.nan)
    if condensation == "paper":
        _solve_batch(params, kt, t_out, float(rtol), float(h_max), int(max_steps), values, slopes,
                     hist["var_theta"], hist["cov_theta_theta_dot"], hist["var_theta_dot"],
                     hist["c_eq"], hist["k_eq"], hist["p_uplift"],
                     status, t_stop, n_steps, n_rejected, peak, t_peak, min_k)
    else:
        for lo in range(0, n, TABLE_CHUNK):
            hi = min(lo + TABLE_CHUNK, n)
            tables_v, tables_s = _chunk_tables(block, foundation, shape, lo, hi)
            part = slice(lo, hi)
            _solve_batch_tabulated(params[part], kt, t_out, float(rtol), float(h_max), int(max_steps),
                                   tables_v, tables_s,
                                   hist["var_theta"][part], hist["cov_theta_theta_dot"][part],
                                   hist["var_theta_dot"][part], hist["c_eq"][part], hist["k_eq"][part],
                                   hist["p_uplift"][part], status[part], t_stop[part], n_steps[part],
                                   n_rejected[part], peak[part], t_peak[part], min_k[part])
    tu = params[:, I_TU]
    with np.errstate(divide="ignore"):
        from scipy.special import erfc
        peak_p = np.where(peak > 0, erfc(tu / np.sqrt(2.0 * np.maximum(peak, 1e-300))), 0.0)
    out = {name: a.reshape(shape + (nt,)) for name, a in hist.items()}
    out.update({
        "status": status.reshape(shape), "t_stop": t_stop.reshape(shape),
        "n_steps": n_steps.reshape(shape), "n_rejected": n_rejected.reshape(shape),
        "peak_var_theta": peak.reshape(shape),
        "t_peak_var_theta": t_peak.reshape(shape), "peak_p_uplift": peak_p.reshape(shape),
        "min_k_eq": min_k.reshape(shape),
    })
    return out


def _chunk_tables(block, foundation, shape, lo, hi):
    """Coefficient tables ``(values, slopes)`` of the flattened points ``lo:hi`` of the broadcast ``shape``."""
    def pick(value):
        return np.broadcast_to(np.asarray(value, dtype=float), shape).ravel()[lo:hi]

    blk = SimpleNamespace(m=pick(block.m), b=pick(block.b), h=pick(block.h), g=pick(block.g))
    damping = {"lam" if foundation.contact == "hunt_crossley" else "c": pick(foundation.damping)}
    fnd = SimpleNamespace(k=pick(foundation.k), eps=pick(foundation.eps), damping=pick(foundation.damping),
                          contact=foundation.contact, **damping)
    return cubic_linearization.coefficient_tables(blk, fnd, (hi - lo,))
