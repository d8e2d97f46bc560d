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

Method and how it is checked: ``docs/method.md#coupled-and-condensed-models``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from numba import types

from screening.kernels import dopri
from screening.kernels.interpolation import hermite
from screening.kernels.signatures import function_type, record_type, sdof_coefficients_signature
from screening.physics.contact import law_resultants_trig_jit
from screening.status import DivergenceReason, SampleStatus

#: Which equations a sample integrates.
MODEL_COUPLED = 0
MODEL_CONDENSED = 1

STATUS_OK = int(SampleStatus.ok)
STATUS_OVERTURNED = int(SampleStatus.overturned)
STATUS_DIVERGED = int(SampleStatus.diverged)

REASON_NONE = int(DivergenceReason.none)
REASON_NONFINITE = int(DivergenceReason.non_finite_state)
REASON_LONG_FLIGHT = int(DivergenceReason.long_flight)
REASON_OUT_OF_BOUNDS = int(DivergenceReason.out_of_bounds)
REASON_STEP_UNDERFLOW = int(DivergenceReason.step_underflow)
REASON_STEP_BUDGET = int(DivergenceReason.step_budget)
REASON_NO_EQUILIBRIUM = int(DivergenceReason.no_equilibrium)

#: Per-sample-run parameters of the compiled kernels (SI units), built by :func:`model_record`.
MODEL = np.dtype([
    ("m", "f8"), ("g", "f8"), ("h", "f8"), ("I_cm", "f8"), ("b", "f8"),      # block
    ("k", "f8"), ("eps", "f8"), ("w_rate", "f8"), ("w_indentation", "f8"),  # bed (law's weights)
    ("m_sdof", "f8"),                                                        # I_cm + m h^2 [kg m2]
    ("theta_over", "f8"),        # overturning angle atan(b/h) [rad]
    ("theta_ul", "f8"),          # uplift threshold of the condensation [rad] (condensed uplift flag)
    ("theta_cap", "f8"),         # capacity angle of the condensation [rad] (inf: none)
    ("max_flight", "f8"),        # longest flight before a sample is called diverged [s]
    ("z_max", "f8"), ("z_min", "f8"), ("rate_max", "f8"),   # physical bounds of the coupled state
])


def model_record(block, foundation, cond, max_flight_time=0.5):
    """The :data:`MODEL` record of scalar model objects; ``cond``: the condensation of condensed runs."""
    m, g, h, b = float(block.m), float(block.g), float(block.h), float(block.b)
    rec = np.zeros((), dtype=MODEL)
    values = dict(m=m, g=g, h=h, I_cm=float(block.I_cm), b=b, k=float(foundation.k), eps=float(foundation.eps),
                  w_rate=float(foundation.damping_weights[0]), w_indentation=float(foundation.damping_weights[1]),
                  m_sdof=float(block.m_sdof), theta_over=float(block.slenderness),
                  theta_ul=float(cond.uplift_threshold(block, foundation)),
                  theta_cap=float(cond.capacity_angle(block, foundation)), max_flight=float(max_flight_time),
                  z_max=b,                              # sinking half the base width into the bed: blown up
                  z_min=-2.0 * h,                       # jumping a block height off the bed: blown up
                  rate_max=1e3 * math.sqrt(g / h))      # ~1000 x the free-fall rocking rate: blown up
    for name, value in values.items():
        rec[name] = value
    return rec


# ----------------------------------------------------------------------------- right-hand sides
@numba.njit(cache=True)
def coupled_accelerations(theta, theta_dot, z_cb, z_cb_dot, x_g_ddot, p):
    """``(theta'', z_cb'')`` [rad/s^2, m/s^2] of the coupled eqs. (7)–(8) with ``z_g'' = 0``.

    Eliminating ``z_cb''`` from (8) with (7):
    ``(I_cm + m h^2 cos^2) theta'' = m h x_g'' cos - M_cb + h F_cb sin + m h^2 theta'^2 sin cos``,
    ``z_cb'' = g - F_cb/m - h (theta'^2 cos + theta'' sin)``.
    """
    m, g, h = p.m, p.g, p.h
    s = math.sin(theta)
    c = math.cos(theta)
    force, moment = law_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, p.b, p.k, p.eps, p.w_rate,
                                            p.w_indentation)
    mh = m * h
    theta_ddot = ((mh * x_g_ddot * c - moment + h * force * s + mh * h * theta_dot * theta_dot * s * c)
                  / (p.I_cm + mh * h * c * c))
    z_ddot = g - force / m - h * (theta_dot * theta_dot * c + theta_ddot * s)
    return theta_ddot, z_ddot


@numba.njit(cache=True)
def condensed_acceleration(damping_stiffness, cond, theta, theta_dot, x_g_ddot, p):
    """``theta''`` [rad/s^2] of the condensed SDOF, eq. (22): ``(m h x_g'' - C theta' - K theta) / m_sdof``.

    ``damping_stiffness(cond, theta) -> (C, K)``: the condensation's compiled function and record.
    """
    damping, stiffness = damping_stiffness(cond, theta)
    return (p.m * p.h * x_g_ddot - damping * theta_dot - stiffness * theta) / p.m_sdof


