"""The ``[accuracy]`` stage of a sweep: Monte Carlo where the trust rule cannot promise the target,
within a budget of wall seconds, then best estimates at every point (:mod:`screening.analysis.escalation`,
:mod:`screening.analysis.correction`).

:func:`escalate` runs after the linearization and before the spot checks on a :class:`Stage`: the client,
the study, the resume record, the result being built, the log and the progress switch (plain values, not
the sweep's run object), and optionally where interim answers go and the clock; it returns the escalated
points and what it did.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
import uuid
from typing import NamedTuple

import numpy as np

from screening.analysis import escalation as esc
from screening.analysis.correction import best_estimates, point_features
from screening.analysis.escalation import auto_escalation_model
from screening.analysis.trust import shipped_calibration, trust_indicators
from screening.core import limits
from screening.core.progress import Progress
from screening.core.status import BestMethod, EscalationEstimator, SampleState
from screening.io.errors import exception_line, write_failure_reason
from screening.io.writer import Variable
from screening.solvers import mc_registry
from screening.solvers.model_choice import AUTO, choose, sampler_of
from screening.solvers.schema import ACCURACY
from screening.sweep import _submit
from screening.sweep.grid import Batch, batch_point_models, point_values, swept_columns
from screening.sweep.interrupt import raise_if_interrupted
from screening.sweep.probabilities import levels_at
from screening.sweep.study import build_models
from screening.solvers.estimates import sample_probabilities

__all__ = []

#: Resume records of escalated points are spot parts numbered from here (after any spot check): each
#: point's latest result (its pilot, main or top-up run, with the cost of all its runs), and before them the
#: planner's record (the wall seconds spent).
ESCALATION_RECORD = 5000
PLANNER_RECORD = ESCALATION_RECORD - 1
#: Share of ``budget_s`` the Monte Carlo runs may be planned into; the rest is for the answers at the end.
RUN_SHARE = 0.95
#: Runs still going at this multiple of ``budget_s`` are cancelled (their points keep their earlier runs).
HARD_STOP = 1.08
#: Interim answers (:attr:`Stage.interim`) are written at most this often [s], and never taking more than a
#: fifth of the time.
INTERIM_INTERVAL_S = 10.0
#: The progress line is written at least this often [s].
PROGRESS_INTERVAL_S = 10.0
#: Wall seconds per cost-model second of one worker thread assumed before any run finished.
PRIOR_WALL_PER_COST = 1.0
#: Samples for the probabilities are planned for this share of ``PROBABILITY_SE`` (the plan's estimate moves
#: with the run; judged at ``PROBABILITY_SE`` itself).
PLAN_MARGIN = 0.95
#: The phases of a point's runs, as kept in its resume record.
PILOT, MAIN, TOPUP = 0, 1, 2


class Stage(NamedTuple):
    """What the ``[accuracy]`` stage works with: the dask ``client``, the ``study``, the resume record
    ``store`` (:class:`~screening.io.store.PartialStore`), the ``result`` being built
    (:class:`~screening.io.writer.ResultFile`), the ``log`` function, whether to show ``progress``, the per-point
    ``values`` the linearization left (:func:`screening.sweep.run.stage_inputs`; the stage adds its best
    estimates to them),
    ``interim``: None, or ``interim(write)`` writes a complete interim result (``write(result)`` puts the
    escalated points and best estimates so far into a result and returns them as :func:`escalate` does),
    and the wall ``clock`` [s] the budget is measured on."""

    client: object
    study: object
    store: object
    result: object
    log: object
    progress: bool
    values: dict
    interim: object = None
    clock: object = time.monotonic


def wall_model(walls, costs, prior=PRIOR_WALL_PER_COST):
    """``(overhead [s], wall per cost-model second [1])`` of a run, ``wall = overhead + rate cost``, from the runs
    measured (wall seconds ``walls``, cost-model seconds ``costs``, one worker thread each).

    The rate alone (total wall over total cost) read the short first runs' fixed part (the task's round trip, the
    bed's transfer table, the synthesis plan) as a slow rate: on the acceptance collection the time left said
    3 min 15 s at 10 s, 79 s before the end.  A least-squares line over the runs once there are three of two
    costs or more, its intercept within ``[0, shortest wall]`` and its slope then fitting the total; before,
    the total ratio; before any run, ``(0, prior)``.
    """
    w, c = np.asarray(walls, dtype=float), np.asarray(costs, dtype=float)
    if c.size == 0 or c.sum() <= 0.0:
        return 0.0, prior
    overhead = 0.0
    if c.size >= 3 and np.ptp(c) > 0.0:
        slope, intercept = np.polyfit(c, w, 1)
        overhead = float(np.clip(intercept, 0.0, w.min())) if slope > 0.0 else 0.0
    return overhead, float(max(w.sum() - c.size * overhead, 0.0) / c.sum()) or prior


def _point_table(stage):
    """Flat per-point arrays the escalation needs: status, trust and band, the trust indicators, the
    features of the correction, condensation and eps, and SL's peaks."""
    study, res = stage.study, stage.result
    n, per_case = study.n_points, study.points_per_case
    cols = {name: np.empty(n) for name in ("k_rest", "eps", "envelope_end")}
    cond = np.empty(n, dtype=object)
    swept, case_index = swept_columns(study)
    for c, case in enumerate(study.cases):
        whole = Batch(0, c, c * per_case, (c + 1) * per_case)
        block, foundation, excitation, _ = batch_point_models(study, whole)
        rows = slice(whole.lo, whole.hi)
        cols["k_rest"][rows] = case.condensation_model.stiffness_at_rest(block, foundation)
        cols["eps"][rows] = foundation.eps
        q2 = np.asarray(excitation.envelope(study.times), dtype=float) ** 2
        cols["envelope_end"][rows] = q2[-1] / max(q2.max(), 1e-300)
        cond[rows] = case.condensation_model.name
    values = stage.values
    peak = values["peak_var_theta"]
    ind = trust_indicators(res.peak_p_uplift, values["min_k_eq"], cols["k_rest"], peak, values["slenderness"],
                           values["var_theta_end"], cols["envelope_end"])
    features = {**swept, **({"case": case_index} if study.has_case_dim else {}), **ind}
    return {"status": res.status, "trust": res.sl_trust, "low": values["sl_error_low"],
            "high": values["sl_error_high"], "indicators": ind, "features": features,
            "condensation": cond.astype(str), "eps": cols["eps"], "peak_var_theta": peak,
            "peak_var_theta_dot": values["peak_var_theta_dot"]}

