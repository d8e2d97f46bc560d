"""Compiled kernels of the Monte Carlo engine: right-hand sides and an adaptive integrator.

Everything here is scalar numba code called once per sample (``prange`` over samples).
The public, documented entry point is :func:`screening.solvers.montecarlo.monte_carlo`.

Integrators: the explicit Dormand–Prince 5(4) pair (FSAL, Hairer's PI step control; the
default and the reference) or the linearly implicit Rosenbrock pair RODAS 4(3) (L-stable, for
beds whose damping makes the contact dynamics stiff), chosen per run by the ``integrator``
field of the model record; both measure the error component-wise against ``atol_i + rtol |y_i|``
with absolute scales set by the caller from the physics (``theta_ul``, static indentation,
natural frequencies).  Steps
are clipped to land exactly on the output instants.  The modulated ground acceleration
``q f`` and its exact rate ``q f' + q' f`` are given on the synthesis grid; between grid
points the input is their cubic Hermite interpolant.  Samples are independent, so the
``prange`` loop gives the same numbers for any number of threads or chunking.

Method and how it is checked: ``docs/method.md#coupled-and-condensed-models`` and
``docs/montecarlo_numerics.md`` (the two integrators, stiff beds, cost).  The equations integrated live in
:mod:`screening.kernels.mcs_equations`, the ground input between grid points in
:mod:`screening.kernels._sample_steps` (package-internal, shared with the stiff-bed kernels); the
public names of the equations are importable from here too.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from numba import types

from screening.kernels import dopri
from screening.kernels import rodas as _ro
from screening.core.signatures import function_type, record_type, sdof_coefficients_signature
from screening.kernels.mcs_equations import (INTEGRATOR_EXACT, INTEGRATOR_RODAS,
                                             INTEGRATORS, MODEL, MODEL_CONDENSED, MODEL_COUPLED, NO_PROPAGATOR,
                                             condensed_acceleration, coupled_accelerations,
                                             coupled_accelerations_trig, full_contact_propagator,
                                             input_gain, model_record, vertical_gain)
from screening.kernels._sample_steps import (NO_VERTICAL, err_term, ground_input, ground_input_rate, store_outcome,
                                             vertical_row)
from screening.core.status import DivergenceReason, SampleStatus

__all__ = []

#: Columns of a chunk's step census (accepted steps per sample, by the regime at the step's end): adaptive
#: steps in full contact, in partial contact (uplift), in flight, exact full-contact steps; then the exact
#: steps refused, near uplift and by their error estimate.
CENSUS = ("full_contact", "partial_contact", "flight", "exact", "refused_near_uplift", "refused_error")


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
REASON_LIFT_OFF = int(DivergenceReason.lift_off)


# The shared Dormand–Prince 5(4) tableau (screening.kernels.dopri) as scalars: 4 unrolled states.
from screening.kernels.dopri import (  # noqa: E402  (scalar tableau, one home)
    A21 as _A21, A31 as _A31, A32 as _A32, A41 as _A41, A42 as _A42, A43 as _A43,
    A51 as _A51, A52 as _A52, A53 as _A53, A54 as _A54, A61 as _A61, A62 as _A62, A63 as _A63,
    A64 as _A64, A65 as _A65, B1 as _B1, B3 as _B3, B4 as _B4, B5 as _B5, B6 as _B6,
    C2 as _C2, C3 as _C3, C4 as _C4, C5 as _C5, E1 as _E1, E3 as _E3, E4 as _E4, E5 as _E5,
    E6 as _E6, E7 as _E7)


@numba.njit(cache=True)
def _rhs(model, damping_stiffness, cond, y0, y1, y2, y3, acc, p):
    """Right-hand side at the state ``y`` under the ground input ``acc = (x_g'', a_v)`` [m/s^2]."""
    if model == MODEL_COUPLED:
        a1, a3 = coupled_accelerations(y0, y1, y2, y3, acc[0], p, acc[1])
        return y1, a1, y3, a3
    return y1, condensed_acceleration(damping_stiffness, cond, y0, y1, acc[0], p, acc[1]), 0.0, 0.0


@numba.njit(cache=True)
def _in_uplift(model, theta, z_cb, p):
    if model == MODEL_COUPLED:
        return z_cb - p.b * abs(math.sin(theta)) < 0.0
    return abs(theta) > p.theta_ul


@numba.njit(cache=True)
def _record(model, row, i, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift):
    out_theta[row, i] = y0
    out_theta_dot[row, i] = y1
    out_z[row, i] = y2
    out_z_dot[row, i] = y3
    out_uplift[row, i] = _in_uplift(model, y0, y2, p)


@numba.njit(cache=True)
def _start_outputs(model, row, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift):
    """The initial state in column 0 of row ``row``, NaN (no uplift) in the others."""
    _record(model, row, 0, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift)
    for i in range(1, out_theta.shape[1]):
        out_theta[row, i] = np.nan
        out_theta_dot[row, i] = np.nan
        out_z[row, i] = np.nan
        out_z_dot[row, i] = np.nan
        out_uplift[row, i] = False


@numba.njit(cache=True, inline="always")
def _start(model, row, t_out, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift):
    """Outputs of row ``row`` started (:func:`_start_outputs`) and the integrator's counters:
    ``(t, peak, status, reason, n_accepted, n_rejected, h_min_accepted, flight_start, h_floor, i_out)``."""
    _start_outputs(model, row, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift)
    h_floor = 1e-12 * (t_out[t_out.shape[0] - 1] - t_out[0] + 1.0)
    return t_out[0], abs(y0), STATUS_OK, REASON_NONE, 0, 0, np.inf, -1.0, h_floor, 1


@numba.njit(cache=True)
def _check_state(model, y0, y1, y2, t, flight_start, p, a_v):
    """``(status, reason, flight_start)`` after an accepted step to the state ``y`` at ``t``.

    ``flight_start``: when the current flight began [s] (-1: in contact); ``a_v`` [m/s^2] the vertical
    ground acceleration at ``t`` (the condensed model cannot leave the ground: ``g + a_v < 0`` stops it).
    """
    a0 = abs(y0)
    if a0 > p.theta_over:
        return STATUS_OVERTURNED, REASON_NONE, flight_start
    if model != MODEL_COUPLED and p.g + a_v < 0.0:
        return STATUS_DIVERGED, REASON_LIFT_OFF, flight_start
    if model == MODEL_COUPLED:
        if y2 > p.z_max or y2 < p.z_min or abs(y1) > p.rate_max:
            return STATUS_DIVERGED, REASON_OUT_OF_BOUNDS, flight_start
        if y2 + p.b * abs(math.sin(y0)) <= 0.0:             # flight: no point in contact
            if flight_start < 0.0:
                return STATUS_OK, REASON_NONE, t
            if t - flight_start > p.max_flight:
                return STATUS_DIVERGED, REASON_LONG_FLIGHT, flight_start
            return STATUS_OK, REASON_NONE, flight_start
        return STATUS_OK, REASON_NONE, -1.0
    if abs(y1) > p.rate_max:
        return STATUS_DIVERGED, REASON_OUT_OF_BOUNDS, flight_start
    if a0 > p.theta_cap:                                   # cubic condensation, softening bed
        return STATUS_DIVERGED, REASON_NO_EQUILIBRIUM, flight_start
    return STATUS_OK, REASON_NONE, flight_start


@numba.njit(cache=True, inline="always")
def _landing(t, h, h_max, t_next):
    """``(h, h_proposed, landing)``: the step ``min(h, h_max)`` shortened to land on ``t_next`` when
    it would reach it (``landing``); ``h_proposed`` the step before shortening."""
    h = min(h, h_max)
    if t + h >= t_next - 1e-9 * h:
        return t_next - t, h, True
    return h, h, False


@numba.njit(cache=True, inline="always")
def _next_step(h, fac, landing, h_proposed, h_max):
    """The step after an accepted step ``h`` with growth factor ``fac``; after a landing that had
    shortened the step, at least the step proposed before the landing."""
    h_new = h * fac
    if landing and h_proposed > h:
        h_new = max(h_new, min(h_proposed, h_max))
    return h_new


@numba.njit(cache=True, inline="always")
def _error_norm(e0, e1, e2, e3, y0, y1, y2, y3, n0, n1, n2, n3, s0, s1, s2, s3, rtol, n_comp):
    """RMS over the ``n_comp`` integrated components of the local error ``e`` against
    ``scale + rtol max(|y|, |y_new|)`` (accept at <= 1)."""
    err = (err_term(e0, y0, n0, s0, rtol) + err_term(e1, y1, n1, s1, rtol)
           + err_term(e2, y2, n2, s2, rtol) + err_term(e3, y3, n3, s3, rtol))
    return math.sqrt(err / n_comp)


@numba.njit(cache=True, inline="always")
def _shrink(err, h, factor, h_floor):
    """``(h_new, reason)`` after a rejected step: ``h factor`` (``h / 10`` for a non-finite error);
    ``reason`` is ``REASON_NONE`` unless the step fell below ``h_floor`` (the sample diverged)."""
    if not math.isfinite(err):
        h = 0.1 * h
        return h, REASON_NONFINITE if h < h_floor else REASON_NONE
    h = h * factor
    return h, REASON_STEP_UNDERFLOW if h < h_floor else REASON_NONE


@numba.njit(cache=True, inline="always")
def step_peak(peak, h, theta0, rate0, theta1, rate1):
    """The larger of ``peak`` and the largest ``|theta|`` inside one accepted step.

    Parameters
    ----------
    peak : float
        Largest ``|theta|`` so far [rad].
    h : float
        Step [s].
    theta0, rate0 : float
        Rotation [rad] and its rate [rad s-1] at the start of the step.
    theta1, rate1 : float
        The same at its end.

    Returns
    -------
    float
        ``max(peak, |theta1|, |p(s*)|)`` [rad], with ``p`` the cubic Hermite interpolant of the step and
        ``s*`` its extremum inside the step where the rate changes sign.

    Notes
    -----
    On ``s = (t - t0) / h`` in ``[0, 1]`` the interpolant is

    .. math:: p(s) = H_{00}(s) \\theta_0 + H_{10}(s) h \\dot\\theta_0 + H_{01}(s) \\theta_1 + H_{11}(s) h \\dot\\theta_1

    with the cubic Hermite basis ``H``.  Its derivative ``h dp/dt = a s^2 + b s + c`` with
    ``a = 6 (theta0 - theta1) + 3 h (rate0 + rate1)``, ``b = 6 (theta1 - theta0) - h (4 rate0 + 2 rate1)``,
    ``c = h rate0`` has one root in ``(0, 1)`` where ``rate0 rate1 < 0`` (``a + b + c = h rate1``).  The peak
    over the accepted steps alone misses the true maximum by ``O(h^2)`` (``theta'' h^2 / 8`` at most); the
    interpolant's error is ``O(h^4)`` [1], so the peak no longer depends on the step the tolerance allows.

    References
    ----------
    .. [1] E. Hairer, S. P. Norsett and G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
       Springer (1993), sec. II.6 (dense output).
    """
    peak = max(peak, abs(theta1))
    if not rate0 * rate1 < 0.0:
        return peak
    a = 6.0 * (theta0 - theta1) + 3.0 * h * (rate0 + rate1)
    b = 6.0 * (theta1 - theta0) - h * (4.0 * rate0 + 2.0 * rate1)
    c = h * rate0
    disc = max(b * b - 4.0 * a * c, 0.0)
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    s = 0.5 if q == 0.0 else c / q                    # the root of smaller magnitude (stable form)
    if not 0.0 <= s <= 1.0 and a != 0.0:
        s = q / a
    s = min(max(s, 0.0), 1.0)
    s2, s3 = s * s, s * s * s
    value = ((2.0 * s3 - 3.0 * s2 + 1.0) * theta0 + (s3 - 2.0 * s2 + s) * h * rate0
             + (3.0 * s2 - 2.0 * s3) * theta1 + (s3 - s2) * h * rate1)
    return max(peak, abs(value))


@numba.njit(cache=True, inline="always")
def _accept(model, row, h, t, t_next, landing, i_out, n_acc, h_min_acc, peak, flight_start, y0, y1, y2, y3, p,
            out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, a_v, census, exact):
    """Bookkeeping of an accepted step to the state ``y`` (``a_v``: the vertical ground acceleration at
    its end): counts (and the ``census`` row, ``exact``: an exact step), smallest step, time, peak, status
    checks and the output at a landing.  Returns ``(t, i_out, n_acc, h_min_acc, peak, status, reason,
    flight_start)``."""
    n_acc += 1
    if census.shape[0] > row:
        if exact:
            census[row, 3] += 1
        elif model == MODEL_COUPLED and y2 + p.b * abs(math.sin(y0)) <= 0.0:
            census[row, 2] += 1
        elif model == MODEL_COUPLED and y2 - p.b * abs(math.sin(y0)) < 0.0:
            census[row, 1] += 1
        else:
            census[row, 0] += 1
    if h < h_min_acc and not landing and n_acc > 10:  # skip the ramp-up from the initial guess
        h_min_acc = h
    t = t_next if landing else t + h
    peak = max(peak, abs(y0))
    status, reason, flight_start = _check_state(model, y0, y1, y2, t, flight_start, p, a_v)
    if status == STATUS_OK and landing:
        _record(model, row, i_out, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift)
        i_out += 1
    return t, i_out, n_acc, h_min_acc, peak, status, reason, flight_start


@numba.njit(cache=True)
def integrate_sample(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out, models, y_init, scale,
                     rtol, h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, prop, census):
    """Integrate one sample over ``t_out``; fill row ``row`` of the output arrays.

    ``models[0].integrator`` picks the method (:func:`_sample_loop`): the explicit Dormand-Prince 5(4) pair
    (``"dopri"``, the reference), the linearly implicit RODAS 4(3) pair (``"rodas"``) or the explicit pair with
    exact steps in quiet full contact (``"exact"``).  After overturning or divergence the remaining outputs are NaN.

    Parameters
    ----------
    model : int
        :data:`MODEL_COUPLED` or :data:`MODEL_CONDENSED`.
    damping_stiffness : numba function
        The condensation's compiled ``(cond, theta) -> (C, K)`` (read by the condensed model only).
    conds : numpy.ndarray
        One-element array of the condensation's record.
    row : int
        The sample (row of ``acc`` and of the outputs).
    acc : tuple of numpy.ndarray
        ``(horizontal, vertical)`` ground accelerations [m/s^2] on the grid ``j dt_grid``: the inertial
        ``x_g''`` one row per sample; the vertical ``a_v`` (positive up) one row per sample, one row for
        all, or ``NO_VERTICAL``.
    acc_dot : tuple of numpy.ndarray
        Their rates [m/s^3], same layout.
    dt_grid : float
        Step of the input grid [s] (cubic Hermite interpolation in between).
    t_out : numpy.ndarray
        Output times [s].
    models : numpy.ndarray
        One-element array of the :data:`MODEL` record (:func:`model_record`).
    y_init : numpy.ndarray
        Initial ``(theta, theta', z_cb, z_cb')`` [rad, rad/s, m, m/s].
    scale : numpy.ndarray
        Absolute error scales of the four states (times ``rtol``).
    rtol : float
        Relative tolerance [1].
    h_max : float
        Largest step [s].
    max_steps : int
        Step budget of the sample.
    out_theta, out_theta_dot, out_z, out_z_dot : numpy.ndarray
        Histories (samples x output times) [rad, rad/s, m, m/s], row ``row`` written in place
        (``z_cb`` columns zero for the condensed model; NaN after overturning or divergence).
    out_uplift : numpy.ndarray of bool
        Uplift flag at the output times, same layout.
    prop : numpy.ndarray
        :func:`full_contact_propagator` of the run (read by the exact integrator; else :data:`NO_PROPAGATOR`).
    census : numpy.ndarray
        ``(n_rows, 6)`` int64 step counts by :data:`CENSUS`, row ``row`` incremented (no rows: not counted).

    Returns
    -------
    tuple
        ``(status, reason, peak_abs_theta [rad], n_accepted, n_rejected, h_min_accepted [s])``: status
        ``STATUS_OK``, ``STATUS_OVERTURNED`` or ``STATUS_DIVERGED`` with a ``REASON_*`` code.

    Notes
    -----
    The equations are the coupled eqs. (7)-(8) in [1]_ or the condensed eq. (22)
    (:mod:`screening.kernels.mcs_equations`).  The explicit pair [2]_ with the PI controller of [3]_; RODAS
    [4]_ solves six linear systems with ``I / (gamma h) - J`` a step (``J`` by forward differences at the step's
    start, exact ``df/dt`` from the input's rate; the kinematic rows reduce each solve to 2 x 2); the exact
    steps are ETD2 [5]_ on the full-contact linearization.  All three share the error norm, the output
    landing, the status checks and the returns.  ``tests/unit/kernels/test_mcs_kernels.py`` holds them against
    scipy and each other.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [dormand1980] in the bibliography.
    .. [3] [hairer1993] in the bibliography.
    .. [4] E. Hairer and G. Wanner, Solving Ordinary Differential Equations II: Stiff and
       Differential-Algebraic Problems, 2nd ed., Springer (1996), section IV.7.
    .. [5] [hochbruck2010] in the bibliography; ``docs/montecarlo_numerics.md`` (the integrators).
    """
    return _sample_loop(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out, models, y_init, scale, rtol,
                        h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, prop, census,
                        models[0].integrator)


@numba.njit(cache=True, inline="always")
def _dopri_stages(model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, h, y0, y1, y2, y3, k1_0, k1_1, k1_2,
                  k1_3, p):
    """One Dormand-Prince 5(4) step of ``h`` from ``y`` at ``t`` (``k1``: the rate there): ``(n, k7, e, acc_end)``,
    the new state, its rate, the local error estimate and the ground input at ``t + h``."""
    g0 = y0 + h * _A21 * k1_0
    g1 = y1 + h * _A21 * k1_1
    g2 = y2 + h * _A21 * k1_2
    g3 = y3 + h * _A21 * k1_3
    k2_0, k2_1, k2_2, k2_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                  ground_input(row, acc, acc_dot, dt_grid, t + _C2 * h), p)
    g0 = y0 + h * (_A31 * k1_0 + _A32 * k2_0)
    g1 = y1 + h * (_A31 * k1_1 + _A32 * k2_1)
    g2 = y2 + h * (_A31 * k1_2 + _A32 * k2_2)
    g3 = y3 + h * (_A31 * k1_3 + _A32 * k2_3)
    k3_0, k3_1, k3_2, k3_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                  ground_input(row, acc, acc_dot, dt_grid, t + _C3 * h), p)
    g0 = y0 + h * (_A41 * k1_0 + _A42 * k2_0 + _A43 * k3_0)
    g1 = y1 + h * (_A41 * k1_1 + _A42 * k2_1 + _A43 * k3_1)
    g2 = y2 + h * (_A41 * k1_2 + _A42 * k2_2 + _A43 * k3_2)
    g3 = y3 + h * (_A41 * k1_3 + _A42 * k2_3 + _A43 * k3_3)
    k4_0, k4_1, k4_2, k4_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                  ground_input(row, acc, acc_dot, dt_grid, t + _C4 * h), p)
    g0 = y0 + h * (_A51 * k1_0 + _A52 * k2_0 + _A53 * k3_0 + _A54 * k4_0)
    g1 = y1 + h * (_A51 * k1_1 + _A52 * k2_1 + _A53 * k3_1 + _A54 * k4_1)
    g2 = y2 + h * (_A51 * k1_2 + _A52 * k2_2 + _A53 * k3_2 + _A54 * k4_2)
    g3 = y3 + h * (_A51 * k1_3 + _A52 * k2_3 + _A53 * k3_3 + _A54 * k4_3)
    k5_0, k5_1, k5_2, k5_3 = _rhs(model, damping_stiffness, cond, g0, g1, g2, g3,
                                  ground_input(row, acc, acc_dot, dt_grid, t + _C5 * h), p)
    g0 = y0 + h * (_A61 * k1_0 + _A62 * k2_0 + _A63 * k3_0 + _A64 * k4_0 + _A65 * k5_0)
    g1 = y1 + h * (_A61 * k1_1 + _A62 * k2_1 + _A63 * k3_1 + _A64 * k4_1 + _A65 * k5_1)
    g2 = y2 + h * (_A61 * k1_2 + _A62 * k2_2 + _A63 * k3_2 + _A64 * k4_2 + _A65 * k5_2)
    g3 = y3 + h * (_A61 * k1_3 + _A62 * k2_3 + _A63 * k3_3 + _A64 * k4_3 + _A65 * k5_3)
    acc_end = ground_input(row, acc, acc_dot, dt_grid, t + h)
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
    return (n0, n1, n2, n3), (k7_0, k7_1, k7_2, k7_3), (e0, e1, e2, e3), acc_end


# ----------------------------------------------------------------------------- exact full-contact steps
@numba.njit(cache=True, inline="always")
def _mv(prop, r, x0, x1, x2, x3):
    """Rows ``r .. r+3`` of ``prop`` (a 4 x 4 matrix) times ``x``."""
    return (prop[r, 0] * x0 + prop[r, 1] * x1 + prop[r, 2] * x2 + prop[r, 3] * x3,
            prop[r + 1, 0] * x0 + prop[r + 1, 1] * x1 + prop[r + 1, 2] * x2 + prop[r + 1, 3] * x3,
            prop[r + 2, 0] * x0 + prop[r + 2, 1] * x1 + prop[r + 2, 2] * x2 + prop[r + 2, 3] * x3,
            prop[r + 3, 0] * x0 + prop[r + 3, 1] * x1 + prop[r + 3, 2] * x2 + prop[r + 3, 3] * x3)


@numba.njit(cache=True, inline="always")
def _mv2(prop, r, n1, n3):
    """Rows ``r .. r+3`` of ``prop`` times ``(0, n1, 0, n3)`` (a remainder: kinematic rows exact)."""
    return (prop[r, 1] * n1 + prop[r, 3] * n3, prop[r + 1, 1] * n1 + prop[r + 1, 3] * n3,
            prop[r + 2, 1] * n1 + prop[r + 2, 3] * n3, prop[r + 3, 1] * n1 + prop[r + 3, 3] * n3)


@numba.njit(cache=True)
def _remainder(prop, p, x0, x1, x2, x3, u):
    """``(N_1, N_3)``: the coupled accelerations at ``y_star + x`` under ``u`` less their linear part ``L x + B u``."""
    theta = prop[32, 0] + x0
    if abs(theta) < 1e-3:       # sin, cos by their series to theta^5, theta^4: exact in double precision here
        t2 = theta * theta
        a1, a3 = coupled_accelerations_trig(theta * (1.0 - t2 / 6.0 * (1.0 - t2 / 20.0)), 1.0 - 0.5 * t2 * (
            1.0 - t2 / 12.0), prop[32, 1] + x1, prop[32, 2] + x2, prop[32, 3] + x3, u, p, 0.0)
    else:
        a1, a3 = coupled_accelerations(theta, prop[32, 1] + x1, prop[32, 2] + x2, prop[32, 3] + x3, u, p, 0.0)
    return (a1 - (prop[33, 0] * x0 + prop[33, 1] * x1 + prop[33, 2] * x2 + prop[33, 3] * x3) - prop[35, 3] * u,
            a3 - (prop[34, 0] * x0 + prop[34, 1] * x1 + prop[34, 2] * x2 + prop[34, 3] * x3))


@numba.njit(cache=True, inline="always")
def _quiet(prop, p, x0, x1, x2, x3):
    """Whether the deviation ``x`` from rest is far from uplift: ``A_z + b A_theta`` (each linear mode's
    amplitude from its energy) within the margin of row 36 of ``prop``."""
    a_theta = math.sqrt(x0 * x0 + x1 * x1 / prop[35, 1])
    a_z = math.sqrt(x2 * x2 + x3 * x3 / prop[35, 2])
    return a_z + p.b * a_theta <= prop[36, 0]


@numba.njit(cache=True)
def _exact_step(prop, p, x0, x1, x2, x3, c0, c1, c2, c3, u_mid, u_end, m1, m3):
    """One exact full-contact step over a grid interval from the deviation ``x`` from rest.

    Parameters
    ----------
    prop : numpy.ndarray
        :func:`full_contact_propagator` of the interval.
    p : numpy.record
        The :data:`MODEL` record.
    x0, x1, x2, x3 : float
        ``y - y_star`` at the interval's start [rad, rad/s, m, m/s].
    c0, c1, c2, c3 : float
        The input's Hermite data ``(u_j, dt u'_j, u_{j+1}, dt u'_{j+1})`` [m/s^2].
    u_mid, u_end : float
        The input at the interval's middle and end [m/s^2].
    m1, m3 : float
        The remainder at the start (:func:`_remainder`).

    Returns
    -------
    tuple
        ``(x_end, error, remainder_end, quiet)``: the deviation at the end (4 floats), the error estimate
        (4 floats), the remainder there (2 floats), whether start, middle and end are far from uplift.

    Notes
    -----
    ETD2 [1]_: ``x1 = Phi x + W c + Psi1 N0 + Psi2 (N1 - N0)``, ``N1`` at the predictor ``Phi x + W c + Psi1 N0``.
    The error estimate adds the remainder's departure from a straight line at the middle (``(2/3) Psi1 d``)
    and the corrector's change of ``N1`` (``Psi2 (N1c - N1)``).

    References
    ----------
    .. [1] [hochbruck2010] in the bibliography, ``docs/bibliography.md``.
    """
    f0, f1, f2, f3 = _mv(prop, 0, x0, x1, x2, x3)
    w0, w1, w2, w3 = _mv(prop, 4, c0, c1, c2, c3)
    a0, a1, a2, a3 = _mv2(prop, 8, m1, m3)
    q0, q1, q2, q3 = f0 + w0 + a0, f1 + w1 + a1, f2 + w2 + a2, f3 + w3 + a3          # predictor
    n1, n3 = _remainder(prop, p, q0, q1, q2, q3, u_end)
    b0, b1, b2, b3 = _mv2(prop, 12, n1 - m1, n3 - m3)
    e0, e1, e2, e3 = q0 + b0, q1 + b1, q2 + b2, q3 + b3                              # corrector
    f0, f1, f2, f3 = _mv(prop, 16, x0, x1, x2, x3)
    w0, w1, w2, w3 = _mv(prop, 20, c0, c1, c2, c3)
    a0, a1, a2, a3 = _mv2(prop, 24, m1, m3)
    b0, b1, b2, b3 = _mv2(prop, 28, n1 - m1, n3 - m3)
    h0, h1, h2, h3 = f0 + w0 + a0 + b0, f1 + w1 + a1 + b1, f2 + w2 + a2 + b2, f3 + w3 + a3 + b3   # middle
    d1, d3 = _remainder(prop, p, h0, h1, h2, h3, u_mid)
    d1 -= 0.5 * (m1 + n1)
    d3 -= 0.5 * (m3 + n3)
    r1, r3 = _remainder(prop, p, e0, e1, e2, e3, u_end)
    a0, a1, a2, a3 = _mv2(prop, 8, 2.0 / 3.0 * d1, 2.0 / 3.0 * d3)
    b0, b1, b2, b3 = _mv2(prop, 12, r1 - n1, r3 - n3)
    quiet = _quiet(prop, p, x0, x1, x2, x3) and _quiet(prop, p, h0, h1, h2, h3) and _quiet(prop, p, e0, e1, e2, e3)
    return (e0, e1, e2, e3), (a0 + b0, a1 + b1, a2 + b2, a3 + b3), (r1, r3), quiet


@numba.njit(cache=True)
def _exact_double_step(prop, p, x0, x1, x2, x3, c, d, m1, m3):
    """:func:`_exact_step` over two grid intervals (Hermite data ``c`` of the first, ``d`` of the second); the
    middle is the grid point between them, where the input is ``c[2] = d[0]``.  Same returns."""
    f0, f1, f2, f3 = _mv(prop, 0, x0, x1, x2, x3)
    w0, w1, w2, w3 = _mv(prop, 4, c[0], c[1], c[2], c[3])
    l0, l1, l2, l3 = f0 + w0, f1 + w1, f2 + w2, f3 + w3                              # linear part, middle
    f0, f1, f2, f3 = _mv(prop, 0, l0, l1, l2, l3)
    w0, w1, w2, w3 = _mv(prop, 4, d[0], d[1], d[2], d[3])
    a0, a1, a2, a3 = _mv2(prop, 37, m1, m3)
    q0, q1, q2, q3 = f0 + w0 + a0, f1 + w1 + a1, f2 + w2 + a2, f3 + w3 + a3          # predictor
    n1, n3 = _remainder(prop, p, q0, q1, q2, q3, d[2])
    b0, b1, b2, b3 = _mv2(prop, 41, n1 - m1, n3 - m3)
    e0, e1, e2, e3 = q0 + b0, q1 + b1, q2 + b2, q3 + b3                              # corrector
    a0, a1, a2, a3 = _mv2(prop, 8, m1, m3)
    b0, b1, b2, b3 = _mv2(prop, 12, 0.5 * (n1 - m1), 0.5 * (n3 - m3))
    h0, h1, h2, h3 = l0 + a0 + b0, l1 + a1 + b1, l2 + a2 + b2, l3 + a3 + b3          # middle
    d1, d3 = _remainder(prop, p, h0, h1, h2, h3, c[2])
    d1 -= 0.5 * (m1 + n1)
    d3 -= 0.5 * (m3 + n3)
    r1, r3 = _remainder(prop, p, e0, e1, e2, e3, d[2])
    a0, a1, a2, a3 = _mv2(prop, 37, 2.0 / 3.0 * d1, 2.0 / 3.0 * d3)
    b0, b1, b2, b3 = _mv2(prop, 41, r1 - n1, r3 - n3)
    quiet = _quiet(prop, p, x0, x1, x2, x3) and _quiet(prop, p, h0, h1, h2, h3) and _quiet(prop, p, e0, e1, e2, e3)
    return (e0, e1, e2, e3), (a0 + b0, a1 + b1, a2 + b2, a3 + b3), (r1, r3), quiet


@numba.njit(cache=True, inline="always")
def _exact_outcome(prop, xe, err_v, quiet, y0, y1, y2, y3, s0, s1, s2, s3, rtol, census, row):
    """``(n, ok)``: the state at the end of an exact step (deviation ``xe`` from rest, error estimate ``err_v``) and
    whether it is taken (``quiet`` and the error within the explicit pair's norm); a refusal counted in the
    census."""
    n0, n1, n2, n3 = prop[32, 0] + xe[0], prop[32, 1] + xe[1], prop[32, 2] + xe[2], prop[32, 3] + xe[3]
    err = _error_norm(err_v[0], err_v[1], err_v[2], err_v[3], y0, y1, y2, y3, n0, n1, n2, n3, s0, s1, s2, s3, rtol,
                      4.0)
    ok = quiet and err <= 1.0
    if census.shape[0] > row and not ok:
        census[row, 4 if not quiet else 5] += 1
    return (n0, n1, n2, n3), ok


@numba.njit(cache=True, inline="always")
def _hermite_data(row, acc, acc_dot, dt, j):
    """``(u_j, dt u'_j, u_{j+1}, dt u'_{j+1})`` of the horizontal input of sample ``row``."""
    return (acc[0][row, j], acc_dot[0][row, j] * dt, acc[0][row, j + 1], acc_dot[0][row, j + 1] * dt)


@numba.njit(cache=True)
def _sample_loop(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out, models, y_init, scale, rtol, h_max,
                 max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, prop, census, method):
    """:func:`integrate_sample` by ``method``: one loop, one step bookkeeping for the three integrators.

    ``INTEGRATOR_DOPRI``: explicit steps; ``INTEGRATOR_RODAS``: linearly implicit steps; ``INTEGRATOR_EXACT``
    (coupled model, ``prop`` given): explicit steps, and at a grid point where the state is far from uplift
    (:data:`~screening.kernels.mcs_equations.CONTACT_MARGIN`) and no output falls inside, one
    :func:`_exact_double_step` over two grid intervals (else one :func:`_exact_step` over one) when its error
    estimate passes the explicit pair's norm and its middle and end stay far from uplift; the explicit steps land
    on the next grid point while the state is quiet, and after a refused exact step the next try waits 1, 2, 4
    or 8 intervals.  No exact steps under a vertical input.
    """
    cond = conds[0]
    p = models[0]
    n_out = t_out.shape[0]
    n_grid = acc[0].shape[1]
    y0, y1, y2, y3 = y_init[0], y_init[1], y_init[2], y_init[3]
    s0, s1, s2, s3 = scale[0], scale[1], scale[2], scale[3]
    t, peak, status, reason, n_acc, n_rej, h_min_acc, flight_start, h_floor, i_out = _start(
        model, row, t_out, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift)
    coupled = model == MODEL_COUPLED
    n_comp = 4.0 if coupled else 2.0
    kz = 1.0 if coupled else 0.0
    implicit = method == INTEGRATOR_RODAS
    usable = (method == INTEGRATOR_EXACT and coupled and prop.shape[0] > 0 and vertical_row(row, acc[1]) < 0
              and abs(prop[35, 0] - dt_grid) <= 1e-12 * dt_grid)
    log_err_old = dopri.LOG_ERR_START
    stale = True                    # the explicit pair's first rate is to be evaluated
    k1_0 = k1_1 = k1_2 = k1_3 = 0.0
    k7_0 = k7_1 = k7_2 = k7_3 = 0.0
    fresh = True                    # RODAS's f, J, df/dt of the current state are to be evaluated
    f = (0.0, 0.0, 0.0, 0.0)
    jac = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ft = (0.0, 0.0)
    h = min(1e-4, h_max)
    rejected = False
    j_grid = 0
    at_grid = abs(t) <= 1e-12
    wait_until = -1.0               # no exact try before this time
    backoff = 1.0
    m_fresh = False                 # remainder at the current grid point known
    m1 = m3 = 0.0
    y_star2 = prop[32, 2] if usable else 0.0
    while i_out < n_out:
        if n_acc + n_rej >= max_steps:
            status, reason = STATUS_DIVERGED, REASON_STEP_BUDGET
            break
        t_next = t_out[i_out]
        # --- an exact step over the grid interval [j dt, (j + 1) dt]
        if usable and at_grid and t >= wait_until and j_grid + 1 < n_grid:
            x0, x1, x2, x3 = y0 - prop[32, 0], y1 - prop[32, 1], y2 - y_star2, y3 - prop[32, 3]
            if t_next >= (j_grid + 1) * dt_grid - 1e-9 * dt_grid and _quiet(prop, p, x0, x1, x2, x3):
                c = _hermite_data(row, acc, acc_dot, dt_grid, j_grid)
                if not m_fresh:
                    m1, m3 = _remainder(prop, p, x0, x1, x2, x3, c[0])
                span = 1
                ok = False
                if j_grid + 2 < n_grid and t_next >= (j_grid + 2) * dt_grid - 1e-9 * dt_grid:
                    span = 2
                    xe, err_v, rem, quiet = _exact_double_step(prop, p, x0, x1, x2, x3, c,
                                                              _hermite_data(row, acc, acc_dot, dt_grid, j_grid + 1),
                                                              m1, m3)
                    (n0, n1, n2, n3), ok = _exact_outcome(prop, xe, err_v, quiet, y0, y1, y2, y3, s0, s1, s2, s3,
                                                          rtol, census, row)
                if not ok:
                    span = 1
                    u_mid = 0.5 * (c[0] + c[2]) + 0.125 * (c[1] - c[3])
                    xe, err_v, rem, quiet = _exact_step(prop, p, x0, x1, x2, x3, c[0], c[1], c[2], c[3], u_mid, c[2],
                                                       m1, m3)
                    (n0, n1, n2, n3), ok = _exact_outcome(prop, xe, err_v, quiet, y0, y1, y2, y3, s0, s1, s2, s3,
                                                          rtol, census, row)
                if ok:
                    t_end = (j_grid + span) * dt_grid
                    peak = step_peak(peak, span * dt_grid, y0, y1, n0, n1)
                    y0, y1, y2, y3 = n0, n1, n2, n3
                    m1, m3 = rem
                    m_fresh = True
                    stale = True
                    fresh = True
                    landing = t_next <= t_end + 1e-9 * dt_grid
                    t, i_out, n_acc, h_min_acc, peak, status, reason, flight_start = _accept(
                        model, row, span * dt_grid, t, t_next if landing else t_end, landing, i_out, n_acc,
                        h_min_acc, peak, flight_start, y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot,
                        out_uplift, 0.0, census, True)
                    t = t_end
                    j_grid += span
                    backoff = 1.0
                    if status != STATUS_OK:
                        break
                    continue
                wait_until = t + (backoff - 0.5) * dt_grid
                backoff = min(2.0 * backoff, 8.0)
        # --- an adaptive step, landing on the next grid point while quiet
        at_grid = False
        m_fresh = False
        target = t_next
        to_grid = False
        if usable and _quiet(prop, p, y0 - prop[32, 0], y1 - prop[32, 1], y2 - y_star2, y3 - prop[32, 3]):
            j_next = int(t / dt_grid + 1e-9) + 1
            if j_next < n_grid and j_next * dt_grid < t_next - 1e-9 * dt_grid and j_next * dt_grid >= wait_until:
                target = j_next * dt_grid
                to_grid = True
        h, h_proposed, landing = _landing(t, h, h_max, target)
        if implicit:
            if fresh:
                f, jac, ft = _rodas_jacobian(model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, y0, y1,
                                             y2, y3, s0, s1, s2, s3, rtol, p)
                fresh = False
            (n0, n1, n2, n3), (e0, e1, e2, e3), acc_end = _rodas_stages(
                model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, h, y0, y1, y2, y3, f, jac, ft, kz, p)
        else:
            if stale:
                k1_0, k1_1, k1_2, k1_3 = _rhs(model, damping_stiffness, cond, y0, y1, y2, y3,
                                              ground_input(row, acc, acc_dot, dt_grid, t), p)
                stale = False
            (n0, n1, n2, n3), (k7_0, k7_1, k7_2, k7_3), (e0, e1, e2, e3), acc_end = _dopri_stages(
                model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, h, y0, y1, y2, y3, k1_0, k1_1, k1_2,
                k1_3, p)
        err = _error_norm(e0, e1, e2, e3, y0, y1, y2, y3, n0, n1, n2, n3, s0, s1, s2, s3, rtol, n_comp)
        if not err <= 1.0:                                  # rejected (or not finite)
            n_rej += 1
            rejected = True
            if implicit:
                factor = max(_rodas_factor(err), _ro.FAC_MIN)
            else:
                factor = dopri.rejected_step_factor_log(math.log(err)) if math.isfinite(err) else 0.1
            h, reason = _shrink(err, h, factor, h_floor)
            if reason != REASON_NONE:
                status = STATUS_DIVERGED
                break
            continue
        peak = step_peak(peak, h, y0, y1, n0, n1)
        y0, y1, y2, y3 = n0, n1, n2, n3
        fresh = True
        if implicit:
            stale = True
        else:
            k1_0, k1_1, k1_2, k1_3 = k7_0, k7_1, k7_2, k7_3
        t, i_out, n_acc, h_min_acc, peak, status, reason, flight_start = _accept(
            model, row, h, t, target, landing and not to_grid, i_out, n_acc, h_min_acc, peak, flight_start,
            y0, y1, y2, y3, p, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, acc_end[1], census, False)
        if status != STATUS_OK:
            break
        if landing and to_grid:
            t = target
            j_grid = int(target / dt_grid + 0.5)
            at_grid = True
        if implicit:
            fac = min(max(_rodas_factor(err), _ro.FAC_MIN), _ro.FAC_MAX)
        else:
            fac, log_err = dopri.pi_step_factor(err, log_err_old)
            log_err_old = max(log_err, dopri.LOG_ERR_START)
        if rejected:
            fac = min(fac, 1.0)
        rejected = False
        h = _next_step(h, fac, landing, h_proposed, h_max)
    if not math.isfinite(peak):
        peak = 0.0
    return status, reason, peak, n_acc, n_rej, h_min_acc


# ----------------------------------------------------------------------------- linearly implicit steps
@numba.njit(cache=True)
def _rosenbrock_solve(m11, m13, m31, m33, e, kz, j10, j12, j30, j32, r0, r1, r2, r3):
    """``u`` of ``(I / e - J) u = r`` for a Jacobian with kinematic rows ``(0, 1, 0, 0)``, ``(0, 0, 0, kz)``.

    Rows 0 and 2 give ``u0 = e (r0 + u1)``, ``u2 = e (r2 + kz u3)``; the rest is the 2 x 2 system
    ``[[m11, m13], [m31, m33]] (u1, u3) = (r1 + e (j10 r0 + j12 r2), r3 + e (j30 r0 + j32 r2))``
    (Cramer's rule; ``m..`` from :func:`_rodas_stages`).
    """
    q1 = r1 + e * (j10 * r0 + j12 * r2)
    q3 = r3 + e * (j30 * r0 + j32 * r2)
    det = m11 * m33 - m13 * m31
    u1 = (q1 * m33 - m13 * q3) / det
    u3 = (m11 * q3 - m31 * q1) / det
    return e * (r0 + u1), u1, e * (r2 + kz * u3), u3


@numba.njit(cache=True, inline="always")
def _rodas_factor(err):
    """RODAS's step factor after the error ``err`` (order-3 estimate), before clipping."""
    return _ro.SAFETY * max(err, 1e-10) ** (-_ro.EXPONENT)


@numba.njit(cache=True, inline="always")
def _rodas_jacobian(model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, y0, y1, y2, y3, s0, s1, s2, s3,
                    rtol, p):
    """``(f, J, df/dt)`` at the state ``y`` at ``t`` for :func:`_rodas_stages`: the rate (4 floats), rows 1 and 3
    of the Jacobian (forward differences, one evaluation per column; 8 floats) and the rows 1 and 3 of the exact
    time derivative from the input's rate (:func:`input_gain`, :func:`vertical_gain`)."""
    acc_t = ground_input(row, acc, acc_dot, dt_grid, t)
    f0, f1, f2, f3 = _rhs(model, damping_stiffness, cond, y0, y1, y2, y3, acc_t, p)
    d = _ro.JACOBIAN_STEP * max(abs(y0), s0 / rtol)
    _, a1, _, a3 = _rhs(model, damping_stiffness, cond, y0 + d, y1, y2, y3, acc_t, p)
    j10, j30 = (a1 - f1) / d, (a3 - f3) / d
    d = _ro.JACOBIAN_STEP * max(abs(y1), s1 / rtol)
    _, a1, _, a3 = _rhs(model, damping_stiffness, cond, y0, y1 + d, y2, y3, acc_t, p)
    j11, j31 = (a1 - f1) / d, (a3 - f3) / d
    j12 = j13 = j32 = j33 = 0.0
    if model == MODEL_COUPLED:
        d = _ro.JACOBIAN_STEP * max(abs(y2), s2 / rtol)
        _, a1, _, a3 = _rhs(model, damping_stiffness, cond, y0, y1, y2 + d, y3, acc_t, p)
        j12, j32 = (a1 - f1) / d, (a3 - f3) / d
        d = _ro.JACOBIAN_STEP * max(abs(y3), s3 / rtol)
        _, a1, _, a3 = _rhs(model, damping_stiffness, cond, y0, y1, y2, y3 + d, acc_t, p)
        j13, j33 = (a1 - f1) / d, (a3 - f3) / d
    g1, g3 = input_gain(model, y0, p)
    v1, v3 = vertical_gain(model, y0, p)
    rate, rate_v = ground_input_rate(row, acc, acc_dot, dt_grid, t)
    return ((f0, f1, f2, f3), (j10, j11, j12, j13, j30, j31, j32, j33),
            (g1 * rate + v1 * rate_v, g3 * rate + v3 * rate_v))


@numba.njit(cache=True, inline="always")
def _rodas_stages(model, damping_stiffness, cond, row, acc, acc_dot, dt_grid, t, h, y0, y1, y2, y3, f, jac, ft, kz,
                  p):
    """One RODAS step of ``h`` from ``y`` at ``t`` (``f, jac, ft``: :func:`_rodas_jacobian` there; ``kz`` 1 for the
    coupled model, else 0): ``(n, u6, acc_end)``, the new state, the local error estimate and the ground input at
    ``t + h``."""
    f0, f1, f2, f3 = f
    j10, j11, j12, j13, j30, j31, j32, j33 = jac
    ft1, ft3 = ft
    e = _ro.GAMMA * h
    gi = 1.0 / e
    m11 = gi - j11 - e * j10
    m13 = -j13 - e * kz * j12
    m31 = -j31 - e * j30
    m33 = gi - j33 - e * kz * j32
    hi = 1.0 / h
    # --- stage 1
    u10, u11, u12, u13 = _rosenbrock_solve(m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
                                           f0, f1 + _ro.D1 * h * ft1, f2, f3 + _ro.D1 * h * ft3)
    # --- stage 2
    a = ground_input(row, acc, acc_dot, dt_grid, t + _ro.C2 * h)
    g0, g1, g2, g3 = _rhs(model, damping_stiffness, cond, y0 + _ro.A21 * u10, y1 + _ro.A21 * u11,
                          y2 + _ro.A21 * u12, y3 + _ro.A21 * u13, a, p)
    u20, u21, u22, u23 = _rosenbrock_solve(
        m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
        g0 + hi * _ro.G21 * u10, g1 + hi * _ro.G21 * u11 + _ro.D2 * h * ft1,
        g2 + hi * _ro.G21 * u12, g3 + hi * _ro.G21 * u13 + _ro.D2 * h * ft3)
    # --- stage 3
    a = ground_input(row, acc, acc_dot, dt_grid, t + _ro.C3 * h)
    g0, g1, g2, g3 = _rhs(model, damping_stiffness, cond,
                          y0 + _ro.A31 * u10 + _ro.A32 * u20, y1 + _ro.A31 * u11 + _ro.A32 * u21,
                          y2 + _ro.A31 * u12 + _ro.A32 * u22, y3 + _ro.A31 * u13 + _ro.A32 * u23, a, p)
    u30, u31, u32, u33 = _rosenbrock_solve(
        m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
        g0 + hi * (_ro.G31 * u10 + _ro.G32 * u20),
        g1 + hi * (_ro.G31 * u11 + _ro.G32 * u21) + _ro.D3 * h * ft1,
        g2 + hi * (_ro.G31 * u12 + _ro.G32 * u22),
        g3 + hi * (_ro.G31 * u13 + _ro.G32 * u23) + _ro.D3 * h * ft3)
    # --- stage 4
    a = ground_input(row, acc, acc_dot, dt_grid, t + _ro.C4 * h)
    g0, g1, g2, g3 = _rhs(model, damping_stiffness, cond,
                          y0 + _ro.A41 * u10 + _ro.A42 * u20 + _ro.A43 * u30,
                          y1 + _ro.A41 * u11 + _ro.A42 * u21 + _ro.A43 * u31,
                          y2 + _ro.A41 * u12 + _ro.A42 * u22 + _ro.A43 * u32,
                          y3 + _ro.A41 * u13 + _ro.A42 * u23 + _ro.A43 * u33, a, p)
    u40, u41, u42, u43 = _rosenbrock_solve(
        m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
        g0 + hi * (_ro.G41 * u10 + _ro.G42 * u20 + _ro.G43 * u30),
        g1 + hi * (_ro.G41 * u11 + _ro.G42 * u21 + _ro.G43 * u31) + _ro.D4 * h * ft1,
        g2 + hi * (_ro.G41 * u12 + _ro.G42 * u22 + _ro.G43 * u32),
        g3 + hi * (_ro.G41 * u13 + _ro.G42 * u23 + _ro.G43 * u33) + _ro.D4 * h * ft3)
    # --- stage 5 (at t + h)
    acc_end = ground_input(row, acc, acc_dot, dt_grid, t + h)
    v0 = y0 + _ro.A51 * u10 + _ro.A52 * u20 + _ro.A53 * u30 + _ro.A54 * u40
    v1 = y1 + _ro.A51 * u11 + _ro.A52 * u21 + _ro.A53 * u31 + _ro.A54 * u41
    v2 = y2 + _ro.A51 * u12 + _ro.A52 * u22 + _ro.A53 * u32 + _ro.A54 * u42
    v3 = y3 + _ro.A51 * u13 + _ro.A52 * u23 + _ro.A53 * u33 + _ro.A54 * u43
    g0, g1, g2, g3 = _rhs(model, damping_stiffness, cond, v0, v1, v2, v3, acc_end, p)
    u50, u51, u52, u53 = _rosenbrock_solve(
        m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
        g0 + hi * (_ro.G51 * u10 + _ro.G52 * u20 + _ro.G53 * u30 + _ro.G54 * u40),
        g1 + hi * (_ro.G51 * u11 + _ro.G52 * u21 + _ro.G53 * u31 + _ro.G54 * u41),
        g2 + hi * (_ro.G51 * u12 + _ro.G52 * u22 + _ro.G53 * u32 + _ro.G54 * u42),
        g3 + hi * (_ro.G51 * u13 + _ro.G52 * u23 + _ro.G53 * u33 + _ro.G54 * u43))
    # --- stage 6 (at t + h): its increment is the error estimate
    v0 += u50
    v1 += u51
    v2 += u52
    v3 += u53
    g0, g1, g2, g3 = _rhs(model, damping_stiffness, cond, v0, v1, v2, v3, acc_end, p)
    u60, u61, u62, u63 = _rosenbrock_solve(
        m11, m13, m31, m33, e, kz, j10, j12, j30, j32,
        g0 + hi * (_ro.G61 * u10 + _ro.G62 * u20 + _ro.G63 * u30 + _ro.G64 * u40 + _ro.G65 * u50),
        g1 + hi * (_ro.G61 * u11 + _ro.G62 * u21 + _ro.G63 * u31 + _ro.G64 * u41 + _ro.G65 * u51),
        g2 + hi * (_ro.G61 * u12 + _ro.G62 * u22 + _ro.G63 * u32 + _ro.G64 * u42 + _ro.G65 * u52),
        g3 + hi * (_ro.G61 * u13 + _ro.G62 * u23 + _ro.G63 * u33 + _ro.G64 * u43 + _ro.G65 * u53))
    return (v0 + u60, v1 + u61, v2 + u62, v3 + u63), (u60, u61, u62, u63), acc_end


def _integrate_chunk(model, damping_stiffness, conds, acc, acc_dot, dt_grid, t_out, models, y_init, scale, rtol,
                     h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason,
                     n_accepted, n_rejected, h_min, prop, census):
    """Integrate every row of ``acc`` (one sample per row) in parallel; fills the outputs.

    ``damping_stiffness``, ``conds[0]``: the condensation's compiled ``(C, K)`` and its record
    (read by ``model = MODEL_CONDENSED`` only); ``acc``, ``acc_dot``: the pairs ``(horizontal,
    vertical)`` of ground accelerations [m/s^2] and rates [m/s^3] on the grid ``j dt_grid`` (the
    inertial ``x_g''`` one row per sample; the vertical ``a_v``, positive up, one row per sample, one
    row for all, or :data:`NO_VERTICAL`); ``t_out`` output times [s]; ``models[0]``: the
    :data:`MODEL` record; ``y_init`` the initial ``(theta, theta', z_cb, z_cb')``; ``scale``
    absolute tolerances; ``prop``, ``census`` as :func:`integrate_sample`.  Compiled per condensation record
    type by :func:`chunk_integrator`.
    """
    for row in numba.prange(acc[0].shape[0]):
        store_outcome(row, integrate_sample(model, damping_stiffness, conds, row, acc, acc_dot, dt_grid, t_out,
                                             models, y_init, scale, rtol, h_max, max_steps, out_theta,
                                             out_theta_dot, out_z, out_z_dot, out_uplift, prop, census),
                       status, reason, peak, n_accepted, n_rejected, h_min)


_INTEGRATORS = {}


def chunk_integrator(record_dtype):
    """The compiled chunk integrator (every row of the input in parallel, one sample per row) for a
    condensation whose records have ``record_dtype``.

    Explicit signature (the condensation's ``(C, K)`` function is a first-class argument), so it
    is compiled once per record type and cached on disk; samples are independent, so the
    ``prange`` loop gives the same numbers for any number of threads.

    Parameters
    ----------
    record_dtype : numpy.dtype
        The dtype of the condensation's records (:class:`~screening.core.signatures.SdofKernel`).

    Returns
    -------
    numba dispatcher
        ``integrate(model, damping_stiffness, conds, acc, acc_dot, dt_grid, t_out, models, y_init,
        scale, rtol, h_max, max_steps, out_theta, out_theta_dot, out_z, out_z_dot, out_uplift, peak,
        status, reason, n_accepted, n_rejected, h_min, prop, census)``: fills the outputs, returns None.

    References
    ----------
    .. [1] Numba documentation, "Automatic parallelization with @jit",
       https://numba.readthedocs.io/en/stable/user/parallel.html
    .. [2] The package's documentation, ``docs/montecarlo_numerics.md``.
    """
    if record_dtype not in _INTEGRATORS:
        f8, i8 = types.float64, types.int64
        a1 = types.float64[::1]
        a2 = types.float64[:, ::1]
        channels = types.UniTuple(a2, 2)                 # (horizontal, vertical) ground input
        a2_rows = types.Array(types.float64, 2, "C")
        sig = types.void(i8, function_type(sdof_coefficients_signature(record_dtype)),
                         types.Array(record_type(record_dtype), 1, "C"), channels, channels, f8, a1,
                         types.Array(record_type(MODEL), 1, "C"), a1, a1, f8, f8, i8,
                         a2_rows, a2_rows, a2_rows, a2_rows, types.Array(types.boolean, 2, "C"),
                         a1, types.int64[::1], types.int64[::1], types.int64[::1], types.int64[::1], a1,
                         types.float64[:, ::1], types.int64[:, ::1])
        _INTEGRATORS[record_dtype] = numba.njit(sig, cache=True, parallel=True)(_integrate_chunk)
    return _INTEGRATORS[record_dtype]
