"""Where, with which model and with how many samples a sweep with ``[accuracy]`` runs Monte Carlo.

* :func:`escalation_candidates` — the points where the trust rule cannot promise the target;
* :func:`cover_points` — points covering the candidates evenly in feature space (greedy maximin,
  starting from the worst corner), so that the correction (:mod:`screening.analysis.correction`)
  learns from the whole untrusted region, not only its extreme;
* :func:`transition_points` and :func:`transition_first` — the points in the transition of a fragility
  curve (P from ~0 to ~1 along the swept intensity) first, then the coverage of the others;
* :func:`escalation_model` — condensed Monte Carlo where the calibration shows the condensed model
  within the target of the coupled one (only the linearization is in doubt), coupled otherwise;
* :func:`auto_escalation_model` — with ``model = "auto"``, the stiff-bed model where its measured
  validity holds (:mod:`screening.solvers.model_choice`), the choice above elsewhere;
* :func:`samples_needed` — samples for a relative standard error of ``target / 2`` from a pilot run
  (or from the main run, for the top-up round), with a safety factor for heavy tails;
* :func:`meets_target` — whether a run's standard error reached ``target / 2`` of its peak;
* :func:`probability_samples` and :func:`probabilities_met` — the same for the probabilities of a
  transition point (standard error :data:`PROBABILITY_SE`);
* :func:`estimated_cost` — the deterministic cost model: CPU seconds estimated from a run's
  integration steps (the budget is planned on it, so the escalated points and their samples do not
  depend on the speed of the machine);
* :func:`paired_model` — the cheaper model run beside the coupled one for a multi-fidelity estimate
  (``[accuracy] multifidelity``), and :func:`paired_plan` — its samples from a paired pilot.

Pure functions on numpy arrays (the calibration dataset is passed in); no I/O.
"""

from __future__ import annotations

import collections.abc
import dataclasses
import math

import numpy as np

from screening.analysis.correction import atlas_promises, linearization_promises
from screening.analysis.multifidelity import allocate
from screening.analysis.trust import bed_law, p_bin, regime
from screening.core.status import EscalationModel, PointStatus
from screening.solvers import mc_registry
from screening.solvers.estimates import Z, binomial_estimate

__all__ = []

#: Samples of the pilot run at each escalated point (cost per sample and spread of the estimate).
PILOT_SAMPLES = 64
#: Samples from the pilot's standard error are multiplied by this: a small pilot underestimates the
#: spread of heavy-tailed peaks (with 32 samples and no factor, 34 of 41 points ended short).
SAMPLE_SAFETY = 1.5
#: A point is in the transition of a fragility curve where a probability of it (or of its neighbours along the
#: swept intensity) lies in this band [1]: Monte Carlo there decides the curve.
TRANSITION_BAND = (0.02, 0.98)
#: Standard error [1] of every Monte Carlo probability a transition point aims at (the acceptance target of a
#: collection's P(overturn), docs/accuracy_in_sweeps.md).
PROBABILITY_SE = 0.03
#: At most this many transition points are put first (the budget decides how many run).
MAX_TRANSITION_POINTS = 1000
class _StepCosts(collections.abc.Mapping):
    """``{EscalationModel: step_cost_s}`` of the registered models, read when used."""

    def __getitem__(self, code):
        return mc_registry.escalation_model(code).step_cost_s

    def __iter__(self):
        return iter(mc_registry.escalation_models())

    def __len__(self):
        return len(mc_registry.escalation_models())


