"""Probabilities of overturning and of exceeding a rotation, with their standard errors and their source.

Near toppling the variance over the surviving samples is a fragile answer (it moves by tens of per
cent between two runs of a few hundred samples); the probability of overturning and the
probabilities of exceeding rotation thresholds are the robust ones.  This module holds the pure
functions behind them:

* :func:`binomial_estimate` -- a fraction of samples and its standard error (Agresti-Coull);
* :func:`sample_probabilities` -- ``p_overturn`` and ``p_exceed`` per threshold from the per-sample
  peaks ``max_t |theta|`` of a Monte Carlo run (overturned samples count as exceeding every
  threshold; diverged samples are left out);
* :func:`uplift_acceleration` -- the ground acceleration at which the block starts to rock on its
  bed (quasi-static), the level of :func:`screening.analysis.intensity.rocking_start_probability`;
* :func:`source_codes` / :func:`monte_carlo_source` -- the codes of the provenance variable
  ``p_source`` (:data:`screening.status.ProbabilitySource`, with one ``monte_carlo_<model>`` code per
  model :func:`screening.monte_carlo` knows);
* :func:`choose_sources` -- which estimate each grid point of a sweep carries.

Outputs and their meaning: ``docs/outputs_probabilities.md``.
"""

from __future__ import annotations

import numpy as np

from screening.status import BestMethod, ProbabilitySource, SampleState, Trust, probability_sources

#: ``z`` of the Agresti-Coull interval (about 95 %, ``p_tilde +- Z se``).
Z = 2.0


