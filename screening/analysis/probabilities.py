"""Probabilities of overturning and of exceeding a rotation, with their standard errors and their source.

Near toppling the probabilities, not the variance over the surviving samples, are the robust answer.
Pure functions: the sample fractions with their standard errors, the quasi-static uplift acceleration,
the codes of the provenance variable ``p_source`` (:data:`screening.core.status.ProbabilitySource`, one
``monte_carlo_<model>`` code per Monte Carlo model), which estimate each sweep point carries
(:func:`choose_sources`) and which quantity answers it (:func:`answer_quantities`).
``docs/outputs_probabilities.md``.
"""

from __future__ import annotations

import numpy as np

from screening.analysis.fragility import spot_positions
from screening.analysis.trust import P_EDGES
from screening.core.status import (AnswerQuantity, BestMethod, PointStatus, probability_sources, ProbabilitySource,
                                   SampleState, Trust)
from screening.solvers import mc_registry
from screening.solvers.estimates import binomial_estimate, sample_probabilities

__all__ = []


def uplift_acceleration(block, foundation, condensation):
    """Ground acceleration [m s-2] at which the block starts to rock: the quasi-static tilt reaches the
    bed's uplift angle.

    Returns: ``a_ul`` [m s-2].

    Notes
    -----
    The condensed equation of motion ``M theta'' + C theta' + K(theta) theta = -m h a_g`` at rest gives
    ``a_ul = K(theta_ul) theta_ul / (m h)``.  On a linear Winkler bed ``K = 2 k b^3 / 3 - m g h`` and
    ``theta_ul = m g / (2 b^2 k)`` (eq. (19) in [1]), so ``a_ul = g b / (3 h) - g theta_ul``: the
    resultant of the bed's pressure reaches the edge of the kern of the base, a third of the half-width
    from the centre.
    """
    theta_ul = condensation.uplift_threshold(block, foundation)
    moment = condensation.restoring_moment(theta_ul, block, foundation)
    return np.abs(moment / (block.m * block.h))


def source_codes():
    """The codes of the values of ``p_source``.

    Those of :data:`~screening.core.status.ProbabilitySource` and ``monte_carlo_<model>`` for every registered
    Monte Carlo model (:mod:`screening.solvers.mc_registry`).

    Returns: ``{name: code}`` [-].
    """
    return probability_sources(mc_registry.codes())


def monte_carlo_source(model):
    """The ``p_source`` code of a Monte Carlo model.

    Returns: the code [-] (:func:`source_codes`).
    """
    codes = source_codes()
    if f"monte_carlo_{model}" not in codes:
        raise ValueError(f"parameter 'model' must be a Monte Carlo model, one of "
                         f"{[n[len('monte_carlo_'):] for n in codes if n.startswith('monte_carlo_')]} (got {model!r})")
    return codes[f"monte_carlo_{model}"]


