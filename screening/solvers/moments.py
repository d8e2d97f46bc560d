"""Lyapunov covariance propagation closed by stochastic linearization (paper, sections 2.5–2.6).

The moment equations ``dC/dt = P C + C P^T + D`` (eq. 45; eq. 51 with the Kanai–Tajimi
filter) have ``P`` built from ``c_eq`` and ``k_eq`` evaluated at the current moments, so
the whole system is one nonlinear ODE in the independent covariance entries: 3 for
modulated white noise (``var_theta, cov, var_theta_dot``), ``(n_f + 2)(n_f + 3)/2`` for an
excitation with ``n_f`` filter states (10 for Kanai–Tajimi: the 4x4 symmetric covariance of
``theta, theta', u_g, u_g'``).  The excitation enters only through its filter's state-space
matrices (:meth:`screening.core.excitations.Excitation.filter`), its PSD at the rocking frequency and
its stationary covariance (tolerance scales); the compiled loop never looks at its kind.

:func:`solve_moments` integrates a batch of parameter points in one compiled call:
an embedded Dormand–Prince 5(4) pair per point, with absolute tolerances scaled to the
linear stationary moments, dense output for the output grid, and the peak of
``var_theta`` located inside the step where ``cov`` changes sign.  A point whose ``k_eq``
turns negative, whose ``sigma_theta`` passes the slenderness angle, whose state is not
finite, or which exceeds the step budget stops there with a ``status`` code; the other
points of the batch are unaffected.

Condensation.  The condensation (a :class:`~screening.core.condensation.Condensation`, or its
registered name, turned into the object once here) hands the solver its compiled
``(c_eq, k_eq)`` function, one parameter record per point and its coefficient tables
(:meth:`~screening.core.condensation.Condensation.moment_kernel`): the paper's closed forms read a
universal table, others per-point quadrature tables.  The compiled loop calls that function and
never looks at the condensation's name; it is compiled (and cached) once per record type.

Method and how it is checked: ``docs/method.md#moment-equations``.
"""

from __future__ import annotations


import dataclasses

import numba
import numpy as np
from numba import types

from screening.core.condensation import DEFAULT_CONDENSATION, get as get_condensation
from screening.core.signatures import function_type, moment_coefficients_signature, record_type
from screening.core.model.points import flatten, select
from screening.kernels.moment_kernels import (filtered_scales, solve_point_filtered, solve_point_two_states,
                                              solve_point_white, SUMMARIES, SUMMARY, uplift_occupancy)
from screening.solvers.outputs import HISTORY_VARIABLES, solver_summaries
from screening.core.status import PointStatus
from screening.core.validation import check_integer, check_scalar, check_size
from screening.core import limits

__all__ = []

#: Points per call of the compiled solver (bounds the memory of per-point coefficient tables).
CHUNK = 256

#: Default relative tolerance: the peak var_theta within 1e-7 of a converged solution (measured
#: <= 2.3e-8 over the paper's white-noise and Kanai-Tajimi ranges, benchmarks/bench_linearization.py;
#: 1e-7 gave 1.6e-6 for ~15 % fewer steps).
DEFAULT_RTOL = 1e-8
DEFAULT_MAX_STEPS = 200_000

#: Per-point parameters of the condensed oscillator and its excitation (SI units).
OSCILLATOR = np.dtype([
    ("m_sdof", "f8"),             # rotational inertia about the rocking edge [kg m2] (eq. 23)
    ("gain", "f8"),               # m h / m_sdof [1/m]: input gain of the ground acceleration
    ("theta_ul", "f8"),           # uplift threshold [rad]
    ("c_rest", "f8"),             # C(0) [N m s/rad]
    ("k_rest", "f8"),             # K(0) [N m/rad]
    ("S0", "f8"),                 # two-sided PSD level of the driving white noise [m2/s3]
    ("constant_envelope", "f8"),  # 1: q(t) = 1, 0: q(t) = 4 (exp(-t/T1) - exp(-t/T2))
    ("T1", "f8"), ("T2", "f8"),   # envelope times [s]
    ("slenderness", "f8"),        # atan(b/h) [rad]: sigma_theta beyond it stops the point
])


