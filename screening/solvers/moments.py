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

Condensation.  The condensation (a :class:`~screening.condensation.Condensation`, or its
registered name, turned into the object once here) hands the solver its compiled
``(c_eq, k_eq)`` function, one parameter record per point and its coefficient tables
(:meth:`~screening.condensation.Condensation.moment_kernel`): the paper's closed forms read a
universal table, others per-point quadrature tables.  The compiled loop calls that function and
never looks at the condensation's name; it is compiled (and cached) once per record type.

Method and how it is checked: ``docs/method.md#moment-equations``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import types
from scipy.special import erfc

from screening.condensation import get as get_condensation
from screening.kernels import dopri
from screening.kernels.signatures import function_type, moment_coefficients_signature, record_type
from screening.model.excitation import stationary_filter_moments_jit
from screening.model.points import flatten, select
from screening.status import PointStatus

#: Points per call of the compiled solver (bounds the memory of per-point coefficient tables).
CHUNK = 256

DEFAULT_RTOL = 1e-7
DEFAULT_MAX_STEPS = 200_000

#: Smallest absolute-tolerance scale [moment units]: below it the scale would underflow.
SCALE_FLOOR = 1e-300

OK = PointStatus.ok
K_EQ_NEGATIVE = PointStatus.k_eq_negative
BEYOND_SLENDERNESS = PointStatus.sigma_theta_beyond_slenderness
STEP_BUDGET = PointStatus.step_budget_exhausted
NON_FINITE = PointStatus.non_finite_moments

#: Per-point parameters of the condensed oscillator and its excitation (SI units).
OSCILLATOR = np.dtype([
    ("m_sdof", "f8"),             # rotational inertia about the rocking edge [kg m2] (eq. 23)
    ("gain", "f8"),               # m h / m_sdof [1/m]: input gain of the ground acceleration
    ("theta_ul", "f8"),           # uplift threshold [rad]
    ("c_rest", "f8"),             # C(0) [N m s/rad]
    ("k_rest", "f8"),             # K(0) [N m/rad]
    ("S0", "f8"),                 # two-sided PSD level of the driving white noise [m2/s3]
    ("omega_g", "f8"),            # Kanai-Tajimi filter frequency [rad/s] (1 for white noise)
    ("zeta_g", "f8"),             # Kanai-Tajimi filter damping [1] (1 for white noise)
    ("constant_envelope", "f8"),  # 1: q(t) = 1, 0: q(t) = 4 (exp(-t/T1) - exp(-t/T2))
    ("T1", "f8"), ("T2", "f8"),   # envelope times [s]
    ("slenderness", "f8"),        # atan(b/h) [rad]: sigma_theta beyond it stops the point
])

HISTORY_VARIABLES = ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq", "p_uplift")
SUMMARY_VARIABLES = ("status", "t_stop", "n_steps", "peak_var_theta", "t_peak_var_theta",
                     "peak_p_uplift", "min_k_eq")


def oscillator_records(block, foundation, excitation, cond):
    """One :data:`OSCILLATOR` record per point of flat (1-d) model fields."""
    kt = excitation.kind == "kanai_tajimi"
    env = excitation.envelope
    constant = env.kind == "constant"
    fields = {
        "m_sdof": block.m_sdof,
        "gain": block.m * block.h / block.m_sdof,
        "theta_ul": cond.uplift_threshold(block, foundation),
        "c_rest": cond.damping_at_rest(block, foundation),
        "k_rest": cond.stiffness_at_rest(block, foundation),
        "S0": excitation.S0,
        "omega_g": excitation.omega_g if kt else 1.0,
        "zeta_g": excitation.zeta_g if kt else 1.0,
        "constant_envelope": 1.0 if constant else 0.0,
        "T1": 1.0 if constant else env.T1,
        "T2": 0.5 if constant else env.T2,
        "slenderness": block.slenderness,
    }
    n = np.size(block.m)
    out = np.empty(n, dtype=OSCILLATOR)
    for name, value in fields.items():
        out[name] = np.broadcast_to(np.asarray(value, dtype=float), (n,))
    return out


