"""The probabilities of overturning and of exceedance at every point of a sweep, after its Monte Carlo stages.

With ``[accuracy]`` or ``[fragility]`` the workers store the linearization's Gaussian up-crossing
estimates (``p_overturn`` and, per ``[fragility]`` threshold, ``p_exceed``) with standard errors from the
trust band (:func:`screening.workflow.execution.batch_probabilities`).  :func:`finish_probabilities` runs
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
4. elsewhere ``unreliable``: the linearization's number stays, its standard error is NaN.

Outputs and their meaning: ``docs/outputs_probabilities.md``.
"""

from __future__ import annotations

import numpy as np

from screening.analysis.probabilities import choose_sources, monte_carlo_source, sample_probabilities
from screening.solvers import mc_registry
from screening.status import EscalationEstimator, EscalationModel, PointStatus, ProbabilitySource, SampleState

__all__ = ["CORRECTION_HISTORIES", "levels_at", "finish_probabilities", "probabilities_line"]

#: Histories the corrected estimate reads (the last two for Vanmarcke's bandwidth).
CORRECTION_HISTORIES = ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq")


def _monte_carlo_runs(study, escalated=None, spot_runs=None):
    """``[(flat index, model name, peak_abs_theta, sample_state, paired)]`` of the escalated points
    (``escalated``: ``(flat indices, models, runs)`` of :func:`screening.workflow.accuracy.escalate`) and the
    spot checks (``spot_runs``: ``(grid indices, results)``) of ``study``; ``paired``: ``(peak_abs_theta,
    sample_state)`` of the cheaper model paired with a multi-fidelity escalated point, else None."""
    out = []
    if escalated is not None:
        flat, models, results = escalated
        for i, code, r in zip(flat, models, results):
            paired = (r["cheap_peak_abs_theta"], r["cheap_sample_state"]) if (
                int(r.get("estimator", EscalationEstimator.plain_monte_carlo)) == EscalationEstimator.multifidelity) \
                else None
            out.append((int(i), EscalationModel(int(code)).name, r["peak_abs_theta"], r["sample_state"], paired))
    if spot_runs is not None:
        spots, results = spot_runs
        for index, r in zip(spots, results):
            out.append((int(np.ravel_multi_index(index, study.shape)) if index else 0,
                        mc_registry.names()[int(r["mcs_model"])] if "mcs_model" in r else study.mcs.model,
                        r["peak_abs_theta"], r["sample_state"], None))
    return out


