"""Specialised compiled step loops of the moment solver, one per state size.

:mod:`screening.solvers.moments` documents the method; this module holds its two compiled
integrators of one parameter point:

* :func:`solve_point_white`: modulated white noise, the 3 moments ``(var_theta, cov,
  var_theta_dot)`` held in scalar locals (no arrays, no runtime-length loops);
* :func:`solve_point_filtered`: an input shaped by a linear filter (Kanai–Tajimi, Clough–Penzien,
  any :class:`screening.core.excitations.Excitation` with filter states), the packed covariance of
  ``(theta, theta', x)`` (10 entries for Kanai–Tajimi, 21 for Clough–Penzien) from the filter's
  state-space matrices (:func:`augmented_rhs`, numpy reference :func:`lyapunov_rhs`).

Both run the same Dormand–Prince 5(4) pair, controller and dense output
(:mod:`screening.kernels.dopri`) and share every piece of step bookkeeping through the inlined
helpers below (first step, trial step and step budget, accept/reject verdict, peak search,
history stores, end of step with status and PI controller): only the state and its stages are
written per state size.  The PI controller works on the logarithms of the error norms (one
``log`` and one ``exp`` per step); the envelope's two exponentials are carried from step to step
(:func:`envelope_state`, :func:`stage_gains`: no ``exp`` per step).  The condensation enters
only through its compiled ``(c_eq, k_eq)`` function ``coefficients`` (a first-class function),
its record ``cond`` and its table (``table``); the paper's reads its table without a logarithm
(:mod:`screening.core.condensation.uplift_integrals`).  Cost (white noise, one core): ~170 ns per
step, ~14 ns of it per ``coefficients`` call (six per step), ~15 ns the controller
(``benchmarks/bench_linearization.py``).

Histories are written only when ``store`` is true (output arrays with at least one row per point
otherwise untouched): a screen without histories skips the dense output, the coefficient
evaluations and the ``erfc`` at the output times.
"""

from __future__ import annotations

import collections
import math

import numba
import numpy as np
from scipy import special

from screening.core.condensation.api import equivalent_coefficients_from_moments
from screening.core.condensation.registry import DEFAULT_CONDENSATION
from screening.kernels import dopri
from screening.kernels.dopri import (
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
    B1, B3, B4, B5, B6, C2, C3, C4, E1, E3, E4, E5, E6, E7, dense_value)
from screening.core.signatures import FMA
from screening.core.status import PointStatus

__all__ = []

#: Smallest absolute-tolerance scale [moment units]: below it the scale would underflow.
SCALE_FLOOR = 1e-300

OK = PointStatus.ok
K_EQ_NEGATIVE = PointStatus.k_eq_negative
BEYOND_SLENDERNESS = PointStatus.sigma_theta_beyond_slenderness
STEP_BUDGET = PointStatus.step_budget_exhausted
NON_FINITE = PointStatus.non_finite_moments

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
def envelope_rates(osc):
    """``(1/T1, 1/T2)`` [1/s] of the envelope ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))``.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``T1``, ``T2`` [s]).

    Returns
    -------
    tuple of float
        ``(1/T1, 1/T2)`` [1/s].

    Notes
    -----
    The decay rates of the two exponentials of eq. (57) in [1]_.

    """
    return 1.0 / osc.T1, 1.0 / osc.T2


@numba.njit(cache=True, inline="always")
def envelope_state(osc, t):
    """``(exp(-t/T1), exp(-t/T2))`` at time ``t`` [s]: the envelope's state, carried from step to step
    by the factors of :func:`stage_gains` (no ``exp`` per step).

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``T1``, ``T2`` [s]).
    t : float
        Time [s].

    Returns
    -------
    tuple of float
        ``(e1, e2) = (exp(-t/T1), exp(-t/T2))`` [1]; ``q(t) = 4 (e1 - e2)`` (eq. (57) in [1]_).

    """
    r1, r2 = envelope_rates(osc)
    return math.exp(-t * r1), math.exp(-t * r2)


@numba.njit(cache=True, inline="always")
def initial_gain(osc, e1, e2):
    """Input gain ``m h q(t) / M`` [1/m] from the :func:`envelope_state` ``(e1, e2)`` at ``t``.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``gain = m h / m_sdof`` [1/m]).
    e1, e2 : float
        The envelope state ``exp(-t/T1)``, ``exp(-t/T2)`` [1] at ``t``.

    Returns
    -------
    float
        ``alpha(t) = m h q(t) / m_sdof`` [1/m] (``m h / m_sdof`` for a constant envelope).

    Notes
    -----
    The gain of eq. (43) in [1]_ with the envelope of eq. (57).

    """
    return osc.gain * (1.0 if osc.constant_envelope == 1.0 else 4.0 * (e1 - e2))


