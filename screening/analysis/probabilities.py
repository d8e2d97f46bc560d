"""Probabilities of overturning and of exceeding a rotation, with their standard errors and their source.

Near toppling the variance over the surviving samples is a fragile answer (it moves by tens of per
cent between two runs of a few hundred samples); the probability of overturning and the
probabilities of exceeding rotation thresholds are the robust ones.  This module holds the pure
functions behind them:

* :func:`binomial_estimate`, :func:`sample_probabilities` -- the fractions of samples with their
  standard errors, from :mod:`screening.solvers.estimates` (below the solvers, which use them);
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

from screening.solvers.estimates import Z, binomial_estimate, sample_probabilities
from screening.status import BestMethod, ProbabilitySource, SampleState, Trust, probability_sources

__all__ = ["uplift_acceleration", "source_codes", "monte_carlo_source", "choose_sources",
           "overturning_probability", "TOPPLING_FRACTION", "spot_check_probabilities", "probability_text", "Z",
           "binomial_estimate", "sample_probabilities"]


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
    and ``monte_carlo_<model>`` for every registered Monte Carlo model (:mod:`screening.solvers.mc_registry`)."""
    from screening.solvers import mc_registry

    return probability_sources(mc_registry.names())


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