@numba.njit(cache=True)
def _rhs(model, damping_stiffness, cond, y0, y1, y2, y3, acc, p):
    if model == MODEL_COUPLED:
        a1, a3 = coupled_accelerations(y0, y1, y2, y3, acc, p)
        return y1, a1, y3, a3
    return y1, condensed_acceleration(damping_stiffness, cond, y0, y1, acc, p), 0.0, 0.0


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
    return hermite(acc[row, j], acc[row, j + 1], acc_dot[row, j], acc_dot[row, j + 1], x - j, dt)


@numba.njit(cache=True)
def _in_uplift(model, theta, z_cb, p):
    if model == MODEL_COUPLED:
        return z_cb - p.b * abs(math.sin(theta)) < 0.0
    return abs(theta) > p.theta_ul


# The shared Dormand–Prince 5(4) tableau (screening.kernels.dopri) as scalars: 4 unrolled states.
from screening.kernels.dopri import (  # noqa: E402  (scalar tableau, one home)
    A21 as _A21, A31 as _A31, A32 as _A32, A41 as _A41, A42 as _A42, A43 as _A43,
    A51 as _A51, A52 as _A52, A53 as _A53, A54 as _A54, A61 as _A61, A62 as _A62, A63 as _A63,
    A64 as _A64, A65 as _A65, B1 as _B1, B3 as _B3, B4 as _B4, B5 as _B5, B6 as _B6,
    C2 as _C2, C3 as _C3, C4 as _C4, C5 as _C5, E1 as _E1, E3 as _E3, E4 as _E4, E5 as _E5,
    E6 as _E6, E7 as _E7)


@numba.njit(cache=True)
def _err_term(e, y, ynew, scale, rtol):
    sc = scale + rtol * max(abs(y), abs(ynew))
    r = e / sc
    return r * r


@numba.njit(cache=True)
def integrate_sample(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out, models, y_init, scale,
                     rtol, h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift):
    """Integrate one sample over ``t_out``; fill row ``row`` of the output arrays.

    ``conds[0]``, ``models[0]``: the condensation's and the model's records (see
    :func:`_integrate_chunk`).  ``out_z``, ``out_z_dot`` receive ``z_cb``, ``z_cb'`` (zero for the
    condensed model).

    Returns ``(status, reason, peak_abs_theta, n_accepted, n_rejected, h_min_accepted)``.
    After overturning or divergence the remaining outputs are NaN.
    """
    cond = conds[0]
    p = models[0]
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
    log_err_old = dopri.LOG_ERR_START
    flight_start = -1.0
    k1_0, k1_1, k1_2, k1_3 = _rhs(model, damping_stiffness, cond, y0, y1, y2, y3, _hermite(row, acc, acc_dot, dt_grid, t), p)
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
        k2_0, k2_1, k2_2, k2_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C2 * h), p)
        g0 = y0 + h * (_A31 * k1_0 + _A32 * k2_0)
        g1 = y1 + h * (_A31 * k1_1 + _A32 * k2_1)
        g2 = y2 + h * (_A31 * k1_2 + _A32 * k2_2)
        g3 = y3 + h * (_A31 * k1_3 + _A32 * k2_3)
        k3_0, k3_1, k3_2, k3_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C3 * h), p)
        g0 = y0 + h * (_A41 * k1_0 + _A42 * k2_0 + _A43 * k3_0)
        g1 = y1 + h * (_A41 * k1_1 + _A42 * k2_1 + _A43 * k3_1)
        g2 = y2 + h * (_A41 * k1_2 + _A42 * k2_2 + _A43 * k3_2)
        g3 = y3 + h * (_A41 * k1_3 + _A42 * k2_3 + _A43 * k3_3)
        k4_0, k4_1, k4_2, k4_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C4 * h), p)
        g0 = y0 + h * (_A51 * k1_0 + _A52 * k2_0 + _A53 * k3_0 + _A54 * k4_0)
        g1 = y1 + h * (_A51 * k1_1 + _A52 * k2_1 + _A53 * k3_1 + _A54 * k4_1)
        g2 = y2 + h * (_A51 * k1_2 + _A52 * k2_2 + _A53 * k3_2 + _A54 * k4_2)
        g3 = y3 + h * (_A51 * k1_3 + _A52 * k2_3 + _A53 * k3_3 + _A54 * k4_3)
        k5_0, k5_1, k5_2, k5_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                      _hermite(row, acc, acc_dot, dt_grid, t + _C5 * h), p)
        g0 = y0 + h * (_A61 * k1_0 + _A62 * k2_0 + _A63 * k3_0 + _A64 * k4_0 + _A65 * k5_0)
        g1 = y1 + h * (_A61 * k1_1 + _A62 * k2_1 + _A63 * k3_1 + _A64 * k4_1 + _A65 * k5_1)
        g2 = y2 + h * (_A61 * k1_2 + _A62 * k2_2 + _A63 * k3_2 + _A64 * k4_2 + _A65 * k5_2)
        g3 = y3 + h * (_A61 * k1_3 + _A62 * k2_3 + _A63 * k3_3 + _A64 * k4_3 + _A65 * k5_3)
        acc_end = _hermite(row, acc, acc_dot, dt_grid, t + h)
        k6_0, k6_1, k6_2, k6_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3, acc_end, p)
        n0 = y0 + h * (_B1 * k1_0 + _B3 * k3_0 + _B4 * k4_0 + _B5 * k5_0 + _B6 * k6_0)
        n1 = y1 + h * (_B1 * k1_1 + _B3 * k3_1 + _B4 * k4_1 + _B5 * k5_1 + _B6 * k6_1)
        n2 = y2 + h * (_B1 * k1_2 + _B3 * k3_2 + _B4 * k4_2 + _B5 * k5_2 + _B6 * k6_2)
        n3 = y3 + h * (_B1 * k1_3 + _B3 * k3_3 + _B4 * k4_3 + _B5 * k5_3 + _B6 * k6_3)
        k7_0, k7_1, k7_2, k7_3 = _rhs(model, damping_stiffness, cond, n0, n1, n2, n3, acc_end, p)
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
            h = h * dopri.rejected_step_factor_log(math.log(err))
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
        if a0 > p.theta_over:
            status = STATUS_OVERTURNED
            break
        if model == MODEL_COUPLED:
            if (y2 > p.z_max or y2 < p.z_min or abs(y1) > p.rate_max):
                status, reason = STATUS_DIVERGED, REASON_OUT_OF_BOUNDS
                break
            if y2 + p.b * abs(math.sin(y0)) <= 0.0:         # flight: no point in contact
                if flight_start < 0.0:
                    flight_start = t
                elif t - flight_start > p.max_flight:
                    status, reason = STATUS_DIVERGED, REASON_LONG_FLIGHT
                    break
            else:
                flight_start = -1.0
        elif abs(y1) > p.rate_max:
            status, reason = STATUS_DIVERGED, REASON_OUT_OF_BOUNDS
            break
        elif a0 > p.theta_cap:                             # cubic condensation, softening bed
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
        fac, log_err = dopri.pi_step_factor(err, log_err_old)
        if rejected:
            fac = min(fac, 1.0)
        rejected = False
        log_err_old = max(log_err, dopri.LOG_ERR_START)
        h_new = h * fac
        if landing and h_proposed > h:
            h_new = max(h_new, min(h_proposed, h_max))
        h = h_new
    if not math.isfinite(peak):
        peak = 0.0
    return status, reason, peak, n_acc, n_rej, h_min_acc