#: Cost model: estimated CPU seconds per integration step (accepted or rejected) of one sample, by
#: :class:`EscalationModel`: each model's ``step_cost_s`` (explicit pair, 20 s records, numba, one thread).
#: With the grid terms below, fitted to the median CPU time of 38 runs (the calibration beds, the statue block
#: on k = 1e8 ... 1e11, both integrators, both models) by ``benchmarks/bench_stiff_mcs.py`` (relative least
#: squares); there the measured / predicted ratio is 0.87-1.16 on every run.  The stiff-bed model's holds only
#: where the run's full-contact share is not known (``estimated_cost``'s ``full_contact``; measured / predicted
#: 0.26-2.7 over intensity); with the share, STIFF_BED_EXACT_COST_S and STIFF_BED_ADAPTIVE_COST_S below.
STEP_COST_S = _StepCosts()
#: Cost model of the stiff-bed model: CPU seconds per input grid interval advanced exactly in full contact
#: (a 2x6 product, the check of the vertical input, the bookkeeping), and per adaptive step (accepted or
#: rejected: six evaluations of the contact's moment law and indentation).  Its steps follow the uplift,
#: not a fixed rate: ``steps = E + A`` with ``E`` the exact intervals (about the full-contact share of the
#: grid intervals) and ``A`` the adaptive steps (uplift, output instants, entering and leaving contact);
#: as the uplift grows ``E`` falls and ``A`` rises, and one adaptive step of up to ``h_max`` can replace
#: several grid intervals, so the steps fall while the cost rises.  Fitted (relative least squares, the
#: synthesis term :func:`grid_point_cost` fixed) to the 64 runs of ``benchmarks/bench_stiff_mcs.py --stiff-bed
#: --samples 128 --repeat 3`` at seeds 0 and 7 (the statue on k = 1e8, 1e10, 1e11 and the cabinet's pads,
#: each from no uplift to near toppling, 128 and 16 samples, median CPU of three): 27 ns, 0.59 us and 47 ms;
#: the figures and the check on a fresh seed are in docs/montecarlo_numerics.md, "Cost model of the
#: stiff-bed model".
STIFF_BED_EXACT_COST_S = 27e-9
STIFF_BED_ADAPTIVE_COST_S = 0.59e-6
#: Cost model of the stiff-bed model: CPU seconds per run, whatever its samples (the input plan, the
#: full-contact propagator's five matrix exponentials, the dataset): as much as 30 samples in full contact.
STIFF_BED_RUN_COST_S = 0.047
#: Cost model of the stiff-bed model's exact-contact sampler (``model="stiff_bed_fast"``, what ``"auto"`` runs;
#: ``estimated_cost(..., exact=True)``): CPU seconds per full-contact interval, per adaptive step, per run and
#: per synthesis grid point (its own batched real FFT), fitted as the reference's constants are, by
#: ``benchmarks/bench_stiff_mcs.py --stiff-bed --sampler stiff_bed_fast`` (figures in
#: docs/montecarlo_numerics.md, "Cost model of the stiff-bed model").
FAST_COSTS_S = {"exact": 17.7e-9, "adaptive": 0.234e-6, "run": 2.8e-3, "grid": 11e-9}
#: Cost model: CPU seconds per second of record and sample of the exact-contact sampler before any run at a point
#: (:func:`prior_cost`): the costliest of the 32 fitted runs (2.2 ms a 20 s sample, the statue on k = 1e11 near
#: half uplift); its cheapest was 0.35 ms.
FAST_PRIOR_S_PER_S = 1.1e-4
#: Cost model: estimated CPU seconds per point of one sample's synthesis grid (FFT, modulation and
#: rate of the input) for a grid of :data:`GRID_REFERENCE_POINTS` points per sample.  The input is
#: band-limited at three times the larger of the rocking and vertical frequencies, so on a stiff bed
#: the grid grows as ``sqrt(k)``: on the paper block at k = 1e10 it is ~690,000 points per 20 s
#: sample, and its synthesis costs as much as the integration.
GRID_COST_S = 39e-9
#: Cost model: CPU seconds added per grid point each time a sample's grid doubles (the FFT's
#: ``log2 n`` passes and a working set that outgrows the caches): a point of a 690,000-point grid
#: costs ~85 ns against ~40 ns on the paper bed's 37,000.
GRID_DOUBLING_COST_S = 10.5e-9
#: Grid points per sample at which a point costs :data:`GRID_COST_S`.
GRID_REFERENCE_POINTS = 2**15
#: Cost model: a step of the linearly implicit pair (``integrator="rodas"``) in explicit steps (six
#: stages and four Jacobian evaluations against six stages; measured 1.64 coupled, 1.2 condensed).
RODAS_STEP_FACTOR = 1.6
#: Cost model: a coupled run with exact steps in quiet full contact (``integrator="exact"``, the band-limited
#: ground motion on a stiff bed) costs this fraction of its steps at :data:`STEP_COST_S`: measured / predicted
#: 0.30-0.33 (median 0.32) over the 28 coupled points of ``benchmarks/collection_acceptance.py`` (2026-11-29,
#: quiet machine), whose steps are mostly the explicit pair's partial-contact steps at the ground's band.
EXACT_RUN_FACTOR = 0.32
#: Integration steps per second of record and sample assumed before any pilot ran (the stiffest
#: calibration beds take ~6,000; the paper block ~1,100).
PRIOR_STEPS_PER_S = 3000.0
#: Bounds of the samples of the full run at an escalated point.
MIN_SAMPLES = 100
MAX_SAMPLES = 4000
#: At most this many escalated points where the variance is the answer (the correction needs a few dozen, not
#: hundreds); with ``[fragility]`` every candidate may run (the probabilities need Monte Carlo at every point).
MAX_POINTS = 48
#: The condensed model stands in for the coupled one where every calibration row of the (bed law,
#: peak_p_uplift bin) cell, at least this many, has it within ``target / 2``.
MIN_CONDENSED_ROWS = 2