def escalate(stage):
    """Escalate, write the escalated points and the best estimates into ``stage.result``.

    ``stage``: a :class:`Stage`.  Returns ``((flat indices, models, runs), info)``: the escalated points with
    their :class:`~screening.core.status.EscalationModel` codes and the dicts of
    :func:`~screening.sweep.execution.escalation_task` (their sample peaks feed
    :mod:`screening.sweep.probabilities`), and what the escalation did (the run report's ``accuracy``).

    The points whose trust band cannot promise ``[accuracy] target`` are ordered: those in the transition
    of a fragility curve first (:func:`~screening.analysis.escalation.transition_points`: the
    linearization's P(overturn) or P(exceed) between 0.02 and 0.98 along the swept intensity, or a jump
    across that band beside them), then the coverage of the grid's features (with ``[fragility]`` every
    candidate, the budget deciding how many run; else at most
    :data:`~screening.analysis.escalation.MAX_POINTS`); each is given a Monte Carlo
    model (stiff-bed, condensed or coupled, by their measured validity) and runs until its standard
    error reaches the target, within ``budget_s`` wall seconds (:func:`_escalation_runs`).  One line
    before any Monte Carlo says what the pilots of the transition points will cost (:func:`plan_line`).
    The linearization's error learned at the escalated points then gives a best estimate of the peak
    variances at every point (:func:`screening.analysis.correction.best_estimates`).

    Parameters
    ----------
    stage : Stage
        The dask client, the study, the resume record, the result being built, the log function, the
        progress switch, where interim answers go and the clock.

    Returns
    -------
    escalated : tuple
        ``(flat indices, models, runs)`` of the escalated points: their grid positions, their
        :class:`~screening.core.status.EscalationModel` codes and the run dicts (sample peaks [rad], peak
        variances [rad2], [rad2 s-2], their standard errors, CPU time [s]).
    info : dict
        What the escalation did: target [1], budget, wall time and cost [s], points selected, in the
        transition, escalated, short of the target, cut by the budget and failed, the correction's
        leave-one-out RMS [1] and points per best-estimate method (the line of :func:`accuracy_line`).

    Notes
    -----
    The standard error of a Monte Carlo estimate falls as :math:`1/\\sqrt{n}`: from a run of
    :math:`n_0` samples with relative standard error :math:`\\mathrm{se}_0`, a point is given
    :math:`n = s\\, n_0\\, (\\mathrm{se}_0 / (\\mathrm{target}/2))^2` samples, :math:`s` the safety factor
    :data:`~screening.analysis.escalation.SAMPLE_SAFETY`
    (:func:`~screening.analysis.escalation.samples_needed`); a transition point is given the samples its
    probabilities need for a standard error of :data:`~screening.analysis.escalation.PROBABILITY_SE`
    (:func:`~screening.analysis.escalation.probability_samples`).
    """

    acc, study = stage.study.accuracy, stage.study
    pts = _point_table(stage)
    features = point_features(pts["features"])
    candidates = esc.escalation_candidates(pts["status"], pts["trust"], pts["low"], pts["high"], acc.target)
    transition = _transition(stage, pts["status"])
    most = int(candidates.sum()) if study.fragility is not None else esc.MAX_POINTS    # probabilities: every point
    order = esc.transition_first(features, candidates, transition, stage.result.peak_p_uplift, most)
    models = escalation_models(stage, order, esc.escalation_model(
        pts["indicators"], pts["status"], pts["condensation"], pts["eps"],
        esc.condensed_cells(shipped_calibration(), acc.target))[order])
    levels = _levels(stage)[order]
    first = transition[order]

    def answers(result, results, ran):
        return _write_answers(stage, result, pts, features, order, models, first, results,
                              dict(ran, n_candidates=int(candidates.sum())))

    results, ran = _escalation_runs(stage, order, models, first, levels, answers)
    (escalated, models_done, runs), info = answers(stage.result, results, ran)
    stage.log(accuracy_line(info))
    return (escalated, models_done, runs), info


