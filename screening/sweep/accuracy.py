"""The ``[accuracy]`` stage of a sweep: Monte Carlo where the trust rule cannot promise the target,
within the CPU budget, then best estimates at every point (:mod:`screening.analysis.escalation`,
:mod:`screening.analysis.correction`).

:func:`escalate` runs after the linearization and before the spot checks on a :class:`Stage`: the client,
the study, the resume record, the result being built, the log and the progress switch (plain values, not
the sweep's run object); it returns the escalated points and what it did.
"""

from __future__ import annotations

import contextlib
import math
import uuid
from typing import NamedTuple

import numpy as np

from screening.analysis import escalation as esc
from screening.analysis.correction import best_estimates, point_features
from screening.analysis.escalation import auto_escalation_model
from screening.analysis.trust import shipped_calibration, trust_indicators
from screening.core import limits
from screening.core.progress import Progress
from screening.core.status import BestMethod, EscalationEstimator, EscalationModel
from screening.io.errors import exception_line, write_failure_reason
from screening.solvers.model_choice import AUTO, choose
from screening.sweep import _submit
from screening.sweep.grid import Batch, batch_point_models, point_values, swept_columns
from screening.sweep.interrupt import interruptible
from screening.sweep.study import build_models

__all__ = ["ESCALATION_RECORD", "TOPUP_RECORD", "PLANNER_RECORD", "WAVE", "Stage", "escalate", "accuracy_line"]

#: Resume records of escalated points are spot parts numbered from here (after any spot check): the
#: point's result after its waves, its top-up run, and the planner's state after each wave.
ESCALATION_RECORD = 5000
TOPUP_RECORD = ESCALATION_RECORD + 1000
PLANNER_RECORD = ESCALATION_RECORD - 1
#: Escalated points per wave (fixed: the plan must not depend on the number of workers).
WAVE = 4


class Stage(NamedTuple):
    """What the ``[accuracy]`` stage works with: the dask ``client``, the ``study``, the resume record
    ``store`` (:class:`~screening.io.store.PartialStore`), the ``result`` being built
    (:class:`~screening.io.writer.ResultFile`), the ``log`` function and whether to show ``progress``."""

    client: object
    study: object
    store: object
    result: object
    log: object
    progress: bool


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
    peak = res.read("peak_var_theta")
    var_end = res.read("var_theta", -1) if "var_theta" in study.output.stored else np.full(n, np.nan)
    ind = trust_indicators(res.peak_p_uplift, res.read("min_k_eq"), cols["k_rest"], peak, res.read("slenderness"),
                           var_end, cols["envelope_end"])
    dot = res.read("var_theta_dot", None) if "var_theta_dot" in study.output.stored else np.full(n, np.nan)
    features = {**swept, **({"case": case_index} if study.has_case_dim else {}), **ind}
    return {"status": res.status, "trust": res.sl_trust, "low": res.read("sl_error_low"),
            "high": res.read("sl_error_high"), "indicators": ind, "features": features,
            "condensation": cond.astype(str), "eps": cols["eps"], "peak_var_theta": peak,
            "peak_var_theta_dot": dot}

