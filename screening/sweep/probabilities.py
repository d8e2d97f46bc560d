"""The probabilities of overturning and of exceedance at every point of a sweep, after its Monte Carlo stages.

With ``[accuracy]`` or ``[fragility]`` the workers store the linearization's Gaussian up-crossing
estimates (``p_overturn`` and, per ``[fragility]`` threshold, ``p_exceed``) with standard errors from the
trust band (:func:`screening.sweep.execution.batch_probabilities`).  :func:`finish_probabilities` runs
on the client once the escalated points and the spot checks are in, and leaves at every point the
estimate of the best model that ran there, recorded in ``p_source``
(:func:`screening.analysis.probabilities.source_codes`):

1. Monte Carlo where it ran (escalated points and spot checks; the run with more usable samples where
   both did): the fractions of the samples, overturned samples counting as exceeding every threshold
   (:func:`screening.analysis.probabilities.sample_probabilities`);
2. the linearization's estimate where the trust rule vouches for it (``linearization_gaussian``);
3. with ``[accuracy]``, where the correction reaches the point: the up-crossing of the moments rescaled
   to the corrected best estimates (:func:`screening.analysis.fragility.best_exceedance`; needs the
   histories in the result);
4. elsewhere ``unreliable``: ``p_overturn``, ``p_exceed`` and their standard errors are NaN (missing, never a
   number that reads as an answer: a 1 where the linearization stopped, a 6e-188 where it is untrusted);
5. near toppling (:func:`screening.analysis.probabilities.answer_quantities`: the linearization stopped,
   ``p_overturn`` material, or the variance's interval open in heavy uplift), where no Monte Carlo ran:
   the study's own fragility surface (``study_fragility_surface``, :mod:`screening.analysis.fragility_surface`)
   where its leave-one-out check vouches for it and the point lies inside the hull of the Monte Carlo points.

Every point also gets ``answer_quantity`` (:class:`~screening.core.status.AnswerQuantity`): whether its variance
or its probabilities answer it.

Outputs and their meaning: ``docs/outputs_probabilities.md``.
"""

from __future__ import annotations

import numpy as np

from screening.analysis import fragility_surface as fs
from screening.analysis.fragility import band_standard_error, best_exceedance
from screening.analysis.multifidelity import multifidelity_probabilities
from screening.analysis.probabilities import (answer_quantities, choose_sources, monte_carlo_source, reliable_answer,
                                              sample_probabilities, source_codes)
from screening.core.status import (AnswerQuantity, BestMethod, EscalationEstimator,
                                   MONTE_CARLO_SOURCE_BASE, PointStatus, ProbabilitySource, SampleState, Trust)
from screening.io.writer import Variable
from screening.solvers import mc_registry
from screening.sweep.grid import point_values, swept_columns
from screening.sweep.study import build_models

__all__ = []

#: Histories the corrected estimate reads (the last two for Vanmarcke's bandwidth).
CORRECTION_HISTORIES = ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq")
def _monte_carlo_runs(study, escalated=None, spot_runs=None):
    """``[(flat index, model name, peak_abs_theta, sample_state, paired)]`` of the escalated points
    (``escalated``: ``(flat indices, models, runs)`` of :func:`screening.sweep.accuracy.escalate`) and the
    spot checks (``spot_runs``: ``(grid indices, results)``) of ``study``; ``paired``: ``(peak_abs_theta,
    sample_state)`` of the cheaper model paired with a multi-fidelity escalated point, else None."""
    out = []
    if escalated is not None:
        flat, models, results = escalated
        for i, code, r in zip(flat, models, results):
            paired = (r["cheap_peak_abs_theta"], r["cheap_sample_state"]) if (
                int(r.get("estimator", EscalationEstimator.plain_monte_carlo)) == EscalationEstimator.multifidelity) \
                else None
            out.append((int(i), mc_registry.escalation_models()(int(code)).name, r["peak_abs_theta"],
                        r["sample_state"], paired))
    if spot_runs is not None:
        spots, results = spot_runs
        for index, r in zip(spots, results):
            out.append((int(np.ravel_multi_index(index, study.shape)) if index else 0,
                        mc_registry.name_of(r["mcs_model"]) if "mcs_model" in r else study.mcs.model,
                        r["peak_abs_theta"], r["sample_state"], None))
    return out