@numba.njit(cache=True, inline="always")
def stage_gains(osc, e1, e2, h):
    """Input gains at the stage times ``t + C_s h`` of stages 2..6 (stage 7 shares stage 6's time)
    from the :func:`envelope_state` ``(e1, e2)`` at ``t``, and the factors ``(exp(-h/T1), exp(-h/T2))``
    taking that state to ``t + h``: ``(a2, a3, a4, a5, a6, f1, f2)``.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record.
    e1, e2 : float
        The envelope state at ``t`` [1].
    h : float
        Step size [s].

    Returns
    -------
    tuple of float
        ``(a2, a3, a4, a5, a6)`` [1/m], the gains ``m h q(t + C_s h) / m_sdof`` at the Dormand-Prince
        stage times, then ``(f1, f2)`` [1].

    Notes
    -----
    ``q(t + c h) = 4 (e1 exp(-c h/T1) - e2 exp(-c h/T2))`` (eq. (57) in [1]_); the stage nodes ``C_s``
    are Dormand and Prince's [2]_.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    """
    if osc.constant_envelope == 1.0:
        g = osc.gain
        return g, g, g, g, g, 1.0, 1.0
    r1, r2 = envelope_rates(osc)
    g4 = 4.0 * osc.gain
    f1 = _exp_minus(h * r1)
    f2 = _exp_minus(h * r2)
    return (g4 * (e1 * _exp_minus(C2 * h * r1) - e2 * _exp_minus(C2 * h * r2)),
            g4 * (e1 * _exp_minus(C3 * h * r1) - e2 * _exp_minus(C3 * h * r2)),
            g4 * (e1 * _exp_minus(C4 * h * r1) - e2 * _exp_minus(C4 * h * r2)),
            g4 * (e1 * _exp_minus(dopri.C5 * h * r1) - e2 * _exp_minus(dopri.C5 * h * r2)),
            g4 * (e1 * f1 - e2 * f2), f1, f2)