def _transition(stage, status):
    """Per point: in the transition of a fragility curve by the linearization's probabilities (NaN where it
    stopped), along the swept intensity (``S0`` or ``pga``) if there is one."""
    from screening.analysis.escalation import transition_points
    from screening.core.status import PointStatus

    study, values = stage.study, stage.values
    p = [values["p_overturn"]]
    if study.fragility is not None:
        p.append(values["p_exceed"])
    p = np.column_stack(p)
    p[np.asarray(status) != int(PointStatus.ok)] = np.nan
    name = next((d for d in ("S0", "pga") if d in study.dims), None)
    axis = study.dims.index(name) if name is not None else None
    return transition_points(p, study.shape, axis, study.sweeps[name] if name is not None else None)


def _levels(stage):
    """Rotations [rad] of P(overturn) and each ``[fragility]`` threshold at every point (points x levels)."""
    return levels_at(stage.study, stage.values["theta_ul"], stage.values["slenderness"])


def _write_answers(stage, result, pts, features, order, models, first, results, ran):
    """Write the escalated points ``results`` (``{position in order: run}``) and the best estimates at every
    point into ``result``; returns ``((flat indices, models, runs), info)`` as :func:`escalate`.  ``ran``: what
    the runs did (:func:`_escalation_runs`)."""

    acc = stage.study.accuracy
    done = [j for j in range(len(order)) if j in results]
    escalated, models_done = order[done], models[done]
    runs = [results[j] for j in done]
    for j, r in zip(done, runs):
        if "target_met" not in r:                 # judged when the run was kept (its probabilities or its variance)
            r["target_met"] = bool(esc.meets_target(r["peak_var_theta"], r["peak_var_theta_se"], acc.target))
        r["target_met"] = bool(r["target_met"])
        r["transition"] = np.int8(first[j])
    variables, dimensions = escalation_variables(stage.study, escalated, models_done, runs, stage.values)
    best = {}
    for name in ("var_theta", "var_theta_dot"):
        mc = np.array([r[f"peak_{name}"] for r in runs]) if runs else np.zeros(0)
        mc_se = np.array([r[f"peak_{name}_se"] for r in runs]) if runs else np.zeros(0)
        value, se, method, corr = best_estimates(pts[f"peak_{name}"], pts["status"], pts["trust"], pts["low"],
                                                 pts["high"], acc.target, features, escalated, mc, mc_se,
                                                 models_done, atlas=name == "var_theta")
        best[name] = (value, se, method, corr)
    method = best["var_theta"][2]
    variables += best_variables(stage.study, best["var_theta"][:2], best["var_theta_dot"][:2], method,
                                result.coordinates)
    for name in ("var_theta", "var_theta_dot"):                   # handed on to the probabilities
        stage.values[f"best_peak_{name}"], stage.values[f"best_peak_{name}_se"] = (
            np.asarray(v, dtype=float) for v in best[name][:2])
    stage.values["best_method"] = np.asarray(method, dtype=np.int8)

    short = sum(1 for r in runs if not r["target_met"])
    codes, counts = np.unique(method, return_counts=True)
    cost = sum(float(r["cost_s"]) for r in runs)
    cpu = sum(float(r["cpu_time"]) for r in runs)
    info = {"target": acc.target, "budget_s": acc.budget_s, "wall_s": ran["wall_s"], "cost_s": cost, "cpu_s": cpu,
            "n_candidates": int(ran["n_candidates"]), "n_selected": len(order), "n_transition": int(np.sum(first)),
            "n_escalated": len(runs), "n_transition_escalated": int(np.sum(first[done])) if done else 0,
            **{f"n_{m.name}": int(np.sum(models_done == m)) for m in mc_registry.escalation_models()},
            "n_short": short,
            "n_multifidelity": sum(1 for r in runs if int(r.get("estimator", 0)) == EscalationEstimator.multifidelity),
            "n_cut": int(ran["n_cut"]), "n_failed": int(ran["n_failed"]), "warm_up_s": float(ran["warm_up_s"]),
            "n_unreliable": int(np.sum(method == BestMethod.unreliable)),
            "loo_rms": float(best["var_theta"][3].loo_rms), "correction_usable": best["var_theta"][3].usable,
            "methods": {BestMethod(int(c)).name: int(k) for c, k in zip(codes, counts)}}
    result.add(variables, dimensions, dict(
        accuracy_target=acc.target, accuracy_budget_s=acc.budget_s, accuracy_wall_s=info["wall_s"],
        accuracy_cost_s=cost, accuracy_cpu_s=cpu,
        accuracy_n_candidates=np.int32(info["n_candidates"]), accuracy_n_escalated=np.int32(len(runs)),
        accuracy_n_transition=np.int32(info["n_transition"]),
        accuracy_n_cut_by_budget=np.int32(info["n_cut"]),
        accuracy_n_short_of_target=np.int32(short), accuracy_n_unreliable=np.int32(info["n_unreliable"]),
        accuracy_correction_loo_rms=info["loo_rms"],
        accuracy_note=accuracy_line(info)))
    return (escalated, models_done, runs), info