def paired_probabilities(peaks, state, paired, levels):
    """``(p, se)`` [1] of ``[p_overturn, p_exceed(levels)...]`` from a multi-fidelity escalated point's samples
    and its paired cheaper model's (:func:`screening.analysis.multifidelity.multifidelity_probabilities`);
    where a level carries no information in the pair (both models constant over the paired samples) the plain
    binomial estimate of the point's own samples."""
    state, cheap_peaks, cheap_state = np.asarray(state), np.asarray(paired[0], dtype=float), np.asarray(paired[1])

    def flags(s):
        return s == SampleState.overturned, (s == SampleState.standing) | (s == SampleState.overturned)

    over, valid = flags(state)
    cheap_over, cheap_valid = flags(cheap_state)
    peaks = np.asarray(peaks, dtype=float)
    plain = sample_probabilities(peaks, over, valid, levels)
    p = np.concatenate([[plain["p_overturn"]], plain["p_exceed"]])
    se = np.concatenate([[plain["p_overturn_se"]], plain["p_exceed_se"]])
    for k, est in enumerate(multifidelity_probabilities(peaks, over, valid, cheap_peaks, cheap_over, cheap_valid,
                                                        levels)):
        if np.isfinite(est.correlation):
            p[k], se[k] = min(max(est.mean, 0.0), 1.0), est.se
    return p, se


def levels_at(study, theta_ul, slenderness):
    """Rotations [rad] of ``p_overturn`` and of each ``[fragility]`` threshold at points with these angles
    (points x (1 + thresholds)).

    Overturning is counted at the slenderness angle :math:`\\alpha = \\arctan(b/h)`; a ``[fragility]``
    threshold :math:`x` is the rotation :math:`x` itself, or :math:`x\\,\\alpha` or
    :math:`x\\,\\theta_{ul}` with ``relative_to = "slenderness"`` or ``"theta_ul"``.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study (its ``[fragility]`` table, if any).
    theta_ul : array_like
        The uplift angle of each point [rad].
    slenderness : array_like
        The slenderness angle of each point [rad].

    Returns
    -------
    numpy.ndarray
        Rotations [rad], shape ``(points, 1 + thresholds)``: the overturning angle, then each threshold.
    """
    cols = [np.asarray(slenderness, dtype=float)]
    frag = study.fragility
    for threshold in (frag.thresholds if frag is not None else ()):
        scale = {None: 1.0, "slenderness": slenderness, "theta_ul": theta_ul}[frag.relative_to]
        cols.append(threshold * np.asarray(scale, dtype=float) * np.ones_like(cols[0]))
    return np.stack(cols, axis=-1)


def _corrected_estimates(study, res, points, values=None):
    """``(p, se)`` (points x levels) of the up-crossing of the moments rescaled to the best estimates at the
    flat indices ``points`` of the result ``res`` of ``study``; None where the result does not store the
    histories it needs."""
    import xarray as xr

    if not points.size or not set(CORRECTION_HISTORIES) <= set(study.output.stored):
        return None
    index = [tuple(int(i) for i in np.unravel_index(p, study.shape)) for p in points]
    data = {name: (("point", "t"), np.stack([res.history(name, ix) for ix in index])) for name in CORRECTION_HISTORIES}
    for name in ("peak_var_theta", "best_peak_var_theta", "best_peak_var_theta_se", "best_peak_var_theta_dot",
                 "best_peak_var_theta_dot_se", "theta_ul", "slenderness", "status", "best_method"):
        if values is not None and name in values:
            column = np.asarray(values[name], dtype=float)
        else:
            column = np.asarray(res.status, dtype=float) if name == "status" else res.read(name)
        data[name] = ("point", column[points])
    blocks = [build_models(study.cases[case], values, study.t_end)[0]
              for case, values in (point_values(study, ix) for ix in index)]
    for name in ("m", "I_cm", "h"):
        data[name] = ("point", np.array([float(getattr(b, name)) for b in blocks]))
    ds = xr.Dataset(data, coords={"t": study.times})
    ds["status"] = ds["status"].astype(np.int8)
    frag = study.fragility
    method = frag.method if frag is not None else "vanmarcke"
    asked = [(1.0, "slenderness")] + ([(t, frag.relative_to) for t in frag.thresholds] if frag is not None else [])
    p, se = np.empty((points.size, len(asked))), np.empty((points.size, len(asked)))
    for j, (threshold, relative_to) in enumerate(asked):
        value, low, high, _ = best_exceedance(ds, threshold, relative_to, method)
        p[:, j], se[:, j] = value.values, band_standard_error(value.values, low.values, high.values)
    return p, se


