"""Execution on dask.distributed: the client, the worker warm-up, and the two task functions.

Each batch of points is **one** task, :func:`solve_batch`: a vectorised call of
:func:`screening.solvers.moments.solve_moments` on arrays (there is no finer task graph); each
Monte Carlo spot check is one task, :func:`spot_task`.  Tasks are submitted with
``retries=TASK_RETRIES``; their results are plain dicts of numpy arrays (the batch record read
by :class:`~screening.io.writer.ResultFile` and saved by
:class:`~screening.io.store.PartialStore`).  Workers must be able to import
:mod:`screening` (same environment).  For a zarr result, :func:`screening.sweep._submit.solve_and_store_batch` also writes the
batch into its region of the store and marks it done: the workers then need the store's folder
(the same path on a shared file system), and return only the batch's summary.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import time
from pathlib import Path

import numpy as np

from screening.analysis import error_model as em
from screening.analysis.escalation import full_contact_share
from screening.analysis.fragility import band_standard_error, linearized_exceedance
from screening.analysis.intensity import input_measures, rocking_start_probability
from screening.analysis.multifidelity import multifidelity_variance
from screening.analysis.probabilities import uplift_acceleration
from screening.analysis.trust import error_model_trust, trust_indicators
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation
from screening.core.status import EscalationEstimator, PointStatus, SampleState, Trust
from screening.io.errors import exception_line, SweepError
from screening.solvers import mc_registry
from screening.solvers.datasets import INTEGRATOR_TEXT
from screening.solvers.model_choice import resolve
from screening.solvers.moments import solve_moments
from screening.solvers.outputs import HISTORY_VARIABLES, of_stage, OUTPUTS, selected

__all__ = []

CONNECT_TIMEOUT = "15s"
TASK_RETRIES = 2
#: Histories of a spot check.
SPOT_HISTORIES = ("var_theta", "var_theta_dot", "var_theta_se", "var_theta_dot_se")
#: Linearization histories a spot check is compared against.
SPOT_LINEAR = ("var_theta", "var_theta_dot")


# ============================================================================ tasks
def solve_batch(block, foundation, excitation, condensation, t_out, rtol, max_steps, histories=HISTORY_VARIABLES,
                fragility=None, trust_models=None, derived_inputs=(), underivable=None, cutoff=None,
                probabilities=False):
    """The dask task: one vectorised :func:`solve_moments` call on a batch of points.

    ``condensation`` is a :class:`screening.core.condensation.Condensation`; ``histories``: the history
    variables to return (none: the solver skips its output stores).  Returns a dict of 1-d/2-d
    arrays over the batch: those histories as ``float32`` (points x time), the summaries
    (``float64``/``int32``), ``status`` (``int8``), ``theta_ul`` and ``slenderness`` [rad].
    ``fragility`` (a :class:`~screening.sweep.study.Fragility`): also ``p_exceed`` (points x
    thresholds) [1], from the float64 histories while they are in memory
    (:func:`screening.analysis.fragility.exceedance_probability`).  Always the
    intensity measures of each point's input (:func:`batch_intensity`), with the ground-motion band limit
    ``cutoff`` [rad/s] of the excitation (default its :meth:`~screening.core.excitations.Excitation.reference_cutoff`), and the
    probability that rocking starts (:func:`batch_rocking_start`, same band limit);
    ``derived_inputs`` (names of the ``inputs`` stage): those inputs per point.  ``underivable``
    (boolean per point, or None): points whose ``S0`` could not follow from their target PGA (their
    excitation holds a placeholder): status ``beyond_float_range``, NaN values, ``sl_trust`` untrusted.
    ``probabilities`` (:attr:`Study.probabilities <screening.sweep.study.Study>`): also the linearization's ``p_overturn``,
    ``p_overturn_se`` and, with ``fragility``, ``p_exceed_se`` (:func:`batch_probabilities`).

    Parameters
    ----------
    block : screening.core.model.Block
        The block(s) of the batch (array fields over its points where swept).
    foundation : screening.core.model.Foundation
        The bed(s).
    excitation : screening.core.excitations.Excitation
        The ground motion model(s).
    condensation : screening.core.condensation.Condensation
        The condensation of the batch's case.
    t_out : numpy.ndarray
        Output times [s].
    rtol : float
        Relative tolerance of the moment integration [1].
    max_steps : int
        Most integration steps per point.
    histories : tuple of str, optional
        History variables to return.
    fragility : screening.sweep.study.Fragility, optional
        The ``[fragility]`` thresholds and method.
    trust_models : dict, optional
        ``{condensation: ErrorModel}`` of the trust rule (read here if None).
    derived_inputs : tuple of str, optional
        Per-point inputs to return (``("S0",)`` for a target PGA).
    underivable : numpy.ndarray of bool, optional
        Points whose ``S0`` could not follow from their target PGA.
    cutoff : float, optional
        Band limit of the ground motion [rad s-1].
    probabilities : bool, optional
        Also the linearization's probabilities.

    Returns
    -------
    dict
        ``{variable: array}`` flat over the batch (points, or points x time for histories), in the
        units of :mod:`screening.solvers.outputs`.

    Notes
    -----
    Per point, the covariance of rotation and rotational velocity follows the Lyapunov moment equation
    :math:`\\dot{\\mathbf{C}} = \\mathbf{P}\\mathbf{C} + \\mathbf{C}\\mathbf{P}^\\top
    + \\mathbb{E}[\\mathbf{v}\\mathbf{v}^\\top]`, eq. (45) in [1] (eq. (51) for filtered noise), with the
    equivalent stiffness and damping of eqs. (35)-(36) in [1] (corrected, ``docs/method.md``) updated at
    every step.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "The module map", ``docs/architecture.md``.
    """
    probabilities = probabilities or fragility is not None
    res = solve_moments(block, foundation, excitation, t_out, rtol=rtol, max_steps=max_steps,
                        condensation=condensation, histories=bool(histories) or probabilities)
    shape = res["status"].shape
    n = res["status"].size
    out = {name: OUTPUTS[name].cast(res[name], shape) for name in histories}
    out.update({o.name: o.cast(res[o.name], shape) for o in of_stage("linearize") if o.shape == "point"})
    model = {"theta_ul": condensation.uplift_threshold(block, foundation), "slenderness": block.slenderness}
    out.update({o.name: o.cast(model[o.name], shape) for o in of_stage("model")})
    out.update(batch_trust(res, block, foundation, excitation, condensation, out, t_out, trust_models))
    if probabilities:
        out.update(batch_probabilities(res, block, foundation, excitation, out, t_out, fragility))
    out.update(batch_intensity(excitation, t_out, n, cutoff))
    out.update(batch_rocking_start(block, foundation, excitation, condensation, t_out, n, cutoff))
    for name in derived_inputs:
        out[name] = OUTPUTS[name].cast(getattr(excitation, name), shape)
    if underivable is not None:
        out = _flag_points(out, np.broadcast_to(underivable, shape).reshape(n))
    return out


def _flag_points(out, bad):
    """A batch result with the points ``bad`` (boolean per point) flagged ``beyond_float_range``: NaN
    values, zero counts, ``sl_trust`` untrusted (what :func:`failed_result` gives a failed batch)."""
    out = {name: np.array(value) for name, value in out.items()}
    for name, value in out.items():
        value[bad] = OUTPUTS[name].failed
    out["status"][bad] = PointStatus.beyond_float_range
    return out


def batch_intensity(excitation, t_out, n, cutoff=None):
    """The intensity measures of the ``n`` points of a batch (the ``intensity`` stage of
    :mod:`screening.solvers.outputs`: [m s-2, m s-2, m s-1]), band-limited to
    ``cutoff`` [rad/s] (default: the excitation's :meth:`~screening.core.excitations.Excitation.reference_cutoff`).

    Parameters
    ----------
    excitation : screening.core.excitations.Excitation
        The ground motion model(s) of the batch.
    t_out : array_like
        Output times [s]; the last is the record length.
    n : int
        Points of the batch.
    cutoff : float, optional
        Band limit [rad s-1].

    Returns
    -------
    dict
        ``pga_median`` [m s-2] (median peak ground acceleration), ``rms_acceleration`` [m s-2] and
        ``arias_intensity`` [m s-1], one value per point.

    Notes
    -----
    Arias intensity :math:`I_a = \\frac{\\pi}{2g}\\int_0^T \\mathbb{E}[a^2]\\,dt` [1]; the median peak
    by random vibration theory [2].

    References
    ----------
    .. [1] A. Arias, "A measure of earthquake intensity", in R. J. Hansen (ed.), Seismic Design for
       Nuclear Power Plants, MIT Press, Cambridge MA (1970) 438-483.
    .. [2] D. M. Boore, "Simulation of ground motion using the stochastic method", Pure and Applied
       Geophysics 160 (2003) 635-676. https://doi.org/10.1007/PL00012553
    .. [3] screening documentation, "Intensity measures of the stochastic inputs", ``docs/intensity_measures.md``.
    """
    measures = input_measures(excitation, float(np.asarray(t_out)[-1]),
                              excitation.reference_cutoff() if cutoff is None else cutoff)
    return {name: np.broadcast_to(measures[name], (n,)).astype(np.float64) if np.size(measures[name]) != n
            else np.asarray(measures[name], dtype=np.float64).reshape(n)
            for name in (o.name for o in of_stage("intensity"))}


def batch_rocking_start(block, foundation, excitation, condensation, t_out, n, cutoff=None):
    """The uplift acceleration [m s-2] and the probability that rocking starts [1] of the ``n`` points of a
    batch (the ``rocking`` stage of :mod:`screening.solvers.outputs`), band-limited to the ground motion's
    ``cutoff`` [rad/s] (default the excitation's :meth:`~screening.core.excitations.Excitation.reference_cutoff`: the
    band its PGA refers to).

    A bed the condensation cannot carry gives NaN (the solver flags the point).

    Parameters
    ----------
    block : screening.core.model.Block
        The block(s).
    foundation : screening.core.model.Foundation
        The bed(s).
    excitation : screening.core.excitations.Excitation
        The ground motion model(s).
    condensation : screening.core.condensation.Condensation
        The case's condensation.
    t_out : array_like
        Output times [s]; the last is the record length.
    n : int
        Points of the batch.
    cutoff : float, optional
        Band limit [rad s-1].

    Returns
    -------
    dict
        ``uplift_acceleration`` [m s-2] and ``p_rocking_start`` [1], one value per point.

    Notes
    -----
    :math:`p = 1 - \\exp(-\\int_0^T \\nu(a_{ul}, t)\\,dt)` with Rice's rate :math:`\\nu` of crossings of
    :math:`\\pm a_{ul}` by the modulated ground acceleration [1], [2].

    References
    ----------
    .. [1] [rice1944] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "Probabilities of overturning and of exceedance",
       ``docs/outputs_probabilities.md``.
    """
    try:
        with np.errstate(all="ignore"):
            a_ul = uplift_acceleration(block, foundation, condensation)
            p = rocking_start_probability(excitation, float(np.asarray(t_out)[-1]),
                                          excitation.reference_cutoff() if cutoff is None else cutoff, a_ul)
    except (ArithmeticError, ValueError):       # a bed the condensation cannot carry: the solver flags it
        a_ul = p = np.nan
    return {name: np.broadcast_to(np.asarray(value, dtype=np.float64), (n,)).copy() if np.size(value) != n
            else np.asarray(value, dtype=np.float64).reshape(n)
            for name, value in (("uplift_acceleration", a_ul), ("p_rocking_start", p))}


def batch_trust(res, block, foundation, excitation, condensation, out, t_out, models=None):
    """``sl_trust`` (:class:`screening.core.status.Trust`) and the error band of a batch, from what the
    solver returned, by the error atlas model (:func:`screening.analysis.trust.error_model_trust`; without
    histories the decay indicator is unknown: at best ``check``).

    ``models``: ``{condensation: ErrorModel}`` (:func:`screening.analysis.error_model.shipped_model`), read
    once by the client and sent with the task: worker threads must not read netCDF while the client writes
    one (HDF5 is not thread-safe).  None reads the shipped model here.

    Parameters
    ----------
    res : dict
        The solver's arrays (``var_theta`` [rad2], points x time, when it returned histories).
    block : screening.core.model.Block
        The block(s).
    foundation : screening.core.model.Foundation
        The bed(s).
    excitation : screening.core.excitations.Excitation
        The ground motion model(s).
    condensation : screening.core.condensation.Condensation
        The case's condensation.
    out : dict
        The batch's summaries so far: ``status``, ``peak_p_uplift`` [1], ``min_k_eq`` [N m rad-1],
        ``peak_var_theta`` [rad2], ``slenderness`` [rad].
    t_out : array_like
        Output times [s].
    models : dict, optional
        The error models per condensation.

    Returns
    -------
    dict
        ``sl_trust`` (:class:`~screening.core.status.Trust` codes), ``sl_error_low`` and ``sl_error_high``
        [1]: the band of ``SL / MCS - 1`` of peak var_theta.
    """
    n = out["status"].size

    def on_points(value):          # a per-point array of the batch, or one value for all its points
        value = np.asarray(value, dtype=float)
        return np.full(n, value.item()) if value.size == 1 else value.reshape(n)

    var_end = res["var_theta"].reshape(n, -1)[:, -1] if "var_theta" in res else np.full(n, np.nan)
    q = excitation.envelope(np.asarray(t_out, dtype=float)[:, None])      # (t, points) or (t, 1)
    q2 = np.asarray(q, dtype=float) ** 2
    envelope_end = q2[-1] / np.maximum(q2.max(axis=0), 1e-300)
    indicators = trust_indicators(out["peak_p_uplift"], out["min_k_eq"],
                                  on_points(condensation.stiffness_at_rest(block, foundation)),
                                  out["peak_var_theta"], out["slenderness"], var_end, on_points(envelope_end))
    covered = excitation.kind in em.ATLAS_KINDS and foundation.law in em.ATLAS_CONTACTS
    flag, low, high = error_model_trust(em.model_features(indicators, block, foundation, excitation), out["status"],
                                        condensation.name, covered, models)
    return {"sl_trust": np.asarray(flag, dtype=np.int8), "sl_error_low": np.asarray(low, dtype=float),
            "sl_error_high": np.asarray(high, dtype=float)}


def batch_probabilities(res, block, foundation, excitation, out, t_out, fragility=None):
    """The linearization's probabilities of a batch, by the analysis layer's own function on the solver's
    float64 arrays (:func:`screening.analysis.fragility.linearized_exceedance`, the up-crossing ``method`` of
    ``fragility``, else Vanmarcke's): ``p_overturn`` (``|theta|`` beyond ``atan(b/h)``) and ``p_overturn_se``,
    and with ``fragility`` ``p_exceed`` and ``p_exceed_se`` (points x thresholds) [1].

    The standard errors are a quarter of the change of the probability across the point's trust band
    ``[sl_error_low, sl_error_high]`` of ``SL / MCS - 1`` (both variances divided by ``1 + e``; the band stands
    for two standard errors each way), at least what the trust rule leaves open below a small probability
    (:func:`~screening.analysis.fragility.band_standard_error`), at the ``trusted`` points (the only ones where it
    is used); NaN elsewhere and where the band is not finite or reaches ``e <= -1``.

    Parameters
    ----------
    res : dict
        The solver's float64 histories (points x time): ``var_theta`` [rad2], ``var_theta_dot``
        [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1], ``c_eq`` [N m s rad-1], ``k_eq`` [N m rad-1], and
        ``status``.
    block : screening.core.model.Block
        The block(s).
    foundation : screening.core.model.Foundation
        The bed(s).
    excitation : screening.core.excitations.Excitation
        The ground motion model(s).
    out : dict
        The batch's summaries: ``status``, ``sl_trust``, ``sl_error_low``, ``sl_error_high`` [1],
        ``slenderness`` and ``theta_ul`` [rad] as the thresholds need.
    t_out : array_like
        Output times [s].
    fragility : screening.sweep.study.Fragility, optional
        The thresholds and the up-crossing method.

    Returns
    -------
    dict
        ``p_overturn``, ``p_overturn_se`` [1] per point; with ``fragility`` ``p_exceed`` and ``p_exceed_se``
        (points x thresholds).

    Notes
    -----
    The probability that :math:`|\\theta|` exceeds a level :math:`x` within the record, from the Gaussian
    moments: Rice's up-crossing rate :math:`\\nu = \\frac{\\sigma_{\\dot\\theta}}{\\pi\\sigma_\\theta}
    e^{-x^2/2\\sigma_\\theta^2}` of the two barriers [2], with Vanmarcke's bandwidth correction [3].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [rice1944] in the bibliography, ``docs/bibliography.md``.
    .. [3] [vanmarcke1975] in the bibliography, ``docs/bibliography.md``.
    """
    n = out["status"].size
    shape = res["status"].shape
    t = np.asarray(t_out, dtype=float)
    moments = [np.asarray(res[name], dtype=float).reshape(n, -1)
               for name in ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq")]
    m_sdof = np.broadcast_to(np.asarray(block.m_sdof, dtype=float), shape).reshape(n)
    status = np.asarray(res["status"]).reshape(n)
    method = fragility.method if fragility is not None else "vanmarcke"
    levels = [(1.0, "slenderness")] + ([(x, fragility.relative_to) for x in fragility.thresholds]
                                       if fragility is not None else [])
    with np.errstate(divide="ignore", invalid="ignore"):
        edges = [1.0 / (1.0 + out["sl_error_high"]), 1.0 / (1.0 + out["sl_error_low"])]
    # a standard error only where the linearization's estimate can be vouched for at all (trusted points)
    usable = np.all([np.isfinite(e) & (e > 0) for e in edges], axis=0) & (out["sl_trust"] == Trust.trusted)
    at = np.flatnonzero(usable)

    def probability(rows, level, factor=1.0):         # the three moments scaled by ``factor``
        var, var_dot, cov, c_eq, k_eq = (a[rows] for a in moments)
        return linearized_exceedance(t, var * factor, var_dot * factor, cov * factor, c_eq, k_eq, m_sdof[rows],
                                     status[rows], level[rows], method)

    p, se = np.empty((n, len(levels))), np.full((n, len(levels)), np.nan)
    for j, (threshold, relative_to) in enumerate(levels):
        level = np.full(n, float(threshold)) if relative_to is None else float(threshold) * out[relative_to]
        p[:, j] = probability(slice(None), level)
        if at.size:
            lo, hi = (probability(at, level, e[at][:, None]) for e in edges)
            se[at, j] = band_standard_error(p[at, j], lo, hi)
    result = {"p_overturn": p[:, 0], "p_overturn_se": se[:, 0]}
    if fragility is not None:
        result.update(p_exceed=p[:, 1:], p_exceed_se=se[:, 1:])
    return result


def failed_result(n, nt, histories=HISTORY_VARIABLES, fragility=None, derived_inputs=(), probabilities=False):
    """Batch result for ``n`` points whose task failed: each declared variable's failed value (status
    ``task_failed``, NaN values, zero counts, ``sl_trust`` untrusted).

    Parameters
    ----------
    n : int
        Points of the batch.
    nt : int
        Output instants.
    histories : tuple of str, optional
        The stored histories.
    fragility : screening.sweep.study.Fragility, optional
        The ``[fragility]`` table (``p_exceed`` per threshold).
    derived_inputs : tuple of str, optional
        Per-point inputs of the study.
    probabilities : bool, optional
        Whether the points carry the probabilities.

    Returns
    -------
    dict
        ``{variable: array}`` shaped as :func:`solve_batch`'s result.
    """
    n_thresholds = len(fragility.thresholds) if fragility is not None else 0
    return {o.name: o.failed_array(n, nt, n_thresholds)
            for o in selected(histories, derived_inputs, probabilities, fragility is not None)}


def spot_arrays(ds):
    """A Monte Carlo dataset reduced to the arrays of a spot check: the histories, the sample counts, the
    integration steps of all samples and the synthesis grid points they read, the per-sample peaks and states."""
    out = {name: np.asarray(ds[name].values, dtype=np.float64) for name in SPOT_HISTORIES}
    n_over, n_div = int(ds["n_overturned"]), int(ds["n_diverged"])
    out.update(n_overturned=np.int32(n_over), n_diverged=np.int32(n_div),
               n_used=np.int32(ds.sizes["sample"] - n_over - n_div), n_steps=np.int64(ds["n_steps"].values.sum()),
               peak_abs_theta=np.asarray(ds["peak_abs_theta"].values, dtype=np.float64),
               sample_state=sample_state(ds["overturned"].values, ds["diverged"].values))
    out["n_grid"] = np.int64(ds.sizes["sample"] * int(ds.attrs["input_grid_points"]))   # synthesis grid read (cost model)
    integrator = ds.attrs.get("integrator")                     # which steps the run took (cost model)
    out["rodas"] = np.bool_(integrator == INTEGRATOR_TEXT["rodas"])
    out["exact"] = np.bool_(integrator in (INTEGRATOR_TEXT["exact"], INTEGRATOR_TEXT["exact_contact"]))
    # the share of the used samples' time in full contact (the stiff-bed model's cost model; NaN: not known)
    out["full_contact"] = (np.float64(full_contact_share(ds["p_uplift"].values, int(out["n_used"]), ds.sizes["sample"]))
                           if "p_uplift" in ds else np.float64(np.nan))
    return out


def spot_task(block, foundation, excitation, condensation, samples, model, t_end, dt, seed, linear=None,
              progress=None):
    """The dask task of one spot check: :func:`screening.solvers.montecarlo.monte_carlo` reduced to arrays.

    Parameters
    ----------
    block : screening.core.model.Block
        The block of the point (SI fields, scalars).
    foundation : screening.core.model.Foundation
        Its bed (SI fields, scalars).
    excitation : screening.core.excitations.base.Excitation
        Its excitation (``S0`` [m2 s-3]).
    condensation : screening.core.condensation.Condensation or None
        The point's condensation, used by a model that uses one (``model="condensed"``; the others have none).
    samples : int
        Monte Carlo samples.
    model : str
        A registered Monte Carlo model's name, or ``"auto"`` (resolved once, for this point).
    t_end, dt : float
        Record length and output time step [s].
    seed : int
        Seed of the ground-motion synthesis.
    linear : tuple, optional
        ``(t_out [s], rtol, max_steps, names)``: also solve the linearization at the point and return its
        histories ``names`` as ``sl_<name>`` (for a result that does not store them on the grid).
    progress : tuple, optional
        ``(topic, spot)``: the samples done are sent as worker events ``{"spot": spot, "done": n}`` on ``topic``.

    Returns
    -------
    dict
        :func:`spot_arrays` of the run (histories [rad2, rad2 s-2], counts, steps, per-sample peaks [rad] and
        states), its model's code ``mcs_model``, and the ``sl_<name>`` histories asked for (float64).
    """
    from screening.solvers.montecarlo import monte_carlo

    task_threads()
    mc = resolve(model, block, foundation, excitation)          # "auto": once, for this point
    kw = {"condensation": condensation} if mc.uses_condensation else {}
    ds = monte_carlo(block, foundation, excitation, n_samples=samples, model=mc, t_end=t_end, dt=dt,
                     seed=seed, progress=_sample_events(progress), **kw)
    out = spot_arrays(ds)
    out["mcs_model"] = np.int8(mc_registry.code(mc.name))
    if linear is not None:
        t_out, rtol, max_steps, names = linear
        res = solve_moments(block, foundation, excitation, t_out, rtol=rtol, max_steps=max_steps,
                            condensation=condensation)
        for name in names:
            out[f"sl_{name}"] = np.asarray(res[name], dtype=np.float64).reshape(-1)
    return out


def paired_escalation(block, foundation, excitation, condensation, samples, model, t_end, dt, seed, cheap_model,
                      cheap_condensation, cheap_samples, progress=None):
    """``samples`` samples of ``model`` and ``cheap_samples`` (``>= samples``) of the registered ``cheap_model`` (with
    ``cheap_condensation`` where it reads one) on the same ground motions (the first ``samples`` paired).

    Returns ``(arrays, extra)``: :func:`spot_arrays` of the expensive run with ``var_theta`` and ``var_theta_se``
    the two-fidelity estimate (:func:`screening.analysis.multifidelity.multifidelity_variance`; ``var_theta_dot``
    stays the plain one), and the cheap run's ``cheap_*`` results, the correlation of the influence values at the
    peak of var_theta and the :class:`~screening.core.status.EscalationEstimator` code.  Where the cheap model refuses
    the point (``ValueError`` before any work) the result is the plain one, with ``cheap_samples`` 0.
    ``progress``: the expensive run's samples, as for :func:`spot_task`."""
    from screening.solvers.montecarlo import monte_carlo

    task_threads()

    def run(name, cond, n, events=None):
        kw = {"condensation": cond} if mc_registry.get(name).uses_condensation else {}
        return monte_carlo(block, foundation, excitation, n_samples=n, model=name, t_end=t_end, dt=dt, seed=seed,
                           sample_histories=True, progress=events, **kw)

    hi = run(model, condensation, int(samples), _sample_events(progress))
    out = spot_arrays(hi)
    try:
        lo = run(cheap_model, cheap_condensation, int(cheap_samples))
    except ValueError:                  # the cheap model cannot carry this block on this bed: plain Monte Carlo
        return out, {"estimator": np.int8(EscalationEstimator.plain_monte_carlo), "cheap_samples": np.int32(0),
                     "correlation": np.float64(np.nan)}
    cheap = spot_arrays(lo)
    valid_hi = ~(hi["overturned"].values | hi["diverged"].values)
    valid_lo = ~(lo["overturned"].values | lo["diverged"].values)
    est = multifidelity_variance(hi["theta_sample"].values, valid_hi, lo["theta_sample"].values, valid_lo)
    out["var_theta"], out["var_theta_se"] = np.asarray(est.mean, dtype=float), np.asarray(est.se, dtype=float)
    at = int(np.nanargmax(est.mean)) if np.any(np.isfinite(est.mean)) else -1
    code = EscalationEstimator.multifidelity if cheap_samples > samples else EscalationEstimator.plain_monte_carlo
    extra = {"estimator": np.int8(code), "cheap_samples": np.int32(cheap_samples),
             "cheap_n_steps": cheap["n_steps"],
             "cheap_n_grid": cheap["n_grid"],
             "correlation": np.float64(est.correlation[at] if at >= 0 else np.nan),
             "cheap_peak_abs_theta": cheap["peak_abs_theta"], "cheap_sample_state": cheap["sample_state"]}
    return out, extra


def escalation_task(block, foundation, excitation, condensation, samples, model, t_end, dt, seed, cheap=None,
                    progress=None):
    """The dask task of one escalated point: :func:`spot_task` reduced to its peaks, per-sample peaks,
    the integration steps and synthesis grid points of all samples and whether the steps were the
    linearly implicit pair's (``n_steps``, ``n_grid``, ``rodas``, for the cost model) and the CPU time
    it took (``cpu_time`` [s], of the worker thread).

    ``cheap = (model, condensation, samples)``: a cheaper registered model also runs on the same ground
    motions (:func:`paired_escalation`); peak var_theta is then the two-fidelity estimate and the result
    carries the cheap run's per-sample peaks for the probabilities.  ``estimator`` says which estimate it is.
    ``progress``: as for :func:`spot_task`.

    Parameters
    ----------
    block : screening.core.model.Block
        The block at the point.
    foundation : screening.core.model.Foundation
        The bed.
    excitation : screening.core.excitations.Excitation
        The ground motion model.
    condensation : screening.core.condensation.Condensation
        The case's condensation (for a model that reads one).
    samples : int
        Monte Carlo samples.
    model : str
        A registered Monte Carlo model's name.
    t_end : float
        Record length [s].
    dt : float
        Output step [s].
    seed : int
        Seed of the ground motions.
    cheap : tuple, optional
        ``(model, condensation, samples)`` of the paired cheaper model.
    progress : tuple, optional
        ``(topic, run)`` of the worker events.

    Returns
    -------
    dict
        ``peak_var_theta`` [rad2], ``peak_var_theta_dot`` [rad2 s-2] and their standard errors,
        ``cpu_time`` [s], ``samples``, ``n_steps``, ``n_grid``, ``rodas``, ``exact``, ``full_contact`` (the cost
        model's, :func:`spot_arrays`), the sample counts, per-sample
        ``peak_abs_theta`` [rad] and ``sample_state``, ``estimator``, ``cheap_samples``, ``correlation``.

    Notes
    -----
    The peak of the sample variance :math:`\\hat\\sigma^2_\\theta(t)` over the output times, with the
    standard error of the variance estimate at that time.

    References
    ----------
    .. [1] screening documentation, "Monte Carlo numerics", ``docs/montecarlo_numerics.md``.
    .. [2] B. Peherstorfer, K. Willcox and M. Gunzburger, "Optimal model management for multifidelity
       Monte Carlo estimation", SIAM J. Sci. Comput. 38(5) (2016) A3163-A3194.
       https://doi.org/10.1137/15M1046472
    """
    start = time.thread_time()
    if cheap is None:
        run = spot_task(block, foundation, excitation, condensation, samples, model, t_end, dt, seed,
                         progress=progress)
        extra = {"estimator": np.int8(EscalationEstimator.plain_monte_carlo), "cheap_samples": np.int32(0),
                 "correlation": np.float64(np.nan)}
    else:
        run, extra = paired_escalation(block, foundation, excitation, condensation, samples, model, t_end, dt, seed,
                                       *cheap, progress=progress)
    out = {"cpu_time": np.float64(time.thread_time() - start), "samples": np.int32(samples),
           "n_grid": run["n_grid"], "rodas": run["rodas"], "exact": run["exact"], "full_contact": run["full_contact"]}
    for name in ("var_theta", "var_theta_dot"):
        history, se = run[name], run[f"{name}_se"]
        at = int(np.nanargmax(history)) if np.any(np.isfinite(history)) else -1
        out[f"peak_{name}"] = np.float64(history[at] if at >= 0 else np.nan)
        out[f"peak_{name}_se"] = np.float64(se[at] if at >= 0 else np.nan)
    for name in ("n_overturned", "n_diverged", "n_used", "n_steps", "peak_abs_theta", "sample_state"):
        out[name] = run[name]
    out.update(extra)
    return out


def _sample_events(progress):
    """A ``monte_carlo`` progress function sending worker events, or False (outside a worker: nothing)."""
    if progress is None:
        return False
    from distributed import get_worker

    try:
        worker = get_worker()
    except ValueError:
        return False
    topic, spot = progress
    return lambda done: worker.log_event(topic, {"spot": int(spot), "done": int(done)})


def sample_state(overturned, diverged):
    """Per-sample :class:`~screening.core.status.SampleState` codes from the flags of a Monte Carlo run.

    A diverged sample is ``diverged_or_failed`` even if also flagged overturned.

    Parameters
    ----------
    overturned : array_like of bool
        Per sample: it overturned.
    diverged : array_like of bool
        Per sample: its integration diverged or failed.

    Returns
    -------
    numpy.ndarray of int8
        ``standing`` (0), ``overturned`` (1) or ``diverged_or_failed`` (2) per sample.
    """
    state = np.full(np.shape(overturned), SampleState.standing, dtype=np.int8)
    state[np.asarray(overturned, dtype=bool)] = SampleState.overturned
    state[np.asarray(diverged, dtype=bool)] = SampleState.diverged_or_failed
    return state


# ============================================================================ cluster
#: Default execution: in-process (``workers = 0``) for grids of at most this many points with at
#: most one Monte Carlo spot check (under a second of solver work: starting worker processes and
#: loading the solvers in each costs more), otherwise this many local worker processes.
IN_PROCESS_MAX_POINTS = 500
DEFAULT_WORKERS = 2


def default_workers(study):
    """Local workers for ``study`` when none are asked for: 0 (in-process) for a small study, else 2.

    Small: at most :data:`IN_PROCESS_MAX_POINTS` points and at most one Monte Carlo spot check
    (starting worker processes would cost more than the work).

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.

    Returns
    -------
    int
        0 or :data:`DEFAULT_WORKERS`.

    References
    ----------
    .. [1] Dask.distributed documentation, https://distributed.dask.org/en/stable/
    .. [2] screening documentation, "Distributed runs", ``docs/distributed.md``.
    """
    spots = 0 if study.mcs is None else (study.mcs.count if study.mcs.points == "auto" else len(study.mcs.points))
    return 0 if study.n_points <= IN_PROCESS_MAX_POINTS and spots <= 1 else DEFAULT_WORKERS


def warm_up(excitations=None):
    """Import the solver and load its compiled code on a worker; returns the time taken [s].

    Solves one point (the paper's block on its bed) for 0.1 s under each excitation, so that the moment solver's
    loops a run needs are loaded (from numba's cache, or compiled) before the first batch, and no other.

    Parameters
    ----------
    excitations : sequence of screening.core.excitations.Excitation, optional
        One per state size of the run (:func:`screening.sweep.grid.warm_up_excitations`); default white noise at
        the default band.

    Returns
    -------
    float
        The time taken [s].

    References
    ----------
    .. [1] Dask.distributed documentation, https://distributed.dask.org/en/stable/
    .. [2] screening documentation, "Distributed runs", ``docs/distributed.md``.
    .. [3] Numba documentation, "Notes on caching",
       https://numba.readthedocs.io/en/stable/developer/caching.html
    """
    start = time.perf_counter()
    for excitation in excitations or (WhiteNoise(1e-5),):
        solve_moments(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8), excitation, np.array([0.0, 0.1]))
    return time.perf_counter() - start


@contextlib.contextmanager
def dask_client(workers=2, scheduler=None, client=None, cluster=None, log=None):
    """A ``distributed.Client``: the given one, one connected to ``scheduler`` (an address
    or a scheduler JSON file), one of a new dask-jobqueue cluster (``cluster``, a study's ``[cluster]``
    table), or a new ``LocalCluster`` of ``workers`` single-threaded processes (closed on exit);
    ``workers = 0``: one worker thread in this process (no process started, the same tasks and futures,
    so one orchestration serves both).  The workers of a scheduler or a jobqueue cluster must run this
    client's versions (:func:`~screening.sweep.connect.check_workers`).

    A client made here is never dask's default: the run submits to it by name, and a caller's later
    dask or xarray work in the same process does not go to a cluster this function has closed (with
    some library versions a closed default client made xarray's next ``to_netcdf`` fail with "IOLoop
    is closed" and the one after it hang).

    Parameters
    ----------
    workers : int, optional
        Worker processes of a new local cluster; 0: one worker thread in this process.
    scheduler : str or os.PathLike, optional
        Address or scheduler file of an existing cluster (checked first,
        :func:`~screening.sweep.connect.check_scheduler`).
    client : distributed.Client, optional
        A client to use as it is (not closed).
    cluster : screening.sweep.config.ClusterSpec, optional
        A ``[cluster]`` table: its jobs are submitted, the client waits for the first worker.
    log : callable, optional
        Receives one-line messages (waiting for the queue, a worker refused); default: none.

    Returns
    -------
    contextlib.AbstractContextManager
        Yields the ``distributed.Client``.

    Raises
    ------
    SweepError
        A scheduler that cannot be reached or has no workers, workers with other versions, or a
        cluster that cannot start.

    References
    ----------
    .. [1] Dask.distributed documentation, https://distributed.dask.org/en/stable/
    .. [2] screening documentation, "Distributed runs", ``docs/distributed.md``.
    """
    if client is not None:
        yield client
        return
    from distributed import Client

    if cluster is not None:
        with _jobqueue_client(cluster, log or (lambda msg: None)) as c:
            yield c
        return
    if scheduler:
        from screening.sweep.connect import check_scheduler, check_workers

        check_scheduler(scheduler)                 # bounded handshake, sane peer, sane JSON file
        try:
            if str(scheduler).endswith(".json") and Path(scheduler).is_file():
                c = Client(scheduler_file=str(scheduler), timeout=CONNECT_TIMEOUT, set_as_default=False)
            else:
                c = Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
        except Exception as exc:                   # noqa: BLE001 - a peer that changed since the check
            raise SweepError(f"cannot connect to the dask scheduler {scheduler}: {exception_line(exc)}") from None
        try:
            try:
                c.wait_for_workers(1, timeout=30)
            except TimeoutError:
                raise SweepError(f"the dask scheduler {scheduler} has no workers") from None
            done = check_workers(c, log)
            try:
                yield c
            finally:
                done()
        finally:
            c.close()
        return
    import dask

    config = {**LOCAL_CLUSTER_CONFIG, "distributed.worker.multiprocessing-method": _worker_start_method()}
    with dask.config.set(config), _quiet_worker_log(), _local_client(workers) as c:
        yield c


#: How often [s] a run waiting for its first batch job says so: every 10 s for a minute, then every minute.
QUEUE_WAIT_LINES = (10.0, 60.0)


@contextlib.contextmanager
def _jobqueue_client(spec, log):
    """A client of the dask-jobqueue cluster of ``spec`` (:func:`~screening.sweep.connect.jobqueue_cluster`),
    once its first worker is there and checked; the jobs are cancelled on exit."""
    from distributed import Client

    from screening.sweep.connect import check_workers, jobqueue_cluster

    cluster = jobqueue_cluster(spec)
    try:
        try:
            cluster.adapt(minimum_jobs=spec.jobs, maximum_jobs=spec.jobs)       # a retired job is replaced
        except Exception as exc:                  # noqa: BLE001 - dask-jobqueue raises many types
            raise SweepError(f"cannot submit the jobs of the dask-jobqueue cluster: {exception_line(exc)}") from None
        with Client(cluster, set_as_default=False) as c:
            log(f"submitted {spec.jobs} {spec.kind} job(s) of {spec.cores} worker(s) each (workers retire after "
                f"{spec.lifetime_s:g} +- {spec.lifetime_stagger_s:g} s; new jobs take their place); dask dashboard "
                f"{cluster.dashboard_link}")
            start = time.monotonic()
            while True:
                waited = time.monotonic() - start
                try:
                    c.wait_for_workers(1, timeout=QUEUE_WAIT_LINES[waited >= 60])
                    break
                except TimeoutError:
                    log(f"waiting for the first worker: {time.monotonic() - start:.0f} s since the jobs were "
                        "submitted (the batch queue starts them)")
            done = check_workers(c, log)
            try:
                yield c
            finally:
                done()
    finally:
        with contextlib.suppress(Exception):
            cluster.close()


@contextlib.contextmanager
def _quiet_worker_log():
    """A local cluster's workers log every failed task with its traceback; the sweep reports each failed batch
    in one line of its own, so their log is silenced (forked workers inherit the level) while it runs."""
    logger = logging.getLogger("distributed.worker")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


#: dask settings of a local cluster: its scheduler (in this process) keeps the last messages sent to
#: each worker for debugging, 1,000 by default with the arguments of every task in them: a few only,
#: or the client's memory grows with the number of batches.
LOCAL_CLUSTER_CONFIG = {"distributed.admin.low-level-log-length": 16}


#: dask's environment variable for how worker processes start (honoured when set)
START_METHOD_VARIABLE = "DASK_DISTRIBUTED__WORKER__MULTIPROCESSING_METHOD"


def _worker_start_method():
    """How the local cluster starts its worker processes: ``"fork"`` or ``"spawn"``.

    Forked workers start with this process's modules (numpy, numba, scipy, xarray, distributed,
    the solvers) already imported instead of importing them again, about 1 s per run.
    Fork only on Linux (unsafe on macOS, absent on Windows), and only while this process has not
    started numba's parallel threads (a Monte Carlo ran here): its OpenMP runtime cannot be used
    by a forked child.  A method set in the environment for dask
    (``DASK_DISTRIBUTED__WORKER__MULTIPROCESSING_METHOD=spawn``, e.g. in a notebook whose
    threads make fork unsafe) is used as it is.
    """
    import dask
    import numba.np.ufunc.parallel as numba_parallel

    if os.environ.get(START_METHOD_VARIABLE):
        return dask.config.get("distributed.worker.multiprocessing-method")
    if sys.platform.startswith("linux") and not getattr(numba_parallel, "_is_initialized", True):
        return "fork"
    return "spawn"


#: The module whose ``dask_setup`` every worker process of a local cluster runs when it starts.
WORKER_SETUP = "screening.sweep.interrupt"


#: Environment variable of a local cluster's worker processes: the numba threads of each task there.
THREADS_VARIABLE = "SCREENING_TASK_THREADS"


def worker_environment(workers, cores=None):
    """Environment of a local cluster's worker processes: the cores shared out among them as numba threads per
    task (:data:`THREADS_VARIABLE`, at least 1), which :func:`task_threads` applies.

    Each worker runs one task at a time, and a Monte Carlo chunk's ``prange`` would otherwise use every core in
    every worker: ``workers x cores`` threads on ``cores`` cores.  Measured on the acceptance collection (2
    workers, 2 cores, warm cache, another job's load of 1-4 beside): its Monte Carlo took 103-132 s with one thread
    per worker (three runs) against 116-171 s with two (two runs), and the task's thread time then counts all its
    work (152-154 CPU s against 103-107).
    """
    cores = (os.cpu_count() or 1) if cores is None else cores
    return {THREADS_VARIABLE: str(max(1, cores // max(int(workers), 1)))}


def task_threads():
    """Numba's threads for the calling thread's parallel loops, as :func:`worker_environment` set them (nothing
    outside a local cluster's worker process); returns how many there are."""
    import numba

    share = os.environ.get(THREADS_VARIABLE)
    if share:
        numba.set_num_threads(max(1, min(int(share), numba.config.NUMBA_NUM_THREADS)))
    return numba.get_num_threads()


@contextlib.contextmanager
def _local_client(workers):
    """A client of a new local cluster of ``workers`` processes (0: one worker thread in this process)."""
    from distributed import Client, LocalCluster

    if workers == 0:
        try:
            cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                                   silence_logs=logging.ERROR, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
        except Exception as exc:                      # noqa: BLE001 - dask raises RuntimeError & co
            raise SweepError(f"cannot start the in-process dask scheduler: {type(exc).__name__}: {exc}") from None
        try:
            with Client(cluster, set_as_default=False) as c:
                yield c
        finally:
            cluster.close()
        return
    try:
        # the scheduler's HTTP server binds 8787 even without a dashboard, and warns on stderr when
        # that port is taken (another run, another cluster): give it a free port on localhost instead
        from screening.sweep.interrupt import deferred_interrupt

        with deferred_interrupt() as pressed:     # a half-started cluster closes noisily: finish starting
            try:
                # dask's own log lines are silenced up to ERROR: what they report that matters (a failed
                # or killed task) reaches the run as a task failure with its own one-line message; the
                # rest is shutdown noise (a worker's heartbeat to a scheduler closed by Ctrl-C)
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.CRITICAL,
                                       scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                                       preload=[WORKER_SETUP], env=worker_environment(workers))
            except Exception:                         # noqa: BLE001 - a worker hit by the Ctrl-C too
                if pressed:
                    raise KeyboardInterrupt from None
                raise
        if pressed:
            cluster.close()
            raise KeyboardInterrupt
    except Exception as exc:                          # noqa: BLE001 - dask raises RuntimeError & co
        raise SweepError(f"cannot start a local dask cluster of {workers} worker(s): "
                         f"{type(exc).__name__}: {exc}") from None
    try:
        with Client(cluster, set_as_default=False) as c:
            yield c
    except KeyboardInterrupt:
        _stop_workers(cluster)
        raise
    finally:
        cluster.close()


def _stop_workers(cluster, timeout=0.5):
    """Stop the worker processes of a local ``cluster`` within about ``timeout`` [s] (after a Ctrl-C).

    A worker closes only once its running task is done, and a task holds the GIL for most of
    its time, so a graceful close takes a few task durations (seconds for a large batch): the
    processes are asked to stop and killed if they do not within ``0.8 timeout``, not restarted.
    """
    import asyncio

    async def stop_all():
        nannies = list(cluster.workers.values())
        for nanny in nannies:
            nanny.close_gracefully(reason="screening-interrupted")      # not restarted when killed
        await asyncio.gather(*(nanny.kill(timeout=timeout) for nanny in nannies), return_exceptions=True)

    with contextlib.suppress(Exception):
        cluster.sync(stop_all)
