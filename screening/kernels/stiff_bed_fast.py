"""Compiled sample integrator of the stiff-bed model's exact-contact sampler (``model="stiff_bed_fast"``,
:mod:`screening.solvers.stiff_bed_fast`).

The same equations as :mod:`screening.kernels.stiff_bed_kernels` (the reference), integrated differently:

* full contact (``|theta| <= theta_ul``) is the linear oscillator ``m0 x'' + c0 x' + k0 x = mh u(t)``; it is
  advanced in closed form over any interval (:func:`oscillator_step`: the exponential of the 2x2 system and
  the polynomial particular solution of the cubic Hermite input), a whole grid interval by the precomputed
  ``[Phi | Gamma]``; the exit at ``|theta| = theta_ul`` and the zero crossing (where the transfer ratio
  applies) are located on the closed form (Newton in the bracket), so no adaptive step enters full contact;
* uplift is integrated by the adaptive Dormand–Prince 5(4) pair on the model's acceleration (one indentation
  solve per evaluation, :func:`uplift_acceleration`); an accepted step that ends in full contact is cut where
  the block re-enters it, the last root of ``|theta| = theta_ul`` on the step's dense output (no step redone);
  the outputs are read from the step's cubic Hermite interpolant instead of landing steps on them.  Moving towards full contact the next
  step shrinks with the contact law's time scale ``|theta| / |theta'|`` (the error controller alone lags
  behind it: all its rejections were there), and the last stage of a step is the next one's first.

Method and measurements: ``docs/stiff_bed.md`` ("Exact-contact sampler").
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.core.condensation import cubic
from screening.kernels import dopri
from screening.kernels._sample_steps import err_term, store_outcome
from screening.kernels.dopri import (P, A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65,
                                     B1, B3, B4, B5, B6, C2, C3, C4, C5, E1, E3, E4, E5, E6, E7)
from screening.kernels import mcs_kernels as kern
from screening.kernels.stiff_bed_contact import constraint_damping_jit, indentation_curvature_jit
from screening.kernels.stiff_bed_kernels import transfer_ratio_jit

__all__ = []

#: What :func:`integrate_sample` counts when asked (``counts`` of shape ``(len(COUNTS),)``; an uplift attempt's
#: phase by ``|theta|`` at its start).
COUNTS = ("full contact: whole grid intervals", "full contact: closed-form pieces", "uplift: accepted steps",
          "uplift: rejected steps", "uplift: steps cut at the re-entry", "exits from full contact",
          "transfers at the zero crossing", "uplift attempts at |theta|/theta_ul in (1, 10]", "... (10, 100]",
          "... (100, 1000]", "... above 1000")

#: Largest phase ``omega_r h`` [rad] of a closed-form piece in full contact when the block may leave it within a
#: grid interval: the exit is checked at the ends of pieces this short (a sinusoid sampled every 0.5 rad shows
#: any excursion beyond ``theta_ul`` larger than 3 % of its amplitude).
PIECE_PHASE = 0.5


@numba.njit(cache=True)
def oscillator_exponential(omega2, c, tau):
    """``exp(A tau)`` of ``A = [[0, 1], [-omega2, -c]]`` in closed form: ``(E00, E01, E10, E11)``.

    Parameters
    ----------
    omega2 : float
        ``k0 / m0`` [s-2], > 0.
    c : float
        ``c0 / m0`` [s-1], >= 0.
    tau : float
        Interval [s], >= 0.

    Returns
    -------
    tuple of float
        The four entries [1, s, s-2, 1].

    Notes
    -----
    With ``mu = -c/2`` and ``d2 = c^2/4 - omega2``: ``exp(A tau) = e^{mu tau} (ch I + sh (A - mu I))``,
    ``ch, sh = cos(w tau), sin(w tau)/w`` (``w^2 = -d2``, underdamped), ``cosh(d tau), sinh(d tau)/d``
    (``d^2 = d2``, overdamped; from the two real exponentials) or ``1, tau`` (critical); a series near
    critical damping.
    """
    mu = -0.5 * c
    d2 = 0.25 * c * c - omega2
    x2 = abs(d2) * tau * tau
    if x2 < 1e-8:                                      # near critical: series of ch, sh in d2 tau^2
        em = math.exp(mu * tau)
        ch = em * (1.0 + 0.5 * d2 * tau * tau)
        sh = em * tau * (1.0 + d2 * tau * tau / 6.0)
    elif d2 < 0.0:
        w = math.sqrt(-d2)
        em = math.exp(mu * tau)
        ch = em * math.cos(w * tau)
        sh = em * math.sin(w * tau) / w
    else:
        d = math.sqrt(d2)
        e1 = math.exp((mu + d) * tau)
        e2 = math.exp((mu - d) * tau)
        ch = 0.5 * (e1 + e2)
        sh = 0.5 * (e1 - e2) / d
    return ch + 0.5 * c * sh, sh, -omega2 * sh, ch - 0.5 * c * sh


@numba.njit(cache=True)
def oscillator_step(omega2, c, g, x0, v0, p0, p1, p2, p3, tau):
    """Exact state of ``x'' + c x' + omega2 x = g P(s)`` at ``s = tau`` from ``(x0, v0)`` at ``s = 0``, with
    the cubic input ``P(s) = p0 + p1 s + p2 s^2 + p3 s^3``.

    Parameters
    ----------
    omega2, c : float
        ``k0 / m0`` [s-2] and ``c0 / m0`` [s-1] (:func:`oscillator_exponential`).
    g : float
        ``mh / m0`` [rad per m]: the input's coefficient.
    x0, v0 : float
        Initial rotation [rad] and rate [rad s-1].
    p0, p1, p2, p3 : float
        The input's coefficients [m s-2, m s-3, m s-4, m s-5].
    tau : float
        Interval [s].

    Returns
    -------
    tuple of float
        ``(x, v)`` at ``tau`` [rad, rad s-1].

    Notes
    -----
    The particular solution is the cubic ``q0 + q1 s + q2 s^2 + q3 s^3`` with ``omega2 q3 = g p3``,
    ``omega2 q2 = g p2 - 3 c q3``, ``omega2 q1 = g p1 - 2 c q2 - 6 q3``, ``omega2 q0 = g p0 - c q1 - 2 q2``;
    the rest decays as ``exp(A s)`` (:func:`oscillator_exponential`).
    """
    q3 = g * p3 / omega2
    q2 = (g * p2 - 3.0 * c * q3) / omega2
    q1 = (g * p1 - 2.0 * c * q2 - 6.0 * q3) / omega2
    q0 = (g * p0 - c * q1 - 2.0 * q2) / omega2
    e00, e01, e10, e11 = oscillator_exponential(omega2, c, tau)
    r0 = x0 - q0
    r1 = v0 - q1
    x = q0 + tau * (q1 + tau * (q2 + tau * q3)) + e00 * r0 + e01 * r1
    v = q1 + tau * (2.0 * q2 + 3.0 * tau * q3) + e10 * r0 + e11 * r1
    return x, v


@numba.njit(cache=True, inline="always")
def _hermite_poly(u0, u1, d0, d1, dt, s0):
    """Coefficients ``(p0, p1, p2, p3)`` in ``sigma = s - s0`` of the cubic Hermite interpolant on ``[0, dt]``
    of the node values ``u0, u1`` and rates ``d0, d1``."""
    c2 = (3.0 * (u1 - u0) / dt - 2.0 * d0 - d1) / dt
    c3 = (2.0 * (u0 - u1) / dt + d0 + d1) / (dt * dt)
    p0 = u0 + s0 * (d0 + s0 * (c2 + s0 * c3))
    p1 = d0 + s0 * (2.0 * c2 + 3.0 * c3 * s0)
    p2 = c2 + 3.0 * c3 * s0
    return p0, p1, p2, c3


def grid_propagator(omega2, c, g, dt, tau=None):
    """``[Phi | Gamma]`` (2 x 6) of one grid interval: ``(x, v)(dt) = Phi (x, v)(0) + Gamma (u0, u1, dt d0, dt d1)``,
    from :func:`oscillator_step` (the same map as :func:`screening.kernels.stiff_bed_kernels.linear_propagator`).

    Parameters
    ----------
    omega2, c, g : float
        ``k0 / m0`` [s-2], ``c0 / m0`` [s-1], ``mh / m0`` [rad per m].
    dt : float
        Grid step [s].
    tau : float, optional
        End of the map within the interval [s] (default ``dt``).

    Returns
    -------
    numpy.ndarray
        ``(2, 6)``: the state at ``tau`` from the state at the interval's start and its input.
    """
    out = np.empty((2, 6))
    unit = np.eye(6)
    for col in range(6):
        x0, v0, u0, u1, r0, r1 = unit[col]
        p0, p1, p2, p3 = _hermite_poly(u0, u1, r0 / dt, r1 / dt, dt, 0.0)
        if col < 2:
            p0 = p1 = p2 = p3 = 0.0
        out[:, col] = oscillator_step(omega2, c, g, x0, v0, p0, p1, p2, p3, dt if tau is None else tau)
    return out


def grid_pieces(omega2, c, g, dt):
    """``(m, 2, 6)``: :func:`grid_propagator` to ``i dt / m`` (``i = 1..m``), ``m = ceil(omega dt / PIECE_PHASE)``.

    Parameters
    ----------
    omega2, c, g : float
        ``k0 / m0`` [s-2], ``c0 / m0`` [s-1], ``mh / m0`` [rad per m].
    dt : float
        Grid step [s].

    Returns
    -------
    numpy.ndarray
        The maps of the pieces' ends.
    """
    m = max(1, int(math.ceil(math.sqrt(omega2) * dt / PIECE_PHASE)))
    return np.stack([grid_propagator(omega2, c, g, dt, i * dt / m) for i in range(1, m + 1)])


#: Largest ``|theta|`` [rad] where :func:`_sin_cos` sums its Taylor polynomials (error below 1e-16 relative).
SERIES_LIMIT = 0.3
#: Below this ``|theta|`` [rad] :func:`_sin_cos` stops at ``theta^7`` and ``theta^8`` (error below 1e-19 relative).
SHORT_SERIES_LIMIT = 0.02


@numba.njit(cache=True, inline="always")
def _sin_cos(theta):
    """``(sin theta, cos theta)``: Taylor polynomials to ``theta^13`` and ``theta^14`` up to
    :data:`SERIES_LIMIT` (within an ulp of ``math.sin``, ``math.cos``; a third of their cost), else ``math``."""
    if abs(theta) > SERIES_LIMIT:
        return math.sin(theta), math.cos(theta)
    t2 = theta * theta
    if t2 < SHORT_SERIES_LIMIT * SHORT_SERIES_LIMIT:          # the first terms suffice: a shorter chain
        return (theta * (1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0)))),
                1.0 + t2 * (-0.5 + t2 * (1.0 / 24.0 + t2 * (-1.0 / 720.0 + t2 * (1.0 / 40320.0)))))
    s = theta * (1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0 + t2 * (
        1.0 / 362880.0 + t2 * (-1.0 / 39916800.0 + t2 * (1.0 / 6227020800.0)))))))
    c = 1.0 + t2 * (-0.5 + t2 * (1.0 / 24.0 + t2 * (-1.0 / 720.0 + t2 * (1.0 / 40320.0 + t2 * (
        -1.0 / 3628800.0 + t2 * (1.0 / 479001600.0 + t2 * (-1.0 / 87178291200.0)))))))
    return s, c


@numba.njit(cache=True)
def uplift_acceleration(sp, cp, theta, theta_dot, x_g_ddot):
    """Compiled :func:`screening.kernels.stiff_bed_contact.rocking_acceleration` without vertical input: one
    indentation solve per call (the reference solves it twice).

    Parameters
    ----------
    sp, cp : numpy.record
        The :data:`screening.kernels.stiff_bed_contact.STIFF` and ``"cubic"`` condensation records.
    theta, theta_dot : float
        Rotation [rad] and rate [rad s-1].
    x_g_ddot : float
        Inertial ground acceleration [m s-2].

    Returns
    -------
    float
        ``theta''`` [rad s-2].
    """
    s, c = _sin_cos(theta)
    sigma = 1.0 if theta >= 0.0 else -1.0
    a = sigma * s
    z, dz, v = cubic.quasi_static_indentation_jit(cp, a)
    d2z = indentation_curvature_jit(cp, a, z, dz, v)
    damping = constraint_damping_jit(cp, a, z, dz, v)
    b, k, eps = cp.b, cp.k, cp.eps
    m, h = sp.m, sp.h
    mgh = m * sp.g * h
    b3 = b * b * b
    if a <= cp.theta_ul:
        moment = (2.0 / 3.0 * b3 * k + eps * k * (2.0 * b3 * z * z + 0.4 * b3 * b * b * a * a)) * a
    else:
        ba = b * a
        v2 = v * v
        moment = (k * v2 * (2.0 * ba - z) / 6.0 + eps * k * v2 * v2 * (4.0 * ba - z) / 20.0) / (a * a)
    u = sigma * c * dz + h * s
    m_eff = sp.I_cm + m * (h * h * c * c + u * u)
    dm_eff = m * (-2.0 * h * h * c * s + 2.0 * u * (c * c * d2z - a * dz + h * c))
    q = sigma * c * moment - mgh * s
    return (m * h * c * x_g_ddot - q - c * c * damping * theta_dot - 0.5 * dm_eff * theta_dot * theta_dot) / m_eff


#: Per-bed constants of :func:`lifted_acceleration` (:func:`lifted_record`).
LIFTED = ("m", "g", "h", "I_cm", "b", "k", "eps", "w_rate", "w_indentation", "theta_ul")


def lifted_record(sp, cp):
    """The constants of :func:`lifted_acceleration` (:data:`LIFTED`, SI) from the model's two records.

    Parameters
    ----------
    sp, cp : numpy.record
        The :data:`screening.kernels.stiff_bed_contact.STIFF` and ``"cubic"`` condensation records.

    Returns
    -------
    numpy.ndarray
        ``(len(LIFTED),)``.
    """
    return _lifted(sp, cp)


@numba.njit(cache=True)
def _lifted(sp, cp):
    """Compiled :func:`lifted_record`."""
    return np.array([sp.m, sp.g, sp.h, sp.I_cm, cp.b, cp.k, cp.eps, cp.w_rate, cp.w_indentation, cp.theta_ul])


@numba.njit(cache=True, inline="always")
def lifted_acceleration(par, sp, cp, theta, theta_dot, x_g_ddot):
    """:func:`uplift_acceleration` with the uplift branch of the contact law written out once (two square
    roots, three divisions); in full contact and beyond the capacity angle it is :func:`uplift_acceleration`.

    Parameters
    ----------
    par : numpy.ndarray
        :func:`lifted_record`.
    sp, cp : numpy.record
        The model's records (:func:`uplift_acceleration`).
    theta, theta_dot : float
        Rotation [rad] and rate [rad s-1].
    x_g_ddot : float
        Inertial ground acceleration [m s-2].

    Returns
    -------
    float
        ``theta''`` [rad s-2].

    Notes
    -----
    Uplift (``eps z^3``-free Winkler pressure with its cubic term, contact from the corner): ``A = 2 m g a / k``,
    ``S = sqrt(1 + 2 eps A)``, ``v = sqrt(2 A / (1 + S))``, ``Z = v - b a``, ``Z' = m g / (k S v) - b``,
    ``Z'' = -(m g / k) (2 eps m g v / (k S) + S (Z' + b)) / (S v)^2``, the bed moment
    ``(k v^2 (2 b a - Z) / 6 + eps k v^4 (4 b a - Z) / 20) / a^2`` and ``C_D`` of
    :func:`screening.kernels.stiff_bed_contact.constraint_damping` with ``L = v / a`` (``docs/stiff_bed.md``).
    """
    s, c = _sin_cos(theta)
    sigma = 1.0 if theta >= 0.0 else -1.0
    a = sigma * s
    m, g, h, i_cm, b, k, eps, w_rate, w_ind, tu = par[0], par[1], par[2], par[3], par[4], par[5], par[6], par[7], \
        par[8], par[9]
    if a <= tu:
        return uplift_acceleration(sp, cp, theta, theta_dot, x_g_ddot)
    mg_k = m * g / k
    big_a = 2.0 * mg_k * a
    if eps == 0.0:
        S = 1.0
        v = math.sqrt(big_a)
    else:
        s2 = 1.0 + 2.0 * eps * big_a
        if s2 <= 0.0:
            return uplift_acceleration(sp, cp, theta, theta_dot, x_g_ddot)
        S = math.sqrt(s2)
        v = math.sqrt(2.0 * big_a / (1.0 + S))
    inv_sv = 1.0 / (S * v)
    inv_a = 1.0 / a
    ba = b * a
    z = v - ba
    dz = mg_k * inv_sv - b
    qq = dz + b
    d2z = -mg_k * (2.0 * eps * mg_k / S * v + S * qq) * inv_sv * inv_sv
    length = v * inv_a
    r = qq - 0.5 * length
    t3 = qq - length / 3.0
    l2 = length * length
    damping = w_rate * length * (r * r + l2 / 12.0) + w_ind * v * length * (0.5 * t3 * t3 + l2 / 36.0)
    v2 = v * v
    moment = (k * v2 * (2.0 * ba - z) / 6.0 + eps * k * v2 * v2 * (4.0 * ba - z) / 20.0) * inv_a * inv_a
    mgh = m * g * h
    u = sigma * c * dz + h * s
    m_eff = i_cm + m * (h * h * c * c + u * u)
    dm_eff = m * (-2.0 * h * h * c * s + 2.0 * u * (c * c * d2z - a * dz + h * c))
    q = sigma * c * moment - mgh * s
    return (m * h * c * x_g_ddot - q - c * c * damping * theta_dot - 0.5 * dm_eff * theta_dot * theta_dot) / m_eff


@numba.njit(cache=True)
def modulate(z, cos_shift, sin_shift, q, q_dot, acc, rate):
    """``acc = q f``, ``rate = q' f + q f'`` from ``f + i f' = z e^{i d_omega t / 2}`` (the half-bin shift as its
    cosine and sine), row by row, in one pass (:func:`screening.solvers.stiff_bed_fast.band_samples`).

    Parameters
    ----------
    z : numpy.ndarray
        ``(rows, >= n)`` complex: the inverse FFT of the batch.
    cos_shift, sin_shift, q, q_dot : numpy.ndarray
        ``(n,)``: the shift's cosine and sine [1], the envelope [1] and its rate [s-1].
    acc, rate : numpy.ndarray
        ``(rows, n)`` outputs [m s-2, m s-3], written in place.

    Returns
    -------
    None
    """
    n = acc.shape[1]
    for r in range(acc.shape[0]):
        for j in range(n):
            f = z[r, j].real * cos_shift[j] - z[r, j].imag * sin_shift[j]
            fd = z[r, j].real * sin_shift[j] + z[r, j].imag * cos_shift[j]
            acc[r, j] = q[j] * f
            rate[r, j] = q_dot[j] * f + q[j] * fd


@numba.njit(cache=True, inline="always")
def _dense_sum(k1, k3, k4, k5, k6, k7, s):
    """``sum_i K_i q_i(s)`` of the Dormand-Prince dense output (:func:`screening.kernels.dopri.dense_output`)."""
    ks = (k1, 0.0, k3, k4, k5, k6, k7)
    val = 0.0
    for i in range(7):
        val += ks[i] * s * (P[i, 0] + s * (P[i, 1] + s * (P[i, 2] + s * P[i, 3])))
    return val


@numba.njit(cache=True, inline="always")
def _dense_rotation(x, h, k1, k3, k4, k5, k6, k7, s):
    """The rotation of the step's dense output at fraction ``s`` and its derivative in ``s``."""
    val = 0.0
    der = 0.0
    ks = (k1, 0.0, k3, k4, k5, k6, k7)
    for i in range(7):
        val += ks[i] * s * (P[i, 0] + s * (P[i, 1] + s * (P[i, 2] + s * P[i, 3])))
        der += ks[i] * (P[i, 0] + s * (2.0 * P[i, 1] + s * (3.0 * P[i, 2] + s * 4.0 * P[i, 3])))
    return x + h * val, h * der


@numba.njit(cache=True, inline="always")
def _input(acc, acc_dot, row, dt, n_grid, t):
    """Cubic Hermite ground input of row ``row`` at ``t``."""
    x = t / dt
    j = int(x)
    if j > n_grid - 2:
        j = n_grid - 2
    if j < 0:
        j = 0
    s = x - j
    u0 = acc[row, j]
    u1 = acc[row, j + 1]
    d0 = dt * acc_dot[row, j]
    d1 = dt * acc_dot[row, j + 1]
    s2 = s * s
    s3 = s2 * s
    return (2.0 * s3 - 3.0 * s2 + 1.0) * u0 + (3.0 * s2 - 2.0 * s3) * u1 + (s3 - 2.0 * s2 + s) * d0 + (s3 - s2) * d1


@numba.njit(cache=True)
def _locate(osc, x0, v0, p0, p1, p2, p3, lo, hi, f_hi, target):
    """Time ``sigma`` in ``(lo, hi]`` where the closed-form rotation from ``(x0, v0)`` reaches ``target``
    (``f_hi = x(hi) - target``), and the state there: Newton in the bracket.

    A piece that starts on ``target`` (a re-entry at ``theta_ul``) and dips to the other side before crossing
    back has no bracket at ``lo``: the bracket's low end moves to the first of ``lo + (hi - lo) 2^-j``
    (``j = 1, 2, ...``) on the other side, so the root found is the return, never the start (a root at ``lo``
    would hand the same state back and forth with the uplift steps, a stall).  If the rotation shows no such
    point (a dip below rounding), the piece ends at ``hi`` with its state there."""
    f_lo = oscillator_step(osc[0], osc[1], osc[2], x0, v0, p0, p1, p2, p3, lo)[0] - target
    if f_lo == 0.0 or (f_lo > 0.0) == (f_hi > 0.0):
        width = hi - lo
        found = False
        for j in range(1, 60):
            s = lo + width * 0.5 ** j
            f = oscillator_step(osc[0], osc[1], osc[2], x0, v0, p0, p1, p2, p3, s)[0] - target
            if f != 0.0 and (f > 0.0) != (f_hi > 0.0):
                lo, f_lo, found = s, f, True
                break
        if not found:
            x, v = oscillator_step(osc[0], osc[1], osc[2], x0, v0, p0, p1, p2, p3, hi)
            return hi, x, v
    s = lo + (hi - lo) * f_lo / (f_lo - f_hi) if f_lo != f_hi else 0.5 * (lo + hi)
    x = target
    v = 0.0
    for _ in range(40):
        x, v = oscillator_step(osc[0], osc[1], osc[2], x0, v0, p0, p1, p2, p3, s)
        f = x - target
        if (f > 0.0) == (f_lo > 0.0):
            lo, f_lo = s, f
        else:
            hi, f_hi = s, f
        if abs(f) <= 1e-13 * abs(target) + 1e-300 or hi - lo <= 1e-15 * (1.0 + hi):
            break
        s_new = s - f / v if v != 0.0 else 0.5 * (lo + hi)
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        s = s_new
    return s, target, v


@numba.njit(cache=True)
def integrate_sample(sp, cp, osc, prop, pieces, log_amp, log_eta, row, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol,
                     h_max, max_steps, out_theta, out_theta_dot, out_uplift, counts):
    """Integrate one sample of the stiff-bed model (module docstring); fill row ``row`` of the outputs.

    Parameters
    ----------
    sp, cp : numpy.record
        The :data:`screening.kernels.stiff_bed_contact.STIFF` and ``"cubic"`` condensation records.
    osc : numpy.ndarray
        ``(omega2 [s-2], c [s-1], g [rad per m], omega_r [rad s-1])`` of the full-contact oscillator.
    prop : numpy.ndarray
        ``(2, 6)`` :func:`grid_propagator` of the grid step.
    pieces : numpy.ndarray
        ``(m, 2, 6)``: :func:`grid_propagator` from the interval's start to ``i dt / m``, ``i = 1..m``
        (:func:`grid_pieces`).
    log_amp, log_eta : numpy.ndarray
        The transfer table (:func:`screening.solvers.stiff_bed.transfer_table`; with ``sp.by_rate`` keyed by the
        rate at the zero crossing, :func:`screening.solvers.stiff_bed.impact_table`, and read at ``|theta'|``
        there).
    row : int
        The sample (row of ``acc`` and of the outputs).
    acc, acc_dot : numpy.ndarray
        Inertial ground acceleration [m s-2] and its rate [m s-3] on the grid ``j dt_grid``, one row per sample.
    dt_grid : float
        Grid step [s].
    t_out : numpy.ndarray
        Output times [s].
    y_init, scale : numpy.ndarray
        Initial ``(theta, theta')`` and absolute error scales (times ``rtol``) [rad, rad s-1].
    rtol, h_max : float
        Relative tolerance [1] and largest adaptive step [s].
    max_steps : int
        Budget of adaptive steps and closed-form pieces.
    out_theta, out_theta_dot : numpy.ndarray
        Histories [rad, rad s-1] (NaN after overturning or divergence).
    out_uplift : numpy.ndarray of bool
        Uplift flag at the output times.
    counts : numpy.ndarray
        ``(len(COUNTS),)`` integers incremented by the work done (:data:`COUNTS`), or ``(0,)`` (not counted).

    Returns
    -------
    tuple
        ``(status, reason, peak_abs_theta [rad], n_accepted, n_rejected, h_min_accepted [s])`` (closed-form
        pieces count as accepted steps).
    """
    n_out = t_out.shape[0]
    n_grid = acc.shape[1]
    omega2, c_osc, g_osc, omega = osc[0], osc[1], osc[2], osc[3]
    x, v = y_init[0], y_init[1]
    s0, s1 = scale[0], scale[1]
    tu = sp.theta_ul
    t = t_out[0]
    t_end = t_out[n_out - 1]
    out_theta[row, 0] = x
    out_theta_dot[row, 0] = v
    out_uplift[row, 0] = abs(x) > tu
    for i in range(1, n_out):
        out_theta[row, i] = np.nan
        out_theta_dot[row, i] = np.nan
        out_uplift[row, i] = False
    peak = abs(x)
    amp = abs(x)
    status = kern.STATUS_OK
    reason = kern.REASON_NONE
    n_acc = 0
    n_rej = 0
    h_min_acc = np.inf
    log_err_old = dopri.LOG_ERR_START
    h = min(0.5 / omega, h_max)
    h_keep = h
    in_contact = abs(x) <= tu
    h_floor = 1e-12 * (t_end - t_out[0] + 1.0)
    i_out = 1
    tol_t = 1e-9 * dt_grid
    counting = counts.shape[0] > 0
    par = _lifted(sp, cp)
    have_k1 = False
    k1_keep = 0.0
    x_start, v_start = x, v
    while i_out < n_out:
        if n_acc + n_rej >= max_steps:
            status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_BUDGET
            break
        if in_contact:
            # ------------------------------------------------------------ full contact, closed form
            j = int(math.floor(t / dt_grid + 1e-9))
            if j > n_grid - 2:
                j = n_grid - 2
            t_grid = (j + 1) * dt_grid
            t_next = t_out[i_out]
            target = t_next if t_next < t_grid - tol_t else t_grid
            at_output = abs(target - t_next) <= tol_t
            on_grid = abs(t - j * dt_grid) <= tol_t and target == t_grid
            u0 = acc[row, j]
            u1 = acc[row, j + 1]
            r0 = dt_grid * acc_dot[row, j]
            r1 = dt_grid * acc_dot[row, j + 1]
            done = False
            if on_grid:
                nx = prop[0, 0] * x + prop[0, 1] * v + prop[0, 2] * u0 + prop[0, 3] * u1 + prop[0, 4] * r0 \
                    + prop[0, 5] * r1
                nv = prop[1, 0] * x + prop[1, 1] * v + prop[1, 2] * u0 + prop[1, 3] * u1 + prop[1, 4] * r0 \
                    + prop[1, 5] * r1
                # no exit inside the interval: the amplitude about the quasi-static deflection at the start, plus
                # how far the deflection moves (its change and the Hermite overshoot)
                e0 = g_osc * u0 / omega2
                e1 = g_osc * u1 / omega2
                amp0 = math.sqrt((x - e0) ** 2 + (v / omega) ** 2)
                bound = max(abs(e0), abs(e1)) + amp0 + abs(e1 - e0) + 0.25 * g_osc / omega2 * (abs(r0) + abs(r1))
                crossed = x * nx < 0.0 or (x == 0.0 and nx != 0.0)
                if bound <= tu and abs(nx) <= tu and not (crossed and amp > tu):
                    if crossed:
                        amp = 0.0
                    x, v = nx, nv
                    t = t_grid
                    n_acc += 1
                    if counting:
                        counts[0] += 1
                    done = True
            if not done:
                # pieces short against the rocking period, each checked for the zero crossing and the exit
                p0, p1, p2, p3 = _hermite_poly(u0, u1, r0 / dt_grid, r1 / dt_grid, dt_grid, t - j * dt_grid)
                span = target - t
                m = pieces.shape[0] if on_grid else max(1, min(int(math.ceil(omega * span / PIECE_PHASE)), 256))
                s_start = 0.0
                x_prev = x
                left = False
                nx, nv = x, v
                for piece in range(1, m + 1):
                    n_acc += 1
                    if counting:
                        counts[1] += 1
                    s_end = span if piece == m else piece * (span / m)
                    if on_grid:
                        pp = pieces[piece - 1]
                        nx = pp[0, 0] * x + pp[0, 1] * v + pp[0, 2] * u0 + pp[0, 3] * u1 + pp[0, 4] * r0 \
                            + pp[0, 5] * r1
                        nv = pp[1, 0] * x + pp[1, 1] * v + pp[1, 2] * u0 + pp[1, 3] * u1 + pp[1, 4] * r0 \
                            + pp[1, 5] * r1
                    else:
                        nx, nv = oscillator_step(omega2, c_osc, g_osc, x, v, p0, p1, p2, p3, s_end)
                    crossed = x_prev * nx < 0.0 or (x_prev == 0.0 and nx != 0.0)
                    if crossed and amp > tu:
                        # the transfer: at the zero crossing, the rate times sqrt(eta) (eta at amp, or at the rate there)
                        sz, zx, zv = _locate(osc, x, v, p0, p1, p2, p3, s_start, s_end, nx, 0.0)
                        zv *= math.sqrt(transfer_ratio_jit(log_amp, log_eta, abs(zv) if sp.by_rate != 0.0 else amp))
                        if counting:
                            counts[6] += 1
                        amp = 0.0
                        t = t + sz
                        x, v = 0.0, zv
                        left = True                     # go on from the crossing
                        break
                    if abs(nx) > tu:
                        side = tu if nx > 0.0 else -tu
                        se, ex, ev = _locate(osc, x, v, p0, p1, p2, p3, s_start, s_end, nx - side, side)
                        t = t + se
                        x, v = ex, ev
                        if crossed:
                            amp = 0.0
                        left = True
                        in_contact = False
                        have_k1 = False
                        if counting:
                            counts[5] += 1
                        h = min(h_keep, 0.5 / omega)     # the stiff end of the moment law
                        break
                    if crossed:
                        amp = 0.0
                    x_prev = nx
                    s_start = s_end
                if left:
                    amp = max(amp, abs(x))
                    if abs(x) > peak:
                        peak = abs(x)
                    continue
                x, v = nx, nv
                t = target
            amp = max(amp, abs(x))
            if abs(x) > peak:
                peak = abs(x)
            if at_output:
                out_theta[row, i_out] = x
                out_theta_dot[row, i_out] = v
                out_uplift[row, i_out] = False
                i_out += 1
            continue
        # ---------------------------------------------------------------- uplift, adaptive step
        k1_0 = v
        if have_k1:                                     # first same as last: the previous step's end
            k1_1 = k1_keep
        else:
            k1_1 = lifted_acceleration(par, sp, cp, x, v, _input(acc, acc_dot, row, dt_grid, n_grid, t))
        reentry = False
        s_re = 1.0
        v_re = 0.0
        rejected = False
        while True:
            if n_acc + n_rej >= max_steps:
                break
            h = min(h, h_max)
            landing = False
            if t + h >= t_end - 1e-9 * h:
                h = t_end - t
                landing = True
            g0 = x + h * A21 * k1_0
            g1 = v + h * A21 * k1_1
            k2_0 = g1
            k2_1 = lifted_acceleration(par, sp, cp, g0, g1, _input(acc, acc_dot, row, dt_grid, n_grid, t + C2 * h))
            g0 = x + h * (A31 * k1_0 + A32 * k2_0)
            g1 = v + h * (A31 * k1_1 + A32 * k2_1)
            k3_0 = g1
            k3_1 = lifted_acceleration(par, sp, cp, g0, g1, _input(acc, acc_dot, row, dt_grid, n_grid, t + C3 * h))
            g0 = x + h * (A41 * k1_0 + A42 * k2_0 + A43 * k3_0)
            g1 = v + h * (A41 * k1_1 + A42 * k2_1 + A43 * k3_1)
            k4_0 = g1
            k4_1 = lifted_acceleration(par, sp, cp, g0, g1, _input(acc, acc_dot, row, dt_grid, n_grid, t + C4 * h))
            g0 = x + h * (A51 * k1_0 + A52 * k2_0 + A53 * k3_0 + A54 * k4_0)
            g1 = v + h * (A51 * k1_1 + A52 * k2_1 + A53 * k3_1 + A54 * k4_1)
            k5_0 = g1
            k5_1 = lifted_acceleration(par, sp, cp, g0, g1, _input(acc, acc_dot, row, dt_grid, n_grid, t + C5 * h))
            g0 = x + h * (A61 * k1_0 + A62 * k2_0 + A63 * k3_0 + A64 * k4_0 + A65 * k5_0)
            g1 = v + h * (A61 * k1_1 + A62 * k2_1 + A63 * k3_1 + A64 * k4_1 + A65 * k5_1)
            u_end = _input(acc, acc_dot, row, dt_grid, n_grid, t + h)
            k6_0 = g1
            k6_1 = lifted_acceleration(par, sp, cp, g0, g1, u_end)
            n0 = x + h * (B1 * k1_0 + B3 * k3_0 + B4 * k4_0 + B5 * k5_0 + B6 * k6_0)
            n1 = v + h * (B1 * k1_1 + B3 * k3_1 + B4 * k4_1 + B5 * k5_1 + B6 * k6_1)
            k7_0 = n1
            k7_1 = lifted_acceleration(par, sp, cp, n0, n1, u_end)
            e0 = h * (E1 * k1_0 + E3 * k3_0 + E4 * k4_0 + E5 * k5_0 + E6 * k6_0 + E7 * k7_0)
            e1 = h * (E1 * k1_1 + E3 * k3_1 + E4 * k4_1 + E5 * k5_1 + E6 * k6_1 + E7 * k7_1)
            err = math.sqrt(0.5 * (err_term(e0, x, n0, s0, rtol) + err_term(e1, v, n1, s1, rtol)))
            if counting:
                if err > 1.0 or not math.isfinite(err):
                    counts[3] += 1
                ratio = abs(x) / tu
                counts[7 if ratio <= 10.0 else 8 if ratio <= 100.0 else 9 if ratio <= 1000.0 else 10] += 1
            if not math.isfinite(err):
                n_rej += 1
                h = 0.1 * h
                rejected = True
                if h < h_floor:
                    status, reason = kern.STATUS_DIVERGED, kern.REASON_NONFINITE
                    break
                continue
            if err > 1.0:
                n_rej += 1
                h = h * dopri.rejected_step_factor_log(math.log(err))
                rejected = True
                if h < h_floor:
                    status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_UNDERFLOW
                    break
                continue
            side = 1.0 if x > 0.0 else -1.0
            if side * n0 < tu:
                # re-entry into full contact: the step ends where |theta| = theta_ul, the last root of its dense
                # output (Newton from the step's end, kept in the bracket), and the closed form takes over there
                lo = 0.0
                hi = 1.0
                s_re = 1.0
                for _ in range(30):
                    val, der = _dense_rotation(x, h, k1_0, k3_0, k4_0, k5_0, k6_0, k7_0, s_re)
                    f = side * val - tu
                    if f >= 0.0:
                        lo = s_re
                    else:
                        hi = s_re
                    if abs(f) <= 1e-12 * tu or hi - lo <= 1e-14:
                        break
                    s_new = s_re - f / (side * der) if der != 0.0 else 0.5 * (lo + hi)
                    if not (lo < s_new < hi):
                        s_new = 0.5 * (lo + hi)
                    s_re = s_new
                v_re = v + h * _dense_sum(k1_1, k3_1, k4_1, k5_1, k6_1, k7_1, s_re)
                reentry = True
                if counting:
                    counts[4] += 1
            break
        if status != kern.STATUS_OK or n_acc + n_rej >= max_steps:
            if status == kern.STATUS_OK:
                status, reason = kern.STATUS_DIVERGED, kern.REASON_STEP_BUDGET
            break
        n_acc += 1
        if counting:
            counts[2] += 1
        if h < h_min_acc and not landing and not reentry and n_acc > 10:
            h_min_acc = h
        t_new = t + s_re * h if reentry else t_end if landing else t + h
        if reentry:
            landing = False
        # outputs inside the step: its cubic Hermite interpolant (theta with theta', theta' with theta'')
        while i_out < n_out and t_out[i_out] <= t_new + 1e-9 * h:
            s = (t_out[i_out] - t) / h
            if s > 1.0:
                s = 1.0
            s2 = s * s
            s3 = s2 * s
            w00 = 2 * s3 - 3 * s2 + 1
            w01 = 3 * s2 - 2 * s3
            w10 = s3 - 2 * s2 + s
            w11 = s3 - s2
            xo = w00 * x + w01 * n0 + h * (w10 * v + w11 * n1)
            vo = w00 * v + w01 * n1 + h * (w10 * k1_1 + w11 * k7_1)
            out_theta[row, i_out] = xo
            out_theta_dot[row, i_out] = vo
            out_uplift[row, i_out] = abs(xo) > tu
            if abs(xo) > peak:
                peak = abs(xo)
            i_out += 1
        if reentry:
            n0 = tu if x > 0.0 else -tu
            n1 = v_re
        crossed = x * n0 < 0.0
        t = t_new
        x_start, v_start = x, v
        x, v = n0, n1
        have_k1 = not reentry
        k1_keep = k7_1
        if crossed:
            if amp > tu:
                rr = math.sqrt(transfer_ratio_jit(log_amp, log_eta, abs(v) if sp.by_rate != 0.0 else amp))
                x *= rr
                v *= rr
                have_k1 = False
            amp = 0.0
        a0 = abs(x)
        amp = max(amp, a0)
        if a0 > peak:
            peak = a0
        if a0 > sp.theta_over:
            status = kern.STATUS_OVERTURNED
            break
        if abs(v) > sp.rate_max or not math.isfinite(v):
            status, reason = kern.STATUS_DIVERGED, kern.REASON_OUT_OF_BOUNDS
            break
        if a0 > sp.theta_cap:
            status, reason = kern.STATUS_DIVERGED, kern.REASON_NO_EQUILIBRIUM
            break
        fac, log_err = dopri.pi_step_factor(err, log_err_old)
        if rejected:
            fac = min(fac, 1.0)
        if x * v < 0.0 and x_start * v_start < 0.0:
            # moving towards full contact: the time scale |theta| / |theta'| of the contact law shrinks
            # from step to step, so the next step shrinks with it
            ratio = (a0 * abs(v_start)) / (abs(x_start) * abs(v))
            if ratio < 1.0:
                fac *= max(ratio, dopri.FAC_MIN)
        log_err_old = max(log_err, dopri.LOG_ERR_START)
        if reentry:
            h_keep = h
        else:
            h = h * fac
            h_keep = h
        if a0 <= tu:
            in_contact = True
    if not math.isfinite(peak):
        peak = 0.0
    return status, reason, peak, n_acc, n_rej, h_min_acc


@numba.njit(cache=True, parallel=True)
def integrate_chunk(sp, cp, osc, prop, pieces, log_amp, log_eta, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max,
                    max_steps, out_theta, out_theta_dot, out_uplift, peak, status, reason, n_accepted, n_rejected,
                    h_min, counts):
    """:func:`integrate_sample` for every row of ``acc`` (``prange`` over samples); the per-sample outcomes
    written in place (``sp``, ``cp`` the 1-element record arrays; ``counts`` ``(rows, len(COUNTS))``, or
    ``(0, len(COUNTS))``).
    """
    no_counts = np.zeros(0, dtype=np.int64)
    for row in numba.prange(acc.shape[0]):
        cnt = counts[row] if counts.shape[0] > 0 else no_counts
        store_outcome(row, integrate_sample(sp[0], cp[0], osc, prop, pieces, log_amp, log_eta, row, acc, acc_dot, dt_grid,
                                            t_out, y_init, scale, rtol, h_max, max_steps, out_theta, out_theta_dot,
                                            out_uplift, cnt),
                      status, reason, peak, n_accepted, n_rejected, h_min)