def surface_estimates(columns, case, counts, n_used):
    """The study's fragility surfaces at every point, for every level, where they are vouched for.

    Parameters
    ----------
    columns : dict of str to numpy.ndarray
        ``{swept input: values}`` at every point of the study (flat) [SI units].
    case : numpy.ndarray of int
        Case index of every point (a surface is fitted per case: the cases differ in more than the
        swept inputs).
    counts : dict of int to numpy.ndarray
        ``{flat index: samples reaching each level}`` at the Monte Carlo points [-]: overturned, then
        exceeding each ``[fragility]`` threshold (overturned samples exceed every level).
    n_used : dict of int to int
        ``{flat index: usable samples}`` (standing or overturned) at the same points [-].

    Returns
    -------
    p, se : numpy.ndarray
        ``(points, levels)`` [1]: the surface's probability and its standard error; NaN where it is not
        vouched for.
    usable : numpy.ndarray of bool
        True where every level's surface is vouched for and the point lies inside the hull of the case's
        Monte Carlo points.
    notes : list of str
        One line per case and level: the form, the Monte Carlo points, the leave-one-out share, the
        dispersion, or why there is no surface.

    Notes
    -----
    Per case: :func:`~screening.analysis.fragility_surface.surface_inputs` of the case's points,
    :func:`~screening.analysis.fragility_surface.study_surface` on its Monte Carlo points for each level,
    :func:`~screening.analysis.fragility_surface.predict_surface` and
    :func:`~screening.analysis.fragility_surface.inside_hull` at its points.
    """
    n = case.size
    levels = len(next(iter(counts.values()))) if counts else 1
    p, se = np.full((n, levels), np.nan), np.full((n, levels), np.nan)
    usable = np.zeros(n, dtype=bool)
    notes = []
    for c in np.unique(case):
        rows = np.flatnonzero(case == c)
        z, names = fs.surface_inputs({name: values[rows] for name, values in columns.items()})
        z = z if z.shape[0] == rows.size else np.zeros((rows.size, 0))          # no swept input at all
        position = {int(r): j for j, r in enumerate(rows)}
        mc = np.array([position[f] for f in sorted(counts) if f in position], dtype=int)
        flats = [f for f in sorted(counts) if f in position]
        label = f"case {c}: " if np.unique(case).size > 1 else ""
        if mc.size == 0:
            notes.append(f"{label}no Monte Carlo point: no fragility surface")
            continue
        k = np.array([counts[f] for f in flats], dtype=float)
        m = np.array([n_used[f] for f in flats], dtype=float)
        fits = [fs.study_surface(z[mc], k[:, j], m) for j in range(levels)]
        for j, fit in enumerate(fits):
            level = "p_overturn" if j == 0 else f"p_exceed[{j - 1}]"
            if fit is None:
                notes.append(f"{label}{level}: no fragility surface ({mc.size} Monte Carlo points, "
                             f"{int(np.sum((k[:, j] > 0) & (k[:, j] < m)))} with 0 < overturned < samples: too few "
                             f"for a form)")
            else:
                notes.append(f"{label}{level}: {fit.form} probit surface in {', '.join(names)} on {mc.size} Monte "
                             f"Carlo points, leave-one-out {fit.loo_share:.0%} of {fit.loo_in_play} within "
                             f"{fs.LOO_Z:g} SE, dispersion {fit.dispersion:.2f}, standard errors widened "
                             f"x{fit.loo_scale:.2f} by the held-out errors: "
                             + ("vouched for" if fit.vouched else f"not vouched for ({fit.reason})"))
        if not all(fit is not None and fit.vouched for fit in fits):
            continue
        inside = fs.inside_hull(z[mc], z)
        for j, fit in enumerate(fits):
            pj, sej = fs.predict_surface(fit, fs.surface_terms(z, fit.form))
            p[rows[inside], j], se[rows[inside], j] = pj[inside], sej[inside]
        usable[rows[inside]] = True
    return p, se, usable, notes