def escalation_candidates(status, trust, low, high, target):
    """The points to escalate to Monte Carlo: where no linearization estimate promises the target.

    Neither the linearization (:func:`~screening.analysis.correction.linearization_promises`) nor the
    atlas-corrected linearization (:func:`~screening.analysis.correction.atlas_promises`: the error
    atlas interval narrower than the target) promises ``target``; the stopped points are included
    (Monte Carlo is their only estimate), the failed tasks are not.

    Parameters
    ----------
    status : array_like of int
        :class:`~screening.core.status.PointStatus` codes.
    trust : array_like of int
        ``sl_trust`` codes (:class:`~screening.core.status.Trust`).
    low, high : array_like
        The predicted band of ``SL / MCS - 1`` [1].
    target : float
        Relative error aimed at [1].

    Returns
    -------
    numpy.ndarray of bool
        Flat, one per point.

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "Best estimates in a sweep: how often they hold" (this package's
       documentation).
    """
    status = np.asarray(status).reshape(-1)
    promised = linearization_promises(trust, low, high, target).reshape(-1) | \
        (atlas_promises(low, high, target).reshape(-1) & (status == int(PointStatus.ok)))
    return (status != int(PointStatus.task_failed)) & ~promised


def cover_points(features, candidates, priority, count):
    """Flat indices of up to ``count`` candidate points covering them in feature space.

    Greedy maximin on the standardised features (NaN treated as the column mean): the first point
    has the highest ``priority`` (e.g. ``peak_p_uplift``: the worst corner), each next one is the
    candidate farthest from those already chosen (ties: lowest index).

    Parameters
    ----------
    features : array_like
        ``(points, features)`` [any units: standardised per column].
    candidates : array_like of bool
        The candidate points (flat).
    priority : array_like
        Per point; the first point chosen has the highest (NaN: lowest).
    count : int
        At most this many points.

    Returns
    -------
    numpy.ndarray of int
        Flat indices of the chosen points, in the order chosen.

    Notes
    -----
    The farthest-point (maximin) greedy choice of [1], started at the point of highest priority.

    References
    ----------
    .. [1] T. F. Gonzalez, "Clustering to minimize the maximum intercluster distance", Theoretical Computer
       Science 38 (1985) 293-306 (the greedy farthest-point choice).
    """
    idx = np.flatnonzero(np.asarray(candidates).reshape(-1))
    if idx.size == 0 or count < 1:
        return np.zeros(0, dtype=int)
    x = _standardised(np.asarray(features, dtype=float)[idx])
    prio = np.nan_to_num(np.asarray(priority, dtype=float).reshape(-1)[idx], nan=-np.inf)
    first = int(np.argmax(prio))
    chosen = [first]
    dist = np.sum((x - x[first]) ** 2, axis=1)
    while len(chosen) < min(count, idx.size):
        nxt = int(np.argmax(dist))
        if dist[nxt] <= 0:          # duplicates in feature space: take the next by priority
            rest = np.setdiff1d(np.arange(idx.size), chosen)
            nxt = int(rest[np.argmax(prio[rest])])
        chosen.append(nxt)
        dist = np.minimum(dist, np.sum((x - x[nxt]) ** 2, axis=1))
        dist[chosen] = -1.0
    return idx[np.array(chosen)]