def escalation_models(stage, order, calibrated):
    """:class:`~screening.core.status.EscalationModel` of the ``order`` ed points: with ``[accuracy] model = "auto"``
    the measured validity rule's choice per point where it is the stiff-bed model, the calibration's
    (``calibrated``) elsewhere (:func:`~screening.analysis.escalation.auto_escalation_model`); an explicit model
    at every point.  Resolved once here: the tasks receive the model's name."""
    study = stage.study
    model = getattr(study.accuracy, "model", AUTO)
    if model != AUTO:
        return np.full(len(order), int(mc_registry.get(model).escalation_code), dtype=np.int8)
    chosen = []
    for flat in order:
        case, values = point_values(study, tuple(int(i) for i in np.unravel_index(int(flat), study.shape)))
        block, foundation, excitation = build_models(study.cases[case], values, study.t_end)
        chosen.append(choose(block, foundation, excitation.kind)[0])
    return auto_escalation_model(calibrated, chosen)


def _threads(client):
    """Worker threads of the client's cluster (at least 1)."""
    try:
        return max(int(sum(client.nthreads().values())), 1)
    except Exception:                                   # noqa: BLE001 - a client without workers yet
        return 1


def plan_line(budget_s, n_points, n_transition, pilot_s, threads, all_pilots_s=None):
    """One line before any Monte Carlo: the budget, the points, and what the pilots cost (all of them go
    first); where even the transition points' pilots cannot fit, the budget they need.

    Parameters
    ----------
    budget_s : float
        ``[accuracy] budget_s`` [s] (wall).
    n_points, n_transition : int
        Points that may run Monte Carlo, and those of them in the transition of a fragility curve.
    pilot_s : float
        Estimated wall time [s] of the transition points' pilots on ``threads`` worker threads.
    threads : int
        Worker threads.
    all_pilots_s : float, optional
        Estimated wall time [s] of the pilots of all ``n_points``.

    Returns
    -------
    str

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "A budget in seconds" (this package's documentation).
    """
    if pilot_s > RUN_SHARE * budget_s and n_transition:
        need = math.ceil(pilot_s / RUN_SHARE)
        return (f"accuracy: budget_s = {budget_s:g} s cannot hold even the pilots of the {n_transition} point(s) in "
                f"the transition of a fragility curve (about {pilot_s:.0f} s on {threads} worker thread(s)); give "
                f"[accuracy] budget_s >= {need} for them (running what fits)")
    return (f"accuracy: Monte Carlo at up to {n_points} point(s)"
            + (f", the {n_transition} in the transition of a fragility curve first" if n_transition else "")
            + f", within budget_s = {budget_s:g} s of wall time on {threads} worker thread(s)"
            + (f"; the pilots ({esc.PILOT_SAMPLES} samples at every point, first) take about {all_pilots_s:.0f} s"
               if all_pilots_s is not None else f"; their pilots take about {pilot_s:.0f} s" if n_transition else ""))