def binomial_estimate(hits, n):
    """Fraction ``p = hits / n`` [1] of Bernoulli trials and its standard error [1].

    Parameters
    ----------
    hits : number of successes (array-like, >= 0).
    n : number of trials (array-like, broadcast with ``hits``); NaN where ``n = 0``.

    Returns
    -------
    p, se : arrays [1].

    Notes
    -----
    The estimate is the unbiased ``p = k / n``.  Its standard error is the Agresti-Coull one,
    ``se = sqrt(p~ (1 - p~) / (n + z^2))`` with ``p~ = (k + z^2 / 2) / (n + z^2)`` and ``z = 2``
    (:data:`Z`): ``p~ +- 2 se`` is the Agresti-Coull 95 % interval.  Unlike the Wald error
    ``sqrt(p (1 - p) / n)`` it does not vanish when no sample (or every sample) overturned: at
    ``k = 0`` it is about ``1.4 / n``, so ``p + 2 se`` bounds ``p`` by about ``3 / n`` as the rule of
    three does.

    References
    ----------
    Agresti, A. and Coull, B. A. (1998) Approximate is better than "exact" for interval estimation
    of binomial proportions, The American Statistician 52(2), 119-126.
    """
    k = np.asarray(hits, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.where(n > 0, k / n, np.nan)
        tilde = (k + Z * Z / 2.0) / (n + Z * Z)
        se = np.where(n > 0, np.sqrt(tilde * (1.0 - tilde) / (n + Z * Z)), np.nan)
    return p[()], se[()]


def sample_probabilities(peak_abs_theta, overturned, valid, levels=()):
    """``p_overturn`` and ``p_exceed`` of a Monte Carlo run from its per-sample peaks.

    Parameters
    ----------
    peak_abs_theta : peak ``|theta|`` [rad] of each sample over the record, samples on the LAST axis.
    overturned : True for the samples that overturned (same shape).
    valid : True for the samples in the estimate (not diverged, task not failed; same shape).
    levels : rotation thresholds [rad], shape ``(L,)`` or the leading shape of the peaks plus ``(L,)``.

    Returns
    -------
    dict with ``p_overturn``, ``p_overturn_se`` (leading shape) and ``p_exceed``, ``p_exceed_se``
    (leading shape + ``(L,)``), all [1], from :func:`binomial_estimate` over the valid samples;
    NaN where no sample is valid.

    Notes
    -----
    ``p_overturn = #(overturned & valid) / #valid``; ``p_exceed(a) = #((max|theta| > a or overturned)
    & valid) / #valid``: an overturned sample has passed every rotation on its way down.
    """
    peaks = np.asarray(peak_abs_theta, dtype=float)
    over = np.asarray(overturned, dtype=bool) & np.asarray(valid, dtype=bool)
    valid = np.broadcast_to(np.asarray(valid, dtype=bool), peaks.shape)
    n = valid.sum(axis=-1)
    p_over, se_over = binomial_estimate(over.sum(axis=-1), n)
    levels = np.asarray(levels, dtype=float)
    if levels.ndim <= 1:
        levels = np.broadcast_to(levels, peaks.shape[:-1] + levels.shape[-1:])
    with np.errstate(invalid="ignore"):
        beyond = (peaks[..., None, :] > levels[..., :, None]) | over[..., None, :]
    hits = (beyond & valid[..., None, :]).sum(axis=-1)
    p_exc, se_exc = binomial_estimate(hits, n[..., None])
    return {"p_overturn": p_over, "p_overturn_se": se_over, "p_exceed": p_exc, "p_exceed_se": se_exc}


def uplift_acceleration(block, foundation, condensation):
    """Ground acceleration [m s-2] at which the block starts to rock: the quasi-static tilt reaches the
    bed's uplift angle.

    Parameters
    ----------
    block, foundation : :class:`~screening.model.Block`, bed (array fields broadcast).
    condensation : :class:`~screening.condensation.base.Condensation` of the bed's moment law.

    Notes
    -----
    The condensed equation of motion ``M theta'' + C theta' + K(theta) theta = -m h a_g`` at rest gives
    ``a_ul = K(theta_ul) theta_ul / (m h)``.  On a linear Winkler bed ``K = 2 k b^3 / 3 - m g h`` and
    ``theta_ul = m g / (2 b^2 k)``, so ``a_ul = g b / (3 h) - g theta_ul``: the resultant of the bed's
    pressure reaches the edge of the kern of the base, a third of the half-width from the centre.
    """
    theta_ul = condensation.uplift_threshold(block, foundation)
    moment = condensation.restoring_moment(theta_ul, block, foundation)
    return np.abs(moment / (block.m * block.h))


def source_codes():
    """``{name: code}`` of the values of ``p_source``: those of :data:`~screening.status.ProbabilitySource`
    and ``monte_carlo_<model>`` for every model of :data:`screening.solvers.montecarlo.MODELS`."""
    from screening.solvers.montecarlo import MODELS

    return probability_sources(MODELS)


def monte_carlo_source(model):
    """The ``p_source`` code of Monte Carlo ``model`` (a name in :data:`screening.solvers.montecarlo.MODELS`).
    Raises ``ValueError`` for a model it does not know."""
    codes = source_codes()
    if f"monte_carlo_{model}" not in codes:
        raise ValueError(f"parameter 'model' must be a Monte Carlo model, one of "
                         f"{[n[len('monte_carlo_'):] for n in codes if n.startswith('monte_carlo_')]} (got {model!r})")
    return codes[f"monte_carlo_{model}"]


def choose_sources(status_ok, trust, band_finite, best_method=None):
    """``p_source`` of every point before Monte Carlo: where the linearization's Gaussian estimate is vouched for.

    Parameters
    ----------
    status_ok : True where the linearization ran to the end.
    trust : ``sl_trust`` codes (:class:`~screening.status.Trust`).
    band_finite : True where the trust band of the point is finite.
    best_method : ``best_method`` codes of ``[accuracy]`` (:class:`~screening.status.BestMethod`) or None.

    Returns
    -------
    int8 array of :data:`~screening.status.ProbabilitySource` codes: with ``[accuracy]``,
    ``linearization_gaussian`` where the rule promises the target, ``corrected_linearization_gaussian``
    where the correction reaches the point, else ``unreliable``; without it, ``linearization_gaussian``
    where the point is ``trusted`` with a finite band, else ``unreliable``.  Monte Carlo points are
    set by the caller (:func:`monte_carlo_source`).
    """
    ok = np.asarray(status_ok, dtype=bool)
    src = np.full(ok.shape, int(ProbabilitySource.unreliable), dtype=np.int8)
    if best_method is None:
        use = ok & (np.asarray(trust) == int(Trust.trusted)) & np.asarray(band_finite, dtype=bool)
        src[use] = int(ProbabilitySource.linearization_gaussian)
        return src
    best = np.asarray(best_method)
    src[ok & (best == int(BestMethod.linearization))] = int(ProbabilitySource.linearization_gaussian)
    corrected = int(ProbabilitySource.corrected_linearization_gaussian)
    src[ok & (best == int(BestMethod.corrected_linearization))] = corrected
    return src


def overturning_probability(ds, method="vanmarcke"):
    """``(p_overturn, note)`` [1] of a result dataset, on its grid, for a fragility over an intensity.

    A sweep with ``[accuracy]`` or ``[fragility]`` stores ``p_overturn`` with ``p_source``: that estimate,
    NaN where ``p_source`` is ``unreliable`` (a fit must not learn from numbers nothing vouches for).  A
    :func:`screening.monte_carlo` result: its ``p_overturn``.  Any other result (no stored estimate): the
    Gaussian up-crossing of ``atan(b/h)`` by the linearization's moments
    (:func:`screening.analysis.fragility.exceedance_probability`, ``method``), which nothing vouches for
    near toppling.  ``note``: a one-line caveat, or ``""`` when there is none.
    """
    from screening.analysis.fragility import exceedance_probability

    if "p_overturn" in ds.variables and "p_source" in ds.variables:
        unreliable = ds["p_source"] == int(ProbabilitySource.unreliable)
        n = int(unreliable.sum())
        note = f"{n} point(s) whose p_source is unreliable left out of the fit" if n else ""
        return ds["p_overturn"].where(~unreliable), note
    if "p_overturn" in ds.variables:
        return ds["p_overturn"], ""
    p = exceedance_probability(ds, 1.0, "slenderness", method)
    return p, ("the result stores no p_overturn: the linearization's Gaussian up-crossing of atan(b/h), which "
               "nothing vouches for near toppling (run the study with [accuracy] or [fragility])")


#: A Monte Carlo point where more than this fraction of the samples overturned is near toppling: its
#: variances are over the survivors only and move from run to run; its probabilities are the answer.
TOPPLING_FRACTION = 0.05


def spot_check_probabilities(ds):
    """``p_overturn`` and, where the result has ``[fragility]`` thresholds, ``p_exceed`` of each Monte Carlo
    spot check of a sweep result, from its stored sample peaks and states (``mcs_peak_abs_theta``,
    ``mcs_sample_state``).

    Returns a dict of arrays over ``spot``: ``p_overturn``, ``p_overturn_se``, ``near_toppling``
    (``p_overturn > TOPPLING_FRACTION``), and ``p_exceed``, ``p_exceed_se`` (spot x thresholds) with
    ``thresholds`` (the values of the result's ``threshold`` coordinate, ``()`` without) and ``relative_to``.
    """
    from screening.analysis.fragility import spot_positions

    state = np.asarray(ds["mcs_sample_state"].values)
    peaks = np.asarray(ds["mcs_peak_abs_theta"].values, dtype=float)
    relative_to = str(ds["p_exceed"].attrs.get("relative_to", "None")) if "p_exceed" in ds.variables else "None"
    thresholds = (np.asarray(ds["threshold"].values, dtype=float) if "threshold" in ds.variables
                  and "p_exceed" in ds.variables else np.zeros(0))
    scale = (np.ones(ds.sizes["spot"]) if relative_to == "None" else
             np.broadcast_to(ds[relative_to].isel({d: i for d, i in spot_positions(ds).items()
                                                   if d in ds[relative_to].dims}).values, (ds.sizes["spot"],)))
    levels = scale[:, None] * thresholds[None, :]
    got = sample_probabilities(peaks, state == SampleState.overturned,
                               (state == SampleState.standing) | (state == SampleState.overturned), levels)
    with np.errstate(invalid="ignore"):
        got["near_toppling"] = got["p_overturn"] > TOPPLING_FRACTION
    got.update(thresholds=tuple(thresholds), relative_to=relative_to)
    return got


def probability_text(p, se):
    """``"0.43 +- 0.05"`` (or ``"n/a"``)."""
    return f"{p:.3g} +- {se:.2g}" if np.isfinite(p) else "n/a"