def transition_points(p, shape, axis=None, intensity=None, band=TRANSITION_BAND):
    """Which points lie in the transition of a fragility curve, from P ~ 0 to P ~ 1 along the intensity.

    A curve is the line of points along the swept intensity (``axis`` of the grid) with every other
    coordinate fixed, one per probability level (P(overturn), each P(exceed)).  A point is in its transition
    where its probability lies in ``band``, and on both sides of a step of the curve that crosses the band
    between neighbours or that goes from a known probability below the top of the band to one not known
    (NaN: the linearization stopped).

    Parameters
    ----------
    p : array_like
        ``(points, levels)`` (or ``(points,)``) probabilities [1], flat over the grid; NaN where not known.
    shape : tuple of int
        The grid's shape (``prod(shape)`` points).
    axis : int, optional
        The intensity's axis in ``shape``; None (no swept intensity): the band alone decides.
    intensity : array_like, optional
        The intensity's values along ``axis`` [any unit] (the curve is read in their order; default as stored).
    band : tuple of float, default TRANSITION_BAND
        ``(low, high)`` [1].

    Returns
    -------
    numpy.ndarray of bool
        Flat, one per point; the rule of ``docs/accuracy_in_sweeps.md``, "A budget in seconds".
    """
    shape = tuple(int(k) for k in shape)
    n = int(np.prod(shape, dtype=np.int64))
    p = np.asarray(p, dtype=float).reshape(n, -1)
    low, high = band
    with np.errstate(invalid="ignore"):
        mark = (np.isfinite(p) & (p >= low) & (p <= high)).any(axis=1)
        if axis is None or not shape or shape[axis] < 2:
            return mark
        g = np.moveaxis(p.reshape(shape + (p.shape[1],)), axis, -2)
        perm = np.argsort(np.asarray(intensity, dtype=float), kind="stable") if intensity is not None else \
            np.arange(shape[axis])
        g = g[..., perm, :]
        known = np.isfinite(g)
        below, above = known & (g < low), known & (g > high)
        under_top = known & (g <= high)
        t = np.zeros(g.shape, dtype=bool)
        pair = (below[..., :-1, :] & above[..., 1:, :]) | (above[..., :-1, :] & below[..., 1:, :]) | \
            (~known[..., :-1, :] & under_top[..., 1:, :]) | (under_top[..., :-1, :] & ~known[..., 1:, :])
        t[..., :-1, :] |= pair
        t[..., 1:, :] |= pair
    back = np.empty_like(t)
    back[..., perm, :] = t
    return mark | np.moveaxis(back, -2, axis).reshape(n, -1).any(axis=1)


def transition_first(features, candidates, transition, priority, count, most_transition=MAX_TRANSITION_POINTS):
    """Flat indices of candidate points: those in a curve's transition first, then the coverage of the others.

    The transition candidates (up to ``most_transition``) in the greedy maximin order of
    :func:`cover_points`, then the other candidates continuing the same order (each the farthest from
    every point chosen before it), up to ``count`` points in all -- never fewer than the transition
    points.  Without transition points it is :func:`cover_points`.

    Parameters
    ----------
    features : array_like
        ``(points, features)`` [any units: standardised per column].
    candidates, transition : array_like of bool
        The candidate points, and those in the transition of a fragility curve (:func:`transition_points`).
    priority : array_like
        Per point; the first point of each group has the highest (NaN: lowest).
    count : int
        At most this many points beyond the transition points.
    most_transition : int, default MAX_TRANSITION_POINTS
        At most this many transition points.

    Returns
    -------
    numpy.ndarray of int
        Flat indices of the chosen points, in the order chosen.

    References
    ----------
    .. [1] T. F. Gonzalez, "Clustering to minimize the maximum intercluster distance", Theoretical Computer
       Science 38 (1985) 293-306 (the greedy farthest-point choice).
    """
    candidates = np.asarray(candidates, dtype=bool).reshape(-1)
    idx = np.flatnonzero(candidates)
    if idx.size == 0:
        return np.zeros(0, dtype=int)
    x = _standardised(np.asarray(features, dtype=float)[idx])
    prio = np.nan_to_num(np.asarray(priority, dtype=float).reshape(-1)[idx], nan=-np.inf)
    first = np.asarray(transition, dtype=bool).reshape(-1)[idx]
    chosen, dist = [], np.full(idx.size, np.inf)
    for group in (first, ~first):
        cap = len(chosen) + min(int(group.sum()), most_transition) if group is first else max(int(count), len(chosen))
        avail = group.copy()
        while avail.any() and len(chosen) < cap:
            d = np.where(avail, dist, -np.inf)
            if not chosen or d.max() <= 0:          # the first point, or duplicates in feature space: by priority
                nxt = int(np.flatnonzero(avail)[np.argmax(prio[avail])])
            else:
                nxt = int(np.argmax(d))
            chosen.append(nxt)
            avail[nxt] = False
            dist = np.minimum(dist, np.sum((x - x[nxt]) ** 2, axis=1))
    return idx[np.array(chosen, dtype=int)]


def _standardised(x):
    """Columns of ``x`` standardised (NaN: the column mean), as :func:`cover_points` compares them."""
    if not x.shape[1]:
        return x
    mean = np.nanmean(np.where(np.isfinite(x), x, np.nan), axis=0)
    mean = np.where(np.isfinite(mean), mean, 0.0)
    x = np.where(np.isfinite(x), x, mean)
    sd = x.std(axis=0)
    return (x - x.mean(axis=0)) / np.where(sd > 0, sd, 1.0)