def _escalation_runs(stage, order, models, first, levels, answers):
    """Pilot, main and top-up Monte Carlo runs at the ``order`` ed points, within ``budget_s`` wall seconds.

    Each point runs a pilot of :data:`~screening.analysis.escalation.PILOT_SAMPLES` samples, then the samples
    its target needs by the pilot (where its probabilities answer it -- a transition point, ``first``, or a
    pilot sample that overturned or exceeded a ``[fragility]`` threshold -- their standard error
    :data:`~screening.analysis.escalation.PROBABILITY_SE` at the rotations ``levels``; else the variance's
    ``target / 2``), then, where still short, a top-up by the main run's standard error.  At most one run per
    worker thread is in flight; a free thread takes the next point's pilot (every point a first answer before
    any is refined, so a run stopped at any moment has answers), then the next run of the highest point in the
    order, those deciding a fragility curve (a probability strictly between 0 and 1) first.  What a point runs
    depends on its own runs only, so where the budget does not bind
    the points and their samples are the same on every machine and after any interruption.

    The budget binds on the ``stage.clock``: a run is started only if its wall time (its cost-model seconds,
    :func:`~screening.analysis.escalation.estimated_cost`, times the wall seconds per cost second measured
    on the runs so far) ends within :data:`RUN_SHARE` of the budget; a main or top-up run that does not fit
    is shortened to what fits (not below what the point has), a pilot that does not fit is not started; runs
    still going at :data:`HARD_STOP` times the budget are cancelled.  Then which points ran depends on the
    machine; the result says what ran at each point (``esc_samples``, ``esc_target_met``).

    Every finished run is kept at once in the resume record (the point's latest result, with the cost of all
    its runs) and the wall seconds spent in the planner's record, so an interrupted run loses no finished run
    and its budget goes on from what was spent.  ``answers(result, results, ran)`` writes the answers so far;
    with ``stage.interim`` they are written as a complete interim result at most every
    :data:`INTERIM_INTERVAL_S`.

    Returns ``({position: result}, ran)``: each result carries its total ``cpu_time`` and ``cost_s``; ``ran``:
    ``wall_s`` (wall seconds of the stage, earlier runs included), ``n_cut`` (points the budget left short
    or without a run), ``n_failed`` (failed tasks), ``warm_up_s`` (the kernels' compilation on the workers, not
    charged).
    """

    study, store, acc, clock = stage.study, stage.store, stage.study.accuracy, stage.clock
    most = min(esc.MAX_SAMPLES, limits.MAX_SAMPLE_VALUES // study.times.size)
    token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"
    threads = _threads(stage.client)
    results, phase, todo, finished = {}, {}, {}, set()     # todo: {j: (samples, cheap samples)} ready to submit
    counters = {"failed": 0, "cut": set()}

    def index_of(j):
        return tuple(int(i) for i in np.unravel_index(order[j], study.shape))

    def cost(j, r, cheap=True):
        """Estimated cost [s] of run ``r`` at point ``j`` (``cheap``: with its paired cheaper model's samples)."""
        c = esc.estimated_cost(r["n_steps"], models[j], r.get("n_grid", 0), bool(r.get("rodas", False)),
                               int(r.get("samples", 1)), full_contact=r.get("full_contact"),
                               exact=bool(r.get("exact", False)))
        if cheap and int(r.get("cheap_samples", 0)) > 0:
            c += esc.estimated_cost(r["cheap_n_steps"], esc.PAIRED_MODEL[2], r["cheap_n_grid"], False,
                                    int(r["cheap_samples"]))
        return c

    def runs_model(j):
        """The Monte Carlo model that runs at point ``j``: its escalation model, with ``model = "auto"`` that
        model's sampler."""
        model = getattr(acc, "model", AUTO)
        return sampler_of(mc_registry.escalation_models()(int(models[j])).name) if model == AUTO else model

    def partner(j):
        """``(model, condensation)`` paired with point ``j``'s runs, or None (plain Monte Carlo only)."""
        pair = esc.paired_model(models[j]) if acc.multifidelity else None
        return None if pair is None else pair[:2]

    def hits(j, r):
        """``(samples reaching each level, usable samples)`` of run ``r`` at point ``j``."""
        state = np.asarray(r["sample_state"])
        valid = (state == SampleState.standing) | (state == SampleState.overturned)
        got = sample_probabilities(np.asarray(r["peak_abs_theta"], dtype=float), state == SampleState.overturned,
                                   valid, levels[j, 1:])
        n = int(valid.sum())
        k = np.rint(np.concatenate([[got["p_overturn"]], np.atleast_1d(got["p_exceed"])]) * n) if n else np.zeros(0)
        return k, n

    def rel_se(r):
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(r["peak_var_theta_se"] / r["peak_var_theta"])

    def probabilities_answer(j, r):
        """Whether point ``j``'s probabilities answer it: in a curve's transition by the linearization, or a
        sample of run ``r`` reached a level (overturned, or exceeded a ``[fragility]`` threshold)."""
        return bool(first[j]) or bool(np.any(hits(j, r)[0] > 0))

    def deciding(j):
        """Point ``j`` decides a fragility curve: in a transition, or its runs so far put a probability strictly
        between 0 and 1."""
        if first[j]:
            return True
        k, n = hits(j, results[j])
        return bool(np.any((k > 0) & (k < n)))

    def met(j, r):
        if probabilities_answer(j, r):
            return esc.probabilities_met(*hits(j, r))
        return bool(esc.meets_target(r["peak_var_theta"], r["peak_var_theta_se"], acc.target))

    def wanted(j, r):
        """Samples its target needs by run ``r`` of point ``j``."""
        if probabilities_answer(j, r):
            k, n = hits(j, r)
            return esc.probability_samples(k, n, most, se=PLAN_MARGIN * esc.PROBABILITY_SE)
        return esc.samples_needed(rel_se(r), int(r["samples"]), acc.target, most)

    def next_run(j):
        """``(samples, cheap samples, cost per sample [s])`` of point ``j``'s next run, or None (done)."""
        r, ph = results[j], phase[j]
        if ph == TOPUP or (ph == MAIN and met(j, r)) or (ph == PILOT and probabilities_answer(j, r) and met(j, r)):
            return None
        n, n_cheap = wanted(j, r), 0
        rate = cost(j, r, cheap=False) / max(int(r["samples"]), 1)
        if ph == PILOT:
            if int(r.get("cheap_samples", 0)) > 0:              # a paired pilot: multi-fidelity if it pays
                plan = esc.paired_plan(r, models[j], esc.PILOT_SAMPLES, n)
                if plan.estimator == "multifidelity":
                    rate_cheap = (cost(j, r) - cost(j, r, cheap=False)) / esc.PILOT_SAMPLES
                    n, n_cheap = plan.n_expensive, plan.n_cheap
                    rate += rate_cheap * n_cheap / n           # per expensive sample, its cheap ones included
            big = (n_cheap >= 2 * esc.PILOT_SAMPLES and n >= esc.PILOT_SAMPLES) if n_cheap else (
                n > int(r["samples"]) if probabilities_answer(j, r) else n >= 2 * esc.PILOT_SAMPLES)
            return (n, n_cheap, rate) if big else None
        paired = int(r.get("estimator", EscalationEstimator.plain_monte_carlo)) == EscalationEstimator.multifidelity
        if paired:
            n_cheap = math.ceil(int(r["cheap_samples"]) * n / int(r["samples"]))
            rate = cost(j, r) / max(int(r["samples"]), 1)
        return (n, n_cheap, rate) if n > int(r["samples"]) else None

    def settle(j):
        """Point ``j``'s last run is in: queue its next run, or count it finished."""
        nxt = next_run(j)
        if nxt is None:
            finished.add(j)
            bar.update(1)
        else:
            todo[j] = nxt

    # -- the resume record: every point's latest run, and the wall seconds spent
    plan = store.load_spot(PLANNER_RECORD, np.asarray(order, dtype=np.int64))
    spent_before = float(plan["spent_s"]) if plan is not None and "spent_s" in plan else 0.0
    needed = {"cpu_time", "peak_var_theta", "samples", "n_steps", "cost_s", "phase", "sample_state"}
    for j in range(len(order)):
        part = store.load_spot(ESCALATION_RECORD + j, index_of(j))
        if part is not None and needed <= set(part):
            results[j], phase[j] = part, int(part["phase"])

    # -- before any Monte Carlo: what the transition points' pilots cost, on the workers there are
    pilot_prior = {j: esc.prior_cost(esc.PILOT_SAMPLES, study.t_end, models[j],
                                     exact=mc_registry.get(runs_model(j)).run_integrator == "exact_contact")
                   * (2 if partner(j) else 1) for j in range(len(order))}
    pilots_s = sum(pilot_prior[j] for j in range(len(order)) if first[j] and j not in results)
    every_s = sum(pilot_prior[j] for j in range(len(order)) if j not in results)
    stage.log(plan_line(acc.budget_s, len(order), int(np.sum(first)),
                        PRIOR_WALL_PER_COST * pilots_s / threads, threads, PRIOR_WALL_PER_COST * every_s / threads))
    warm_up = 0.0
    if len(results) < len(order) or any(next_run(j) is not None for j in results):
        stage.log("accuracy: compiling the Monte Carlo kernels on the workers (cached after the first run; not "
                  "charged to budget_s)")
        t0 = time.perf_counter()
        used = {runs_model(j) for j in range(len(order))} | {partner(j)[0] for j in range(len(order)) if partner(j)}
        stage.client.run(_submit.warm_up_monte_carlo, tuple(sorted(used)))
        warm_up = time.perf_counter() - t0
    start = clock()
    runs_wall, runs_cost = [], []                          # wall seconds of finished runs, their cost-model seconds
    fitted = {"model": (0.0, PRIOR_WALL_PER_COST), "runs": {}}   # wall_model of them; runs per point
    pilot_costs = []                                       # cost-model seconds of the pilots run

    def now():
        return spent_before + clock() - start

    def wall_per_cost():
        return fitted["model"][1]

    def overhead():
        return fitted["model"][0]

    def eta():
        """Seconds left: the runs queued and in flight and the points not started (each as a finished point's runs
        cost on average; before any, its pilot), at the measured rate (before any: the prior), within the budget.
        Called from the display's thread: None where the loop changed the queue meanwhile."""
        try:
            left = sum(n * rate for n, _, rate in list(todo.values())) + sum(list(in_flight.values()))
            done = [float(results[j]["cost_s"]) for j in list(finished) if j in results]
            per_point = float(np.mean(done)) if done else None        # a finished point's runs, all told
            fresh = [j for j in range(len(order)) if j not in results and j not in in_flight and j not in counters["cut"]]
            left += sum(per_point or pilot_prior[j] for j in fresh)
            runs = list(fitted["runs"].values())
            n_runs = len(todo) + len(fresh) * (float(np.mean(runs)) if runs else 1.0)
        except RuntimeError:
            return None
        return min((wall_per_cost() * left + overhead() * n_runs) / threads, max(acc.budget_s - now(), 0.0))

    topic = f"screening-escalation-samples-{token}"
    samples_done, signal = {}, threading.Event()        # signal: a run ended
    in_flight, pending, started = {}, {}, {}     # in flight: {j: estimated cost}; pending: {future: (j, phase)}
    label = "accuracy: points done (Monte Carlo)"
    interim = {"last": now(), "took": 0.0, "count": 0}

    def submit(j, samples, what, cheap_samples=0):
        model = runs_model(j)
        cheap = (*partner(j), int(cheap_samples)) if cheap_samples else None
        return _submit.submit_escalation(stage.client, study, int(order[j]), samples, model,
                                         key=f"escalate-{('pilot', 'full', 'topup')[what]}-{token}-{j:04d}",
                                         cheap=cheap, progress=(topic, 3 * j + what))

    def keep(j, r, what):
        """``r`` is the point's result from now on; CPU time and cost add up over its runs; kept at once."""
        before = results.get(j)
        r["cost_s"] = np.float64(cost(j, r) + (float(before["cost_s"]) if before is not None else 0.0))
        r["cpu_time"] = np.float64(r["cpu_time"] + (float(before["cpu_time"]) if before is not None else 0.0))
        r["phase"] = np.int8(what)
        r["target_met"] = np.int8(met(j, r))
        results[j], phase[j] = r, what
        try:
            store.save_spot(ESCALATION_RECORD + j, index_of(j), r)
        except OSError as exc:
            stage.log(f"warning: cannot save the resume record of escalated point {j} ({write_failure_reason(exc)})")

    def save_plan():
        try:
            store.save_spot(PLANNER_RECORD, np.asarray(order, dtype=np.int64), {"spent_s": np.float64(now())})
        except OSError as exc:
            stage.log(f"warning: cannot save the resume record of the escalation plan ({write_failure_reason(exc)})")

    def fill():
        """Start runs on the free threads: the next pilot (every point a first answer before any is refined),
        then the next run of the highest point, those deciding a fragility curve first."""
        deadline = RUN_SHARE * acc.budget_s
        while len(pending) < threads:
            pilot = next((j for j in range(len(order)) if j not in results and j not in in_flight
                          and j not in counters["cut"]), None)
            ready = sorted(todo, key=lambda j: (not deciding(j), j)) if pilot is None else []
            if ready:
                j = ready[0]
                n, n_cheap, rate = todo.pop(j)
                have = int(results[j]["samples"])
                fits = int((deadline - now() - overhead()) / max(wall_per_cost() * rate, 1e-300))
                if n > fits:                                  # the budget binds: what fits, if it adds samples
                    counters["cut"].add(j)
                    n_cheap = math.ceil(n_cheap * fits / n) if n_cheap else 0
                    n = fits
                    if n < have + esc.PILOT_SAMPLES // 2:
                        finished.add(j)
                        bar.update(1)
                        continue
                what = MAIN if phase[j] == PILOT else TOPUP
                fut = submit(j, n, what, n_cheap)
                in_flight[j] = n * rate
            else:
                j = pilot
                if j is None:
                    return
                guess = max(pilot_costs, default=pilot_prior[j])
                if now() + overhead() + wall_per_cost() * guess > deadline:
                    counters["cut"].add(j)
                    bar.update(1)
                    continue
                fut = submit(j, esc.PILOT_SAMPLES, PILOT, esc.PILOT_SAMPLES if partner(j) else 0)
                in_flight[j] = guess
                what = PILOT
            pending[fut] = (j, what)
            started[fut] = clock()
            fut.add_done_callback(lambda _: signal.set())

    def arrived(fut):
        j, what = pending.pop(fut)
        in_flight.pop(j, None)
        took = clock() - started.pop(fut)
        try:
            r = fut.result()
        except Exception as exc:          # noqa: BLE001 - the point keeps what it has
            counters["failed"] += 1
            stage.log(f"warning: Monte Carlo at escalated point {j} failed: {exception_line(exc)}")
            finished.add(j)
            bar.update(1)
            return
        finally:
            fut.release()
        keep(j, r, what)
        if what == PILOT:
            pilot_costs.append(cost(j, r))
        runs_wall.append(took)
        runs_cost.append(cost(j, r))
        fitted["model"] = wall_model(runs_wall, runs_cost)
        fitted["runs"][j] = fitted["runs"].get(j, 0) + 1
        settle(j)

    def write_interim():
        """A complete interim result with the answers so far (at most every INTERIM_INTERVAL_S, and at most
        a fifth of the time)."""
        if stage.interim is None or not results or len(results) == interim["count"]:
            return
        if now() - interim["last"] < max(INTERIM_INTERVAL_S, 4 * interim["took"]):
            return
        t0 = clock()
        try:
            stage.interim(lambda result: answers(result, dict(results), ran())[0])
        except OSError as exc:
            stage.log(f"warning: cannot write the interim result ({write_failure_reason(exc)})")
        interim.update(last=now(), took=clock() - t0, count=len(results))

    def ran():
        return {"wall_s": now(), "n_cut": len(counters["cut"]), "n_failed": counters["failed"], "warm_up_s": warm_up}

    with Progress(len(order), label=label, enabled=stage.progress and len(order) > 0, eta=eta,
                  line_interval=PROGRESS_INTERVAL_S) as bar:
        def count(event):            # per-sample progress of the running points (worker events)
            samples_done[event[1]["spot"]] = max(samples_done.get(event[1]["spot"], 0), int(event[1]["done"]))
            bar.label = f"{label}, {sum(samples_done.values())} samples"

        stage.client.subscribe_topic(topic, count)
        try:
            for j in sorted(results):
                settle(j)
            fill()
            while pending:
                raise_if_interrupted()
                signal.clear()
                done = [fut for fut in pending if fut.done()]
                if not done:            # wake at least every second: the clock, the progress line, a Ctrl-C
                    signal.wait(min(1.0, max(HARD_STOP * acc.budget_s - now(), 0.01)))
                    done = [fut for fut in pending if fut.done()]
                for fut in sorted(done, key=lambda f: pending[f][0]):
                    arrived(fut)
                if now() > HARD_STOP * acc.budget_s and pending:
                    cut = sorted(j for j, _ in pending.values())
                    for fut in list(pending):
                        fut.cancel()
                        j, _ = pending.pop(fut)
                        counters["cut"].add(j)
                    counters["cut"].update(todo)
                    todo.clear()
                    stage.log(f"warning: accuracy: budget_s = {acc.budget_s:g} s reached with {len(cut)} run(s) still "
                              f"going: cancelled (points {', '.join(str(j) for j in cut)} keep their earlier runs)")
                    break
                if done:
                    save_plan()
                    write_interim()
                fill()
        finally:
            save_plan()                                 # the wall seconds spent, also when interrupted
            with contextlib.suppress(Exception):        # noqa: BLE001 - only the display
                stage.client.unsubscribe_topic(topic)
    return results, ran()


def accuracy_line(info):
    """One line: what the ``[accuracy]`` escalation covered and what it could not.

    Parameters
    ----------
    info : dict
        What :func:`escalate` did (its second return value): ``target`` [1], ``budget_s`` and ``wall_s``
        (wall), ``cost_s`` (cost model) and ``cpu_s`` (measured CPU) [s], point counts and ``methods``
        (points per best-estimate method).

    Returns
    -------
    str
        The line of the run's log and of the result's ``accuracy_note`` attribute.
    """
    methods = ", ".join(f"{name} {n}" for name, n in info["methods"].items())
    left = info["n_candidates"] - info["n_escalated"]
    transition = info.get("n_transition", 0)
    return (f"accuracy (target {info['target']:g}): {info['n_candidates']} point(s) beyond the trust rule's promise"
            + (f", {transition} in the transition of a fragility curve" if transition else "") + "; "
            f"Monte Carlo at {info['n_escalated']} ("
            + (f"{info.get('n_transition_escalated', 0)} of the transition; " if transition else "")
            + f"{info['n_coupled']} coupled, {info['n_condensed']} condensed"
            + "".join(f", {info[f'n_{m.name}']} {m.name.replace('_', '-')}" for m in mc_registry.escalation_models()
                      if m.name not in ("coupled", "condensed") and info.get(f"n_{m.name}")) + "; "
            + (f"{info['n_multifidelity']} multi-fidelity; " if info.get("n_multifidelity") else "") +
            f"{info['n_short']} short of the target's standard error"
            + (f"; {info['n_cut']} cut short by the budget" if info.get("n_cut") else "") + ") in "
            f"{info['wall_s']:.0f} of {info['budget_s']:g} wall s ({info['cost_s']:.1f} CPU s by the cost model, "
            f"{info['cpu_s']:.1f} s measured); {left} without Monte Carlo"
            f" (correction leave-one-out RMS {info['loo_rms']:.2f}{'' if info['correction_usable'] else ', not usable'}); "
            f"best estimates: {methods}")


def escalation_variables(study, flat_indices, models, runs, linear):
    """The variables of the ``[accuracy]`` Monte Carlo points on dimension ``escalation`` and their dimensions, for
    :meth:`~screening.io.writer.ResultFile.add` (``runs``: the dicts of
    :func:`~screening.sweep.execution.escalation_task`; ``models``: their
    :class:`~screening.core.status.EscalationModel` codes; ``linear``: the linearization's per-point values,
    :func:`~screening.sweep.run.stage_inputs`)."""
    n = len(runs)
    most = max((int(r["samples"]) for r in runs), default=1)
    # (a one-point grid has no grid dimension; no escalated point: empty coordinates)
    idx = np.unravel_index(np.asarray(flat_indices, dtype=np.int64), study.shape) if study.shape else ()
    coords = [Variable(f"esc_{dim}", "i4" if dim == "case" else "f8", ("escalation",),
                       np.asarray(idx[axis], dtype=np.int32) if dim == "case" else study.sweeps[dim][idx[axis]], False,
                       table=ACCURACY, compress=False) for axis, dim in enumerate(study.dims)]
    at = " ".join(c.name for c in coords)

    def column(key, dtype, default=None):
        return np.array([r[key] if default is None else r.get(key, default) for r in runs], dtype=dtype)

    flags = {"esc_grid_index": np.asarray(flat_indices, dtype=np.int32), "esc_model": np.asarray(models, dtype=np.int8),
             "esc_samples": column("samples", np.int32), "esc_estimator": column("estimator", np.int8, 0),
             "esc_cheap_samples": column("cheap_samples", np.int32, 0)}
    values = {"esc_correlation": column("correlation", float, np.nan), "esc_cpu_time": column("cpu_time", float),
              "esc_cost": column("cost_s", float)}
    flags2 = {"esc_target_met": column("target_met", np.int8), "esc_transition": column("transition", np.int8, 0)}
    values2 = {f"esc_{name}": column(name, float) for name in ("peak_var_theta", "peak_var_theta_se",
                                                               "peak_var_theta_dot", "peak_var_theta_dot_se")}
    at_grid = np.asarray(flat_indices, dtype=np.int64)
    values2["esc_sl_peak_var_theta"] = linear["peak_var_theta"][at_grid]
    values2["esc_sl_peak_var_theta_dot"] = linear["peak_var_theta_dot"][at_grid]
    counts = {f"esc_{name}": column(name, np.int32) for name in ("n_overturned", "n_diverged", "n_used")}
    peaks = np.full((n, most), np.nan)
    state = np.full((n, most), -1, dtype=np.int8)
    for i, r in enumerate(runs):
        peaks[i, :r["peak_abs_theta"].size] = r["peak_abs_theta"]
        state[i, :r["sample_state"].size] = r["sample_state"]
    out = [Variable(name, v.dtype, ("escalation",), v, np.nan if v.dtype.kind == "f" else False, at, ACCURACY)
           for group in (flags, values, flags2, values2, counts) for name, v in group.items()]
    out += [Variable("esc_peak_abs_theta", "f8", ("escalation", "esc_sample"), peaks, np.nan, at, ACCURACY),
            Variable("esc_sample_state", "i1", ("escalation", "esc_sample"), state, np.int8(-1), at, ACCURACY)]
    return coords + out, {"escalation": n, "esc_sample": most}


def best_variables(study, var_theta, var_theta_dot, method, at):
    """The variables of the per-point best estimates: ``var_theta`` and ``var_theta_dot`` are ``(value, se)`` flat
    arrays, ``method`` the flat :class:`~screening.core.status.BestMethod` codes, ``at`` the grid variables'
    ``coordinates`` attribute."""
    out = [Variable(name, "f8", study.dims, np.asarray(values, dtype=float).reshape(study.shape), np.nan, at, ACCURACY)
           for base, (value, se) in (("best_peak_var_theta", var_theta), ("best_peak_var_theta_dot", var_theta_dot))
           for name, values in ((base, value), (f"{base}_se", se))]
    out.append(Variable("best_method", "i1", study.dims, np.asarray(method, dtype=np.int8).reshape(study.shape), False,
                        at, ACCURACY))
    return out