def _integrate_chunk(model, damping_stiffness, conds, acc, acc_dot, dt_grid, t_out, models, y_init, scale, rtol,
                     h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason,
                     n_accepted, n_rejected, h_min):
    """Integrate every row of ``acc`` (one sample per row) in parallel; fills the outputs.

    ``damping_stiffness``, ``conds[0]``: the condensation's compiled ``(C, K)`` and its record
    (read by ``model = MODEL_CONDENSED`` only); ``acc``, ``acc_dot``: ground acceleration [m/s^2]
    and its rate [m/s^3] on the grid ``j dt_grid``; ``t_out`` output times [s]; ``models[0]``: the
    :data:`MODEL` record; ``y_init`` the initial ``(theta, theta', z_cb, z_cb')``; ``scale``
    absolute tolerances.  Compiled per condensation record type by :func:`chunk_integrator`.
    """
    for row in numba.prange(acc.shape[0]):
        st, rs, pk, na, nr, hm = integrate_sample(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out,
                                                  models, y_init, scale, rtol, h_max, max_steps, out_theta,
                                                  out_theta_dot, out_z, out_z_dot, out_uplift)
        status[row] = st
        reason[row] = rs
        peak[row] = pk
        n_accepted[row] = na
        n_rejected[row] = nr
        h_min[row] = hm


_INTEGRATORS = {}


def chunk_integrator(record_dtype):
    """The compiled :func:`_integrate_chunk` for a condensation whose records have ``record_dtype``.

    Explicit signature (the condensation's ``(C, K)`` function is a first-class argument), so it
    is compiled once per record type and cached on disk.
    """
    if record_dtype not in _INTEGRATORS:
        f8, i8 = types.float64, types.int64
        a1 = types.float64[::1]
        a2 = types.float64[:, ::1]
        a2_rows = types.Array(types.float64, 2, "C")
        sig = types.void(i8, function_type(sdof_coefficients_signature(record_dtype)),
                         types.Array(record_type(record_dtype), 1, "C"), a2, a2, f8, a1,
                         types.Array(record_type(MODEL), 1, "C"), a1, a1, f8, f8, i8,
                         a2_rows, a2_rows, a2_rows, a2_rows, types.Array(types.boolean, 2, "C"),
                         a1, types.int64[::1], types.int64[::1], types.int64[::1], types.int64[::1], a1)
        _INTEGRATORS[record_dtype] = numba.njit(sig, cache=True, parallel=True)(_integrate_chunk)
    return _INTEGRATORS[record_dtype]