def _level_counts(runs, levels):
    """``({flat: samples reaching each level}, {flat: usable samples})`` of the Monte Carlo runs (the run with
    more usable samples where a point has two); ``levels``: the rotations [rad] of every point."""
    counts, used = {}, {}
    for flat, _, peaks, state, _ in runs:
        state = np.asarray(state)
        valid = (state == SampleState.standing) | (state == SampleState.overturned)
        if valid.sum() <= used.get(flat, 0):
            continue
        over = (state == SampleState.overturned)[valid]
        peak = np.asarray(peaks, dtype=float)[valid]
        counts[flat] = np.array([over.sum()] + [np.sum((peak > a) | over) for a in levels[flat, 1:]], dtype=float)
        used[flat] = int(valid.sum())
    return counts, used


def finish_probabilities(study, res, values, escalated=None, spot_runs=None, log=None):
    """Replace the workers' linearization estimates in a sweep's result by the best ones and write ``p_source``.

    The sweep's last stage, run on the client once the escalated points and the spot checks are in: at
    every point the probabilities of overturning (and of exceeding each ``[fragility]`` threshold) of the
    best model that ran there, in the order of this module's docstring (Monte Carlo, the trusted
    linearization, the corrected linearization, else ``unreliable`` with a NaN standard error), and near
    toppling where no Monte Carlo ran the study's fragility surface where it is vouched for
    (:func:`surface_estimates`); and at every point which quantity answers it (``answer_quantity``,
    :func:`screening.analysis.probabilities.answer_quantities`).

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study (its grid, ``[fragility]``, ``[accuracy]`` and ``[mcs]`` tables).
    res : ResultFile
        The open result (:class:`~screening.io.writer.ResultFile`): read for the workers'
        estimates ``p_overturn``, ``p_exceed`` [1] and their standard errors, the trust band
        ``sl_error_low``/``sl_error_high`` [1], ``theta_ul`` and ``slenderness`` [rad], ``status``,
        ``sl_trust``, ``peak_p_uplift`` (and ``best_method`` with ``[accuracy]``); the probabilities,
        ``p_source``, ``answer_quantity`` and the notes written into it.
    values : dict
        The per-point values of :func:`screening.sweep.run.stage_inputs` (with the ``[accuracy]`` stage's best
        estimates), handed on by the run.
    escalated : tuple, optional
        ``(flat indices, EscalationModel codes, runs)`` of the escalated points
        (:func:`screening.sweep.accuracy.escalate`), each run with ``peak_abs_theta`` [rad] and
        ``sample_state`` per sample (and its paired cheaper model's for a multi-fidelity point).
    spot_runs : tuple, optional
        ``(grid index tuples, results)`` of the Monte Carlo spot checks, each result with
        ``peak_abs_theta`` [rad], ``sample_state`` and optionally ``mcs_model`` (a code of
        :func:`screening.solvers.mc_registry.names`; default the study's ``[mcs] model``).
    log : callable, optional
        Called with the answer line (:func:`answer_line`) and the surface's lines.

    Returns
    -------
    dict
        ``{source name: points}``: how many points took their probabilities from each source
        (:func:`screening.analysis.probabilities.source_codes`).

    Notes
    -----
    Where Monte Carlo ran (the run with more usable samples where both did) the probability of a level is
    the fraction ``p = k / n`` of the ``n`` standing or overturned samples that reached it, overturned
    samples exceeding every level, with the Agresti-Coull standard error
    ``se = sqrt(p~ (1 - p~) / (n + 4))``, ``p~ = (k + 2) / (n + 4)`` [2]_
    (:func:`screening.solvers.estimates.binomial_estimate`).

    References
    ----------
    .. [1] screening documentation, "Probabilities of overturning and of exceedance",
       ``docs/outputs_probabilities.md``.
    .. [2] [agresti1998] in the bibliography, ``docs/bibliography.md``.
    """
    res.commit()                    # a zarr store creates the variables defined since (best estimates) here
    n = study.n_points
    thresholds = len(study.fragility.thresholds) if study.fragility is not None else 0
    p = np.column_stack([values["p_overturn"]] + ([values["p_exceed"]] if thresholds else []))
    se = np.column_stack([values["p_overturn_se"]] + ([values["p_exceed_se"]] if thresholds else []))
    low, high = values["sl_error_low"], values["sl_error_high"]
    best = np.asarray(values["best_method"]).astype(np.int8) if study.accuracy is not None else None
    source = choose_sources(res.status == PointStatus.ok, res.sl_trust, np.isfinite(low) & np.isfinite(high), best)

    corrected = np.flatnonzero(source == ProbabilitySource.corrected_linearization_gaussian)
    estimate = _corrected_estimates(study, res, corrected, values)
    if estimate is None:
        source[corrected] = ProbabilitySource.unreliable
    else:
        p[corrected], se[corrected] = estimate
    unreliable = source == ProbabilitySource.unreliable
    se[unreliable] = np.nan

    levels = levels_at(study, values["theta_ul"], values["slenderness"])
    used = np.zeros(n)
    runs = _monte_carlo_runs(study, escalated, spot_runs)
    for flat, model, peaks, state, paired in runs:
        state = np.asarray(state)
        valid = (state == SampleState.standing) | (state == SampleState.overturned)
        if valid.sum() <= used[flat]:
            continue
        if paired is not None:
            p[flat], se[flat] = paired_probabilities(peaks, state, paired, levels[flat, 1:])
        else:
            got = sample_probabilities(np.asarray(peaks, dtype=float), state == SampleState.overturned, valid,
                                       levels[flat, 1:])
            p[flat] = np.concatenate([[got["p_overturn"]], got["p_exceed"]])
            se[flat] = np.concatenate([[got["p_overturn_se"]], got["p_exceed_se"]])
        source[flat] = monte_carlo_source(model)
        used[flat] = valid.sum()

    # near toppling, where no Monte Carlo ran: the study's fragility surface where it is vouched for
    surface_p, surface_se, usable, notes = surface_estimates(*swept_columns(study), *_level_counts(runs, levels))
    usable &= source < MONTE_CARLO_SOURCE_BASE
    best_p, best_se = p[:, 0].copy(), se[:, 0].copy()
    best_p[usable], best_se[usable] = surface_p[usable, 0], surface_se[usable, 0]
    if best is not None:
        variance_vouched = best != BestMethod.unreliable
    else:
        variance_vouched = ((res.status == PointStatus.ok) & (res.sl_trust == Trust.trusted) & np.isfinite(low)
                            & np.isfinite(high))
    answer = answer_quantities(res.status, best_p, best_se, low, high, res.peak_p_uplift, variance_vouched)
    take = usable & (answer != AnswerQuantity.variance)
    p[take], se[take] = surface_p[take], surface_se[take]
    source[take] = ProbabilitySource.study_fragility_surface

    unvouched = source == ProbabilitySource.unreliable            # nothing vouches for a number: missing values
    p[unvouched], se[unvouched] = np.nan, np.nan
    answers = {"p_overturn": p[:, 0], "p_overturn_se": se[:, 0]}
    if thresholds:
        answers.update(p_exceed=p[:, 1:], p_exceed_se=se[:, 1:])
    write_probabilities(res, study, answers, source, answer)
    line = answer_line(answer, reliable_answer(answer, variance_vouched, source), variance_vouched)
    res.set_attrs(answer_note=line, fragility_surface_note="; ".join(notes))
    if log is not None:                      # many cases: one line, each surface's note in the result's attribute
        shown = notes if len(notes) <= 4 else [
            f"{len(notes)} surfaces (per case and quantity), {sum('vouched for' in n and 'not vouched' not in n for n in notes)}"
            f" vouched for, used at {int(take.sum())} point(s) where no Monte Carlo ran; each in the result's "
            "fragility_surface_note attribute"]
        for text in [line] + [f"fragility surface: {note}" for note in shown]:
            log(text)
    names = {code: name for name, code in source_codes().items()}
    codes, counts = np.unique(source, return_counts=True)
    return {names[int(c)]: int(k) for c, k in zip(codes, counts)}