def escalate(stage):
    """Escalate, write the escalated points and the best estimates into ``stage.result``.

    ``stage``: a :class:`Stage`.  Returns ``((flat indices, models, runs), info)``: the escalated points with
    their :class:`~screening.core.status.EscalationModel` codes and the dicts of
    :func:`~screening.sweep.execution.escalation_task` (their sample peaks feed
    :mod:`screening.sweep.probabilities`), and what the escalation did (the run report's ``accuracy``).

    The points whose trust band cannot promise ``[accuracy] target`` are ordered to cover the grid's
    features, given a Monte Carlo model each (stiff-bed, condensed or coupled, by their measured
    validity) and run wave by wave within ``budget_s`` (:func:`_escalation_runs`); the linearization's
    error learned at the escalated points then gives a best estimate of the peak variances at every
    point (:func:`screening.analysis.correction.best_estimates`).

    Parameters
    ----------
    stage : Stage
        The dask client, the study, the resume record, the result being built, the log function and
        the progress switch.

    Returns
    -------
    escalated : tuple
        ``(flat indices, models, runs)`` of the escalated points: their grid positions, their
        :class:`~screening.core.status.EscalationModel` codes and the run dicts (sample peaks [rad], peak
        variances [rad2], [rad2 s-2], their standard errors, CPU time [s]).
    info : dict
        What the escalation did: target [1], budget and cost [s], points selected, escalated, short
        of the target and failed, the correction's leave-one-out RMS [1] and points per best-estimate
        method (the line of :func:`accuracy_line`).

    Notes
    -----
    The standard error of a Monte Carlo estimate falls as :math:`1/\\sqrt{n}`: from a pilot of
    :math:`n_0` samples with relative standard error :math:`\\mathrm{se}_0`, a point is given
    :math:`n = s\\, n_0\\, (\\mathrm{se}_0 / (\\mathrm{target}/2))^2` samples, :math:`s` the safety factor
    :data:`~screening.analysis.escalation.SAMPLE_SAFETY`
    (:func:`~screening.analysis.escalation.samples_needed`).

    References
    ----------
    .. [1] screening documentation, "Best estimates in a sweep: how often they hold",
       ``docs/accuracy_in_sweeps.md``.
    .. [2] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733

    Examples
    --------
    The stage works on plain values (a live dask client and result; see :func:`run_sweep
    <screening.sweep.run.run_sweep>`, which builds it):

    >>> Stage._fields
    ('client', 'study', 'store', 'result', 'log', 'progress')
    """
    acc = stage.study.accuracy
    pts = _point_table(stage)
    features = point_features(pts["features"])
    candidates = esc.escalation_candidates(pts["status"], pts["trust"], pts["low"], pts["high"], acc.target)
    order = esc.cover_points(features, candidates, stage.result.peak_p_uplift, esc.MAX_POINTS)
    models = escalation_models(stage, order, esc.escalation_model(
        pts["indicators"], pts["status"], pts["condensation"], pts["eps"],
        esc.condensed_cells(shipped_calibration(), acc.target))[order])
    results, cost, spent, failed = _escalation_runs(stage, order, models)
    done = [j for j in range(len(order)) if j in results]
    escalated, models = order[done], models[done]
    runs = [results[j] for j in done]
    stage.result.write_escalation(escalated, models, runs)

    best = {}
    for name in ("var_theta", "var_theta_dot"):
        mc = np.array([r[f"peak_{name}"] for r in runs]) if runs else np.zeros(0)
        mc_se = np.array([r[f"peak_{name}_se"] for r in runs]) if runs else np.zeros(0)
        value, se, method, corr = best_estimates(pts[f"peak_{name}"], pts["status"], pts["trust"], pts["low"],
                                                 pts["high"], acc.target, features, escalated, mc, mc_se, models,
                                                 atlas=name == "var_theta")
        best[name] = (value, se, method, corr)
    method = best["var_theta"][2]
    stage.result.write_best(best["var_theta"][:2], best["var_theta_dot"][:2], method)

    short = sum(1 for r in runs if not r["target_met"])
    codes, counts = np.unique(method, return_counts=True)
    info = {"target": acc.target, "budget_s": acc.budget_s, "cost_s": cost, "cpu_s": spent,
            "n_candidates": int(candidates.sum()), "n_selected": len(order), "n_escalated": len(runs),
            "n_coupled": int(np.sum(models == EscalationModel.coupled)),
            "n_condensed": int(np.sum(models == EscalationModel.condensed)),
            "n_stiff_bed": int(np.sum(models == EscalationModel.stiff_bed)), "n_short": short,
            "n_multifidelity": sum(1 for r in runs if int(r.get("estimator", 0)) == EscalationEstimator.multifidelity),
            "n_failed": failed, "n_unreliable": int(np.sum(method == BestMethod.unreliable)),
            "loo_rms": float(best["var_theta"][3].loo_rms), "correction_usable": best["var_theta"][3].usable,
            "methods": {BestMethod(int(c)).name: int(k) for c, k in zip(codes, counts)}}
    stage.result.set_attrs(
        accuracy_target=acc.target, accuracy_budget_s=acc.budget_s, accuracy_cost_s=cost, accuracy_cpu_s=spent,
        accuracy_n_candidates=np.int32(info["n_candidates"]), accuracy_n_escalated=np.int32(len(runs)),
        accuracy_n_short_of_target=np.int32(short), accuracy_n_unreliable=np.int32(info["n_unreliable"]),
        accuracy_correction_loo_rms=info["loo_rms"],
        accuracy_note=accuracy_line(info))
    stage.log(accuracy_line(info))
    return (escalated, models, runs), info

