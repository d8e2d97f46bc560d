"""Specialised compiled step loops of the moment solver, one per state size.

:mod:`screening.solvers.moments` documents the method; this module holds its two compiled
integrators of one parameter point:

* :func:`solve_point_white`: modulated white noise, the 3 moments ``(var_theta, cov,
  var_theta_dot)`` held in scalar locals (no arrays, no runtime-length loops);
* :func:`solve_point_kt`: Kanai–Tajimi, the 10 entries of the 4x4 covariance of ``(theta,
  theta', u_g, u_g')`` in fixed-size arrays with constant-length loops.

Both run the same Dormand–Prince 5(4) pair, controller and dense output
(:mod:`screening.kernels.dopri`); the PI controller works on the logarithms of the error norms
(one ``log`` and one ``exp`` per step instead of two powers) and the stage gains and the
white-noise right-hand side multiply by reciprocals computed once instead of dividing (about 7 %
less time per step; results change at the solver tolerance, ~1e-9 on peak ``var_theta``).  The
condensation enters only through its compiled ``(c_eq, k_eq)`` function ``coefficients`` (a
first-class function), its record ``cond`` and its table (``table``).

Histories are written only when ``store`` is true (output arrays with at least one row per point
otherwise untouched): a screen without histories skips the dense output, the coefficient
evaluations and the ``erfc`` at the output times.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.kernels import dopri
from screening.kernels.dopri import (
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
    B1, B3, B4, B5, B6, C2, C3, C4, E1, E3, E4, E5, E6, E7, dense_weights)
from screening.model.excitation import stationary_filter_moments_jit
from screening.status import PointStatus

#: Smallest absolute-tolerance scale [moment units]: below it the scale would underflow.
SCALE_FLOOR = 1e-300

OK = PointStatus.ok
K_EQ_NEGATIVE = PointStatus.k_eq_negative
BEYOND_SLENDERNESS = PointStatus.sigma_theta_beyond_slenderness
STEP_BUDGET = PointStatus.step_budget_exhausted
NON_FINITE = PointStatus.non_finite_moments

#: Logarithm of the previous error norm before the first step.
LOG_ERR_START = math.log(1e-4)

#: Bisection halvings locating the peak of var_theta inside a step (~6e-8 of a step).
PEAK_HALVINGS = 24


# ---------------------------------------------------------------- shared pieces
@numba.njit(cache=True, inline="always")
def _exp_minus(x):
    """``exp(-x)`` for ``0 <= x``; a 7-term series below 0.02 (error < 1e-16)."""
    if x < 0.02:
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x / 720.0)))))
    return math.exp(-x)


@numba.njit(cache=True, inline="always")
def _gain(osc, e1, e2, r1, r2, c):
    """``m h q(t + c) / M`` from ``e1 = exp(-t/T1)``, ``e2 = exp(-t/T2)``, ``r1 = 1/T1``, ``r2 = 1/T2``
    and the stage offset ``c`` [s]."""
    return osc.gain * 4.0 * (e1 * _exp_minus(c * r1) - e2 * _exp_minus(c * r2))


@numba.njit(cache=True, inline="always")
def initial_gain(osc, t):
    """Input gain ``m h q(t) / M`` [1/m] at time ``t`` [s]."""
    return osc.gain * (1.0 if osc.constant_envelope == 1.0 else
                       4.0 * (math.exp(-t / osc.T1) - math.exp(-t / osc.T2)))


@numba.njit(cache=True, inline="always")
def stage_gains(osc, t, h):
    """Input gains at the stage times ``t + C_s h`` of stages 2..6 (stage 7 shares stage 6's time)."""
    if osc.constant_envelope == 1.0:
        g = osc.gain
        return g, g, g, g, g
    r1 = 1.0 / osc.T1
    r2 = 1.0 / osc.T2
    e1 = math.exp(-t * r1)
    e2 = math.exp(-t * r2)
    return (_gain(osc, e1, e2, r1, r2, C2 * h), _gain(osc, e1, e2, r1, r2, C3 * h),
            _gain(osc, e1, e2, r1, r2, C4 * h), _gain(osc, e1, e2, r1, r2, dopri.C5 * h),
            _gain(osc, e1, e2, r1, r2, h))


@numba.njit(cache=True, inline="always")
def p_uplift(osc, var_theta):
    """Uplift occupancy ``erfc(theta_ul / sqrt(2 var_theta))`` [1] (eq. 58)."""
    if var_theta <= 0.0:
        return 0.0
    return math.erfc(osc.theta_ul / math.sqrt(2.0 * var_theta))


# ---------------------------------------------------------------- white noise: 3 scalar moments
@numba.njit(cache=True, inline="always")
def _white_rhs(coefficients, cond, table, inv_m, S0, alpha, y0, y1, y2):
    """Eq. (45): ``(d var_theta, d cov, d var_theta_dot, c_eq, k_eq)`` at input gain ``alpha``
    (``inv_m = 1 / m_sdof``)."""
    c_eq, k_eq = coefficients(cond, table, y0, y1)
    kap = k_eq * inv_m
    gam = c_eq * inv_m
    return (2.0 * y1, y2 - kap * y0 - gam * y1,
            -2.0 * kap * y1 - 2.0 * gam * y2 + 2.0 * math.pi * S0 * alpha * alpha, c_eq, k_eq)


@numba.njit(cache=True, inline="always")
def _white_scales(osc):
    """Absolute-tolerance scales of ``(var_theta, cov, var_theta_dot)`` from the linear oscillator."""
    m = osc.m_sdof
    w2 = abs(osc.k_rest) / m
    if w2 <= 0.0:
        w2 = 1.0
    zw = max(0.5 * osc.c_rest / m, 0.05)
    g2 = osc.gain ** 2
    vd = math.pi * osc.S0 * g2 / (2.0 * zw)
    v = vd / w2
    return (max(v, SCALE_FLOOR), max(math.sqrt(v) * math.sqrt(vd), SCALE_FLOOR), max(vd, SCALE_FLOOR))


@numba.njit(cache=True, inline="always")
def _store_white(coefficients, cond, table, osc, i, k, y0, y1, y2,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    var_theta[i, k] = y0
    cov[i, k] = y1
    var_theta_dot[i, k] = y2
    c, kk = coefficients(cond, table, y0, y1)
    c_eq_o[i, k] = c
    k_eq_o[i, k] = kk
    p_upl[i, k] = p_uplift(osc, y0)


@numba.njit(cache=True)
def solve_point_white(coefficients, cond, table, osc, t_out, rtol, h_max, max_steps, store, i,
                      var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                      status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    """One white-noise point into row ``i`` of the outputs (histories only if ``store``)."""
    s0, s1, s2 = _white_scales(osc)
    inv_m = 1.0 / osc.m_sdof
    S0 = osc.S0
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    t = t_out[0]
    y0 = 0.0
    y1 = 0.0
    y2 = 0.0
    k1a, k1b, k1c, c0, k0 = _white_rhs(coefficients, cond, table, inv_m, S0, initial_gain(osc, t), y0, y1, y2)
    if store:
        _store_white(coefficients, cond, table, osc, i, 0, y0, y1, y2,
                     var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    next_out = 1
    best = 0.0
    best_t = t
    lowest_k = k0
    steps = 0
    rejected = 0
    log_err_old = LOG_ERR_START
    code = OK
    h = 0.0
    if not (k0 > 0.0):
        code = K_EQ_NEGATIVE
        t_end = t  # no step is taken
    else:
        h = min(h_max, 0.05 / math.sqrt(k0 / osc.m_sdof), t_end - t)
    while t < t_end:
        if steps >= max_steps:
            code = STEP_BUDGET
            break
        if t + h > t_end:
            h = t_end - t
        a2, a3, a4, a5, a6 = stage_gains(osc, t, h)
        z0 = y0 + h * (A21 * k1a)
        z1 = y1 + h * (A21 * k1b)
        z2 = y2 + h * (A21 * k1c)
        k2a, k2b, k2c, _, _ = _white_rhs(coefficients, cond, table, inv_m, S0, a2, z0, z1, z2)
        z0 = y0 + h * (A31 * k1a + A32 * k2a)
        z1 = y1 + h * (A31 * k1b + A32 * k2b)
        z2 = y2 + h * (A31 * k1c + A32 * k2c)
        k3a, k3b, k3c, _, _ = _white_rhs(coefficients, cond, table, inv_m, S0, a3, z0, z1, z2)
        z0 = y0 + h * (A41 * k1a + A42 * k2a + A43 * k3a)
        z1 = y1 + h * (A41 * k1b + A42 * k2b + A43 * k3b)
        z2 = y2 + h * (A41 * k1c + A42 * k2c + A43 * k3c)
        k4a, k4b, k4c, _, _ = _white_rhs(coefficients, cond, table, inv_m, S0, a4, z0, z1, z2)
        z0 = y0 + h * (A51 * k1a + A52 * k2a + A53 * k3a + A54 * k4a)
        z1 = y1 + h * (A51 * k1b + A52 * k2b + A53 * k3b + A54 * k4b)
        z2 = y2 + h * (A51 * k1c + A52 * k2c + A53 * k3c + A54 * k4c)
        k5a, k5b, k5c, _, _ = _white_rhs(coefficients, cond, table, inv_m, S0, a5, z0, z1, z2)
        z0 = y0 + h * (A61 * k1a + A62 * k2a + A63 * k3a + A64 * k4a + A65 * k5a)
        z1 = y1 + h * (A61 * k1b + A62 * k2b + A63 * k3b + A64 * k4b + A65 * k5b)
        z2 = y2 + h * (A61 * k1c + A62 * k2c + A63 * k3c + A64 * k4c + A65 * k5c)
        k6a, k6b, k6c, _, _ = _white_rhs(coefficients, cond, table, inv_m, S0, a6, z0, z1, z2)
        n0 = y0 + h * (B1 * k1a + B3 * k3a + B4 * k4a + B5 * k5a + B6 * k6a)
        n1 = y1 + h * (B1 * k1b + B3 * k3b + B4 * k4b + B5 * k5b + B6 * k6b)
        n2 = y2 + h * (B1 * k1c + B3 * k3c + B4 * k4c + B5 * k5c + B6 * k6c)
        k7a, k7b, k7c, c_new, k_new = _white_rhs(coefficients, cond, table, inv_m, S0, a6, n0, n1, n2)
        ea = E1 * k1a + E3 * k3a + E4 * k4a + E5 * k5a + E6 * k6a + E7 * k7a
        eb = E1 * k1b + E3 * k3b + E4 * k4b + E5 * k5b + E6 * k6b + E7 * k7b
        ec = E1 * k1c + E3 * k3c + E4 * k4c + E5 * k5c + E6 * k6c + E7 * k7c
        ea = abs(h * ea) / (rtol * s0 + rtol * max(abs(y0), abs(n0)))
        eb = abs(h * eb) / (rtol * s1 + rtol * max(abs(y1), abs(n1)))
        ec = abs(h * ec) / (rtol * s2 + rtol * max(abs(y2), abs(n2)))
        finite = (ea < 1e300) and (eb < 1e300) and (ec < 1e300)
        err = max(max(max(0.0, ea), eb), ec)
        steps += 1
        if not finite:
            if h > 1e-12 * t_end:
                h *= 0.2
                continue
            code = NON_FINITE
            break
        if err > 1.0:
            h *= dopri.rejected_step_factor(err)
            rejected += 1
            continue
        # accepted step [t, t + h]
        t_new = t + h
        if store:
            while next_out < nt and t_out[next_out] <= t_new * (1.0 + 1e-14):
                w1, w3, w4, w5, w6, w7 = dense_weights((t_out[next_out] - t) / h)
                _store_white(coefficients, cond, table, osc, i, next_out,
                             y0 + h * (k1a * w1 + k3a * w3 + k4a * w4 + k5a * w5 + k6a * w6 + k7a * w7),
                             y1 + h * (k1b * w1 + k3b * w3 + k4b * w4 + k5b * w5 + k6b * w6 + k7b * w7),
                             y2 + h * (k1c * w1 + k3c * w3 + k4c * w4 + k5c * w5 + k6c * w6 + k7c * w7),
                             var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
                next_out += 1
        # peak of var_theta: d(var)/dt = 2 cov changes sign from + to -
        # (only where the step could hold a new maximum)
        bound = max(y0, n0) + h * max(abs(y1), abs(n1)) * 2.0
        if y1 > 0.0 and n1 <= 0.0 and bound > best:
            lo = 0.0
            hi = 1.0
            for _ in range(PEAK_HALVINGS):
                mid = 0.5 * (lo + hi)
                w1, w3, w4, w5, w6, w7 = dense_weights(mid)
                if y1 + h * (k1b * w1 + k3b * w3 + k4b * w4 + k5b * w5 + k6b * w6 + k7b * w7) > 0.0:
                    lo = mid
                else:
                    hi = mid
            w1, w3, w4, w5, w6, w7 = dense_weights(0.5 * (lo + hi))
            v = y0 + h * (k1a * w1 + k3a * w3 + k4a * w4 + k5a * w5 + k6a * w6 + k7a * w7)
            if v > best:
                best = v
                best_t = t + 0.5 * (lo + hi) * h
        if n0 > best:
            best = n0
            best_t = t_new
        if k_new < lowest_k:
            lowest_k = k_new
        y0, y1, y2 = n0, n1, n2
        k1a, k1b, k1c = k7a, k7b, k7c
        t = t_new
        if not (k_new > 0.0):
            code = K_EQ_NEGATIVE
            break
        if y0 > osc.slenderness ** 2:
            code = BEYOND_SLENDERNESS
            break
        log_err = math.log(max(err, 1e-10))
        fac = dopri.accepted_step_factor_log(log_err, log_err_old)
        log_err_old = log_err
        h = min(h * fac, h_max)
    status[i] = code
    t_stop[i] = t
    n_steps[i] = steps
    n_rejected[i] = rejected
    peak_var[i] = best
    t_peak[i] = best_t
    min_k_eq[i] = lowest_k


# ---------------------------------------------------------------- Kanai-Tajimi: 10 moments
#: Independent entries of the 4x4 symmetric covariance, stored as (00 01 02 03 11 12 13 22 23 33).
N_KT = 10


@numba.njit(cache=True, inline="always")
def _kt_rhs(coefficients, cond, table, osc, alpha, y, dy):
    """Eq. (51) into ``dy``; returns ``(c_eq, k_eq)`` at ``y`` (``alpha``: input gain at the stage time)."""
    c_eq, k_eq = coefficients(cond, table, y[0], y[1])
    m = osc.m_sdof
    kap = k_eq / m
    gam = c_eq / m
    wg = osc.omega_g
    zg = osc.zeta_g
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
    dy[0] = 2.0 * c01
    dy[1] = c11 + a10
    dy[2] = c12 + c03
    dy[3] = c13 + a30
    dy[4] = 2.0 * a11
    dy[5] = a12 + c13
    dy[6] = a13 + a31
    dy[7] = 2.0 * c23
    dy[8] = c33 + a32
    dy[9] = 2.0 * a33 + 2.0 * math.pi * osc.S0
    return c_eq, k_eq


@numba.njit(cache=True, inline="always")
def _kt_scales(osc, scale):
    """Absolute-tolerance scales of the 10 moments from the linear oscillator under the filter."""
    m = osc.m_sdof
    w2 = abs(osc.k_rest) / m
    if w2 <= 0.0:
        w2 = 1.0
    zw = max(0.5 * osc.c_rest / m, 0.05)
    wg = osc.omega_g
    zg = osc.zeta_g
    num = wg**4 + 4.0 * zg * zg * wg * wg * w2
    den = (w2 - wg * wg) ** 2 + 4.0 * zg * zg * wg * wg * w2
    s_eff = osc.S0 * num / den
    g2 = osc.gain ** 2
    vd = math.pi * s_eff * g2 / (2.0 * zw)
    d0 = vd / w2
    d2, d3 = stationary_filter_moments_jit(osc.S0, wg, zg)
    diag = (d0, vd, d2, d3)
    idx = 0
    for i in range(4):
        for j in range(i, 4):
            scale[idx] = max(math.sqrt(diag[i]) * math.sqrt(diag[j]), SCALE_FLOOR)   # no S0^2 underflow
            idx += 1


@numba.njit(cache=True, inline="always")
def _kt_dense(y, K1, K3, K4, K5, K6, K7, h, theta, j):
    w1, w3, w4, w5, w6, w7 = dense_weights(theta)
    return y[j] + h * (K1[j] * w1 + K3[j] * w3 + K4[j] * w4 + K5[j] * w5 + K6[j] * w6 + K7[j] * w7)


@numba.njit(cache=True, inline="always")
def _store_kt(coefficients, cond, table, osc, i, k, y0, y1, y4,
              var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    _store_white(coefficients, cond, table, osc, i, k, y0, y1, y4,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)


@numba.njit(cache=True)
def solve_point_kt(coefficients, cond, table, osc, t_out, rtol, h_max, max_steps, store, i,
                   var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                   status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    """One Kanai–Tajimi point into row ``i`` of the outputs (histories only if ``store``)."""
    n = N_KT
    y = np.zeros(n)
    yn = np.empty(n)
    z = np.empty(n)
    K1 = np.empty(n)
    K2 = np.empty(n)
    K3 = np.empty(n)
    K4 = np.empty(n)
    K5 = np.empty(n)
    K6 = np.empty(n)
    K7 = np.empty(n)
    scale = np.empty(n)
    _kt_scales(osc, scale)
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    t = t_out[0]
    c0, k0 = _kt_rhs(coefficients, cond, table, osc, initial_gain(osc, t), y, K1)
    if store:
        _store_kt(coefficients, cond, table, osc, i, 0, y[0], y[1], y[4],
                  var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    next_out = 1
    best = 0.0
    best_t = t
    lowest_k = k0
    steps = 0
    rejected = 0
    log_err_old = LOG_ERR_START
    code = OK
    h = 0.0
    if not (k0 > 0.0):
        code = K_EQ_NEGATIVE
        t_end = t  # no step is taken
    else:
        h = min(h_max, 0.05 / math.sqrt(k0 / osc.m_sdof), t_end - t)
    while t < t_end:
        if steps >= max_steps:
            code = STEP_BUDGET
            break
        if t + h > t_end:
            h = t_end - t
        a2, a3, a4, a5, a6 = stage_gains(osc, t, h)
        for j in range(n):
            z[j] = y[j] + h * (A21 * K1[j])
        _kt_rhs(coefficients, cond, table, osc, a2, z, K2)
        for j in range(n):
            z[j] = y[j] + h * (A31 * K1[j] + A32 * K2[j])
        _kt_rhs(coefficients, cond, table, osc, a3, z, K3)
        for j in range(n):
            z[j] = y[j] + h * (A41 * K1[j] + A42 * K2[j] + A43 * K3[j])
        _kt_rhs(coefficients, cond, table, osc, a4, z, K4)
        for j in range(n):
            z[j] = y[j] + h * (A51 * K1[j] + A52 * K2[j] + A53 * K3[j] + A54 * K4[j])
        _kt_rhs(coefficients, cond, table, osc, a5, z, K5)
        for j in range(n):
            z[j] = y[j] + h * (A61 * K1[j] + A62 * K2[j] + A63 * K3[j] + A64 * K4[j] + A65 * K5[j])
        _kt_rhs(coefficients, cond, table, osc, a6, z, K6)
        for j in range(n):
            yn[j] = y[j] + h * (B1 * K1[j] + B3 * K3[j] + B4 * K4[j] + B5 * K5[j] + B6 * K6[j])
        c_new, k_new = _kt_rhs(coefficients, cond, table, osc, a6, yn, K7)
        err = 0.0
        finite = True
        for j in range(n):
            e = E1 * K1[j] + E3 * K3[j] + E4 * K4[j] + E5 * K5[j] + E6 * K6[j] + E7 * K7[j]
            e = abs(h * e) / (rtol * scale[j] + rtol * max(abs(y[j]), abs(yn[j])))
            if not (e < 1e300):
                finite = False
            err = max(err, e)
        steps += 1
        if not finite:
            if h > 1e-12 * t_end:
                h *= 0.2
                continue
            code = NON_FINITE
            break
        if err > 1.0:
            h *= dopri.rejected_step_factor(err)
            rejected += 1
            continue
        # accepted step [t, t + h]
        t_new = t + h
        if store:
            while next_out < nt and t_out[next_out] <= t_new * (1.0 + 1e-14):
                theta = (t_out[next_out] - t) / h
                _store_kt(coefficients, cond, table, osc, i, next_out,
                          _kt_dense(y, K1, K3, K4, K5, K6, K7, h, theta, 0),
                          _kt_dense(y, K1, K3, K4, K5, K6, K7, h, theta, 1),
                          _kt_dense(y, K1, K3, K4, K5, K6, K7, h, theta, 4),
                          var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
                next_out += 1
        bound = max(y[0], yn[0]) + h * max(abs(y[1]), abs(yn[1])) * 2.0
        if y[1] > 0.0 and yn[1] <= 0.0 and bound > best:
            lo = 0.0
            hi = 1.0
            for _ in range(PEAK_HALVINGS):
                mid = 0.5 * (lo + hi)
                if _kt_dense(y, K1, K3, K4, K5, K6, K7, h, mid, 1) > 0.0:
                    lo = mid
                else:
                    hi = mid
            v = _kt_dense(y, K1, K3, K4, K5, K6, K7, h, 0.5 * (lo + hi), 0)
            if v > best:
                best = v
                best_t = t + 0.5 * (lo + hi) * h
        if yn[0] > best:
            best = yn[0]
            best_t = t_new
        if k_new < lowest_k:
            lowest_k = k_new
        y, yn = yn, y
        K1, K7 = K7, K1
        t = t_new
        if not (k_new > 0.0):
            code = K_EQ_NEGATIVE
            break
        if y[0] > osc.slenderness ** 2:
            code = BEYOND_SLENDERNESS
            break
        log_err = math.log(max(err, 1e-10))
        fac = dopri.accepted_step_factor_log(log_err, log_err_old)
        log_err_old = log_err
        h = min(h * fac, h_max)
    status[i] = code
    t_stop[i] = t
    n_steps[i] = steps
    n_rejected[i] = rejected
    peak_var[i] = best
    t_peak[i] = best_t
    min_k_eq[i] = lowest_k