def choose_sources(status_ok, trust, band_finite, best_method=None):
    """``p_source`` of every point before Monte Carlo: where the linearization's Gaussian estimate is vouched for.

    Returns: :data:`~screening.core.status.ProbabilitySource` codes [-]: with ``[accuracy]``,
    ``linearization_gaussian`` where the rule promises the target, ``corrected_linearization_gaussian``
    where the correction reaches the point, else ``unreliable``; without it, ``linearization_gaussian``
    where the point is ``trusted`` with a finite band, else ``unreliable``.  Monte Carlo points are set by
    the caller (:func:`monte_carlo_source`).
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
    """The probability of overturning [1] of a result dataset, on its grid, for a fragility over an intensity.

    A sweep with ``[accuracy]`` or ``[fragility]`` stores ``p_overturn`` with ``p_source``: that estimate,
    NaN where ``p_source`` is ``unreliable`` (a fit must not learn from numbers nothing vouches for).  A
    :func:`screening.monte_carlo` result: its ``p_overturn``.  Any other result (no stored estimate): the
    Gaussian up-crossing of ``atan(b/h)`` by the linearization's moments
    (:func:`screening.analysis.fragility.exceedance_probability`, ``method``), which nothing vouches for
    near toppling.

    Returns ``(p_overturn, note)``: ``p_overturn`` the probability [1]; ``note`` a one-line caveat, or
    ``""`` when there is none.
    """
    from screening.analysis.fragility import STORED, exceedance_probability

    if "p_overturn" in ds.variables and "p_source" in ds.variables:
        unreliable = ds["p_source"] == int(ProbabilitySource.unreliable)
        n = int(unreliable.sum())
        note = f"{n} point(s) whose p_source is unreliable left out of the fit" if n else ""
        return ds["p_overturn"].where(~unreliable).assign_attrs(method=STORED), note
    if "p_overturn" in ds.variables:
        return ds["p_overturn"].assign_attrs(method="monte_carlo"), ""
    p = exceedance_probability(ds, 1.0, "slenderness", method)
    return p, ("the result stores no p_overturn: the linearization's Gaussian up-crossing of atan(b/h), which "
               "nothing vouches for near toppling (run the study with [accuracy] or [fragility])")


#: A Monte Carlo point where more than this fraction of the samples overturned is near toppling: its
#: variances are over the survivors only and move from run to run; its probabilities are the answer.
TOPPLING_FRACTION = 0.05


def spot_check_probabilities(ds):
    """The probabilities of each Monte Carlo spot check of a sweep result, from its sample peaks and states.

    ``p_overturn`` and, where the result has ``[fragility]`` thresholds, ``p_exceed``, from the stored
    ``mcs_peak_abs_theta`` [rad] and ``mcs_sample_state`` (diverged or failed samples left out).

    Returns: arrays over ``spot``: ``p_overturn``, ``p_overturn_se`` [1], ``near_toppling`` (``p_overturn >
    TOPPLING_FRACTION``), and ``p_exceed``, ``p_exceed_se`` [1] (spot x thresholds) with ``thresholds`` (the
    values of the result's ``threshold`` coordinate, ``()`` without) and ``relative_to``.
    """
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
    """A probability and its standard error as text: ``"0.43 +- 0.05"`` (or ``"n/a"``).

    Units: ``p`` [1], ``se`` [1].

    Returns: three significant digits for ``p``, two for ``se``; ``"n/a"`` where ``p`` is not finite.
    """
    return f"{p:.3g} +- {se:.2g}" if np.isfinite(p) else "n/a"


#: Peak probability of uplift from which a point is in heavy uplift (the last bin of the trust cells).
HEAVY_UPLIFT = P_EDGES[-2]
#: Solver statuses of a linearization that stopped because the block is near toppling.
NEAR_TOPPLING_STATUS = (PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness)


def answer_quantities(status, p_overturn, p_overturn_se, low, high, peak_p_uplift, variance_vouched=None):
    """Which quantity answers each point: the peak variance or, near toppling, the probabilities.

    Units: p_overturn, p_overturn_se [1], low, high [1], ``peak_p_uplift`` [1].

    Returns: :class:`~screening.core.status.AnswerQuantity` codes [-], the first rule that holds:
    ``probabilities_stopped`` where the linearization stopped near toppling (:data:`NEAR_TOPPLING_STATUS`);
    ``probabilities_overturning`` where ``p_overturn`` is vouched for and ``p_overturn - 2 se >=
    TOPPLING_FRACTION``; ``probabilities_open_interval`` at status ok in heavy uplift (``peak_p_uplift >=
    HEAVY_UPLIFT``) with the interval open or the variance not vouched for (its interval too wide);
    ``variance`` elsewhere (also where the task failed or the solver gave up for another reason: nothing
    there says the block topples).

    Notes
    -----
    A variance over the surviving samples changes meaning once a material share of the samples overturns:
    the survivors are the samples that rocked least.  :data:`TOPPLING_FRACTION` (5 %) is the share from
    which a Monte Carlo point is already called near toppling; two standard errors below it keep a point
    whose overturning is not established with its variance.
    """
    status = np.asarray(status).reshape(-1)
    p, se = np.asarray(p_overturn, dtype=float).reshape(-1), np.asarray(p_overturn_se, dtype=float).reshape(-1)
    low, high = np.asarray(low, dtype=float).reshape(-1), np.asarray(high, dtype=float).reshape(-1)
    uplift = np.asarray(peak_p_uplift, dtype=float).reshape(-1)
    out = np.full(status.shape, int(AnswerQuantity.variance), dtype=np.int8)
    with np.errstate(invalid="ignore"):
        unvouched = (np.zeros(status.shape, dtype=bool) if variance_vouched is None
                     else ~np.asarray(variance_vouched, dtype=bool).reshape(-1))
        open_interval = (status == int(PointStatus.ok)) & (uplift >= HEAVY_UPLIFT) & (
            (low <= -1) | np.isposinf(high) | unvouched)
        material = np.isfinite(se) & (p - 2.0 * se >= TOPPLING_FRACTION)
    out[open_interval] = int(AnswerQuantity.probabilities_open_interval)
    out[material] = int(AnswerQuantity.probabilities_overturning)
    out[np.isin(status, [int(s) for s in NEAR_TOPPLING_STATUS])] = int(AnswerQuantity.probabilities_stopped)
    return out


def reliable_answer(answer, variance_vouched, source):
    """Whether a point's answer is vouched for: its variance where the variance answers it, its probabilities
    where they do.

    Returns: True where the quantity that answers the point is vouched for.
    """
    answer = np.asarray(answer).reshape(-1)
    by_variance = answer == int(AnswerQuantity.variance)
    return np.where(by_variance, np.asarray(variance_vouched, dtype=bool).reshape(-1),
                    np.asarray(source).reshape(-1) != int(ProbabilitySource.unreliable))