def oscillator_records(block, foundation, excitation, cond):
    """One :data:`OSCILLATOR` record per point: the condensed oscillator and its input, for the compiled loops.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block, flat (1-d) or scalar fields.
    foundation : screening.core.model.Foundation
        The bed, flat or scalar fields.
    excitation : screening.core.excitations.Excitation
        The input, flat or scalar fields.
    cond : screening.core.condensation.Condensation
        The condensation (its threshold, ``C(0)`` and ``K(0)``).

    Returns
    -------
    numpy.ndarray
        Structured array of :data:`OSCILLATOR` (``m_sdof`` [kg m2], ``gain`` [m-1], ``theta_ul`` [rad],
        ``c_rest`` [N m s/rad], ``k_rest`` [N m/rad], ``S0`` [m2 s-3], the envelope, ``slenderness`` [rad]).

    Notes
    -----
    ``m_sdof = I_cm + m h^2`` (eq. (23) in [1]), input gain ``m h / m_sdof`` (eq. (43)), envelope
    ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` (eq. (57)).

    """
    env = excitation.envelope
    constant = env.kind == "constant"
    fields = {
        "m_sdof": block.m_sdof,
        "gain": block.m * block.h / block.m_sdof,
        "theta_ul": cond.uplift_threshold(block, foundation),
        "c_rest": cond.damping_at_rest(block, foundation),
        "k_rest": cond.stiffness_at_rest(block, foundation),
        "S0": excitation.S0,
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


class FilterArrays:
    """The excitation's filter for the compiled loops, one row per point: ``A`` (n, n_f, n_f), ``B``,
    ``C`` (n, n_f), ``D`` (n,) and the absolute-tolerance scales of the packed moments (n, m)
    (:func:`screening.kernels.moment_kernels.filtered_scales`; empty for white noise)."""

    def __init__(self, excitation, osc):
        n = osc.size
        filt = excitation.filter()
        nf = np.shape(filt.A)[-1]
        self.A = np.array(np.broadcast_to(filt.A, (n, nf, nf)), dtype=float, order="C")
        self.B = np.array(np.broadcast_to(filt.B, (n, nf)), dtype=float, order="C")
        self.C = np.array(np.broadcast_to(filt.C, (n, nf)), dtype=float, order="C")
        self.D = np.array(np.broadcast_to(filt.D, (n,)), dtype=float, order="C")
        self.states = nf
        if nf == 0:
            self.scale = np.zeros((n, 0))
            self.unit_variances = np.ones((n, 0))
            return
        with np.errstate(all="ignore"):
            w = np.sqrt(np.abs(osc["k_rest"]) / osc["m_sdof"])
            psd = np.asarray(excitation.psd(np.where(w > 0.0, w, 1.0)), dtype=float)
            # stationary covariance of the filter states per unit S0: finite and positive unless a filter
            # frequency is beyond float64 (an intensity beyond it is the solver's to flag)
            unit = np.broadcast_to(dataclasses.replace(excitation, S0=np.ones(n)).stationary_covariance(),
                                   (n, nf, nf))
            self.unit_variances = np.diagonal(unit, axis1=-2, axis2=-1)
            cov = unit * osc["S0"][:, None, None]
            self.scale = np.array(filtered_scales(osc, cov, np.broadcast_to(psd, (n,))), dtype=float, order="C")

    def select(self, part):
        out = object.__new__(FilterArrays)
        out.A, out.B, out.C, out.D, out.scale = (a[part] for a in (self.A, self.B, self.C, self.D, self.scale))
        out.states = self.states
        out.unit_variances = self.unit_variances[part]
        return out


def in_float_range(osc, filters):
    """Points whose scales the compiled loops can form in float64.

    Parameters
    ----------
    osc : numpy.ndarray
        :data:`OSCILLATOR` records, one per point.
    filters : FilterArrays
        The excitation's filter of every point.

    Returns
    -------
    numpy.ndarray
        Boolean per point: False where ``theta_ul^2``, ``m_sdof``, ``S0 gain^2``, ``k_rest / m_sdof``,
        ``c_rest / m_sdof`` or the filter's stationary moments under- or overflow (``k >= ~1e200``,
        ``m <= ~1e-200``, a filter frequency ``<= ~1e-150``).

    Notes
    -----
    The loops divide by ``theta_ul^2`` (eq. (19) in [1]) and ``m_sdof``; a point beyond float range would
    stop the whole batch, so it is flagged :attr:`~screening.core.status.PointStatus.beyond_float_range` instead.

    """
    tiny = np.finfo(float).tiny
    with np.errstate(all="ignore"):
        fields = np.stack([osc[name] for name in osc.dtype.names])
        scales = np.stack([osc["theta_ul"] ** 2, osc["m_sdof"], osc["S0"] * osc["gain"] ** 2,
                           np.abs(osc["k_rest"]) / osc["m_sdof"], np.abs(osc["c_rest"]) / osc["m_sdof"]])
        ok = np.all(np.isfinite(fields), axis=0) & np.all(np.isfinite(scales), axis=0)
        ok &= (scales[0] >= tiny) & (scales[1] >= tiny)
        for a in (filters.A, filters.B, filters.C, filters.unit_variances):
            ok &= np.all(np.isfinite(a.reshape(a.shape[0], -1)), axis=1)
        ok &= np.all(filters.unit_variances >= tiny, axis=1)
    return ok


def _solve_representable(representable, shape, block, foundation, excitation, t_out, rtol, h_max, max_steps,
                         cond, histories):
    """:func:`solve_moments` of the points :func:`in_float_range`; the others flagged, NaN, not integrated."""
    n, nt = representable.size, t_out.size
    out = {name: np.full((n, nt), np.nan) for name in HISTORY_VARIABLES} if histories else {}
    out.update({name: np.full(n, np.nan) for name in solver_summaries()})
    out["status"] = np.full(n, PointStatus.beyond_float_range, dtype=np.int8)
    for name in ("n_steps", "n_rejected"):
        out[name] = np.zeros(n, dtype=np.int64)
    index = np.flatnonzero(representable)
    if index.size:
        part = solve_moments(select(block, index), select(foundation, index), select(excitation, index), t_out,
                             rtol=rtol, h_max=h_max, max_steps=max_steps, condensation=cond, histories=histories)
        for name, value in part.items():
            out[name][index] = value
    return {name: a.reshape(shape + a.shape[1:]) for name, a in out.items()}


# ---------------------------------------------------------------- compiled batch
@numba.njit(cache=True)
def _summarize(out, s):
    out.status, out.t_stop, out.n_steps, out.n_rejected = s.status, s.t_stop, s.n_steps, s.n_rejected
    out.peak_var_theta, out.t_peak_var_theta, out.min_k_eq = s.peak_var_theta, s.t_peak_var_theta, s.min_k_eq


def _batch_filtered(coefficients, conds, osc, tables, table_index, fa, fb, fc, fd, scale, t_out, rtol, h_max,
                    max_steps, store, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl, summaries):
    """Every point of a batch driven through a shaping filter (``fa, fb, fc, fd``: each point's ``A, B, C, D``);
    compiled per condensation record type by :func:`batch_solver`, histories written only if ``store``."""
    for i in range(osc.shape[0]):
        _summarize(summaries[i], solve_point_filtered(
            coefficients, conds[i], tables[table_index[i]], osc[i], fa[i], fb[i], fc[i], fd[i], scale[i], t_out,
            rtol, h_max, max_steps, store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl))


def _batch_two_states(coefficients, conds, osc, tables, table_index, fa, fb, fc, fd, scale, t_out, rtol, h_max,
                      max_steps, store, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl, summaries):
    """:func:`_batch_filtered` for filters of two states (Kanai–Tajimi without a band): loops of constant length."""
    for i in range(osc.shape[0]):
        _summarize(summaries[i], solve_point_two_states(
            coefficients, conds[i], tables[table_index[i]], osc[i], fa[i], fb[i], fc[i], fd[i], scale[i], t_out,
            rtol, h_max, max_steps, store, i, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl))


def _batch_white(coefficients, conds, osc, tables, table_index, fa, fb, fc, fd, scale, t_out, rtol, h_max,
                 max_steps, store, var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl, summaries):
    """:func:`_batch_filtered` for white noise without a band (no filter states): 3 scalar moments."""
    for i in range(osc.shape[0]):
        _summarize(summaries[i], solve_point_white(
            coefficients, conds[i], tables[table_index[i]], osc[i], t_out, rtol, h_max, max_steps, store, i,
            var_theta, cov, var_theta_dot, c_eq_o, k_eq_o, p_upl))


#: The batch loop by number of filter states (any other number: :func:`_batch_filtered`).  Three functions, not one
#: branching loop: a run compiles only the state size its excitation has (the three together took 48 s to compile
#: cold, the filtered one alone 23 s).
_BATCHES = {0: _batch_white, 2: _batch_two_states}


_SOLVERS = {}


def batch_solver(record_dtype, n_states=4):
    """The compiled batch integrator of the moment equations for one condensation record type and state size.

    Parameters
    ----------
    record_dtype : numpy.dtype
        The dtype of the condensation's per-point records (:meth:`~screening.core.condensation.Condensation.moment_kernel`).
    n_states : int, optional
        Filter states of the excitation (0: white noise without a band; 2: Kanai–Tajimi without a band).

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The batch loop of that state size compiled once per record type with an explicit signature (the condensation's
        coefficient function is a first-class argument), so numba caches it on disk like any other kernel.

    Notes
    -----
    It integrates eq. (45) in [1] (white noise) or eq. (51) (a filtered input) for every point of a
    batch (:func:`screening.kernels.moment_kernels.moment_equations` is their numpy reference).

    """
    batch = _BATCHES.get(n_states, _batch_filtered)
    if (record_dtype, batch) not in _SOLVERS:
        f8, i8 = types.float64, types.int64
        a1 = types.float64[::1]
        a2 = types.float64[:, ::1]
        a3 = types.float64[:, :, ::1]
        cond = record_type(record_dtype)
        sig = types.void(function_type(moment_coefficients_signature(record_dtype)),
                         types.Array(cond, 1, "C"), types.Array(record_type(OSCILLATOR), 1, "C"), a3,
                         types.int64[::1], a3, a2, a2, a1, a2, a1, f8, f8, i8, types.boolean, a2, a2, a2, a2, a2, a2,
                         types.Array(record_type(SUMMARY), 1, "C"))
        _SOLVERS[record_dtype, batch] = numba.njit(sig, cache=True)(batch)
    return _SOLVERS[record_dtype, batch]


def solve_moments(block, foundation, excitation, t_out, rtol=DEFAULT_RTOL, h_max=None,
                  max_steps=DEFAULT_MAX_STEPS, condensation=DEFAULT_CONDENSATION, histories=True):
    """Integrate the linearized moment equations for a batch of parameter points.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block; fields may be arrays (broadcast).
    foundation : screening.core.model.Foundation
        The bed; fields may be arrays (broadcast).
    excitation : screening.core.excitations.Excitation
        The input (``S0`` [m2 s-3], its envelope and filter); fields may be arrays (broadcast).
    t_out : array_like
        Increasing output times [s], starting at the initial time (zero covariance).
    rtol : float, optional
        Relative tolerance of the Dormand–Prince pair (absolute tolerances are ``rtol`` times the linear
        stationary moments of each point; default :data:`DEFAULT_RTOL`).
    h_max : float, optional
        Largest step [s]; default ``(t_out[-1] - t_out[0]) / 20``.
    max_steps : int, optional
        Step budget per point (accepted + rejected).
    condensation : str or screening.core.condensation.Condensation, optional
        A condensation or a registered name (default :data:`screening.core.condensation.DEFAULT_CONDENSATION`;
        ``"paper"``: eqs. (17)-(25) in [1]; ``"virtual_work"``: docs/heavy_uplift.md; ``"cubic"``:
        :mod:`screening.core.condensation.cubic`, raises ``ValueError`` for a softening bed that cannot carry
        the block through uplift).
    histories : bool, optional
        False: per-point summaries only (no dense output, no coefficient evaluations at the output
        times; the history keys are absent from the result).

    Returns
    -------
    dict
        Numpy arrays: the time histories ``var_theta`` [rad2], ``var_theta_dot`` [rad2 s-2],
        ``cov_theta_theta_dot`` [rad2 s-1], ``c_eq`` [N m s/rad], ``k_eq`` [N m/rad], ``p_uplift`` [1] of
        shape ``shape + (len(t_out),)`` (NaN after a point stopped; only if ``histories``), and per point
        ``status`` (:class:`~screening.core.status.PointStatus`), ``t_stop`` [s], ``n_steps``, ``n_rejected``,
        ``peak_var_theta`` [rad2] with ``t_peak_var_theta`` [s], ``peak_p_uplift`` [1] and ``min_k_eq``
        [N m/rad] (over the integrated span).

    Notes
    -----
    The Lyapunov equation ``dC/dt = P C + C P^T + E[v v^T]`` (eq. (45) in [1]; eq. (51) for a filtered
    input) with ``P`` built from the equivalent coefficients at the current moments (eq. (31)), one
    nonlinear ODE in the independent covariance entries; ``p_uplift`` is eq. (58).  Numpy reference of
    the right-hand side: :func:`screening.kernels.moment_kernels.moment_equations`.

    """
    cond = get_condensation(condensation)
    t_out = np.ascontiguousarray(t_out, dtype=float)
    if t_out.ndim != 1 or t_out.size < 2 or np.any(np.diff(t_out) <= 0):
        raise ValueError("parameter 't_out' must be an increasing 1-d array of at least 2 times")
    rtol = check_scalar("rtol", rtol, lower=0.0, upper=limits.MAX_RTOL, upper_inclusive=True)
    max_steps = check_integer("max_steps", max_steps, 1)
    (block, foundation, excitation), shape = flatten(block, foundation, excitation)
    cond.check(block, foundation)
    n, nt = int(np.prod(shape, dtype=int)), t_out.size
    if histories:
        check_size("t_out", n * nt * len(HISTORY_VARIABLES), limits.MAX_HISTORY_VALUES,
                   f"history values ({n} points x {nt} output times x {len(HISTORY_VARIABLES)})")
    h_max = (t_out[-1] - t_out[0]) / 20.0 if h_max is None else check_scalar("h_max", h_max, lower=0.0)
    osc = oscillator_records(block, foundation, excitation, cond)
    filters = FilterArrays(excitation, osc)
    representable = in_float_range(osc, filters)
    if not representable.all():
        return _solve_representable(representable, shape, block, foundation, excitation, t_out, rtol, h_max,
                                    max_steps, cond, histories)
    hist = {name: np.full((n if histories else 0, nt), np.nan) for name in HISTORY_VARIABLES}
    summaries = np.zeros(n, dtype=SUMMARY)
    for lo in range(0, n, CHUNK):
        part = slice(lo, min(lo + CHUNK, n))
        kernel = cond.moment_kernel(select(block, part), select(foundation, part))
        f = filters.select(part)
        solver = batch_solver(kernel.records.dtype, f.A.shape[1])
        solver(kernel.coefficients, kernel.records, osc[part], kernel.tables,
               kernel.table_index, f.A, f.B, f.C, f.D, f.scale, t_out, float(rtol), float(h_max), int(max_steps),
               bool(histories),
               hist["var_theta"][part], hist["cov_theta_theta_dot"][part], hist["var_theta_dot"][part],
               hist["c_eq"][part], hist["k_eq"][part], hist["p_uplift"][part], summaries[part])
    out = {name: a.reshape(shape + (nt,)) for name, a in hist.items()} if histories else {}
    out.update({name: np.ascontiguousarray(summaries[name]).reshape(shape) for name in SUMMARIES})
    out["peak_p_uplift"] = uplift_occupancy(osc["theta_ul"], summaries["peak_var_theta"]).reshape(shape)
    return out