def write_probabilities(res, study, values, source, answer):
    """Write into ``res`` the per-point probabilities after the Monte Carlo stages: ``values`` maps ``p_overturn``,
    ``p_overturn_se`` (flat) and ``p_exceed``, ``p_exceed_se`` (flat x thresholds) to their final values;
    ``source`` the flat ``p_source`` codes (:func:`screening.solvers.schema.probability_source_attributes`),
    ``answer`` the flat ``answer_quantity`` codes (:class:`~screening.core.status.AnswerQuantity`)."""
    for name, value in values.items():
        value = np.asarray(value, dtype=float)
        res.write(name, Ellipsis, value.reshape(study.shape + value.shape[1:]))
    at = res.grid_coordinates()
    res.add([Variable(name, "i1", study.dims, np.asarray(codes, dtype=np.int8).reshape(study.shape), False, at)
             for name, codes in (("p_source", source), ("answer_quantity", answer))])


def probabilities_line(counts):
    """One line: where the points' p_overturn / p_exceed come from.

    Parameters
    ----------
    counts : dict
        Points per source name (``p_source``'s ``flag_meanings``), as the sweep's probability stage
        returns them.

    Returns
    -------
    str
        The line of the run's log.
    """
    return "probabilities (p_overturn, p_exceed) by source: " + ", ".join(f"{name} {k}" for name, k in counts.items())