def escalation_models(stage, order, calibrated):
    """:class:`~screening.core.status.EscalationModel` of the ``order`` ed points: with ``[accuracy] model = "auto"``
    the measured validity rule's choice per point where it is the stiff-bed model, the calibration's
    (``calibrated``) elsewhere (:func:`~screening.analysis.escalation.auto_escalation_model`); an explicit model
    at every point.  Resolved once here: the tasks receive the model's name."""
    study = stage.study
    model = getattr(study.accuracy, "model", AUTO)
    if model != AUTO:
        return np.full(len(order), int(EscalationModel[model]), dtype=np.int8)
    chosen = []
    for flat in order:
        case, values = point_values(study, tuple(int(i) for i in np.unravel_index(int(flat), study.shape)))
        block, foundation, excitation = build_models(study.cases[case], values, study.t_end)
        chosen.append(choose(block, foundation, excitation.kind)[0])
    return auto_escalation_model(calibrated, chosen)


def _escalation_runs(stage, order, models):
    """Pilot, main and top-up Monte Carlo runs at the ``order`` ed points, within the budget.

    The budget is planned on the deterministic cost model (:func:`~screening.analysis.escalation.estimated_cost`
    of each run's integration steps), never on the measured CPU time, so the points run and their
    samples are the same for a given study and seed on every machine.

    1. Wave by wave (:data:`WAVE` points): a pilot of :data:`~screening.analysis.escalation.PILOT_SAMPLES`
       samples, then the samples the target's standard error needs (with a safety factor), each point
       given a fair share of the budget's :data:`~screening.analysis.escalation.MAIN_SHARE`; after each
       wave the points are cut to those the budget affords (in the covering order).
    2. Top-up: a point whose standard error is still above ``target / 2`` of its peak runs again with
       the samples its main run's standard error asks for, while the whole budget allows.

    Returns ``({position: result}, estimated cost [s], CPU seconds spent, failed tasks)``; each result
    carries its total ``cpu_time``, ``cost_s`` and ``target_met``.  Finished points, the planner's state
    after each wave (points planned, waves done, costs seen) and the top-up runs are kept in the resume
    record, so that an interrupted run resumes to the same result.
    """
    from distributed import as_completed

    study, store, acc = stage.study, stage.store, stage.study.accuracy
    most = min(esc.MAX_SAMPLES, limits.MAX_SAMPLE_VALUES // study.times.size)
    token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"
    results, failed = {}, 0

    def index_of(j):
        return tuple(int(i) for i in np.unravel_index(order[j], study.shape))

    def cost(j, r, cheap=True):
        """Estimated cost [s] of run ``r`` at point ``j`` (``cheap``: with its paired cheaper model's samples)."""
        c = esc.estimated_cost(r["n_steps"], models[j], r.get("n_grid", 0), bool(r.get("rodas", False)),
                               int(r.get("samples", 1)), full_contact=r.get("full_contact"))
        if cheap and int(r.get("cheap_samples", 0)) > 0:
            c += esc.estimated_cost(r["cheap_n_steps"], esc.PAIRED_MODEL[2], r["cheap_n_grid"], False,
                                    int(r["cheap_samples"]))
        return c

    def partner(j):
        """``(model, condensation)`` paired with point ``j``'s runs, or None (plain Monte Carlo only)."""
        pair = esc.paired_model(models[j]) if acc.multifidelity else None
        return None if pair is None else pair[:2]

    def load(record, j):
        """A kept result (``ESCALATION_RECORD``: with the cost of all its runs) or top-up run of point ``j``."""
        part = store.load_spot(record + j, index_of(j))
        needed = {"cpu_time", "peak_var_theta", "samples", "n_steps"} | ({"cost_s"} if record == ESCALATION_RECORD
                                                                          else set())
        return part if part is not None and needed <= set(part) else None

    plan = store.load_spot(PLANNER_RECORD, np.asarray(order, dtype=np.int64))
    if plan is not None and {"todo", "w", "costs", "pilot_costs", "loaded"} <= set(plan):
        todo, w, loaded = [int(j) for j in plan["todo"]], int(plan["w"]), int(plan["loaded"])
        costs, pilot_costs = [float(c) for c in plan["costs"]], [float(c) for c in plan["pilot_costs"]]
        waves_done = set(todo[:w])
    else:                                                   # no wave finished: the plan starts afresh
        todo, w, loaded, costs, pilot_costs, waves_done = list(range(len(order))), 0, 0, [], [], set()
    for j in waves_done:
        part = load(ESCALATION_RECORD, j)
        if part is not None:
            results[j] = part

    def spent():
        """Estimated cost [s] of every run so far (each result carries the cost of all its runs)."""
        return sum(float(r["cost_s"]) for r in results.values())

    topic = f"screening-escalation-samples-{token}"
    samples_done, subscribed = {}, False

    def submit(j, samples, what, cheap_samples=0):
        model = EscalationModel(int(models[j])).name
        cheap = (*partner(j), int(cheap_samples)) if cheap_samples else None
        return _submit.submit_escalation(stage.client, study, int(order[j]), samples, model,
                                           key=f"escalate-{what}-{token}-{j:04d}", cheap=cheap,
                                           progress=(topic, 3 * j + ("pilot", "full", "topup").index(what)))

    def gather(futures):
        nonlocal failed
        out = {}
        for fut in interruptible(as_completed(list(futures), loop=stage.client.loop)):
            j = futures[fut]
            try:
                out[j] = fut.result()
            except Exception as exc:          # noqa: BLE001 - the point stays uncovered
                failed += 1
                stage.log(f"warning: Monte Carlo at escalated point {j} failed: {exception_line(exc)}")
            fut.release()
        return out

    def keep(j, r, before=None):
        """``r`` is the point's result from now on; CPU time and cost add up over its runs."""
        r["cost_s"] = np.float64(cost(j, r) + (float(before["cost_s"]) if before is not None else 0.0))
        r["cpu_time"] = np.float64(r["cpu_time"] + (float(before["cpu_time"]) if before is not None else 0.0))
        results[j] = r

    def save(js):
        for j in js:
            try:
                store.save_spot(ESCALATION_RECORD + j, index_of(j), results[j])
            except OSError as exc:
                stage.log(f"warning: cannot save the resume record of escalated point {j} "
                         f"({write_failure_reason(exc)})")

    def rel_se(r):
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(r["peak_var_theta_se"] / r["peak_var_theta"])

    def save_plan():
        store.save_spot(PLANNER_RECORD, np.asarray(order, dtype=np.int64),
                        {"todo": np.asarray(todo, dtype=np.int64), "w": np.int64(w), "loaded": np.int64(loaded),
                         "costs": np.asarray(costs, dtype=float), "pilot_costs": np.asarray(pilot_costs, dtype=float)})

    main_budget = esc.MAIN_SHARE * acc.budget_s
    if w < len(todo):
        stage.client.run(_submit.warm_up_monte_carlo)     # compile outside the budget
    label = "accuracy: Monte Carlo at escalated points"
    with Progress(len(todo) - w, label=label, enabled=stage.progress and w < len(todo)) as bar:
        def count(event):            # per-sample progress of the running points (worker events)
            samples_done[event[1]["spot"]] = max(samples_done.get(event[1]["spot"], 0), int(event[1]["done"]))
            bar.label = f"{label} ({sum(samples_done.values())} samples done)"

        if w < len(todo):
            stage.client.subscribe_topic(topic, count)
            subscribed = True
        while w < len(todo):
            pilots, committed = {}, 0.0
            for j in todo[w:w + WAVE]:
                guess = max(pilot_costs, default=esc.prior_cost(esc.PILOT_SAMPLES, study.t_end, models[j]))
                if spent() + committed + guess > main_budget:
                    break
                pilots[submit(j, esc.PILOT_SAMPLES, "pilot", esc.PILOT_SAMPLES if partner(j) else 0)] = j
                committed += guess
            if not pilots:
                break
            pilot = gather(pilots)
            needed = {}
            for j in sorted(pilot):
                keep(j, pilot[j])
                pilot_costs.append(float(pilot[j]["cost_s"]))
                n = esc.samples_needed(rel_se(pilot[j]), esc.PILOT_SAMPLES, acc.target, most)
                rate, n_cheap = cost(j, pilot[j], cheap=False) / esc.PILOT_SAMPLES, 0
                if int(pilot[j].get("cheap_samples", 0)) > 0:       # a paired pilot: multi-fidelity if it pays
                    plan = esc.paired_plan(pilot[j], models[j], esc.PILOT_SAMPLES, n)
                    if plan.estimator == "multifidelity":
                        rate_cheap = (cost(j, pilot[j]) - cost(j, pilot[j], cheap=False)) / esc.PILOT_SAMPLES
                        n, n_cheap = plan.n_expensive, plan.n_cheap
                        rate += rate_cheap * n_cheap / n          # per expensive sample, its cheap ones included
                needed[j] = (rate, n, n_cheap)
                costs.append(rate * n + float(pilot[j]["cost_s"]))
            # as many points as the budget affords at the samples the target needs (coverage and
            # accuracy both; never fewer than the correction needs), re-estimated after every wave
            affordable = esc.affordable_points(main_budget, float(np.median(costs))) if costs else len(todo)
            todo = todo[:max(affordable - loaded, w + WAVE)]
            full, committed = {}, 0.0
            for j in sorted(pilot):
                rate, wanted, n_cheap = needed[j]
                # a fair share of what is left for each point still to run (a paired run keeps its ratio)
                left = todo[todo.index(j):]
                share = (main_budget - spent() - committed) / max(len(left), 1)
                n = min(wanted, int(share / max(rate, 1e-300)))
                n_cheap = math.ceil(n_cheap * n / wanted) if n_cheap else 0
                big = (n_cheap >= 2 * esc.PILOT_SAMPLES and n >= esc.PILOT_SAMPLES) if n_cheap else (
                    n >= 2 * esc.PILOT_SAMPLES)
                if big and spent() + committed + rate * n <= main_budget:
                    full[submit(j, n, "full", n_cheap)] = j
                    committed += rate * n
            finished = gather(full)
            for j in sorted(finished):
                keep(j, finished[j], before=pilot[j])
            save(sorted(pilot))
            bar.update(len(todo[w:w + WAVE]))
            w += WAVE
            try:
                save_plan()
            except OSError as exc:
                stage.log("warning: cannot save the resume record of the escalation plan "
                          f"({write_failure_reason(exc)})")
        if w < len(todo):                                   # the budget ended the waves: the plan is final
            todo = todo[:w]
            with contextlib.suppress(OSError):
                save_plan()

    # top-up: points still short of the target's standard error, in the covering order
    # (each top-up run is kept apart from the point's result: the plan is made from the waves' results alone)
    topup, committed, finished = {}, 0.0, {}
    for j in sorted(results):
        r = results[j]
        if esc.meets_target(r["peak_var_theta"], r["peak_var_theta_se"], acc.target):
            continue
        n = esc.samples_needed(rel_se(r), int(r["samples"]), acc.target, most)
        rate = cost(j, r) / max(int(r["samples"]), 1)
        paired = int(r.get("estimator", EscalationEstimator.plain_monte_carlo)) == EscalationEstimator.multifidelity
        n_cheap = math.ceil(int(r["cheap_samples"]) * n / int(r["samples"])) if paired else 0
        if n > int(r["samples"]) and spent() + committed + rate * n <= acc.budget_s:
            part = load(TOPUP_RECORD, j)
            if part is not None and int(part["samples"]) == n and int(part.get("cheap_samples", 0)) == n_cheap:
                finished[j] = part
            else:
                topup[submit(j, n, "topup", n_cheap)] = j
            committed += rate * n
    ran = gather(topup) if topup else {}
    for j in sorted(ran):
        try:
            store.save_spot(TOPUP_RECORD + j, index_of(j), ran[j])
        except OSError as exc:
            stage.log(f"warning: cannot save the resume record of escalated point {j} ({write_failure_reason(exc)})")
    finished.update(ran)
    for j in sorted(finished):
        keep(j, finished[j], before=results[j])
    for r in results.values():
        r["target_met"] = bool(esc.meets_target(r["peak_var_theta"], r["peak_var_theta_se"], acc.target))
    cpu = sum(float(r["cpu_time"]) for r in results.values())
    if subscribed:
        with contextlib.suppress(Exception):        # noqa: BLE001 - only the display
            stage.client.unsubscribe_topic(topic)
    return results, spent(), cpu, failed


def accuracy_line(info):
    """One line: what the ``[accuracy]`` escalation covered and what it could not.

    Parameters
    ----------
    info : dict
        What :func:`escalate` did (its second return value): ``target`` [1], ``budget_s``, ``cost_s``
        and ``cpu_s`` [s], point counts and ``methods`` (points per best-estimate method).

    Returns
    -------
    str
        The line of the run's log and of the result's ``accuracy_note`` attribute.

    References
    ----------
    .. [1] screening documentation, "Best estimates in a sweep: how often they hold",
       ``docs/accuracy_in_sweeps.md``.
    .. [2] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733

    Examples
    --------
    >>> info = {"target": 0.15, "budget_s": 600, "cost_s": 412.0, "cpu_s": 398.7, "n_candidates": 12,
    ...         "n_escalated": 10, "n_coupled": 7, "n_condensed": 3, "n_short": 1, "n_failed": 0,
    ...         "loo_rms": 0.08, "correction_usable": True,
    ...         "methods": {"linearization": 88, "corrected_linearization": 2, "coupled_monte_carlo": 7,
    ...                     "condensed_monte_carlo": 3}}
    >>> print(accuracy_line(info))   # doctest: +NORMALIZE_WHITESPACE
    accuracy (target 0.15): 12 point(s) beyond the trust rule's promise; Monte Carlo at 10 (7 coupled,
    3 condensed; 1 short of the target's standard error) for 412.0 of 600 CPU s by the cost model
    (398.7 s measured); 2 without Monte Carlo (correction leave-one-out RMS 0.08); best estimates:
    linearization 88, corrected_linearization 2, coupled_monte_carlo 7, condensed_monte_carlo 3
    """
    methods = ", ".join(f"{name} {n}" for name, n in info["methods"].items())
    left = info["n_candidates"] - info["n_escalated"]
    return (f"accuracy (target {info['target']:g}): {info['n_candidates']} point(s) beyond the trust rule's promise; "
            f"Monte Carlo at {info['n_escalated']} ({info['n_coupled']} coupled, {info['n_condensed']} condensed"
            + (f", {info['n_stiff_bed']} stiff-bed" if info.get("n_stiff_bed") else "") + "; "
            + (f"{info['n_multifidelity']} multi-fidelity; " if info.get("n_multifidelity") else "") +
            f"{info['n_short']} short of the target's standard error) for {info['cost_s']:.1f} of "
            f"{info['budget_s']:g} CPU s by the cost model ({info['cpu_s']:.1f} s measured); {left} without Monte Carlo"
            f" (correction leave-one-out RMS {info['loo_rms']:.2f}{'' if info['correction_usable'] else ', not usable'}); "
            f"best estimates: {methods}")