# ---------------------------------------------------------------- compiled pieces
@numba.njit(cache=True, inline="always")
def _exp_minus(x):
    """``exp(-x)`` for ``0 <= x``; a 7-term series below 0.02 (error < 1e-16)."""
    if x < 0.02:
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x / 720.0)))))
    return math.exp(-x)


@numba.njit(cache=True)
def _stage_gains(osc, t, h, gains):
    """``m h q(t + c_s h) / M`` at the 7 stage times of a Dormand–Prince step (eq. 57, 2 exp per step)."""
    if osc.constant_envelope == 1.0:
        for s in range(7):
            gains[s] = osc.gain
        return
    e1 = math.exp(-t / osc.T1)
    e2 = math.exp(-t / osc.T2)
    for s in range(7):
        c = dopri.C[s] * h
        gains[s] = osc.gain * 4.0 * (e1 * _exp_minus(c / osc.T1) - e2 * _exp_minus(c / osc.T2))


@numba.njit(cache=True, inline="always")
def _rhs(coefficients, cond, values, slopes, osc, kt, alpha, y, dy, row):
    """Moment equations (45)/(51) into ``dy[row]``; returns ``(c_eq, k_eq)`` at ``y``.

    ``alpha = m h q(t) / M`` is the input gain at the stage time.
    """
    c_eq, k_eq = coefficients(cond, values, slopes, y[0], y[1])
    m = osc.m_sdof
    kap = k_eq / m
    gam = c_eq / m
    if not kt:
        dy[row, 0] = 2.0 * y[1]
        dy[row, 1] = y[2] - kap * y[0] - gam * y[1]
        dy[row, 2] = -2.0 * kap * y[1] - 2.0 * gam * y[2] + 2.0 * math.pi * osc.S0 * alpha * alpha
        return c_eq, k_eq
    # 4x4 symmetric C stored as (00 01 02 03 11 12 13 22 23 33)
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
    dy[row, 0] = 2.0 * c01
    dy[row, 1] = c11 + a10
    dy[row, 2] = c12 + c03
    dy[row, 3] = c13 + a30
    dy[row, 4] = 2.0 * a11
    dy[row, 5] = a12 + c13
    dy[row, 6] = a13 + a31
    dy[row, 7] = 2.0 * c23
    dy[row, 8] = c33 + a32
    dy[row, 9] = 2.0 * a33 + 2.0 * math.pi * osc.S0
    return c_eq, k_eq


@numba.njit(cache=True)
def _linear_scales(osc, kt, scale):
    """Diagonal moment scales from the linear no-uplift oscillator (for absolute tolerances)."""
    m = osc.m_sdof
    w2 = abs(osc.k_rest) / m
    if w2 <= 0.0:
        w2 = 1.0
    zw = max(0.5 * osc.c_rest / m, 0.05)  # floor: undamped points still get a finite scale
    s_eff = osc.S0
    if kt:
        wg = osc.omega_g
        zg = osc.zeta_g
        num = wg**4 + 4.0 * zg * zg * wg * wg * w2
        den = (w2 - wg * wg) ** 2 + 4.0 * zg * zg * wg * wg * w2
        s_eff = osc.S0 * num / den
    g2 = osc.gain ** 2
    var_theta_dot = math.pi * s_eff * g2 / (2.0 * zw)
    diag = np.empty(4)
    diag[0] = var_theta_dot / w2
    diag[1] = var_theta_dot
    if kt:
        diag[2], diag[3] = stationary_filter_moments_jit(osc.S0, osc.omega_g, osc.zeta_g)
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
def _p_uplift(osc, var_theta):
    """Uplift occupancy ``erfc(theta_ul / sqrt(2 var_theta))`` [1] (eq. 58)."""
    if var_theta <= 0.0:
        return 0.0
    return math.erfc(osc.theta_ul / math.sqrt(2.0 * var_theta))