def uplift_occupancy(theta_ul, var_theta):
    """Uplift occupancy ``P(|theta| > theta_ul)`` [1] of a zero-mean Gaussian rotation of given variance.

    Parameters
    ----------
    theta_ul : array_like
        Uplift angle [rad].
    var_theta : array_like
        Variance of the rotation [rad2] (broadcast with ``theta_ul``); 0 where it is not positive.

    Returns
    -------
    numpy.ndarray
        ``erfc(theta_ul / sqrt(2 var_theta))`` [1].

    Notes
    -----
    Eq. (58) in [1].  The numpy reference of the compiled :func:`p_uplift`, which the step loops evaluate
    at every output instant; :mod:`screening.solvers.moments` applies it to the peak variance.

    """
    var_theta = np.asarray(var_theta, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(var_theta > 0, special.erfc(theta_ul / np.sqrt(2.0 * np.maximum(var_theta, 1e-300))), 0.0)


@numba.njit(cache=True, inline="always")
def p_uplift(osc, var_theta):
    """Uplift occupancy ``erfc(theta_ul / sqrt(2 var_theta))`` [1] (eq. 58): compiled twin of
    :func:`uplift_occupancy`.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``theta_ul`` [rad]).
    var_theta : float
        Variance of the rotation [rad^2]; 0 returned where it is not positive.

    Returns
    -------
    float
        ``P(|theta| > theta_ul)`` [1] of a zero-mean Gaussian rotation.

    Notes
    -----
    Eq. (58) in [1]_.

    """
    if var_theta <= 0.0:
        return 0.0
    return math.erfc(osc.theta_ul / math.sqrt(2.0 * var_theta))


@numba.njit(cache=True, inline="always")
def first_step(osc, k0, h_max, t, t_end):
    """``(h, code, t_end)`` before the first step: a twentieth of the linear period at ``k_eq = k0``,
    or no step at all (``K_EQ_NEGATIVE``, ``t_end = t``) if ``k0`` is not positive.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``m_sdof`` [kg m^2]).
    k0 : float
        Equivalent stiffness at the start [N m/rad].
    h_max : float
        Largest step [s].
    t : float
        Start time [s].
    t_end : float
        End time [s].

    Returns
    -------
    h : float
        First trial step [s], ``min(h_max, 0.05 / sqrt(k0 / m_sdof), t_end - t)``.
    code : PointStatus
        ``OK`` or ``K_EQ_NEGATIVE``.
    t_end : float
        The end time [s] (``t`` when no step is taken).

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    if not (k0 > 0.0):
        return 0.0, K_EQ_NEGATIVE, t
    return min(h_max, 0.05 / math.sqrt(k0 / osc.m_sdof), t_end - t), OK, t_end


@numba.njit(cache=True, inline="always")
def trial_step(h, t, t_end, steps, max_steps):
    """``(h, code)`` of the next trial step: ``h`` cut to end at ``t_end``; ``STEP_BUDGET`` once
    ``steps`` (accepted and rejected) reach ``max_steps``.

    Parameters
    ----------
    h : float
        Proposed step [s].
    t : float
        Current time [s].
    t_end : float
        End time [s].
    steps : int
        Steps taken so far (accepted and rejected).
    max_steps : int
        Step budget of the point.

    Returns
    -------
    h : float
        The step [s], at most ``t_end - t``.
    code : PointStatus
        ``OK`` or ``STEP_BUDGET``.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    if t + h > t_end:
        h = t_end - t
    return h, (STEP_BUDGET if steps >= max_steps else OK)


@numba.njit(cache=True, inline="always")
def judge_step(err, finite, h, t_end):
    """Verdict on a trial step of error norm ``err``: ``(accepted, h, rejected, code)``.

    Not finite: retried at a fifth of ``h`` (not counted as rejected) until ``h`` reaches
    ``1e-12 t_end``, then ``NON_FINITE``; ``err > 1``: rejected, retried at the controller's ``h``.

    Parameters
    ----------
    err : float
        Error norm of the trial step [1] (1 is the tolerance).
    finite : bool
        Whether every error component was finite.
    h : float
        The trial step [s].
    t_end : float
        End time [s].

    Returns
    -------
    accepted : bool
        Whether the step is accepted.
    h : float
        The step [s] (to retry with, if not accepted).
    rejected : int
        1 for a step rejected on its error, else 0.
    code : PointStatus
        ``OK`` or ``NON_FINITE``.

    Notes
    -----
    A rejected step shrinks by ``max(0.2, 0.9 err^(-1/5))`` (:func:`screening.kernels.dopri.rejected_step_factor`),
    the standard controller of an order-5 pair [2]_.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    if not finite:
        if h > 1e-12 * t_end:
            return False, h * 0.2, 0, OK
        return False, h, 0, NON_FINITE
    if err > 1.0:
        return False, h * dopri.rejected_step_factor(err), 1, OK
    return True, h, 0, OK


@numba.njit(cache=True, inline="always")
def end_of_step(osc, t, h, h_max, e1, e2, f1, f2, var_theta, k_eq, lowest_k, err, log_err_old):
    """After an accepted step ``[t, t + h]`` ending at ``var_theta`` [rad2], ``k_eq`` [N m/rad]:
    ``(t + h, e1, e2, h, log_err_old, lowest_k, code)`` with the envelope state carried by
    ``(f1, f2)``, the next step size (PI controller, at most ``h_max``) and the status.

    Parameters
    ----------
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record (``slenderness`` [rad]).
    t : float
        Start of the accepted step [s].
    h : float
        Its size [s].
    h_max : float
        Largest step [s].
    e1, e2 : float
        Envelope state at ``t`` [1] (:func:`envelope_state`).
    f1, f2 : float
        Factors taking it to ``t + h`` [1] (:func:`stage_gains`).
    var_theta : float
        Rotation variance at ``t + h`` [rad^2].
    k_eq : float
        Equivalent stiffness at ``t + h`` [N m/rad].
    lowest_k : float
        Lowest ``k_eq`` so far [N m/rad].
    err : float
        Error norm of the step [1].
    log_err_old : float
        Logarithm of the previous accepted error norm (the PI controller's memory).

    Returns
    -------
    tuple
        ``(t + h, e1 f1, e2 f2, h_next, log_err, lowest_k, code)``; ``code`` is ``K_EQ_NEGATIVE`` for
        ``k_eq <= 0``, ``BEYOND_SLENDERNESS`` for ``var_theta > slenderness^2``, else ``OK``.

    Notes
    -----
    The PI step-size controller [2]_ (:func:`screening.kernels.dopri.pi_step_factor`).

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    if k_eq < lowest_k:
        lowest_k = k_eq
    code = OK
    if not (k_eq > 0.0):
        code = K_EQ_NEGATIVE
    elif var_theta > osc.slenderness ** 2:
        code = BEYOND_SLENDERNESS
    fac, log_err_old = dopri.pi_step_factor(err, log_err_old)
    return t + h, e1 * f1, e2 * f2, min(h * fac, h_max), log_err_old, lowest_k, code


@numba.njit(cache=True, inline="always")
def peak_in_step(t, h, v0, v1, c0, c1, kv, kc, best, best_t):
    """Largest ``var_theta`` so far, ``(best, best_t)``, after the accepted step ``[t, t + h]``.

    Inside the step a maximum sits where ``d var_theta / dt = 2 cov`` changes sign from + to -, located
    by bisection on the dense output (only where the step could hold a new maximum).

    Parameters
    ----------
    t : float
        Start of the step [s].
    h : float
        Its size [s].
    v0, v1 : float
        ``var_theta`` at the step's ends [rad^2].
    c0, c1 : float
        ``cov(theta, theta')`` at the step's ends [rad^2/s].
    kv, kc : tuple of float
        Their six dense-output stage derivatives (:func:`screening.kernels.dopri.dense_value`).
    best : float
        Largest ``var_theta`` before the step [rad^2].
    best_t : float
        Its time [s].

    Returns
    -------
    best : float
        Largest ``var_theta`` [rad^2] up to ``t + h``.
    best_t : float
        Its time [s] (to ~6e-8 of a step, :data:`PEAK_HALVINGS`).

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    bound = max(v0, v1) + h * max(abs(c0), abs(c1)) * 2.0
    if c0 > 0.0 and c1 <= 0.0 and bound > best:
        lo = 0.0
        hi = 1.0
        for _ in range(PEAK_HALVINGS):
            mid = 0.5 * (lo + hi)
            if dense_value(c0, kc, h, mid) > 0.0:
                lo = mid
            else:
                hi = mid
        v = dense_value(v0, kv, h, 0.5 * (lo + hi))
        if v > best:
            best = v
            best_t = t + 0.5 * (lo + hi) * h
    if v1 > best:
        best = v1
        best_t = t + h
    return best, best_t


@numba.njit(cache=True, inline="always")
def store_outputs(coefficients, cond, table, osc, i, k, var, cv, vd,
                  var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """Write the moments ``(var, cv, vd)`` and the coefficients at them into column ``k`` of row ``i``.

    Parameters
    ----------
    coefficients : numba function
        The condensation's compiled ``(cond, table, var_theta, cov) -> (c_eq, k_eq)``.
    cond : numpy.record
        Its record.
    table : numpy.ndarray
        Its table.
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record.
    i : int
        Row (point) of the outputs.
    k : int
        Column (output time) of the outputs.
    var, cv, vd : float
        ``var_theta`` [rad^2], ``cov`` [rad^2/s], ``var_theta_dot`` [rad^2/s^2].
    var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl : numpy.ndarray
        The history arrays (points x output times), written in place; ``p_upl`` gets eq. (58) in [1]_.

    Returns
    -------
    None

    """
    var_theta[i, k] = var
    cov[i, k] = cv
    var_theta_dot[i, k] = vd
    c, kk = coefficients(cond, table, var, cv)
    c_eq_o[i, k] = c
    k_eq_o[i, k] = kk
    p_upl[i, k] = p_uplift(osc, var)


@numba.njit(cache=True, inline="always")
def store_dense_outputs(coefficients, cond, table, osc, i, next_out, t_out, t, h, y, ks,
                        var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """Store every output time inside the accepted step ``[t, t + h]`` from the dense output; returns
    the next output index.

    Parameters
    ----------
    coefficients, cond, table, osc, i
        As in :func:`store_outputs`.
    next_out : int
        Index of the next output time to write.
    t_out : numpy.ndarray
        Output times [s].
    t : float
        Start of the step [s].
    h : float
        Its size [s].
    y : tuple of float
        ``(var_theta, cov, var_theta_dot)`` at ``t``.
    ks : tuple of tuple
        Their stage derivatives (three tuples for :func:`screening.kernels.dopri.dense_value`).
    var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl : numpy.ndarray
        The history arrays (points x output times), written in place (:func:`store_outputs`).

    Returns
    -------
    int
        The index of the first output time after ``t + h``.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    nt = t_out.shape[0]
    t_new = t + h
    while next_out < nt and t_out[next_out] <= t_new * (1.0 + 1e-14):
        theta = (t_out[next_out] - t) / h
        store_outputs(coefficients, cond, table, osc, i, next_out, dense_value(y[0], ks[0], h, theta),
                      dense_value(y[1], ks[1], h, theta), dense_value(y[2], ks[2], h, theta),
                      var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
        next_out += 1
    return next_out


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


#: Per-point summaries a kernel returns as a :data:`Summary`, by name, and their types (the record the batch
#: stores them in): :class:`~screening.core.status.PointStatus`, ``t_stop`` [s], steps, rejected steps,
#: ``peak_var_theta`` [rad^2] at ``t_peak_var_theta`` [s], ``min_k_eq`` [N m/rad].
SUMMARY = np.dtype([("status", np.int8), ("t_stop", np.float64), ("n_steps", np.int64), ("n_rejected", np.int64),
                    ("peak_var_theta", np.float64), ("t_peak_var_theta", np.float64), ("min_k_eq", np.float64)])
SUMMARIES = SUMMARY.names
Summary = collections.namedtuple("Summary", SUMMARIES)


@numba.njit(cache=True, fastmath=FMA)
def solve_point_white(coefficients, cond, table, osc, t_out, rtol, h_max, max_steps, store, i,
                      var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """One white-noise point; histories into row ``i`` of the outputs only if ``store``.  Returns the
    :data:`Summary`.

    Integrates the three moments ``(var_theta, cov, var_theta_dot)`` of the linearized oscillator
    under modulated white noise by the Dormand-Prince 5(4) pair with PI control and dense output,
    from rest at ``t_out[0]`` to ``t_out[-1]``, stopping at the first bad status.

    Parameters
    ----------
    coefficients : numba function
        The condensation's compiled ``(cond, table, var_theta, cov) -> (c_eq, k_eq)``.
    cond : numpy.record
        Its record for the point.
    table : numpy.ndarray
        Its table.
    osc : numpy.record
        The point's :data:`screening.solvers.moments.OSCILLATOR` record.
    t_out : numpy.ndarray
        Output times [s].
    rtol : float
        Relative tolerance [1].
    h_max : float
        Largest step [s].
    max_steps : int
        Step budget.
    store : bool
        Whether to write the histories.
    i : int
        Row of the outputs.
    var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl : numpy.ndarray
        History arrays (points x output times) [rad^2, rad^2/s, rad^2/s^2, N m s/rad, N m/rad, 1].

    Returns
    -------
    tuple
        A :data:`Summary` (:data:`SUMMARY`).

    Notes
    -----
    Eq. (45) in [1]_ with the diffusion of eq. (46):
    ``d var/dt = 2 cov``, ``d cov/dt = vd - (k_eq var + c_eq cov) / m_sdof``,
    ``d vd/dt = -2 (k_eq cov + c_eq vd) / m_sdof + 2 pi S0 alpha(t)^2``; numpy reference:
    :func:`moment_equations`.  Compiling it takes tens of seconds, so the example shows its interface.

    """
    inv_m = 1.0 / osc.m_sdof
    S0 = osc.S0
    t = t_out[0]
    e1, e2 = envelope_state(osc, t)
    y0 = 0.0
    y1 = 0.0
    y2 = 0.0
    k1a, k1b, k1c, c0, k0 = _white_rhs(coefficients, cond, table, inv_m, S0, initial_gain(osc, e1, e2), y0, y1, y2)
    if store:
        store_outputs(coefficients, cond, table, osc, i, 0, y0, y1, y2,
                      var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    h, code, t_end = first_step(osc, k0, h_max, t, t_out[t_out.shape[0] - 1])
    next_out, best, best_t, lowest_k, steps, rejected, log_err_old = 1, 0.0, t, k0, 0, 0, dopri.LOG_ERR_START
    s0, s1, s2 = _white_scales(osc)                 # absolute-tolerance scales
    while t < t_end:
        h, code = trial_step(h, t, t_end, steps, max_steps)
        if code != OK:
            break
        a2, a3, a4, a5, a6, f1, f2 = stage_gains(osc, e1, e2, h)
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
        ea = abs(h * (E1 * k1a + E3 * k3a + E4 * k4a + E5 * k5a + E6 * k6a + E7 * k7a))
        eb = abs(h * (E1 * k1b + E3 * k3b + E4 * k4b + E5 * k5b + E6 * k6b + E7 * k7b))
        ec = abs(h * (E1 * k1c + E3 * k3c + E4 * k4c + E5 * k5c + E6 * k6c + E7 * k7c))
        ea = ea / (rtol * s0 + rtol * max(abs(y0), abs(n0)))
        eb = eb / (rtol * s1 + rtol * max(abs(y1), abs(n1)))
        ec = ec / (rtol * s2 + rtol * max(abs(y2), abs(n2)))
        err = max(max(max(0.0, ea), eb), ec)
        steps += 1
        accepted, h, rejects, code = judge_step(err, (ea < 1e300) and (eb < 1e300) and (ec < 1e300), h, t_end)
        rejected += rejects
        if code != OK:
            break
        if not accepted:
            continue
        ks = ((k1a, k3a, k4a, k5a, k6a, k7a), (k1b, k3b, k4b, k5b, k6b, k7b), (k1c, k3c, k4c, k5c, k6c, k7c))
        if store:
            next_out = store_dense_outputs(coefficients, cond, table, osc, i, next_out, t_out, t, h, (y0, y1, y2), ks,
                                           var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
        best, best_t = peak_in_step(t, h, y0, n0, y1, n1, ks[0], ks[1], best, best_t)
        y0, y1, y2 = n0, n1, n2
        k1a, k1b, k1c = k7a, k7b, k7c
        t, e1, e2, h, log_err_old, lowest_k, code = end_of_step(osc, t, h, h_max, e1, e2, f1, f2, y0, k_new,
                                                                lowest_k, err, log_err_old)
        if code != OK:
            break
    return Summary(status=code, t_stop=t, n_steps=steps, n_rejected=rejected, peak_var_theta=best,
                   t_peak_var_theta=best_t, min_k_eq=lowest_k)


# ---------------------------------------------------------------- filtered input: the augmented system
@numba.njit(cache=True)
def packed_size(n):
    """Independent entries of an ``n x n`` symmetric covariance (the state of :func:`solve_point_filtered`).

    Parameters
    ----------
    n : int
        Dimension of the augmented state ``(theta, theta', x)`` (``n_f + 2``).

    Returns
    -------
    int
        ``n (n + 1) / 2``.

    """
    return n * (n + 1) // 2


def augmented_system(k_eq, c_eq, m_sdof, alpha, filt):
    """Drift matrix and noise vector of the linearized oscillator driven through a shaping filter.

    Parameters
    ----------
    k_eq : float
        Equivalent stiffness [N m/rad].
    c_eq : float
        Equivalent damping [N m s/rad].
    m_sdof : float
        Rotational inertia about the rocking edge [kg m2].
    alpha : float
        Input gain ``m h q(t) / m_sdof`` [m-1].
    filt : screening.core.excitations.Filter
        A scalar filter ``(A_f, B_f, C_f, D_f)`` of ``n_f`` states.

    Returns
    -------
    A : numpy.ndarray
        Drift matrix [n x n], ``n = n_f + 2``, state ``(theta, theta', x)``.
    b : numpy.ndarray
        Noise vector [n].

    Notes
    -----
    ``theta'' = -(k_eq theta + c_eq theta') / m_sdof + alpha (C_f x + D_f w)``, ``x' = A_f x + B_f w``:
    ``A = [[0, 1, 0], [-k_eq/m_sdof, -c_eq/m_sdof, alpha C_f], [0, 0, A_f]]``, ``b = [0, alpha D_f, B_f]``;
    eq. (42) in [1] for white noise (``n_f = 0``, ``D_f = 1``), eq. (52) for the Kanai–Tajimi filter.

    """
    A_f, B_f, C_f, D_f = (np.asarray(m, dtype=float) for m in filt)
    nf = A_f.shape[-1]
    A = np.zeros((nf + 2, nf + 2))
    A[0, 1] = 1.0
    A[1, 0], A[1, 1] = -k_eq / m_sdof, -c_eq / m_sdof
    A[1, 2:] = alpha * C_f
    A[2:, 2:] = A_f
    b = np.concatenate([[0.0, alpha * float(D_f)], B_f])
    return A, b


def lyapunov_rhs(P, A, b, S0):
    """Right-hand side of the moment equations as matrix products (numpy reference of :func:`augmented_rhs`).

    Parameters
    ----------
    P : numpy.ndarray
        Covariance [n x n] of the augmented state.
    A : numpy.ndarray
        Drift matrix [n x n] (:func:`augmented_system`).
    b : numpy.ndarray
        Noise vector [n].
    S0 : float
        Two-sided PSD level of the driving white noise [m2 s-3].

    Returns
    -------
    numpy.ndarray
        ``dP/dt = A P + P A^T + 2 pi S0 b b^T`` [n x n].

    Notes
    -----
    Eq. (45) in [1] (white noise, with eq. (46)) and eq. (51) (the filtered input, with eq. (55)).

    """
    return A @ P + P @ A.T + 2.0 * math.pi * S0 * np.outer(b, b)


def moment_equations(t, P, block, foundation, excitation, condensation=DEFAULT_CONDENSATION):
    """Right-hand side ``dP/dt`` of the linearized moment equations at time ``t`` (numpy reference).

    The whole nonlinear system that the compiled step loops integrate, written as matrix products:
    the equivalent coefficients at the current moments, the augmented drift matrix and noise vector
    at the current input gain, and the Lyapunov right-hand side.

    Parameters
    ----------
    t : float
        Time [s] (the envelope ``q(t)`` scales the input).
    P : numpy.ndarray
        Covariance [n x n] of the state ``(theta, theta', x)`` ([rad2], [rad2 s-1], [rad2 s-2] for
        the rocking entries; ``x`` the ``n_f`` filter states of the excitation, ``n = n_f + 2``).
    block : screening.core.model.Block
        The rigid block, scalar fields (``m`` [kg], ``b``, ``h`` [m], ``m_sdof`` [kg m2]).
    foundation : screening.core.model.Foundation
        The bed, scalar fields.
    excitation : screening.core.excitations.Excitation
        The input, scalar fields (``S0`` [m2 s-3], its envelope and its shaping filter).
    condensation : str or screening.core.condensation.Condensation, optional
        The condensation whose equivalent coefficients close the equations (default
        :data:`screening.core.condensation.DEFAULT_CONDENSATION`).

    Returns
    -------
    numpy.ndarray
        ``dP/dt`` [n x n], symmetric, in the units of ``P`` per second.

    Notes
    -----
    ``dP/dt = A P + P A^T + 2 pi S0 b b^T`` with
    ``A = [[0, 1, 0], [-k_eq/M, -c_eq/M, alpha C_f], [0, 0, A_f]]``, ``b = [0, alpha D_f, B_f]``,
    ``alpha = m h q(t) / M`` and ``(c_eq, k_eq)`` the condensation's equivalent coefficients at
    ``(P[0, 0], P[0, 1])`` (eq. (31) in [1]): eq. (45) in [1] for white noise, eq. (51) for the
    Kanai-Tajimi filter, any filter :func:`augmented_system` accepts.  The compiled loops
    :func:`solve_point_white` and :func:`solve_point_filtered` integrate the same equations on the
    packed upper triangle.

    """
    P = np.asarray(P, dtype=float)
    c_eq, k_eq = equivalent_coefficients_from_moments(P[0, 0], P[0, 1], block, foundation, condensation)
    alpha = block.m * block.h / block.m_sdof * excitation.envelope(t)
    A, b = augmented_system(float(k_eq), float(c_eq), float(block.m_sdof), float(alpha), excitation.filter())
    return lyapunov_rhs(P, A, b, excitation.S0)


@numba.njit(cache=True, inline="always")
def augmented_rhs(kap, gam, alpha, q, fa, fb, fc, fd, y, dy, P, M):
    """Compiled :func:`lyapunov_rhs` on the packed covariance ``y`` (rows of the upper triangle) into ``dy``.

    Rows 0 and 2.. of ``A P`` are read from ``P`` and the filter; zero entries of ``A`` are never
    multiplied.

    Parameters
    ----------
    kap : float
        ``k_eq / m_sdof`` [1/s^2].
    gam : float
        ``c_eq / m_sdof`` [1/s].
    alpha : float
        Input gain ``m h q(t) / m_sdof`` [1/m].
    q : float
        ``2 pi S0`` [m^2/s^3].
    fa, fb, fc, fd : numpy.ndarray or float
        The filter's ``A`` (n_f x n_f), ``B``, ``C`` (n_f) and ``D``.
    y : numpy.ndarray
        Packed covariance, ``n (n + 1) / 2`` entries.
    dy : numpy.ndarray
        Its rate, written in place.
    P, M : numpy.ndarray
        ``n x n`` work arrays.

    Returns
    -------
    None

    Notes
    -----
    ``dP/dt = A P + P A^T + 2 pi S0 b b^T``: eq. (45) in [1]_ for white noise, eq. (51) with eq. (55) for a
    filtered input (:func:`augmented_system` builds ``A`` and ``b``).

    """
    n = P.shape[0]
    nf = n - 2
    idx = 0
    for i in range(n):
        for j in range(i, n):
            P[i, j] = y[idx]
            P[j, i] = y[idx]
            idx += 1
    for j in range(n):
        M[0, j] = P[1, j]
        s = -kap * P[0, j] - gam * P[1, j]
        for k in range(nf):
            s = s + (alpha * fc[k]) * P[2 + k, j]
        M[1, j] = s
        for r in range(nf):
            s = 0.0
            for k in range(nf):
                if fa[r, k] != 0.0:
                    s = s + fa[r, k] * P[2 + k, j]
            M[2 + r, j] = s
    b1 = alpha * fd
    idx = 0
    for i in range(n):
        bi = b1 if i == 1 else (fb[i - 2] if i >= 2 else 0.0)
        for j in range(i, n):
            bj = b1 if j == 1 else (fb[j - 2] if j >= 2 else 0.0)
            dy[idx] = M[i, j] + M[j, i] + q * bi * bj
            idx += 1


@numba.njit(cache=True, inline="always")
def augmented_rhs_two_states(kap, gam, alpha, q, fa, fb, fc, fd, y, dy):
    """:func:`augmented_rhs` written out for a filter of two states (Kanai–Tajimi): the 10 packed
    entries ``(00 01 02 03 11 12 13 22 23 33)`` of ``(theta, theta', x0, x1)``, no work arrays.

    Parameters
    ----------
    kap, gam, alpha, q, fa, fb, fc, fd, y, dy
        As in :func:`augmented_rhs`, with ``fa`` 2 x 2, ``fb``, ``fc`` of 2 and ``y``, ``dy`` of 10 entries.

    Returns
    -------
    None

    Notes
    -----
    Eq. (51) in [1]_ with eqs. (52)-(55) (the Kanai-Tajimi filter), as :func:`lyapunov_rhs`.

    """
    c00, c01, c02, c03, c11, c12, c13, c22, c23, c33 = y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8], y[9]
    g0 = alpha * fc[0]
    g1 = alpha * fc[1]
    f00, f01, f10, f11 = fa[0, 0], fa[0, 1], fa[1, 0], fa[1, 1]
    # rows 1, 2, 3 of A P (row 0 is row 1 of P)
    a10 = -kap * c00 - gam * c01 + g0 * c02 + g1 * c03
    a11 = -kap * c01 - gam * c11 + g0 * c12 + g1 * c13
    a12 = -kap * c02 - gam * c12 + g0 * c22 + g1 * c23
    a13 = -kap * c03 - gam * c13 + g0 * c23 + g1 * c33
    a20 = f00 * c02 + f01 * c03
    a21 = f00 * c12 + f01 * c13
    a22 = f00 * c22 + f01 * c23
    a23 = f00 * c23 + f01 * c33
    a30 = f10 * c02 + f11 * c03
    a31 = f10 * c12 + f11 * c13
    a32 = f10 * c22 + f11 * c23
    a33 = f10 * c23 + f11 * c33
    b1 = alpha * fd
    b2 = fb[0]
    b3 = fb[1]
    dy[0] = 2.0 * c01
    dy[1] = c11 + a10
    dy[2] = c12 + a20
    dy[3] = c13 + a30
    dy[4] = 2.0 * a11 + q * b1 * b1
    dy[5] = a12 + a21 + q * b1 * b2
    dy[6] = a13 + a31 + q * b1 * b3
    dy[7] = 2.0 * a22 + q * b2 * b2
    dy[8] = a23 + a32 + q * b2 * b3
    dy[9] = 2.0 * a33 + q * b3 * b3


@numba.njit(cache=True, inline="always")
def _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, alpha, y, dy, P, M):
    """:func:`augmented_rhs` (:func:`augmented_rhs_two_states` for two filter states) at the
    coefficients of the moments ``y``; returns ``(c_eq, k_eq)``."""
    c_eq, k_eq = coefficients(cond, table, y[0], y[1])
    m = osc.m_sdof
    if n == 10:
        augmented_rhs_two_states(k_eq / m, c_eq / m, alpha, 2.0 * math.pi * osc.S0, fa, fb, fc, fd, y, dy)
    else:
        augmented_rhs(k_eq / m, c_eq / m, alpha, 2.0 * math.pi * osc.S0, fa, fb, fc, fd, y, dy, P, M)
    return c_eq, k_eq


def filtered_scales(osc, filter_covariance, psd_at_rocking):
    """Absolute-tolerance scales of the packed moments of every point, ``(n_points, n (n+1)/2)``.

    The oscillator's entries from the linear oscillator at rest under the input's PSD at its
    frequency, the filter's from its stationary covariance; ``sqrt(d_i) sqrt(d_j)`` (no ``S0^2``
    underflow).

    Parameters
    ----------
    osc : numpy.ndarray
        :data:`screening.solvers.moments.OSCILLATOR` records, one per point.
    filter_covariance : numpy.ndarray
        Stationary covariance of the filter states [..., n_f, n_f].
    psd_at_rocking : numpy.ndarray
        The input's two-sided PSD at the rocking frequency [m^2/s^3], one per point.

    Returns
    -------
    numpy.ndarray
        Scales ``(n_points, n (n + 1) / 2)`` in the units of each packed moment, at least :data:`SCALE_FLOOR`.

    Notes
    -----
    The stationary linear oscillator of frequency ``w`` and damping ratio ``zeta`` under white noise of
    two-sided PSD ``S`` and gain ``alpha`` has ``E[theta'^2] = pi S alpha^2 / (2 zeta w)`` and
    ``E[theta^2] = E[theta'^2] / w^2`` (random vibration of a single degree of freedom [2]_, with the
    spectrum convention of eq. (39) in [1]_); ``zeta w`` is held at least 0.05 [1/s].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [clough1975] in the bibliography, ``docs/bibliography.md``.
    """
    m = osc["m_sdof"]
    w2 = np.abs(osc["k_rest"]) / m
    w2 = np.where(w2 <= 0.0, 1.0, w2)
    zw = np.maximum(0.5 * osc["c_rest"] / m, 0.05)
    vd = math.pi * psd_at_rocking * osc["gain"] ** 2 / (2.0 * zw)
    diag = np.concatenate([np.stack([vd / w2, vd], -1), np.diagonal(filter_covariance, axis1=-2, axis2=-1)], -1)
    root = np.sqrt(diag)
    iu = np.triu_indices(diag.shape[-1])
    return np.maximum(root[:, iu[0]] * root[:, iu[1]], SCALE_FLOOR)


@numba.njit(cache=True, fastmath=FMA)
def solve_point_filtered(coefficients, cond, table, osc, fa, fb, fc, fd, scale, t_out, rtol, h_max, max_steps,
                         store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """One point driven through a shaping filter (``fa, fb, fc, fd``: its ``A, B, C, D``), the packed
    covariance of ``(theta, theta', x)`` as the state; ``scale``: its absolute-tolerance scales
    (:func:`filtered_scales`).  Histories into row ``i`` only if ``store``.  Returns a :data:`Summary`.

    Parameters
    ----------
    coefficients, cond, table, osc : various
        The condensation's compiled coefficients, its record and table, the point's oscillator record,
        as :func:`solve_point_white`.
    fa, fb, fc, fd : numpy.ndarray or float
        The filter's ``A`` (n_f x n_f), ``B``, ``C`` (n_f) and ``D``.
    scale : numpy.ndarray
        Absolute-tolerance scales of the packed moments (:func:`filtered_scales`).
    t_out, rtol, h_max, max_steps, store, i : various
        Output times [s], relative tolerance [1], largest step [s], step budget, whether to write the
        histories and their row, as :func:`solve_point_white`.
    var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl : numpy.ndarray
        History arrays (points x output times), as :func:`solve_point_white`.

    Returns
    -------
    tuple
        A :data:`Summary`, as :func:`solve_point_white`.

    Notes
    -----
    Eq. (51) in [1]_ with eq. (55), on the packed upper triangle (:func:`augmented_rhs`; numpy reference
    :func:`moment_equations`).  Compiling it takes tens of seconds, so the example shows its interface.

    """
    return _filtered_steps(packed_size(fa.shape[0] + 2), coefficients, cond, table, osc, fa, fb, fc, fd, scale,
                           t_out, rtol, h_max, max_steps, store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o,
                           p_upl)


@numba.njit(cache=True, fastmath=FMA)
def solve_point_two_states(coefficients, cond, table, osc, fa, fb, fc, fd, scale, t_out, rtol, h_max, max_steps,
                           store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """:func:`solve_point_filtered` for a filter of two states (Kanai–Tajimi): the 10 moments in loops of
    constant length (unrolled by the compiler) and :func:`augmented_rhs_two_states`.

    Parameters
    ----------
    coefficients, cond, table, osc, fa, fb, fc, fd, scale, t_out, rtol, h_max, max_steps : various
        As :func:`solve_point_filtered`, for a filter of two states (``fa`` 2 x 2, 10 packed moments).
    store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl
        As :func:`solve_point_filtered`.

    Returns
    -------
    tuple
        A :data:`Summary`.

    Notes
    -----
    Eq. (51) in [1]_ with eqs. (52)-(55).  Compiling it takes tens of seconds, so the example shows its
    interface.

    """
    return _filtered_steps(10, coefficients, cond, table, osc, fa, fb, fc, fd, scale, t_out, rtol, h_max, max_steps,
                           store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)


@numba.njit(cache=True, inline="always")
def _filtered_steps(n, coefficients, cond, table, osc, fa, fb, fc, fd, scale, t_out, rtol, h_max, max_steps,
                    store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl):
    """The step loop of :func:`solve_point_filtered` for ``n`` packed moments (inlined: a constant ``n``
    gives constant-length loops)."""
    nn = fa.shape[0] + 2
    i11 = nn                                          # packed index of (1, 1): var_theta_dot
    P = np.empty((nn, nn))
    M = np.empty((nn, nn))
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
    t = t_out[0]
    e1, e2 = envelope_state(osc, t)
    c0, k0 = _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, initial_gain(osc, e1, e2), y, K1, P, M)
    if store:
        store_outputs(coefficients, cond, table, osc, i, 0, y[0], y[1], y[i11],
                      var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    h, code, t_end = first_step(osc, k0, h_max, t, t_out[t_out.shape[0] - 1])
    next_out, best, best_t, lowest_k, steps, rejected, log_err_old = 1, 0.0, t, k0, 0, 0, dopri.LOG_ERR_START
    while t < t_end:
        h, code = trial_step(h, t, t_end, steps, max_steps)
        if code != OK:
            break
        a2, a3, a4, a5, a6, f1, f2 = stage_gains(osc, e1, e2, h)
        for j in range(n):
            z[j] = y[j] + h * (A21 * K1[j])
        _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a2, z, K2, P, M)
        for j in range(n):
            z[j] = y[j] + h * (A31 * K1[j] + A32 * K2[j])
        _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a3, z, K3, P, M)
        for j in range(n):
            z[j] = y[j] + h * (A41 * K1[j] + A42 * K2[j] + A43 * K3[j])
        _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a4, z, K4, P, M)
        for j in range(n):
            z[j] = y[j] + h * (A51 * K1[j] + A52 * K2[j] + A53 * K3[j] + A54 * K4[j])
        _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a5, z, K5, P, M)
        for j in range(n):
            z[j] = y[j] + h * (A61 * K1[j] + A62 * K2[j] + A63 * K3[j] + A64 * K4[j] + A65 * K5[j])
        _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a6, z, K6, P, M)
        for j in range(n):
            yn[j] = y[j] + h * (B1 * K1[j] + B3 * K3[j] + B4 * K4[j] + B5 * K5[j] + B6 * K6[j])
        c_new, k_new = _filtered_rhs(n, coefficients, cond, table, osc, fa, fb, fc, fd, a6, yn, K7, P, M)
        err = 0.0
        finite = True
        for j in range(n):
            e = E1 * K1[j] + E3 * K3[j] + E4 * K4[j] + E5 * K5[j] + E6 * K6[j] + E7 * K7[j]
            e = abs(h * e) / (rtol * scale[j] + rtol * max(abs(y[j]), abs(yn[j])))
            if not (e < 1e300):
                finite = False
            err = max(err, e)
        steps += 1
        accepted, h, rejects, code = judge_step(err, finite, h, t_end)
        rejected += rejects
        if code != OK:
            break
        if not accepted:
            continue
        kv = (K1[0], K3[0], K4[0], K5[0], K6[0], K7[0])
        kc = (K1[1], K3[1], K4[1], K5[1], K6[1], K7[1])
        if store:
            kd = (K1[i11], K3[i11], K4[i11], K5[i11], K6[i11], K7[i11])
            next_out = store_dense_outputs(coefficients, cond, table, osc, i, next_out, t_out, t, h,
                                           (y[0], y[1], y[i11]), (kv, kc, kd),
                                           var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
        best, best_t = peak_in_step(t, h, y[0], yn[0], y[1], yn[1], kv, kc, best, best_t)
        y, yn = yn, y
        K1, K7 = K7, K1
        t, e1, e2, h, log_err_old, lowest_k, code = end_of_step(osc, t, h, h_max, e1, e2, f1, f2, y[0], k_new,
                                                                lowest_k, err, log_err_old)
        if code != OK:
            break
    return Summary(status=code, t_stop=t, n_steps=steps, n_rejected=rejected, peak_var_theta=best,
                   t_peak_var_theta=best_t, min_k_eq=lowest_k)