#: Short names of the answer codes in :func:`answer_line`.
_ANSWER_TEXT = {AnswerQuantity.probabilities_stopped: "linearization stopped",
                AnswerQuantity.probabilities_overturning: "p_overturn material",
                AnswerQuantity.probabilities_open_interval: "heavy uplift without a vouched-for variance"}


def answer_line(answer, reliable, variance_vouched):
    """One line: which quantity answers the points, and how many have no reliable answer.

    Parameters
    ----------
    answer : array_like of int
        :class:`~screening.core.status.AnswerQuantity` codes of the points.
    reliable : array_like of bool
        True where the quantity that answers the point is vouched for
        (:func:`screening.analysis.probabilities.reliable_answer`).
    variance_vouched : array_like of bool
        True where the point's best peak variance is vouched for.

    Returns
    -------
    str
        ``answers: variance N, probabilities M (reason k, ...); unreliable: U variance, W without any
        reliable answer`` -- ``U`` counts the points whose variance is ``unreliable`` (the answer there may
        still be the probabilities), ``W`` those whose answering quantity is not vouched for.
    """
    answer = np.asarray(answer).reshape(-1)
    by_variance = int(np.sum(answer == AnswerQuantity.variance))
    reasons = ", ".join(f"{text} {int(np.sum(answer == code))}" for code, text in _ANSWER_TEXT.items()
                        if np.any(answer == code))
    probabilities = answer.size - by_variance
    return (f"answers: variance {by_variance}, probabilities {probabilities}" + (f" ({reasons})" if reasons else "")
            + f"; unreliable: {int(np.sum(~np.asarray(variance_vouched, dtype=bool)))} variance, "
              f"{int(np.sum(~np.asarray(reliable, dtype=bool)))} without any reliable answer")
