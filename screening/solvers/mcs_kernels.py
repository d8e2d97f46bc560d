"""Compiled kernels of the Monte Carlo engine: right-hand sides and an adaptive integrator.

Everything here is scalar numba code called once per sample (``prange`` over samples).
The public, documented entry point is :func:`screening.solvers.montecarlo.monte_carlo`.

Integrator: explicit Dormand–Prince 5(4) pair (FSAL, Hairer's PI step control), error
measured component-wise against ``atol_i + rtol |y_i|`` with absolute scales set by the
caller from the physics (``theta_ul``, static indentation, natural frequencies).  Steps
are clipped to land exactly on the output instants.  The modulated ground acceleration
``q f`` and its exact rate ``q f' + q' f`` are given on the synthesis grid; between grid
points the input is their cubic Hermite interpolant.  Samples are independent, so the
``prange`` loop gives the same numbers for any number of threads or chunking.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.condensation import cubic as cubic_condensation
from screening.physics.contact import contact_resultants_trig

MODEL_COUPLED = 0
MODEL_CONDENSED = 1

STATUS_OK = 0
STATUS_OVERTURNED = 1
STATUS_DIVERGED = 2

#: Why a sample was flagged as diverged (``reason`` output of the kernel).
REASON_NONE = 0
REASON_NONFINITE = 1
REASON_LONG_FLIGHT = 2
REASON_OUT_OF_BOUNDS = 3
REASON_STEP_UNDERFLOW = 4
REASON_STEP_BUDGET = 5
REASON_NO_EQUILIBRIUM = 6
REASON_NAMES = {REASON_NONE: "none", REASON_NONFINITE: "non-finite state",
                REASON_LONG_FLIGHT: "flight longer than max_flight_time",
                REASON_OUT_OF_BOUNDS: "state out of physical bounds",
                REASON_STEP_UNDERFLOW: "step size underflow", REASON_STEP_BUDGET: "step budget exhausted",
                REASON_NO_EQUILIBRIUM: "|theta| beyond the capacity angle (no quasi-static equilibrium)"}

# Layout of the parameter vector (SI units); built by :func:`pack_parameters`.
(P_M, P_G, P_H, P_ICM, P_B, P_K, P_EPS, P_DAMP, P_WINKLER, P_THETA_OVER, P_MAX_FLIGHT,
 P_Z_MAX, P_Z_MIN, P_RATE_MAX, P_THETA_UL,
 # condensed-model constants (eqs. 24–25): C1, C2 coefficient, K1 = K1_0 + K1_2 theta^2,
 # K2 = MGB/|theta| - K2_32 |theta|^-3/2 - K2_12 |theta|^-1/2 + K2_0
 P_C1, P_C2, P_K1_0, P_K1_2, P_MGB, P_K2_32, P_K2_12, P_K2_0, P_M_SDOF,
 # condensation: 0 paper, 1 cubic (screening.condensation.cubic); m g / (2 b k); capacity angle;
 # rest indentation z0 and d z / d(theta^2) at rest (Newton start of the no-uplift balance)
 P_COND, P_Z_LIN, P_THETA_CAP, P_Z_REST, P_Z_CURV) = range(29)
N_PARAMS = 29


def pack_parameters(block, foundation, max_flight_time=0.5, condensation="paper"):
    """Parameter vector of the compiled kernels (layout ``P_*`` above, SI units).

    ``block`` and ``foundation`` must have scalar fields; ``max_flight_time`` [s].
    ``condensation`` (``"paper"`` or ``"cubic"``) selects the condensed model's ``C``, ``K``;
    with ``"cubic"`` ``P_THETA_UL`` is the cubic threshold and ``P_THETA_CAP`` the capacity
    angle (``inf`` for the paper's condensation and for ``eps >= 0``).
    """
    m, g, h, b = float(block.m), float(block.g), float(block.h), float(block.b)
    k, eps, damping = float(foundation.k), float(foundation.eps), float(foundation.damping)
    winkler = foundation.contact == "winkler"
    mg = m * g
    p = np.zeros(N_PARAMS)
    p[P_M], p[P_G], p[P_H], p[P_ICM], p[P_B] = m, g, h, float(block.I_cm), b
    p[P_K], p[P_EPS], p[P_DAMP] = k, eps, damping
    p[P_WINKLER] = 1.0 if winkler else 0.0
    p[P_THETA_OVER] = math.atan2(b, h)
    p[P_THETA_UL] = mg / (2.0 * b * b * k)
    p[P_MAX_FLIGHT] = max_flight_time
    p[P_Z_MAX] = b                              # sinking half the base width into the bed: blown up
    p[P_Z_MIN] = -2.0 * h                       # jumping a block height off the bed: blown up
    p[P_RATE_MAX] = 1e3 * math.sqrt(g / h)      # ~1000 x the free-fall rocking rate: blown up
    if winkler:
        p[P_C1] = 2.0 / 3.0 * damping * b**3
        p[P_C2] = damping / 12.0 * (2.0 * mg / k) ** 1.5            # x |theta|^-3/2
    else:
        p[P_C1] = damping * b * b * mg / (3.0 * k)
        p[P_C2] = damping * b / 12.0 * (2.0 * mg / k) ** 1.5        # x |theta|^-1/2
    p[P_K1_0] = 2.0 / 3.0 * b**3 * k - mg * h + eps * mg * mg * b / (2.0 * k)
    p[P_K1_2] = eps * 0.4 * k * b**5
    p[P_MGB] = mg * b
    p[P_K2_32] = mg * math.sqrt(2.0 * mg * k) / (3.0 * k)
    p[P_K2_12] = eps * mg * mg / (5.0 * k) * math.sqrt(2.0 * mg / k)
    p[P_K2_0] = -mg * h + eps * mg * mg * b / k
    p[P_M_SDOF] = float(block.I_cm) + m * h * h
    p[P_Z_LIN] = mg / (2.0 * b * k)
    p[P_THETA_CAP] = math.inf
    if condensation == "cubic":
        p[P_COND] = 1.0
        p[P_THETA_UL] = float(cubic_condensation.uplift_threshold(block, foundation))
        p[P_THETA_CAP] = float(cubic_condensation.capacity_angle(block, foundation))
        z0 = float(cubic_condensation.rest_indentation(block, foundation))
        p[P_Z_REST] = z0
        p[P_Z_CURV] = -eps * b * b * z0 / (1.0 + 3.0 * eps * z0 * z0)
    elif condensation != "paper":
        raise ValueError(f"parameter 'condensation' must be one of ('paper', 'cubic') (got {condensation!r})")
    return p


# ----------------------------------------------------------------------------- condensed model
@numba.njit(cache=True)
def rocking_damping_scalar(theta, p):
    """Compiled ``C(theta)`` [N m s/rad] (eq. 24; Winkler: :mod:`screening.condensation.paper`), ``p`` from
    :func:`pack_parameters`."""
    a = abs(theta)
    if a <= p[P_THETA_UL]:
        return p[P_C1]
    r = 1.0 / math.sqrt(a)
    if p[P_WINKLER] != 0.0:
        return p[P_C2] * r * r * r
    return p[P_C2] * r


@numba.njit(cache=True)
def rocking_stiffness_scalar(theta, p):
    """Compiled secant ``K(theta)`` [N m/rad] (eq. 25), ``p`` from :func:`pack_parameters`."""
    a = abs(theta)
    if a <= p[P_THETA_UL]:
        return p[P_K1_0] + p[P_K1_2] * theta * theta
    r = 1.0 / math.sqrt(a)
    return p[P_MGB] * r * r - p[P_K2_32] * r * r * r - p[P_K2_12] * r + p[P_K2_0]


@numba.njit(cache=True)
def cubic_indentation_scalar(a, p):
    """Compiled quasi-static ``(z_cb [m], dz_cb/da [m/rad], v = b a + z_cb [m])`` of the cubic
    condensation at ``a = |theta|`` (:func:`screening.condensation.cubic.quasi_static_indentation`)."""
    b, eps = p[P_B], p[P_EPS]
    if a <= p[P_THETA_UL]:
        # eps z^3 + beta z = z_lin, beta = 1 + eps b^2 a^2: Newton from the Taylor start
        # z0 + (dz/d a^2) a^2 (error O(a^4); monotone like the start z_lin / beta)
        beta = 1.0 + eps * b * b * a * a
        z = p[P_Z_REST] + p[P_Z_CURV] * a * a
        for _ in range(100):
            step = (eps * z * z * z + beta * z - p[P_Z_LIN]) / (3.0 * eps * z * z + beta)
            z -= step
            if abs(step) <= 1e-15 * z:
                break
        return z, -2.0 * eps * b * b * a * z / (beta + 3.0 * eps * z * z), z + b * a
    mg = p[P_M] * p[P_G]
    big_a = 2.0 * mg * a / p[P_K]
    s2 = 1.0 + 2.0 * eps * big_a
    if s2 <= 0.0:                               # beyond the capacity angle: peak load, no rate
        v = 1.0 / math.sqrt(-eps)
        return v - b * a, 0.0, v
    S = math.sqrt(s2)
    v = math.sqrt(2.0 * big_a / (1.0 + S))
    return v - b * a, mg / (p[P_K] * S * v) - b, v


@numba.njit(cache=True)
def cubic_coefficients_scalar(theta, p):
    """Compiled cubic-condensation ``(C(theta) [N m s/rad], K(theta) [N m/rad])``
    (:mod:`screening.condensation.cubic`), one indentation solve for both."""
    a = abs(theta)
    z, dz, v = cubic_indentation_scalar(a, p)
    b, k, eps, lam = p[P_B], p[P_K], p[P_EPS], p[P_DAMP]
    mgh = p[P_M] * p[P_G] * p[P_H]
    b3 = b * b * b
    if a <= p[P_THETA_UL]:
        stiffness = 2.0 / 3.0 * b3 * k - mgh + eps * k * (2.0 * b3 * z * z + 0.4 * b3 * b * b * a * a)
        if p[P_WINKLER] != 0.0:
            return 2.0 / 3.0 * lam * b3, stiffness
        return 2.0 / 3.0 * lam * b3 * (z + a * dz), stiffness
    ba = b * a
    a3 = a * a * a
    v2 = v * v
    stiffness = (k * v2 * (2.0 * ba - z) / 6.0 + eps * k * v2 * v2 * (4.0 * ba - z) / 20.0) / a3 - mgh
    if p[P_WINKLER] != 0.0:
        return lam / (a * a) * (0.5 * dz * v * (ba - z) + (ba * ba * ba + z * z * z) / (3.0 * a)), stiffness
    ba2 = ba * ba
    z2 = z * z
    return (lam / (12.0 * a3) * (3.0 * ba2 * ba2 + 4.0 * ba2 * ba * z + z2 * z2 + 2.0 * a * dz * v2 * (2.0 * ba - z)),
            stiffness)


@numba.njit(cache=True)
def cubic_damping_scalar(theta, p):
    """Compiled cubic-condensation ``C(theta)`` [N m s/rad] (:mod:`screening.condensation.cubic`)."""
    return cubic_coefficients_scalar(theta, p)[0]


@numba.njit(cache=True)
def cubic_stiffness_scalar(theta, p):
    """Compiled cubic-condensation secant ``K(theta)`` [N m/rad] (:mod:`screening.condensation.cubic`)."""
    return cubic_coefficients_scalar(theta, p)[1]


# ----------------------------------------------------------------------------- right-hand sides
@numba.njit(cache=True)
def coupled_accelerations(theta, theta_dot, z_cb, z_cb_dot, x_g_ddot, p):
    """``(theta'', z_cb'')`` [rad/s^2, m/s^2] of the coupled eqs. (7)–(8) with ``z_g'' = 0``.

    Eliminating ``z_cb''`` from (8) with (7):
    ``(I_cm + m h^2 cos^2) theta'' = m h x_g'' cos - M_cb + h F_cb sin + m h^2 theta'^2 sin cos``,
    ``z_cb'' = g - F_cb/m - h (theta'^2 cos + theta'' sin)``.
    """
    m, g, h = p[P_M], p[P_G], p[P_H]
    s = math.sin(theta)
    c = math.cos(theta)
    force, moment = contact_resultants_trig(s, c, theta_dot, z_cb, z_cb_dot, p[P_B], p[P_K],
                                            p[P_EPS], p[P_DAMP], p[P_WINKLER] != 0.0)
    mh = m * h
    theta_ddot = ((mh * x_g_ddot * c - moment + h * force * s + mh * h * theta_dot * theta_dot * s * c)
                  / (p[P_ICM] + mh * h * c * c))
    z_ddot = g - force / m - h * (theta_dot * theta_dot * c + theta_ddot * s)
    return theta_ddot, z_ddot


@numba.njit(cache=True)
def condensed_acceleration(theta, theta_dot, x_g_ddot, p):
    """``theta''`` [rad/s^2] of the condensed SDOF, eq. (22): ``(m h x_g'' - C theta' - K theta) / m_sdof``.

    ``C``, ``K`` of the paper (eqs. 24–25) or, when ``p[P_COND] != 0``, of the cubic condensation.
    """
    if p[P_COND] != 0.0:
        damping, stiffness = cubic_coefficients_scalar(theta, p)
        return (p[P_M] * p[P_H] * x_g_ddot - damping * theta_dot - stiffness * theta) / p[P_M_SDOF]
    return ((p[P_M] * p[P_H] * x_g_ddot - rocking_damping_scalar(theta, p) * theta_dot
             - rocking_stiffness_scalar(theta, p) * theta) / p[P_M_SDOF])


@numba.njit(cache=True)
def _rhs(model, y0, y1, y2, y3, acc, p):
    if model == MODEL_COUPLED:
        a1, a3 = coupled_accelerations(y0, y1, y2, y3, acc, p)
        return y1, a1, y3, a3
    return y1, condensed_acceleration(y0, y1, acc, p), 0.0, 0.0


@numba.njit(cache=True)
def _hermite(row, acc, acc_dot, dt, t):
    """Ground acceleration at ``t`` from grid values and rates of row ``row`` (cubic Hermite)."""
    x = t / dt
    j = int(x)
    n = acc.shape[1]
    if j > n - 2:
        j = n - 2
    if j < 0:
        j = 0
    u = x - j
    u2 = u * u
    u3 = u2 * u
    return ((2.0 * u3 - 3.0 * u2 + 1.0) * acc[row, j] + (-2.0 * u3 + 3.0 * u2) * acc[row, j + 1]
            + dt * ((u3 - 2.0 * u2 + u) * acc_dot[row, j] + (u3 - u2) * acc_dot[row, j + 1]))


@numba.njit(cache=True)
def _in_uplift(model, theta, z_cb, p):
    if model == MODEL_COUPLED:
        return z_cb - p[P_B] * abs(math.sin(theta)) < 0.0
    return abs(theta) > p[P_THETA_UL]


LOG_1EM4 = math.log(1e-4)

# Dormand–Prince 5(4) coefficients.
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63, _A64, _A65 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
_E1, _E3, _E4, _E5, _E6, _E7 = (71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                                22.0 / 525.0, -1.0 / 40.0)


@numba.njit(cache=True)
def _err_term(e, y, ynew, scale, rtol):
    sc = scale + rtol * max(abs(y), abs(ynew))
    r = e / sc
    return r * r


@numba.njit(cache=True)
def integrate_sample(model, row, acc, acc_dot, dt_grid, t_out, p, y_init, scale, rtol, h_max,
                     max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift):
    """Integrate one sample over ``t_out``; fill row ``row`` of the output arrays.

    ``out_z``, ``out_z_dot`` receive ``z_cb``, ``z_cb'`` (zero for the condensed model).

    Returns ``(status, reason, peak_abs_theta, n_accepted, n_rejected, h_min_accepted)``.
    After overturning or divergence the remaining outputs are NaN.
    """
    n_out = t_out.shape[0]
    y0, y1, y2, y3 = y_init[0], y_init[1], y_init[2], y_init[3]
    s0, s1, s2, s3 = scale[0], scale[1], scale[2], scale[3]
    n_comp = 4.0 if model == MODEL_COUPLED else 2.0
    t = t_out[0]
    out_theta[row, 0] = y0
    out_theta_dot[row, 0] = y1
    out_z[row, 0] = y2
    out_z_dot[row, 0] = y3
    out_uplift[row, 0] = _in_uplift(model, y0, y2, p)
    for i in range(1, n_out):
        out_theta[row, i] = np.nan
        out_theta_dot[row, i] = np.nan
        out_z[row, i] = np.nan
        out_z_dot[row, i] = np.nan
        out_uplift[row, i] = False
    peak = abs(y0)
    status = STATUS_OK
    reason = REASON_NONE
    n_acc = 0
    n_rej = 0
    h_min_acc = np.inf
    log_err_old = LOG_1EM4
    flight_start = -1.0
    k1_0, k1_1, k1_2, k1_3 = _rhs(model, y0, y1, y2, y3, _hermite(row, acc, acc_dot, dt_grid, t), p)
    h = min(1e-4, h_max)
    h_floor = 1e-12 * (t_out[n_out - 1] - t_out[0] + 1.0)
    i_out = 1
    rejected = False
    while i_out < n_out:
        if n_acc + n_rej >= max_steps:
            status, reason = STATUS_DIVERGED, REASON_STEP_BUDGET
            break
        t_next = t_out[i_out]
        h = min(h, h_max)
        h_proposed = h
        landing = False
        if t + h >= t_next - 1e-9 * h:
            h = t_next - t
            landing = True
        # --- stages
        g0 = y0 + h * _A21 * k1_0
        g1 = y1 + h * _A21 * k1_1
        g2 = y2 + h * _A21 * k1_2
        g3 = y3 + h * _A21 * k1_3
        k2_0, k2_1, k2_2, k2_3 = _rhs(model, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C2 * h), p)
        g0 = y0 + h * (_A31 * k1_0 + _A32 * k2_0)
        g1 = y1 + h * (_A31 * k1_1 + _A32 * k2_1)
        g2 = y2 + h * (_A31 * k1_2 + _A32 * k2_2)
        g3 = y3 + h * (_A31 * k1_3 + _A32 * k2_3)
        k3_0, k3_1, k3_2, k3_3 = _rhs(model, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C3 * h), p)
        g0 = y0 + h * (_A41 * k1_0 + _A42 * k2_0 + _A43 * k3_0)
        g1 = y1 + h * (_A41 * k1_1 + _A42 * k2_1 + _A43 * k3_1)
        g2 = y2 + h * (_A41 * k1_2 + _A42 * k2_2 + _A43 * k3_2)
        g3 = y3 + h * (_A41 * k1_3 + _A42 * k2_3 + _A43 * k3_3)
        k4_0, k4_1, k4_2, k4_3 = _rhs(model, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C4 * h), p)
        g0 = y0 + h * (_A51 * k1_0 + _A52 * k2_0 + _A53 * k3_0 + _A54 * k4_0)
        g1 = y1 + h * (_A51 * k1_1 + _A52 * k2_1 + _A53 * k3_1 + _A54 * k4_1)
        g2 = y2 + h * (_A51 * k1_2 + _A52 * k2_2 + _A53 * k3_2 + _A54 * k4_2)
        g3 = y3 + h * (_A51 * k1_3 + _A52 * k2_3 + _A53 * k3_3 + _A54 * k4_3)
        k5_0, k5_1, k5_2, k5_3 = _rhs(model, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C5 * h), p)
        g0 = y0 + h * (_A61 * k1_0 + _A62 * k2_0 + _A63 * k3_0 + _A64 * k4_0 + _A65 * k5_0)
        g1 = y1 + h * (_A61 * k1_1 + _A62 * k2_1 + _A63 * k3_1 + _A64 * k4_1 + _A65 * k5_1)
        g2 = y2 + h * (_A61 * k1_2 + _A62 * k2_2 + _A63 * k3_2 + _A64 * k4_2 + _A65 * k5_2)
        g3 = y3 + h * (_A61 * k1_3 + _A62 * k2_3 + _A63 * k3_3 + _A64 * k4_3 + _A65 * k5_3)
        acc_end = _hermite(row, acc, acc_dot, dt_grid, t + h)
        k6_0, k6_1, k6_2, k6_3 = _rhs(model, g0, g1, g2, g3, acc_end, p)
        n0 = y0 + h * (_B1 * k1_0 + _B3 * k3_0 + _B4 * k4_0 + _B5 * k5_0 + _B6 * k6_0)
        n1 = y1 + h * (_B1 * k1_1 + _B3 * k3_1 + _B4 * k4_1 + _B5 * k5_1 + _B6 * k6_1)
        n2 = y2 + h * (_B1 * k1_2 + _B3 * k3_2 + _B4 * k4_2 + _B5 * k5_2 + _B6 * k6_2)
        n3 = y3 + h * (_B1 * k1_3 + _B3 * k3_3 + _B4 * k4_3 + _B5 * k5_3 + _B6 * k6_3)
        k7_0, k7_1, k7_2, k7_3 = _rhs(model, n0, n1, n2, n3, acc_end, p)
        # --- error estimate (5th minus 4th order solution)
        e0 = h * (_E1 * k1_0 + _E3 * k3_0 + _E4 * k4_0 + _E5 * k5_0 + _E6 * k6_0 + _E7 * k7_0)
        e1 = h * (_E1 * k1_1 + _E3 * k3_1 + _E4 * k4_1 + _E5 * k5_1 + _E6 * k6_1 + _E7 * k7_1)
        e2 = h * (_E1 * k1_2 + _E3 * k3_2 + _E4 * k4_2 + _E5 * k5_2 + _E6 * k6_2 + _E7 * k7_2)
        e3 = h * (_E1 * k1_3 + _E3 * k3_3 + _E4 * k4_3 + _E5 * k5_3 + _E6 * k6_3 + _E7 * k7_3)
        err = (_err_term(e0, y0, n0, s0, rtol) + _err_term(e1, y1, n1, s1, rtol)
               + _err_term(e2, y2, n2, s2, rtol) + _err_term(e3, y3, n3, s3, rtol))
        err = math.sqrt(err / n_comp)
        if not math.isfinite(err):
            n_rej += 1
            h = 0.1 * h
            rejected = True
            if h < h_floor:
                status, reason = STATUS_DIVERGED, REASON_NONFINITE
                break
            continue
        if err > 1.0:
            n_rej += 1
            h = h * max(0.2, 0.9 * math.exp(-0.2 * math.log(err)))
            rejected = True
            if h < h_floor:
                status, reason = STATUS_DIVERGED, REASON_STEP_UNDERFLOW
                break
            continue
        # --- accepted step
        n_acc += 1
        if h < h_min_acc and not landing and n_acc > 10:  # skip the ramp-up from the initial guess
            h_min_acc = h
        t = t_next if landing else t + h
        y0, y1, y2, y3 = n0, n1, n2, n3
        k1_0, k1_1, k1_2, k1_3 = k7_0, k7_1, k7_2, k7_3
        a0 = abs(y0)
        if a0 > peak:
            peak = a0
        if a0 > p[P_THETA_OVER]:
            status = STATUS_OVERTURNED
            break
        if model == MODEL_COUPLED:
            if (y2 > p[P_Z_MAX] or y2 < p[P_Z_MIN] or abs(y1) > p[P_RATE_MAX]):
                status, reason = STATUS_DIVERGED, REASON_OUT_OF_BOUNDS
                break
            if y2 + p[P_B] * abs(math.sin(y0)) <= 0.0:         # flight: no point in contact
                if flight_start < 0.0:
                    flight_start = t
                elif t - flight_start > p[P_MAX_FLIGHT]:
                    status, reason = STATUS_DIVERGED, REASON_LONG_FLIGHT
                    break
            else:
                flight_start = -1.0
        elif abs(y1) > p[P_RATE_MAX]:
            status, reason = STATUS_DIVERGED, REASON_OUT_OF_BOUNDS
            break
        elif a0 > p[P_THETA_CAP]:                             # cubic condensation, softening bed
            status, reason = STATUS_DIVERGED, REASON_NO_EQUILIBRIUM
            break
        if landing:
            out_theta[row, i_out] = y0
            out_theta_dot[row, i_out] = y1
            out_z[row, i_out] = y2
            out_z_dot[row, i_out] = y3
            out_uplift[row, i_out] = _in_uplift(model, y0, y2, p)
            i_out += 1
        # --- next step size (PI control, Hairer's DOPRI5 constants)
        log_err = math.log(max(err, 1e-10))
        fac = 0.9 * math.exp(-0.17 * log_err + 0.04 * log_err_old)
        fac = min(5.0, max(0.2, fac))
        if rejected:
            fac = min(fac, 1.0)
        rejected = False
        log_err_old = max(log_err, LOG_1EM4)
        h_new = h * fac
        if landing and h_proposed > h:
            h_new = max(h_new, min(h_proposed, h_max))
        h = h_new
    if not math.isfinite(peak):
        peak = 0.0
    return status, reason, peak, n_acc, n_rej, h_min_acc


@numba.njit(cache=True, parallel=True)
def integrate_chunk(model, acc, acc_dot, dt_grid, t_out, p, y_init, scale, rtol, h_max, max_steps,
                    out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted,
                    n_rejected, h_min):
    """Integrate every row of ``acc`` (one sample per row) in parallel; fills the outputs.

    ``acc``, ``acc_dot``: ground acceleration [m/s^2] and its rate [m/s^3] on the grid
    ``j dt_grid``; ``t_out`` output times [s]; ``p`` from :func:`pack_parameters`;
    ``y_init`` the initial ``(theta, theta', z_cb, z_cb')``; ``scale`` absolute tolerances.
    """
    for row in numba.prange(acc.shape[0]):
        st, rs, pk, na, nr, hm = integrate_sample(model, row, acc, acc_dot, dt_grid, t_out, p, y_init,
                                                  scale, rtol, h_max, max_steps, out_theta, out_theta_dot,
                                                  out_z, out_z_dot, out_uplift)
        status[row] = st
        reason[row] = rs
        peak[row] = pk
        n_accepted[row] = na
        n_rejected[row] = nr
        h_min[row] = hm
