"""Corrected estimates everywhere: the linearization's error learned from the escalated Monte Carlo points.

Where a sweep with ``[accuracy]`` ran Monte Carlo, ``y = log(MCS / SL)`` of a peak variance is known;
:func:`fit_correction` learns it by nearest-neighbour regression over standardised point features
(:func:`point_features`), a local average with a local error that stays honest across regimes where a
global fit would average them away.  :func:`best_estimates` gives one estimate per point with its standard
error and its :class:`screening.core.status.BestMethod`.  Pure numpy; ``docs/method.md#trusting-a-point``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.core.status import BestMethod, PointStatus, Trust
from screening.solvers import mc_registry

__all__ = []

#: Numbers of neighbours tried by the leave-one-out choice.
NEIGHBOURS = (1, 2, 3, 4, 6, 8)
#: A correction needs at least this many escalated points (fewer: no correction anywhere).
MIN_POINTS = 4
#: Local standard error of the log ratio above which a corrected value is not vouched for (a factor ~1.65).
MAX_SE = 0.5
#: Floor of the standard error of a log ratio [1] (model error beyond Monte Carlo noise).
NOISE_FLOOR = 0.05
#: Added to neighbour distances in the weights (standardised units): a coincident point dominates, never divides by 0.
DISTANCE_FLOOR = 1e-3
#: A point is reached if its nearest escalated point is within this many times the spacing of the escalated
#: points (90th percentile of the distances to their own nearest neighbour) in standardised feature space.
REACH = 1.5
#: Standard normal quantile of the error atlas model's two-sided 90 % interval: its half width in
#: ``log(SL / MC)`` is this many standard errors.
INTERVAL_Z = 1.6448536269514722


@dataclass(frozen=True)
class Correction:
    """A fitted correction: the escalated points in standardised feature space and their leave-one-out errors."""

    mean: np.ndarray            # feature means
    scale: np.ndarray           # feature standard deviations (1 where constant)
    z: np.ndarray               # standardised features of the fitted points
    y: np.ndarray               # their log ratios
    y_se: np.ndarray            # their Monte Carlo standard errors (floored)
    k: int                      # neighbours
    loo_residuals: np.ndarray   # y - prediction without the point
    loo_rms: float              # RMS of loo_residuals [1]
    spacing: float              # 90th percentile of the nearest-neighbour distances of the fitted points
    nn_distance: np.ndarray     # distance of each fitted point to its nearest other fitted point

    @property
    def n(self):
        return self.y.size

    @property
    def usable(self):
        """True when enough points were fitted for a leave-one-out check."""
        return self.n >= MIN_POINTS and np.isfinite(self.loo_rms)


def point_features(features):
    """``(points, kept features)`` of a dict of per-point features: log10 of positive ones spanning over a factor 10, constant or all-NaN columns dropped."""
    cols = []
    for value in features.values():
        v = np.asarray(value, dtype=float).reshape(-1)
        fin = v[np.isfinite(v)]
        if fin.size == 0 or np.ptp(fin) == 0:
            continue
        if fin.min() > 0 and fin.max() / fin.min() > 10:
            v = np.log10(np.where(v > 0, v, np.nan))
        cols.append(v)
    n = np.asarray(next(iter(features.values()))).size if features else 0
    return np.column_stack(cols) if cols else np.zeros((n, 0))


def _distances(a, b):
    return np.sqrt(np.maximum(np.sum(a * a, 1)[:, None] + np.sum(b * b, 1)[None, :] - 2 * a @ b.T, 0.0))


def _neighbour_mean(d, y, w, k):
    """Weighted mean of ``y`` over the ``k`` nearest columns of the distance matrix ``d`` (rows: targets);
    weights ``w / (d + DISTANCE_FLOOR)``.  Returns the means and the neighbour indices."""
    k = min(k, d.shape[1])
    nearest = np.argsort(d, axis=1, kind="stable")[:, :k]
    dn = np.take_along_axis(d, nearest, 1)
    wn = w[nearest] / (dn + DISTANCE_FLOOR)
    return np.sum(wn * y[nearest], 1) / np.sum(wn, 1), nearest


def fit_correction(features, y, y_se=None):
    """Fit the log ratio ``y = log(MCS / SL)`` [1] at the escalated points on their features.

    Rows with a non-finite value are dropped.

    Units: ``y`` [1], ``y_se`` [1].

    Returns: the standardised points, the chosen ``k`` and the leave-one-out errors.

    Notes
    -----
    Prediction at ``x``: ``sum_i w_i y_i / sum_i w_i`` over the ``k`` escalated points nearest to ``x``
    in standardised features ``z_j = (x_j - mean_j) / sd_j``, ``w_i = 1 / (y_se_i^2 (d_i + d0))``
    (``d0`` = :data:`DISTANCE_FLOOR`).
    ``k`` minimises the leave-one-out RMS (each point predicted from the others) [hastie2009].
    """
    x = np.asarray(features, dtype=float)
    y = np.asarray(y, dtype=float).reshape(-1)
    y_se = np.zeros_like(y) if y_se is None else np.asarray(y_se, dtype=float).reshape(-1)
    ok = np.isfinite(y) & np.all(np.isfinite(x), axis=1) & np.isfinite(y_se)
    x, y, y_se = x[ok], y[ok], np.maximum(y_se[ok], NOISE_FLOOR)
    n, p = x.shape
    mean = x.mean(axis=0) if n else np.zeros(p)
    scale = x.std(axis=0) if n else np.ones(p)
    scale = np.where(scale > 0, scale, 1.0)
    z = (x - mean) / scale
    if n < 2:
        return Correction(mean, scale, z, y, y_se, 1, np.full(n, np.nan), np.inf, np.nan, np.full(n, np.inf))
    d = _distances(z, z)
    np.fill_diagonal(d, np.inf)                  # leave one out: a point is never its own neighbour
    w = 1.0 / y_se ** 2
    best = None
    for k in NEIGHBOURS:
        if k > n - 1:
            break
        pred, _ = _neighbour_mean(d, y, w, k)
        res = y - pred
        rms = float(np.sqrt(np.mean(res ** 2)))
        if best is None or rms < best[0]:
            best = (rms, k, res)
    rms, k, res = best
    nn = d.min(axis=1)
    return Correction(mean, scale, z, y, y_se, k, res, rms, float(np.quantile(nn, 0.9)), nn)


def predict_correction(correction, features):
    """The correction, its standard error and whether it reaches, at new points.

    Returns ``(y, se, reached)``: ``y`` predicted log ratio [1] (NaN where the features are not finite);
    ``se`` ``sqrt(mean((e_loo,i max(1, d_i / nn_i))^2) + mean((y_i - y)^2))`` [1] over the neighbours ``i``
    used — their own leave-one-out errors ``e_loo,i`` (measured at their nearest-neighbour distance
    ``nn_i``, scaled to the distance ``d_i`` of the point) and their disagreement at the point —, floored at
    :data:`NOISE_FLOOR`; ``reached`` the nearest escalated point is within :data:`REACH` spacings and the
    features are finite.
    """
    x = np.asarray(features, dtype=float)
    z = (x - correction.mean) / correction.scale
    finite = np.all(np.isfinite(z), axis=1)
    n = x.shape[0]
    y, se = np.full(n, np.nan), np.full(n, np.nan)
    reached = np.zeros(n, dtype=bool)
    if correction.n == 0 or not finite.any():
        return y, se, reached
    d = _distances(z[finite], correction.z)
    pred, nearest = _neighbour_mean(d, correction.y, 1.0 / correction.y_se ** 2, correction.k)
    y[finite] = pred
    # the neighbours' own leave-one-out errors, and how much they disagree with each other here
    # a leave-one-out residual was measured at the neighbour's own nearest-neighbour distance: for a point
    # farther away it is scaled up linearly with the distance (a smooth correction changes linearly)
    far = np.maximum(np.take_along_axis(d, nearest, 1) / np.maximum(correction.nn_distance[nearest], DISTANCE_FLOOR),
                     1.0)
    local = np.mean((correction.loo_residuals[nearest] * far) ** 2, axis=1)
    spread = np.mean((correction.y[nearest] - pred[:, None]) ** 2, axis=1)
    se[finite] = np.maximum(np.sqrt(local + spread), NOISE_FLOOR)
    reach = REACH * correction.spacing if np.isfinite(correction.spacing) and correction.spacing > 0 else np.inf
    reached[finite] = d.min(axis=1) <= max(reach, 1e-9)
    return y, se, reached


def linearization_promises(trust, low, high, target):
    """Boolean: ``sl_trust`` is ``trusted`` and the band ``[low, high]`` of ``SL / MCS - 1`` lies within ``+-target``."""
    trust = np.asarray(trust)
    with np.errstate(invalid="ignore"):
        return (trust == int(Trust.trusted)) & (np.maximum(np.abs(low), np.abs(high)) <= target)


def atlas_correction(low, high):
    """The error atlas model's correction of a point and its standard error, from its interval.

    Units: low, high [1].

    Returns: the correction ``y = log(MCS / SL)`` [1] and its standard error [1]; NaN where the interval is
    not finite or reaches ``SL / MCS - 1 <= -1`` (open).

    Notes
    -----
    The interval is symmetric in ``log(SL / MCS)`` about the estimate (``estimate +- q s``,
    :mod:`screening.analysis.error_model`): ``y = -(log(1 + low) + log(1 + high)) / 2`` and
    ``se = (log(1 + high) - log(1 + low)) / (2 z)``, ``z`` = :data:`INTERVAL_Z`.
    """
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        a, b = np.log1p(np.where(low > -1, low, np.nan)), np.log1p(np.where(high > -1, high, np.nan))
    return -(a + b) / 2.0, (b - a) / (2.0 * INTERVAL_Z)


def atlas_promises(low, high, target):
    """Boolean: where the atlas-corrected linearization is within ``target``, ``exp(z se) - 1 <= target`` (:func:`atlas_correction`)."""
    _, se = atlas_correction(low, high)
    with np.errstate(invalid="ignore"):
        return np.isfinite(se) & (np.expm1(INTERVAL_Z * se) <= target)


def within_band(y, low, high):
    """Boolean: the SL error ``exp(-y) - 1`` implied by ``y = log(MCS / SL)`` lies in the band ``[low, high]`` (or there is none)."""
    with np.errstate(invalid="ignore", over="ignore"):
        implied = np.expm1(-np.asarray(y, dtype=float))
        no_band = ~(np.isfinite(low) & np.isfinite(high))
        return no_band | ((implied >= low) & (implied <= high))


def best_estimates(sl_peak, status, trust, low, high, target, features, escalated, mc_peak, mc_se, mc_model,
                   atlas=True):
    """Best estimate of a peak variance at every point: ``(value, se, method, correction)``.

    Parameters
    ----------
    sl_peak : array_like
        Linearization peak per point [rad2 or rad2 s-2].
    status : array_like of int
        :class:`PointStatus` codes.
    trust : array_like of int
        ``sl_trust`` codes.
    low, high : array_like
        The trust band of the SL error per point [1].
    target : float
        Relative error aimed at [1].
    features : array_like
        ``(points, features)`` from :func:`point_features`.
    escalated : array_like of int
        Flat indices of the points with Monte Carlo.
    mc_peak, mc_se : array_like
        The Monte Carlo peak and its standard error there [same units as ``sl_peak``].
    mc_model : array_like of int
        The model run there (:class:`EscalationModel`).
    atlas : bool
        Use the error atlas model's correction (its interval is of peak var_theta: False for other peaks).

    Returns
    -------
    value, se : numpy.ndarray
        Per point [units of ``sl_peak``]; ``se`` NaN where method is ``unreliable``.
    method : numpy.ndarray of int8
        :class:`BestMethod` codes, in this order of preference: Monte Carlo at the point (if it has a
        finite peak); the linearization where the rule promises the target (se: half the band); the
        corrected linearization ``SL exp(y)`` (se ``value x se_y``) by whichever of two corrections has
        the smaller ``se_y``: the study's own (the escalated points') where it is usable, reaches the
        point, ``se_y <= MAX_SE`` and the SL error it implies lies in the trust band
        (:func:`within_band`), or the error atlas model's (:func:`atlas_correction`) where
        ``se_y <= MAX_SE``; else ``unreliable`` (value: SL's where it ran to the end, NaN where it
        stopped).
    correction : Correction
        The fitted correction.
    """
    sl = np.asarray(sl_peak, dtype=float).reshape(-1)
    n = sl.size
    ok = (np.asarray(status).reshape(-1) == int(PointStatus.ok)) & np.isfinite(sl) & (sl > 0)
    low, high = np.asarray(low, dtype=float).reshape(-1), np.asarray(high, dtype=float).reshape(-1)
    value = np.where(ok, sl, np.nan)
    se = np.full(n, np.nan)
    method = np.full(n, int(BestMethod.unreliable), dtype=np.int8)

    promise = ok & linearization_promises(np.asarray(trust).reshape(-1), low, high, target)
    # the band is of SL / MCS - 1: MCS = SL / (1 + e); its half width stands for two standard errors
    se[promise] = (sl * (np.maximum(np.abs(low), np.abs(high)) / 2.0))[promise]
    method[promise] = int(BestMethod.linearization)

    escalated = np.asarray(escalated, dtype=int)
    mc_peak, mc_se = np.asarray(mc_peak, dtype=float), np.asarray(mc_se, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        y_mc = np.log(mc_peak / sl[escalated])
        y_mc_se = mc_se / mc_peak
    correction = fit_correction(np.asarray(features)[escalated], np.where(ok[escalated], y_mc, np.nan), y_mc_se)
    # the error atlas model's correction, and the study's own where that is sharper
    y_hat, y_se = atlas_correction(low, high) if atlas else (np.full(n, np.nan), np.full(n, np.inf))
    y_se = np.where(np.isfinite(y_hat) & np.isfinite(y_se), y_se, np.inf)
    if correction.usable:
        own, own_se, reached = predict_correction(correction, features)
        better = reached & (own_se <= MAX_SE) & within_band(own, low, high) & (own_se < y_se)
        y_hat, y_se = np.where(better, own, y_hat), np.where(better, own_se, y_se)
    use = ok & ~promise & (y_se <= MAX_SE)
    value[use] = sl[use] * np.exp(y_hat[use])
    se[use] = value[use] * y_se[use]
    method[use] = int(BestMethod.corrected_linearization)

    have = np.isfinite(mc_peak) & (mc_peak > 0)
    at = escalated[have]
    value[at], se[at] = mc_peak[have], mc_se[have]
    method[at] = [int(mc_registry.escalation_model(m).best_method) for m in np.asarray(mc_model)[have]]
    return value, se, method, correction