@numba.njit(cache=True)
def _store(coefficients, cond, values, slopes, osc, out_i, k, y, var_theta, cov, var_theta_dot, c_eq_o,
           k_eq_o, p_upl):
    n = y.shape[0]
    var_theta[out_i, k] = y[0]
    cov[out_i, k] = y[1]
    var_theta_dot[out_i, k] = y[2] if n == 3 else y[4]
    c, kk = coefficients(cond, values, slopes, y[0], y[1])
    c_eq_o[out_i, k] = c
    k_eq_o[out_i, k] = kk
    p_upl[out_i, k] = _p_uplift(osc, y[0])


@numba.njit(cache=True)
def _solve_point(coefficients, cond, values, slopes, osc, kt, t_out, rtol, h_max, max_steps, i,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                 status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    n = 10 if kt else 3
    y = np.zeros(n)
    y_new = np.empty(n)
    y_stage = np.empty(n)
    K = np.empty((7, n))
    scale = np.empty(n)
    gains = np.empty(7)
    _linear_scales(osc, kt, scale)
    nt = t_out.shape[0]
    t_end = t_out[nt - 1]
    t = t_out[0]

    gains[0] = osc.gain * (1.0 if osc.constant_envelope == 1.0 else
                           4.0 * (math.exp(-t / osc.T1) - math.exp(-t / osc.T2)))
    c0, k0 = _rhs(coefficients, cond, values, slopes, osc, kt, gains[0], y, K, 0)
    _store(coefficients, cond, values, slopes, osc, i, 0, y, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl)
    next_out = 1
    best = 0.0
    best_t = t
    lowest_k = k0
    steps = 0
    rejected = 0
    err_old = 1e-4
    code = OK
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
        _stage_gains(osc, t, h, gains)
        # stages 2..6
        for s in range(1, 6):
            for j in range(n):
                acc = 0.0
                for q in range(s):
                    acc += dopri.A[s, q] * K[q, j]
                y_stage[j] = y[j] + h * acc
            _rhs(coefficients, cond, values, slopes, osc, kt, gains[s], y_stage, K, s)
        for j in range(n):
            acc = 0.0
            for q in range(6):
                acc += dopri.B[q] * K[q, j]
            y_new[j] = y[j] + h * acc
        c_new, k_new = _rhs(coefficients, cond, values, slopes, osc, kt, gains[6], y_new, K, 6)
        err = 0.0
        finite = True
        for j in range(n):
            e = 0.0
            for q in range(7):
                e += dopri.E[q] * K[q, j]
            e = abs(h * e) / (rtol * scale[j] + rtol * max(abs(y[j]), abs(y_new[j])))
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
        while next_out < nt and t_out[next_out] <= t_new * (1.0 + 1e-14):
            theta = (t_out[next_out] - t) / h
            for j in range(n):
                y_stage[j] = dopri.dense_output(y, K, h, theta, j)
            _store(coefficients, cond, values, slopes, osc, i, next_out, y_stage,
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
                if dopri.dense_output(y, K, h, mid, 1) > 0.0:
                    lo = mid
                else:
                    hi = mid
            v = dopri.dense_output(y, K, h, 0.5 * (lo + hi), 0)
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
            code = K_EQ_NEGATIVE
            break
        if y[0] > osc.slenderness ** 2:
            code = BEYOND_SLENDERNESS
            break
        err = max(err, 1e-10)
        fac = dopri.accepted_step_factor(err, err_old)
        err_old = err
        h = min(h * fac, h_max)
    status[i] = code
    t_stop[i] = t
    n_steps[i] = steps
    n_rejected[i] = rejected
    peak_var[i] = best
    t_peak[i] = best_t
    min_k_eq[i] = lowest_k


def _solve_batch(coefficients, conds, osc, tables_v, tables_s, table_index, kt, t_out, rtol, h_max, max_steps,
                 var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                 status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq):
    """Every point of a batch (compiled per condensation record type by :func:`batch_solver`)."""
    for i in range(osc.shape[0]):
        j = table_index[i]
        _solve_point(coefficients, conds[i], tables_v[j], tables_s[j], osc[i], kt, t_out, rtol, h_max, max_steps,
                     i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl,
                     status, t_stop, n_steps, n_rejected, peak_var, t_peak, min_k_eq)


_SOLVERS = {}


def batch_solver(record_dtype):
    """The compiled :func:`_solve_batch` for a condensation whose records have ``record_dtype``.

    Compiled once per record type with an explicit signature (the condensation's coefficient
    function is a first-class argument), so numba caches it on disk like any other kernel.
    """
    if record_dtype not in _SOLVERS:
        f8, i8 = types.float64, types.int64
        a1 = types.float64[::1]
        a2 = types.float64[:, ::1]
        a3 = types.float64[:, :, ::1]
        cond = record_type(record_dtype)
        sig = types.void(function_type(moment_coefficients_signature(record_dtype)),
                         types.Array(cond, 1, "C"), types.Array(record_type(OSCILLATOR), 1, "C"), a3, a3,
                         types.int64[::1], types.boolean, a1, f8, f8, i8, a2, a2, a2, a2, a2, a2,
                         types.int8[::1], a1, types.int64[::1], types.int64[::1], a1, a1, a1)
        _SOLVERS[record_dtype] = numba.njit(sig, cache=True)(_solve_batch)
    return _SOLVERS[record_dtype]


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
    condensation : a :class:`~screening.condensation.Condensation` or a registered name
        (``"paper"``: eqs. 17–25, default; ``"cubic"``: :mod:`screening.condensation.cubic`,
        raises ``ValueError`` for a softening bed that cannot carry the block through uplift).

    Returns
    -------
    dict of numpy arrays: the time histories ``var_theta`` [rad^2], ``var_theta_dot``
    [rad^2/s^2], ``cov_theta_theta_dot`` [rad^2/s], ``c_eq`` [N m s/rad], ``k_eq`` [N m/rad],
    ``p_uplift`` [1] of shape ``shape + (len(t_out),)`` (NaN after a point stopped), and per
    point ``status`` (:class:`~screening.status.PointStatus`), ``t_stop`` [s], ``n_steps``,
    ``n_rejected``, ``peak_var_theta`` [rad^2] with ``t_peak_var_theta`` [s], ``peak_p_uplift``
    [1] and ``min_k_eq`` [N m/rad] (over the integrated span).
    """
    cond = get_condensation(condensation)
    t_out = np.ascontiguousarray(t_out, dtype=float)
    if t_out.ndim != 1 or t_out.size < 2 or np.any(np.diff(t_out) <= 0):
        raise ValueError("parameter 't_out' must be an increasing 1-d array of at least 2 times")
    (block, foundation, excitation), shape = flatten(block, foundation, excitation)
    cond.check(block, foundation)
    kt = excitation.kind == "kanai_tajimi"
    n, nt = int(np.prod(shape, dtype=int)), t_out.size
    if h_max is None:
        h_max = (t_out[-1] - t_out[0]) / 20.0
    osc = oscillator_records(block, foundation, excitation, cond)
    hist = {name: np.full((n, nt), np.nan) for name in HISTORY_VARIABLES}
    status = np.zeros(n, dtype=np.int8)
    t_stop = np.full(n, np.nan)
    n_steps = np.zeros(n, dtype=np.int64)
    n_rejected = np.zeros(n, dtype=np.int64)
    peak = np.full(n, np.nan)
    t_peak = np.full(n, np.nan)
    min_k = np.full(n, np.nan)
    for lo in range(0, n, CHUNK):
        part = slice(lo, min(lo + CHUNK, n))
        kernel = cond.moment_kernel(select(block, part), select(foundation, part))
        solver = batch_solver(kernel.records.dtype)
        solver(kernel.coefficients, kernel.records, osc[part], kernel.table_values, kernel.table_slopes,
               kernel.table_index, kt, t_out, float(rtol), float(h_max), int(max_steps),
               hist["var_theta"][part], hist["cov_theta_theta_dot"][part], hist["var_theta_dot"][part],
               hist["c_eq"][part], hist["k_eq"][part], hist["p_uplift"][part], status[part], t_stop[part],
               n_steps[part], n_rejected[part], peak[part], t_peak[part], min_k[part])
    tu = osc["theta_ul"]
    with np.errstate(divide="ignore"):
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