def condensed_cells(calibration, target):
    """``{(bed law, bin): True}`` for the cells where condensed Monte Carlo may stand in for coupled.

    A cell qualifies when it holds at least :data:`MIN_CONDENSED_ROWS` points with a condensed run,
    each within ``target / 2`` of the coupled peak var_theta, none with coupled overturning.

    Parameters
    ----------
    calibration : xarray.Dataset
        The calibration dataset (:func:`screening.analysis.trust.shipped_calibration`).
    target : float
        Relative error aimed at [1].

    Returns
    -------
    dict
        ``{(bed law, peak_p_uplift bin): bool}`` over the cells of the calibration.

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "Best estimates in a sweep: how often they hold" (this package's
       documentation).
    .. [2] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    err = (calibration["condensed_peak_var_theta"] / calibration["coupled_peak_var_theta"] - 1.0).values
    over = (calibration["coupled_n_overturned"] / calibration["coupled_n_samples"]).values
    p = calibration["sl_peak_p_uplift"].sel(condensation="paper").values
    laws, bins = bed_law(calibration["eps"].values), p_bin(p)
    cells = {}
    for law in np.unique(laws):
        for b in np.unique(bins[bins >= 0]):
            sel = (laws == law) & (bins == b) & np.isfinite(err)
            ok = sel.sum() >= MIN_CONDENSED_ROWS and np.all(np.abs(err[sel]) <= target / 2) and np.all(over[sel] == 0)
            cells[(str(law), int(b))] = bool(ok)
    return cells


def escalation_model(indicators, status, condensation, eps, cells):
    """The Monte Carlo model of every escalated point: condensed where only the linearization is in doubt.

    Condensed where the paper condensation ran to the end, neither in lock-in nor near toppling, in
    a qualifying cell of :func:`condensed_cells`; coupled otherwise.

    Parameters
    ----------
    indicators : dict
        The trust indicators (:func:`screening.analysis.indicators.trust_indicators`) [1].
    status : array_like of int
        :class:`~screening.core.status.PointStatus` codes.
    condensation : str or array_like of str
        The condensation of each point.
    eps : array_like
        The bed's cubic coefficient [m-2] (its sign is the bed law).
    cells : dict
        :func:`condensed_cells`.

    Returns
    -------
    numpy.ndarray of int8
        :class:`~screening.core.status.EscalationModel` codes.

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "Best estimates in a sweep: how often they hold" (this package's
       documentation).
    .. [2] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    reg = regime(indicators)
    bins = p_bin(indicators["peak_p_uplift"])
    law = np.broadcast_to(bed_law(eps), bins.shape)
    cond = np.broadcast_to(np.asarray(condensation, dtype=str), bins.shape)
    st = np.broadcast_to(np.asarray(status), bins.shape)
    good = np.array([cells.get((str(la), int(b)), False) for la, b in zip(law.ravel(), bins.ravel())],
                    dtype=bool).reshape(bins.shape)
    use = good & (reg == "cell") & (cond == "paper") & (st == int(PointStatus.ok))
    return np.where(use, int(EscalationModel.condensed), int(EscalationModel.coupled)).astype(np.int8)


def auto_escalation_model(calibrated, chosen):
    """:class:`EscalationModel` per point with ``[accuracy] model = "auto"``.

    Parameters
    ----------
    calibrated : array_like of int
        The calibration's choice per point (:func:`escalation_model`: condensed where its cells qualify,
        coupled otherwise).
    chosen : array_like of str
        The Monte Carlo model the measured validity rule picks per point
        (:func:`screening.solvers.model_choice.choose`).

    Returns
    -------
    numpy.ndarray of int8
        The picked model's ``escalation_code`` where it is neither coupled nor condensed, else ``calibrated``.

    References
    ----------
    .. [1] screening documentation, "Automatic model choice", ``docs/model_choice.md``.
    """
    chosen = np.asarray(chosen, dtype=str)
    own = [mc_registry.get(name).escalation_code for name in chosen.ravel()]
    own = np.array([-1 if c is None else int(c) for c in own], dtype=int).reshape(chosen.shape)
    keep = np.isin(own, [EscalationModel.coupled, EscalationModel.condensed]) | (own < 0)   # the calibration decides
    return np.where(keep, np.asarray(calibrated), own).astype(np.int8)


