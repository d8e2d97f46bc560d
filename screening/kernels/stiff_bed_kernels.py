"""The compiled sample integrator of the stiff-bed model (:mod:`screening.solvers.stiff_bed`): the exact
full-contact propagator (numpy) it steps with, the transfer-loss table reader, and the adaptive
Dormand–Prince loop over a chunk of samples (numerics: the stiff-bed model's module docstring and
``docs/stiff_bed.md``).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy import linalg

from screening.kernels import dopri
from screening.kernels.dopri import (A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
                                     B1, B3, B4, B5, B6, C2, C3, C4, C5, E1, E3, E4, E5, E6, E7)
from screening.kernels import mcs_kernels as kern
from screening.kernels._sample_steps import err_term as _err2, ground_input as _input, store_outcome, vertical_row
from screening.kernels.stiff_bed_contact import rocking_acceleration_jit

__all__ = []

#: Rows of the step counts :func:`integrate_sample` keeps when asked (``counts`` of shape ``(8, 2)``):
#: per phase ``(accepted, rejected)`` steps, the phase read from ``|theta|`` at the step's start:
#: ``0`` exact full-contact grid intervals, ``1`` adaptive steps in full contact, ``2..5`` adaptive steps
#: with ``|theta|`` in ``(theta_ul, 10 theta_ul]``, ``(10, 100] theta_ul``, ``(100 theta_ul, 0.05 atan(b/h)]``
#: and above ``0.05 atan(b/h)`` (free rocking on the corner); row ``6``: accepted steps of length ``h_max``
#: and accepted steps landing on an output instant; row ``7``: steps shortened to locate a transfer and
#: transfers.
COUNT_ROWS = ("full contact, exact interval", "full contact, adaptive", "theta_ul < |theta| <= 10 theta_ul",
              "10 theta_ul < |theta| <= 100 theta_ul", "100 theta_ul < |theta| <= 0.05 atan(b/h)",
              "|theta| > 0.05 atan(b/h)", "(at h_max, landing on an output instant)",
              "(shortened to locate, transfers)")
#: Upper ``|theta|`` bounds of the adaptive phases 2, 3 in units of ``theta_ul`` and of phase 4 in units of
#: ``atan(b/h)``.
PHASE_BOUNDS = (10.0, 100.0, 0.05)


def linear_propagator(m0, c0, k0, mh, dt):
    """Exact one-interval map of the full-contact oscillator under a cubic Hermite input.

    The stiff-bed model in full contact is the linear oscillator ``m0 x'' + c0 x' + k0 x = mh u(t)``; over one
    input interval ``[0, dt]`` with ``u`` the cubic Hermite interpolant of the node values ``u0, u1`` and
    rates ``d0, d1``, its state is advanced exactly by ``(x, x')(dt) = Phi (x, x')(0) + Gamma (u0, u1, dt d0,
    dt d1)``.

    Parameters
    ----------
    m0 : float
        Inertia [kg m2].
    c0 : float
        Damping [N m s/rad].
    k0 : float
        Stiffness [N m/rad].
    mh : float
        Input coefficient ``m h`` [kg m].
    dt : float
        Interval [s].

    Returns
    -------
    Phi : numpy.ndarray
        ``(2, 2)`` state transition [1, s; s-1, 1].
    Gamma : numpy.ndarray
        ``(2, 4)`` input matrix [rad per m s-2; rad s-1 per m s-2].

    Notes
    -----
    ``Phi = exp(A dt)``, ``A = [[0, 1], [-k0/m0, -c0/m0]]``.  The response to the forcing
    ``tau^n / n!`` is the state part of ``exp(M_n dt) e_3`` with the augmented generator
    ``M_n = [[A, B e_n^T], [0, J]]``, ``B = (0, mh/m0)``, ``J`` the shift ``w_i' = w_{i-1}``
    (``w_i = tau^i / i!``), Van Loan's block-exponential integral [1]; the Hermite basis
    ``(1 - 3x^2 + 2x^3, 3x^2 - 2x^3, x - 2x^2 + x^3, x^3 - x^2)``, ``x = tau / dt``, is a combination of
    those monomials (``docs/stiff_bed.md``).

    References
    ----------
    .. [1] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Transactions on
       Automatic Control 23(3) (1978) 395-404.
    """
    a_mat = np.array([[0.0, 1.0], [-k0 / m0, -c0 / m0]])
    phi = linalg.expm(a_mat * dt)
    shift = np.diag(np.ones(3), -1)
    mono = np.empty((2, 4))
    for n in range(4):
        gen = np.zeros((6, 6))
        gen[:2, :2] = a_mat
        gen[1, 2 + n] = mh / m0
        gen[2:, 2:] = shift
        mono[:, n] = linalg.expm(gen * dt)[:2, 2] * math.factorial(n) / dt ** n
    basis = np.array([[1.0, 0.0, -3.0, 2.0], [0.0, 0.0, 3.0, -2.0], [0.0, 1.0, -2.0, 1.0], [0.0, 0.0, -1.0, 1.0]])
    return phi, mono @ basis.T


@numba.njit(cache=True, inline="always")
def _accel(sp, cp, theta, theta_dot, acc):
    """:func:`rocking_acceleration_jit` under the ground input ``acc = (x_g'', a_v)``."""
    return rocking_acceleration_jit(sp, cp, theta, theta_dot, acc[0], acc[1])


@numba.njit(cache=True)
def _vertical_quiet(row, acc, acc_dot, j):
    """True when the vertical channel is zero over grid interval ``j`` (values and rates): the exact
    full-contact propagator holds there."""
    vrow = vertical_row(row, acc[1])
    if vrow < 0:
        return True
    v, r = acc[1], acc_dot[1]
    return v[vrow, j] == 0.0 and v[vrow, j + 1] == 0.0 and r[vrow, j] == 0.0 and r[vrow, j + 1] == 0.0


@numba.njit(cache=True)
def transfer_ratio_jit(log_amp, log_eta, amp):
    """Energy ratio ``eta`` of a transfer after a half cycle of amplitude ``amp``.

    Reads the transfer table: linear in ``log amp`` between the table's nodes, the first node's value below
    the first node (1 for :func:`screening.solvers.stiff_bed.transfer_table`, whose first node is
    ``(theta_ul, 1)``), the last value above the last node, and 1 for ``amp <= 0``.

    Parameters
    ----------
    log_amp : numpy.ndarray
        ``log`` of the nodes' half-cycle amplitudes [rad], increasing.
    log_eta : numpy.ndarray
        ``log`` of the nodes' energy ratios [1].
    amp : float
        Half-cycle amplitude [rad].

    Returns
    -------
    float
        ``eta`` [1]: the rocking energy kept through the transfer.

    Notes
    -----
    ``log eta = log eta_j + f (log eta_(j+1) - log eta_j)``, ``f = (log amp - log amp_j) /
    (log amp_(j+1) - log amp_j)`` (``docs/stiff_bed.md``, the transfer loss).

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` (the bed-derived transfer loss).
    """
    if amp <= 0.0:
        return 1.0
    x = math.log(amp)
    n = log_amp.shape[0]
    if x <= log_amp[0]:
        return math.exp(log_eta[0])
    if x >= log_amp[n - 1]:
        return math.exp(log_eta[n - 1])
    j = 0
    while log_amp[j + 1] < x:
        j += 1
    f = (x - log_amp[j]) / (log_amp[j + 1] - log_amp[j])
    return math.exp(log_eta[j] + f * (log_eta[j + 1] - log_eta[j]))


@numba.njit(cache=True, inline="always")
def _transfer(sp, log_amp, log_eta, amp, y0, y1):
    """``(theta, theta_dot)`` after a corner transfer of half-cycle amplitude ``amp`` [rad]: the rate scaled by
    ``sqrt(eta)``, and, where the transfer is located, the rotation past zero with it (the crossing, passed in
    full contact, at the reduced rate).  With ``sp.by_rate`` the table's nodes are crossing rates [rad/s] and
    ``eta`` is read at the rate ``|theta_dot|`` at the crossing (the impact's state) instead of ``amp``."""
    r = math.sqrt(transfer_ratio_jit(log_amp, log_eta, abs(y1) if sp.by_rate != 0.0 else amp))
    if sp.locate != 0.0:
        y0 *= r
    return y0, y1 * r


@numba.njit(cache=True, inline="always")
def _phase(sp, a0):
    """Row of :data:`COUNT_ROWS` of an adaptive step starting at ``|theta| = a0`` [rad]."""
    tu = sp.theta_ul
    if a0 <= tu:
        return 1
    if a0 <= PHASE_BOUNDS[0] * tu:
        return 2
    if a0 <= PHASE_BOUNDS[1] * tu:
        return 3
    if a0 <= PHASE_BOUNDS[2] * sp.theta_over:
        return 4
    return 5


@numba.njit(cache=True)
def integrate_sample(sp, cp, prop, log_amp, log_eta, row, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max,
                     max_steps, out_theta, out_theta_dot, out_uplift, counts):
    """Integrate one sample of the stiff-bed model over ``t_out``; fill row ``row`` of the outputs.

    In full contact with no vertical input the state is advanced over whole grid intervals by the exact
    :func:`linear_propagator`; elsewhere by the adaptive Dormand–Prince 5(4) pair on
    :func:`screening.kernels.stiff_bed_contact.rocking_acceleration_jit`, with the transfer loss
    (:func:`transfer_ratio_jit`) applied when the rotation changes sign.  After overturning or divergence
    the remaining outputs are NaN.

    Parameters
    ----------
    sp : numpy.record
        The :data:`screening.kernels.stiff_bed_contact.STIFF` record (``stiff_record(block, foundation)[0]``).
    cp : numpy.record
        The ``"cubic"`` condensation's :data:`screening.core.condensation.cubic.SDOF_RECORD` record.
    prop : numpy.ndarray
        ``(2, 6)``: ``[Phi | Gamma]`` of :func:`linear_propagator` for the grid step ``dt_grid``.
    log_amp, log_eta : numpy.ndarray
        The transfer table (:func:`screening.solvers.stiff_bed.transfer_table`): ``log`` of the half-cycle
        amplitude [rad] and of the transfer energy ratio [1].
    row : int
        The sample (row of ``acc`` and of the outputs).
    acc : tuple of numpy.ndarray
        ``(horizontal, vertical)`` ground accelerations [m s-2] on the grid ``j dt_grid``: the inertial
        ``x_g''`` one row per sample; the vertical ``a_v`` (positive up) one row per sample, one row for all,
        or :data:`screening.kernels.mcs_kernels.NO_VERTICAL`.
    acc_dot : tuple of numpy.ndarray
        Their rates [m s-3], same layout.
    dt_grid : float
        Step of the input grid [s] (cubic Hermite interpolation in between).
    t_out : numpy.ndarray
        Output times [s].
    y_init : numpy.ndarray
        Initial ``(theta, theta')`` [rad, rad s-1].
    scale : numpy.ndarray
        Absolute error scales of the two states [rad, rad s-1] (times ``rtol``).
    rtol : float
        Relative tolerance [1].
    h_max : float
        Largest step [s].
    max_steps : int
        Step budget of a sample.
    out_theta, out_theta_dot : numpy.ndarray
        Histories (samples x output times) [rad, rad s-1], written in place (NaN after overturning or
        divergence).
    out_uplift : numpy.ndarray of bool
        Uplift flag (``|theta| > theta_ul``) at the output times, same layout.
    counts : numpy.ndarray
        ``(8, 2)`` integers incremented by the step counts of :data:`COUNT_ROWS`, or ``(0, 2)`` (not counted).

    Returns
    -------
    tuple
        ``(status, reason, peak_abs_theta [rad], n_accepted, n_rejected, h_min_accepted [s])`` (exact
        full-contact intervals count as accepted steps): status as
        :data:`screening.kernels.mcs_kernels.STATUS_OK` and its siblings, with a ``REASON_*`` code.

    Notes
    -----
    The equation of motion ``m_eff theta'' + (1/2) dm_eff theta'^2 + C_eff theta' + Q = m h cos(theta)
    x_g''`` on the contact law of eq. (3) in [1] (``docs/stiff_bed.md``), the Dormand–Prince pair [2] with
    the PI step control of [3].  Compiling the kernel takes tens of seconds, so the example shows its
    interface; ``tests/unit/solvers/test_stiff_bed_numerics.py`` holds it against scipy.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [3] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    .. [4] The package's documentation, ``docs/stiff_bed.md`` (the stiff-bed model's numerics).
    """
    n_out = t_out.shape[0]
    n_grid = acc[0].shape[1]
    y0, y1 = y_init[0], y_init[1]
    s0, s1 = scale[0], scale[1]
    tu = sp.theta_ul
    t = t_out[0]
    out_theta[row, 0] = y0
    out_theta_dot[row, 0] = y1
    out_uplift[row, 0] = abs(y0) > tu
    for i in range(1, n_out):
        out_theta[row, i] = np.nan
        out_theta_dot[row, i] = np.nan
        out_uplift[row, i] = False
    peak = abs(y0)
    amp = abs(y0)
    status = kern.STATUS_OK
    reason = kern.REASON_NONE
    n_acc = 0
    n_rej = 0
    h_min_acc = np.inf
    log_err_old = dopri.LOG_ERR_START
    jg = int(math.floor(t / dt_grid + 1e-9))
    at_grid = abs(t - jg * dt_grid) <= 1e-9 * dt_grid
    k1_0 = 0.0
    k1_1 = 0.0
    stale = True
    h = min(1e-4, h_max)
    h_floor = 1e-12 * (t_out[n_out - 1] - t_out[0] + 1.0)
    i_out = 1
    rejected = False
    locating = False
    counting = counts.shape[0] > 0
    while i_out < n_out:
        if n_acc + n_rej >= max_steps:
            status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_BUDGET
            break
        t_next = t_out[i_out]
        full = abs(y0) <= tu
        old0 = y0
        if at_grid and full and jg + 1 < n_grid and (jg + 1) * dt_grid < t_next - 1e-9 * dt_grid \
                and _vertical_quiet(row, acc, acc_dot, jg):
            # --- exact full-contact interval
            u0 = acc[0][row, jg]
            u1 = acc[0][row, jg + 1]
            u2 = dt_grid * acc_dot[0][row, jg]
            u3 = dt_grid * acc_dot[0][row, jg + 1]
            n0 = prop[0, 0] * y0 + prop[0, 1] * y1 + prop[0, 2] * u0 + prop[0, 3] * u1 + prop[0, 4] * u2 \
                + prop[0, 5] * u3
            if abs(n0) <= tu:
                n1 = prop[1, 0] * y0 + prop[1, 1] * y1 + prop[1, 2] * u0 + prop[1, 3] * u1 + prop[1, 4] * u2 \
                    + prop[1, 5] * u3
                jg += 1
                t = jg * dt_grid
                y0, y1 = n0, n1
                n_acc += 1
                if counting:
                    counts[0, 0] += 1
                    if amp > tu and (old0 * y0 < 0.0 or (old0 == 0.0 and y0 != 0.0)):
                        counts[7, 1] += 1
                if old0 * y0 < 0.0 or (old0 == 0.0 and y0 != 0.0):
                    if amp > tu:
                        y0, y1 = _transfer(sp, log_amp, log_eta, amp, y0, y1)
                    amp = 0.0
                a0 = abs(y0)
                amp = max(amp, a0)
                if a0 > peak:
                    peak = a0
                stale = True                    # the first stage of the next adaptive step
                continue
        # --- adaptive step, landing on the next output instant (and on the next grid point in full contact)
        if stale:
            k1_0 = y1
            k1_1 = _accel(sp, cp, y0, y1, _input(row, acc, acc_dot, dt_grid, t))
            stale = False
        target = t_next
        to_grid = False
        j_next = jg + 1 if at_grid else int(math.floor(t / dt_grid)) + 1
        if full and j_next < n_grid and j_next * dt_grid < t_next - 1e-9 * dt_grid:
            target = j_next * dt_grid
            to_grid = True
        h = min(h, h_max)
        h_proposed = h
        landing = False
        if t + h >= target - 1e-9 * h:
            h = target - t
            landing = True
        g0 = y0 + h * A21 * k1_0
        g1 = y1 + h * A21 * k1_1
        k2_0 = g1
        k2_1 = _accel(sp, cp, g0, g1, _input(row, acc, acc_dot, dt_grid, t + C2 * h))
        g0 = y0 + h * (A31 * k1_0 + A32 * k2_0)
        g1 = y1 + h * (A31 * k1_1 + A32 * k2_1)
        k3_0 = g1
        k3_1 = _accel(sp, cp, g0, g1, _input(row, acc, acc_dot, dt_grid, t + C3 * h))
        g0 = y0 + h * (A41 * k1_0 + A42 * k2_0 + A43 * k3_0)
        g1 = y1 + h * (A41 * k1_1 + A42 * k2_1 + A43 * k3_1)
        k4_0 = g1
        k4_1 = _accel(sp, cp, g0, g1, _input(row, acc, acc_dot, dt_grid, t + C4 * h))
        g0 = y0 + h * (A51 * k1_0 + A52 * k2_0 + A53 * k3_0 + A54 * k4_0)
        g1 = y1 + h * (A51 * k1_1 + A52 * k2_1 + A53 * k3_1 + A54 * k4_1)
        k5_0 = g1
        k5_1 = _accel(sp, cp, g0, g1, _input(row, acc, acc_dot, dt_grid, t + C5 * h))
        g0 = y0 + h * (A61 * k1_0 + A62 * k2_0 + A63 * k3_0 + A64 * k4_0 + A65 * k5_0)
        g1 = y1 + h * (A61 * k1_1 + A62 * k2_1 + A63 * k3_1 + A64 * k4_1 + A65 * k5_1)
        acc_end = _input(row, acc, acc_dot, dt_grid, t + h)
        k6_0 = g1
        k6_1 = _accel(sp, cp, g0, g1, acc_end)
        n0 = y0 + h * (B1 * k1_0 + B3 * k3_0 + B4 * k4_0 + B5 * k5_0 + B6 * k6_0)
        n1 = y1 + h * (B1 * k1_1 + B3 * k3_1 + B4 * k4_1 + B5 * k5_1 + B6 * k6_1)
        k7_0 = n1
        k7_1 = _accel(sp, cp, n0, n1, acc_end)
        e0 = h * (E1 * k1_0 + E3 * k3_0 + E4 * k4_0 + E5 * k5_0 + E6 * k6_0 + E7 * k7_0)
        e1 = h * (E1 * k1_1 + E3 * k3_1 + E4 * k4_1 + E5 * k5_1 + E6 * k6_1 + E7 * k7_1)
        err = math.sqrt(0.5 * (_err2(e0, y0, n0, s0, rtol) + _err2(e1, y1, n1, s1, rtol)))
        phase = _phase(sp, abs(y0)) if counting else 0
        if not math.isfinite(err):
            n_rej += 1
            if counting:
                counts[phase, 1] += 1
            h = 0.1 * h
            rejected = True
            if h < h_floor:
                status, reason = kern.STATUS_DIVERGED, kern.REASON_NONFINITE
                break
            continue
        if err > 1.0:
            n_rej += 1
            if counting:
                counts[phase, 1] += 1
            h = h * dopri.rejected_step_factor_log(math.log(err))
            rejected = True
            if h < h_floor:
                status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_UNDERFLOW
                break
            continue
        if sp.locate != 0.0 and amp > tu and old0 * n0 < 0.0 and abs(n0) > tu:
            # a transfer whose step ends in uplift on the other side: shorten the step to the crossing
            # (linear estimate, repeated until the step ends in full contact) so the velocity ratio
            # is applied where the block passes through full contact, not a step later
            n_rej += 1
            if counting:
                counts[7, 0] += 1
            h = h * min(max(old0 / (old0 - n0), 0.01), 0.99)
            locating = True
            if h < h_floor:
                status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_UNDERFLOW
                break
            continue
        n_acc += 1
        if counting:
            counts[phase, 0] += 1
            if h >= h_max:
                counts[6, 0] += 1
            if landing and not to_grid:
                counts[6, 1] += 1
        if h < h_min_acc and not landing and not locating and n_acc > 10:
            h_min_acc = h
        locating = False
        t = target if landing else t + h
        if landing and to_grid:
            jg = j_next
            at_grid = True
        else:
            at_grid = False
        y0, y1 = n0, n1
        k1_0, k1_1 = k7_0, k7_1
        if counting and amp > tu and (old0 * y0 < 0.0 or (old0 == 0.0 and y0 != 0.0)):
            counts[7, 1] += 1
        if old0 * y0 < 0.0 or (old0 == 0.0 and y0 != 0.0):
            if amp > tu:
                y0, y1 = _transfer(sp, log_amp, log_eta, amp, y0, y1)
                k1_0 = y1
                k1_1 = _accel(sp, cp, y0, y1, acc_end)
            amp = 0.0
        a0 = abs(y0)
        amp = max(amp, a0)
        if a0 > peak:
            peak = a0
        if a0 > sp.theta_over:
            status = kern.STATUS_OVERTURNED
            break
        if abs(y1) > sp.rate_max or not math.isfinite(y1):
            status, reason = kern.STATUS_DIVERGED, kern.REASON_OUT_OF_BOUNDS
            break
        if a0 > sp.theta_cap:
            status, reason = kern.STATUS_DIVERGED, kern.REASON_NO_EQUILIBRIUM
            break
        if sp.g + acc_end[1] < 0.0:                    # the block lifts off: not this model's
            status, reason = kern.STATUS_DIVERGED, kern.REASON_LIFT_OFF
            break
        if landing and not to_grid:
            out_theta[row, i_out] = y0
            out_theta_dot[row, i_out] = y1
            out_uplift[row, i_out] = a0 > tu * (1.0 + acc_end[1] / sp.g)
            i_out += 1
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


@numba.njit(cache=True, parallel=True)
def integrate_chunk(sp, cp, prop, log_amp, log_eta, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max,
                    max_steps, out_theta, out_theta_dot, out_uplift, peak, status, reason, n_accepted, n_rejected,
                    h_min, counts):
    """:func:`integrate_sample` for every row of ``acc`` (samples in parallel).

    Fills the histories and the per-sample outcome arrays in place (``prange`` over samples); the
    integrator the registered stiff-bed model calls per chunk of Monte Carlo samples.

    Parameters
    ----------
    sp, cp, prop, log_amp, log_eta, acc, acc_dot, dt_grid, t_out : see integrate_sample
        As in :func:`integrate_sample` (``sp``, ``cp`` here the 1-element arrays of the records).
    y_init, scale, rtol, h_max, max_steps, out_theta, out_theta_dot, out_uplift : see integrate_sample
        As in :func:`integrate_sample` (the histories hold every sample, one row each).
    peak : numpy.ndarray
        Per sample: largest ``|theta|`` [rad], written in place.
    status, reason : numpy.ndarray
        Per sample: outcome code and its reason (:mod:`screening.kernels.mcs_kernels`), written in place.
    n_accepted, n_rejected : numpy.ndarray
        Per sample: accepted and rejected steps, written in place.
    h_min : numpy.ndarray
        Per sample: smallest accepted step [s], written in place.
    counts : numpy.ndarray
        ``(rows, 8, 2)`` integers (the step counts of row ``r``, :data:`COUNT_ROWS`, added to ``counts[r]``)
        or ``(0, 8, 2)`` (not counted).

    Returns
    -------
    None
        The outputs are written in place.

    Notes
    -----
    Each sample is :func:`integrate_sample` (its Notes: the equations of [1], the Dormand–Prince pair [2],
    the step control of [3]).  Compiling the kernel takes tens of seconds, so the example shows its
    interface.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [3] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    .. [4] The package's documentation, ``docs/stiff_bed.md`` (the stiff-bed model's numerics).
    """
    no_counts = np.zeros((0, 2), dtype=np.int64)
    for row in numba.prange(acc[0].shape[0]):
        cnt = counts[row] if counts.shape[0] > 0 else no_counts
        store_outcome(row, integrate_sample(sp[0], cp[0], prop, log_amp, log_eta, row, acc, acc_dot, dt_grid,
                                                  t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                                                  out_theta_dot, out_uplift, cnt),
                            status, reason, peak, n_accepted, n_rejected, h_min)