def paired_probabilities(peaks, state, paired, levels):
    """``(p, se)`` [1] of ``[p_overturn, p_exceed(levels)...]`` from a multi-fidelity escalated point's samples
    and its paired cheaper model's (:func:`screening.analysis.multifidelity.multifidelity_probabilities`);
    where a level carries no information in the pair (both models constant over the paired samples) the plain
    binomial estimate of the point's own samples."""
    from screening.analysis.multifidelity import multifidelity_probabilities

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
    study : screening.workflow.study.Study
        The study (its ``[fragility]`` table, if any).
    theta_ul : array_like
        The uplift angle of each point [rad].
    slenderness : array_like
        The slenderness angle of each point [rad].

    Returns
    -------
    numpy.ndarray
        Rotations [rad], shape ``(points, 1 + thresholds)``: the overturning angle, then each threshold.

    References
    ----------
    .. [1] screening documentation, "Probabilities of overturning and of exceedance",
       ``docs/outputs_probabilities.md``.

    Examples
    --------
    >>> from screening.workflow.study import EXAMPLE_STUDY, parse_study
    >>> text = EXAMPLE_STUDY + '[fragility]\\nthresholds = [0.5, 1.0]\\nrelative_to = "slenderness"\\n'
    >>> levels_at(parse_study(text), theta_ul=[0.01], slenderness=[0.16])
    array([[0.16, 0.08, 0.16]])
    """
    cols = [np.asarray(slenderness, dtype=float)]
    frag = study.fragility
    for threshold in (frag.thresholds if frag is not None else ()):
        scale = {None: 1.0, "slenderness": slenderness, "theta_ul": theta_ul}[frag.relative_to]
        cols.append(threshold * np.asarray(scale, dtype=float) * np.ones_like(cols[0]))
    return np.stack(cols, axis=-1)


def _corrected_estimates(study, res, points):
    """``(p, se)`` (points x levels) of the up-crossing of the moments rescaled to the best estimates at the
    flat indices ``points`` of the result ``res`` of ``study``; None where the result does not store the
    histories it needs."""
    import xarray as xr

    from screening.analysis.fragility import best_exceedance
    from screening.workflow.grid import point_values
    from screening.workflow.study import build_models

    if not points.size or not set(CORRECTION_HISTORIES) <= set(study.output.stored):
        return None
    index = [tuple(int(i) for i in np.unravel_index(p, study.shape)) for p in points]
    data = {name: (("point", "t"), np.stack([res.history(name, ix) for ix in index])) for name in CORRECTION_HISTORIES}
    for name in ("peak_var_theta", "best_peak_var_theta", "best_peak_var_theta_se", "best_peak_var_theta_dot",
                 "best_peak_var_theta_dot_se", "theta_ul", "slenderness", "status", "best_method"):
        data[name] = ("point", res.read(name)[points])
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
        p[:, j], se[:, j] = value.values, (high - low).values / 4.0
    return p, se


def finish_probabilities(study, res, escalated=None, spot_runs=None):
    """Replace the workers' linearization estimates in a sweep's result by the best ones and write ``p_source``.

    The sweep's last stage, run on the client once the escalated points and the spot checks are in: at
    every point the probabilities of overturning (and of exceeding each ``[fragility]`` threshold) of the
    best model that ran there, in the order of this module's docstring (Monte Carlo, the trusted
    linearization, the corrected linearization, else ``unreliable`` with a NaN standard error).

    Parameters
    ----------
    study : screening.workflow.study.Study
        The study (its grid, ``[fragility]``, ``[accuracy]`` and ``[mcs]`` tables).
    res : ResultFile
        The open result (:class:`~screening.workflow.writer.ResultFile`): read for the workers'
        estimates ``p_overturn``, ``p_exceed`` [1] and their standard errors, the trust band
        ``sl_error_low``/``sl_error_high`` [1], ``theta_ul`` and ``slenderness`` [rad], ``status``,
        ``sl_trust`` (and ``best_method`` with ``[accuracy]``); written through ``write_probabilities``.
    escalated : tuple, optional
        ``(flat indices, EscalationModel codes, runs)`` of the escalated points
        (:func:`screening.workflow.accuracy.escalate`), each run with ``peak_abs_theta`` [rad] and
        ``sample_state`` per sample (and its paired cheaper model's for a multi-fidelity point).
    spot_runs : tuple, optional
        ``(grid index tuples, results)`` of the Monte Carlo spot checks, each result with
        ``peak_abs_theta`` [rad], ``sample_state`` and optionally ``mcs_model`` (a code of
        :func:`screening.solvers.mc_registry.names`; default the study's ``[mcs] model``).

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
    .. [2] A. Agresti, B. A. Coull, "Approximate is better than 'exact' for interval estimation of binomial
       proportions", The American Statistician 52(2), 119-126, 1998.

    Examples
    --------
    Two points: the first trusted, the second not, with a spot check of 4 coupled samples (one overturned).

    >>> import numpy as np
    >>> from screening.solvers import mc_registry
    >>> from screening.status import PointStatus, SampleState, Trust
    >>> from screening.workflow.study import EXAMPLE_STUDY, parse_study
    >>> class Result(dict):                   # the reads and the write of a result used here
    ...     status = np.array([PointStatus.ok, PointStatus.ok])
    ...     sl_trust = np.array([Trust.trusted, Trust.untrusted])
    ...     def commit(self):
    ...         pass
    ...     def read(self, name):
    ...         return np.asarray(self[name], dtype=float)
    ...     def write_probabilities(self, values, source):
    ...         self.update(values, p_source=source)
    >>> res = Result(p_overturn=[1e-3, 0.2], p_overturn_se=[2e-4, 0.05], sl_error_low=[-0.1, -0.1],
    ...              sl_error_high=[0.1, 0.1], theta_ul=[1e-3, 1e-3], slenderness=[0.165, 0.165])
    >>> spot = {"mcs_model": mc_registry.names().index("coupled"), "peak_abs_theta": [0.01, 0.02, 0.05, 0.3],
    ...         "sample_state": [SampleState.standing] * 3 + [SampleState.overturned]}
    >>> finish_probabilities(parse_study(EXAMPLE_STUDY), res, spot_runs=([(1,)], [spot]))
    {'linearization_gaussian': 1, 'monte_carlo_coupled': 1}
    >>> res["p_overturn"].tolist(), bool(np.isclose(res["p_overturn_se"][1], np.sqrt(0.375 * 0.625 / 8)))
    ([0.001, 0.25], True)
    """
    from screening.analysis.probabilities import source_codes

    res.commit()                    # a zarr store creates the variables defined since (best estimates) here
    n = study.n_points
    thresholds = len(study.fragility.thresholds) if study.fragility is not None else 0
    p = np.column_stack([res.read("p_overturn")] + ([res.read_all("p_exceed").reshape(n, -1)] if thresholds else []))
    se = np.column_stack([res.read("p_overturn_se")] + (
        [res.read_all("p_exceed_se").reshape(n, -1)] if thresholds else []))
    low, high = res.read("sl_error_low"), res.read("sl_error_high")
    best = res.read("best_method").astype(np.int8) if study.accuracy is not None else None
    source = choose_sources(res.status == PointStatus.ok, res.sl_trust, np.isfinite(low) & np.isfinite(high), best)

    corrected = np.flatnonzero(source == ProbabilitySource.corrected_linearization_gaussian)
    estimate = _corrected_estimates(study, res, corrected)
    if estimate is None:
        source[corrected] = ProbabilitySource.unreliable
    else:
        p[corrected], se[corrected] = estimate
    unreliable = source == ProbabilitySource.unreliable
    se[unreliable] = np.nan

    levels = levels_at(study, res.read("theta_ul"), res.read("slenderness"))
    used = np.zeros(n)
    for flat, model, peaks, state, paired in _monte_carlo_runs(study, escalated, spot_runs):
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

    values = {"p_overturn": p[:, 0], "p_overturn_se": se[:, 0]}
    if thresholds:
        values.update(p_exceed=p[:, 1:], p_exceed_se=se[:, 1:])
    res.write_probabilities(values, source)
    names = {code: name for name, code in source_codes().items()}
    codes, counts = np.unique(source, return_counts=True)
    return {names[int(c)]: int(k) for c, k in zip(codes, counts)}


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

    References
    ----------
    .. [1] screening documentation, "Probabilities of overturning and of exceedance",
       ``docs/outputs_probabilities.md``.

    Examples
    --------
    >>> probabilities_line({"monte_carlo_coupled": 3, "linearization_gaussian": 97})
    'probabilities (p_overturn, p_exceed) by source: monte_carlo_coupled 3, linearization_gaussian 97'
    """
    return "probabilities (p_overturn, p_exceed) by source: " + ", ".join(f"{name} {k}" for name, k in counts.items())