def samples_needed(pilot_rel_se, pilot_samples, target, most=MAX_SAMPLES, safety=SAMPLE_SAFETY):
    """Samples for a relative standard error ``target / 2`` of the peak, from a pilot's relative SE.

    Parameters
    ----------
    pilot_rel_se : float
        The pilot's standard error of the peak over the peak [1].
    pilot_samples : int
        The pilot's samples ``n0``.
    target : float
        Relative error aimed at [1].
    most : int, default MAX_SAMPLES
        Upper bound.
    safety : float, default SAMPLE_SAFETY
        Factor on the estimate [1].

    Returns
    -------
    int
        Samples.

    Notes
    -----
    The standard error falls as ``1/sqrt(n)`` [1]: ``n = safety n0 (se0 / (target / 2))^2``, clipped to
    ``[MIN_SAMPLES, most]``; a pilot without a finite SE asks for ``most``.

    References
    ----------
    .. [1] [rubinstein2017] in the bibliography, ``docs/bibliography.md``.
    """
    if not math.isfinite(pilot_rel_se) or pilot_rel_se <= 0:
        return int(most)
    n = safety * pilot_samples * (pilot_rel_se / (target / 2.0)) ** 2
    return int(min(max(math.ceil(n), MIN_SAMPLES), most))


def meets_target(peak, peak_se, target):
    """Whether a Monte Carlo peak's standard error is at most ``target / 2`` of the peak.

    Two standard errors within the target; False where either is not finite.

    Parameters
    ----------
    peak, peak_se : array_like
        The peak and its standard error [any unit, the same].
    target : float
        Relative error aimed at [1].

    Returns
    -------
    numpy.ndarray of bool

    References
    ----------
    .. [1] [rubinstein2017] in the bibliography, ``docs/bibliography.md``.
    """
    peak, peak_se = np.asarray(peak, dtype=float), np.asarray(peak_se, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.isfinite(peak) & np.isfinite(peak_se) & (peak > 0) & (peak_se <= target / 2.0 * peak)


def probability_samples(hits, used, most=MAX_SAMPLES, se=PROBABILITY_SE):
    """Samples for a standard error of at most ``se`` of every probability, from a run's counts.

    Parameters
    ----------
    hits : array_like of int
        Samples that reached each level (overturned, exceeded each threshold) in the run.
    used : int
        Its usable samples (standing or overturned).
    most : int, default MAX_SAMPLES
        Upper bound.
    se : float, default PROBABILITY_SE
        Standard error aimed at [1].

    Returns
    -------
    int
        Samples, in ``[MIN_SAMPLES, most]``; ``most`` without a usable sample.

    Notes
    -----
    The Agresti-Coull standard error ``sqrt(p~ (1 - p~) / (n + 4))``, ``p~ = (k + 2) / (used + 4)`` [1], of
    the level farthest from 0 and 1 reaches ``se`` at ``n = p~ (1 - p~) / se^2 - 4``; at most 274 for 0.03.

    References
    ----------
    .. [1] [agresti1998] in the bibliography, ``docs/bibliography.md``.
    """
    hits = np.asarray(hits, dtype=float).reshape(-1)
    if int(used) <= 0 or hits.size == 0:
        return int(most)
    q = (hits + Z * Z / 2.0) / (float(used) + Z * Z)
    n = float(np.max(q * (1.0 - q))) / se**2 - Z * Z
    return int(min(max(math.ceil(n), MIN_SAMPLES), most))


def probabilities_met(hits, used, se=PROBABILITY_SE):
    """Whether every probability of a run has a standard error of at most ``se`` [1].

    Parameters
    ----------
    hits : array_like of int
        Samples that reached each level.
    used : int
        Usable samples.
    se : float, default PROBABILITY_SE
        Standard error aimed at [1].

    Returns
    -------
    bool

    References
    ----------
    .. [1] [agresti1998] in the bibliography, ``docs/bibliography.md``.
    """
    if int(used) <= 0:
        return False
    return bool(np.all(binomial_estimate(np.asarray(hits, dtype=float), int(used))[1] <= se))


def grid_point_cost(points_per_sample):
    """Estimated CPU time [s] per point of a synthesis grid of ``points_per_sample`` points.

    Notes
    -----
    ``GRID_COST_S + GRID_DOUBLING_COST_S log2(n / GRID_REFERENCE_POINTS)``, not below half of
    ``GRID_COST_S`` (the passes over the grid that do not grow with it).
    """
    n = max(float(points_per_sample), 1.0)
    return max(GRID_COST_S + GRID_DOUBLING_COST_S * math.log2(n / GRID_REFERENCE_POINTS), 0.5 * GRID_COST_S)


def full_contact_share(p_uplift, n_used, samples):
    """Share of a run's input grid intervals the stiff-bed model advances exactly (in full contact).

    The time mean of the run's uplift occupancy taken out, times the share of the samples used (an
    overturned or diverged sample stops early; counted as stopped at once).

    Parameters
    ----------
    p_uplift : array_like
        The run's uplift occupancy history over the output instants, over the samples used [1].
    n_used : int
        Samples used.
    samples : int
        Samples run.

    Returns
    -------
    float
        The share [1].

    Notes
    -----
    ``(1 - mean_t p_uplift(t)) n_used / samples``, clipped to ``[0, 1]``; ``n_used / samples`` where
    ``p_uplift`` has no finite value (0 when every sample overturned or diverged: all steps adaptive).

    References
    ----------
    .. [1] ``docs/montecarlo_numerics.md``, "Monte Carlo numerics: the sample integrators, stiff beds and the
       cost model" (this package's documentation).
    """
    p = np.asarray(p_uplift, dtype=float)
    p = p[np.isfinite(p)]
    used = min(max(float(n_used) / max(int(samples), 1), 0.0), 1.0)
    if p.size == 0:
        return used
    return float(min(max((1.0 - float(np.mean(p))) * used, 0.0), 1.0))


def estimated_cost(steps, model, grid_points=0, rodas=False, samples=1, full_contact=None, exact=False):
    """Estimated CPU time of a Monte Carlo run from its integration steps and synthesis grid points.

    Parameters
    ----------
    steps : float
        Integration steps, summed over the samples.
    model : int
        :class:`~screening.core.status.EscalationModel` code.
    grid_points : float, default 0
        Synthesis grid points, summed over the samples.
    rodas : bool, default False
        The steps are the linearly implicit pair's.
    samples : int, default 1
        Samples of the run.
    full_contact : float, optional
        Stiff-bed model only: :func:`full_contact_share` of the run [1] (None or NaN: not known).
    exact : bool, default False
        The run took exact steps through full contact: the coupled model's ``integrator="exact"``, the
        stiff-bed model's exact-contact sampler (:data:`FAST_COSTS_S`).

    Returns
    -------
    float
        CPU time [s].

    Notes
    -----
    ``cost = steps x STEP_COST_S[model] (x RODAS_STEP_FACTOR) + grid_points x grid_point_cost(grid_points /
    samples)``.  For the stiff-bed model with ``full_contact = f`` the steps term is split into its
    exact full-contact intervals ``E`` and adaptive steps ``A``::

        E = min(f (grid_points - samples), steps),   A = steps - E
        steps term = E x STIFF_BED_EXACT_COST_S + A x STIFF_BED_ADAPTIVE_COST_S + STIFF_BED_RUN_COST_S

    (``grid_points - samples``: the grid intervals of all samples).  The counts are fixed by the study,
    the seed and the samples, so a budget planned on this cost selects the same points and samples on
    every machine.  The fitted constants and their check: [1], [2].

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "Best estimates in a sweep: how often they hold", section "Cost
       model of the escalation" (this package's documentation).
    .. [2] ``docs/montecarlo_numerics.md``, "Monte Carlo numerics: the sample integrators, stiff beds and the
       cost model" (this package's documentation).
    """
    model = mc_registry.escalation_models()(int(model))
    grid = float(grid_points)
    per_point = grid_point_cost(grid / max(int(samples), 1)) if grid > 0 else 0.0
    if model == EscalationModel.stiff_bed and full_contact is not None and np.isfinite(full_contact):
        f = min(max(float(full_contact), 0.0), 1.0)
        intervals = min(f * max(grid - max(int(samples), 1), 0.0), float(steps))
        c = FAST_COSTS_S if exact else {"exact": STIFF_BED_EXACT_COST_S, "adaptive": STIFF_BED_ADAPTIVE_COST_S,
                                        "run": STIFF_BED_RUN_COST_S, "grid": per_point}
        return (intervals * c["exact"] + (float(steps) - intervals) * c["adaptive"] + c["run"]
                + grid * c["grid"])
    per_step = STEP_COST_S[model] * (RODAS_STEP_FACTOR if rodas else 1.0)
    if exact and model == EscalationModel.coupled:
        per_step *= EXACT_RUN_FACTOR
    return float(steps) * per_step + grid * per_point


def prior_cost(samples, t_end, model, exact=False):
    """Estimated CPU time of a run before any run at the point.

    Parameters
    ----------
    samples : int
        Samples.
    t_end : float
        Record length [s].
    model : int
        :class:`~screening.core.status.EscalationModel` code.
    exact : bool, default False
        As in :func:`estimated_cost`: the stiff-bed model's exact-contact sampler costs ``samples t_end
        FAST_PRIOR_S_PER_S``.

    Returns
    -------
    float
        CPU time [s]: :func:`estimated_cost` of ``samples t_end PRIOR_STEPS_PER_S`` steps.

    References
    ----------
    .. [1] ``docs/accuracy_in_sweeps.md``, "Best estimates in a sweep: how often they hold", section "Cost
       model of the escalation" (this package's documentation).
    """
    if exact and mc_registry.escalation_models()(int(model)) == EscalationModel.stiff_bed:
        return float(samples) * float(t_end) * FAST_PRIOR_S_PER_S
    return estimated_cost(samples * t_end * PRIOR_STEPS_PER_S, model)


#: The cheaper model paired with the coupled one for multi-fidelity estimates: a registered Monte Carlo
#: model, its condensation, and the :class:`EscalationModel` whose step cost the cost model charges it.
#: The virtual-work condensation tracks the coupled peak var_theta within -2 to +16 % on held-out points.
#: The cheap partner of a coupled escalated point in a multi-fidelity estimate: ``(registered Monte Carlo model,
#: condensation, cost class)``.
PAIRED_MODEL = ("condensed", "virtual_work", EscalationModel.condensed)


def paired_model(model):
    """The cheap model run beside an escalated point for a multi-fidelity estimate, or None.

    Parameters
    ----------
    model : int or EscalationModel
        The point's escalation model.

    Returns
    -------
    tuple or None
        :data:`PAIRED_MODEL` (``(registered model, condensation, cost class)``) for a coupled point; None for
        the others (a condensed or stiff-bed point has no cheaper partner).

    References
    ----------
    .. [1] [peherstorfer2016] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "Multi-fidelity Monte Carlo", ``docs/multifidelity.md``.
    """
    return PAIRED_MODEL if EscalationModel(int(model)) == EscalationModel.coupled else None


def paired_plan(pilot, model, pilot_samples, n_plain):
    """The :class:`~screening.analysis.multifidelity.Allocation` of a point from its paired pilot.

    Parameters
    ----------
    pilot : mapping
        The result of a paired pilot run: ``n_steps`` and ``n_grid`` (integration steps and synthesis
        grid points of the expensive model, summed over the samples), ``rodas`` (its steps are the
        linearly implicit pair's), ``cheap_n_steps`` and ``cheap_n_grid`` (the same of the cheap model,
        :data:`PAIRED_MODEL`), ``correlation`` (the two models' correlation at the peak of var_theta,
        in [-1, 1]) and optionally ``cheap_samples`` (default ``pilot_samples``).
    model : int
        :class:`~screening.core.status.EscalationModel` code of the expensive model.
    pilot_samples : int
        Samples of the pilot's expensive model, >= 1.
    n_plain : int
        Samples plain Monte Carlo needs for the target standard error.

    Returns
    -------
    Allocation
        The samples of each model (:func:`~screening.analysis.multifidelity.allocate`), never fewer
        expensive samples than the pilot's when the two-fidelity estimator is chosen.

    Notes
    -----
    The costs per sample are the cost model's (:func:`estimated_cost`: deterministic, so the plan is the
    same on every machine)::

        c_hi = estimated_cost(n_steps, model, n_grid, rodas, pilot_samples) / pilot_samples
        c_lo = estimated_cost(cheap_n_steps, condensed, cheap_n_grid, False, cheap_samples) / cheap_samples

    and the allocation is plain Monte Carlo when the predicted speed-up is below
    :data:`~screening.analysis.multifidelity.MIN_GAIN`.  The pilot's samples are reused, so a two-fidelity
    plan asks for at least ``pilot_samples`` of each model.

    References
    ----------
    .. [1] ``docs/multifidelity.md``, "Multi-fidelity Monte Carlo: what a paired cheap model saves", sections
       "When the cheap model runs" and "In the escalation" (this package's documentation).
    .. [2] ``docs/montecarlo_numerics.md``, section "Cost model of the escalation" (this package's documentation).
    """
    c_hi = estimated_cost(pilot["n_steps"], model, pilot["n_grid"], bool(pilot["rodas"]), pilot_samples) / pilot_samples
    cheap_samples = max(int(pilot.get("cheap_samples", pilot_samples)), 1)
    c_lo = estimated_cost(pilot["cheap_n_steps"], PAIRED_MODEL[2], pilot["cheap_n_grid"], False,
                          cheap_samples) / cheap_samples
    plan = allocate(float(pilot["correlation"]), max(c_hi, 1e-300), max(c_lo, 1e-300), n_plain)
    if plan.estimator == "plain" or plan.n_expensive >= pilot_samples:
        return plan
    return dataclasses.replace(plan, n_expensive=pilot_samples, n_cheap=max(plan.n_cheap, pilot_samples))
