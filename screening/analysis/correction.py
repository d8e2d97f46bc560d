"""Corrected estimates everywhere: the linearization's error learned from the escalated Monte Carlo points.

At the points where a sweep with ``[accuracy]`` ran Monte Carlo (:mod:`screening.analysis.escalation`)
the log ratio ``y = log(MCS / SL)`` of a peak variance is known (with its Monte Carlo standard error).
:func:`fit_correction` learns ``y`` as a linear function of standardised features of the point (the
trust indicators and the swept parameters, :func:`point_features`) by ridge regression, choosing the
ridge weight by leave-one-out; :func:`predict_correction` gives ``y`` and its standard error at
every point.  :func:`best_estimates` combines everything into one estimate per point, with its
standard error and where it comes from (:class:`screening.status.BestMethod`).

Pure functions on numpy arrays; no I/O.  Method: ``docs/method.md#trusting-a-point``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.status import BestMethod, EscalationModel, PointStatus, Trust

#: Ridge weights tried by the leave-one-out choice (on standardised features).
RIDGE_GRID = (1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0)
#: Floor of the standard error of a log ratio in the weights of the fit [1] (model error beyond Monte Carlo noise).
NOISE_FLOOR = 0.1
#: A correction needs at least this many escalated points (fewer: no correction anywhere).
MIN_POINTS = 4
#: Leave-one-out RMS of the log ratio above which the correction is not trusted anywhere (a factor ~1.65).
MAX_LOO_RMS = 0.5
#: A point is reached by the correction if each of its standardised features lies within the range of
#: the escalated points widened by this many standard deviations of the features (no extrapolation).
REACH = 0.25


@dataclass(frozen=True)
class Correction:
    """A fitted correction: ridge coefficients on standardised features, the leave-one-out check."""

    mean: np.ndarray            # feature means
    scale: np.ndarray           # feature standard deviations (1 where constant)
    coef: np.ndarray            # intercept first, then one per feature
    gram_inv: np.ndarray        # (X'X + ridge I)^-1 of the design with intercept
    ridge: float
    loo_rms: float              # RMS of the leave-one-out residuals of y [1]
    loo_residuals: np.ndarray
    low: np.ndarray             # range of the standardised features of the fitted points
    high: np.ndarray
    n: int

    @property
    def usable(self):
        """True when enough points were fitted and the leave-one-out check passed."""
        return self.n >= MIN_POINTS and np.isfinite(self.loo_rms) and self.loo_rms <= MAX_LOO_RMS


def point_features(features):
    """Stack a dict of per-point feature arrays into a (points x features) matrix [mixed units].

    Positive features spanning more than a factor 10 are taken in log10 (swept intensities and
    stiffnesses); constant or all-NaN columns are dropped.
    """
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


def _design(z):
    return np.column_stack([np.ones(len(z)), z])


def _ridge(x, y, w, ridge):
    p = x.shape[1]
    penalty = ridge * np.eye(p)
    penalty[0, 0] = 0.0                         # the intercept is not shrunk
    xw = x * w[:, None]
    gram_inv = np.linalg.inv(x.T @ xw + penalty)
    coef = gram_inv @ xw.T @ y
    hat = np.einsum("ij,jk,ik->i", x, gram_inv, xw)
    loo = (y - x @ coef) / np.maximum(1.0 - hat, 1e-9)
    return coef, gram_inv, loo


def fit_correction(features, y, y_se=None):
    """Fit ``y`` [1] (log ratio MCS / SL at the escalated points) on ``features`` (points x features).

    ``y_se`` [1]: the Monte Carlo standard error of each ``y`` (default 0); a point weighs
    ``w = 1 / (y_se^2 + NOISE_FLOOR^2)``.  Rows with a non-finite value are dropped.  The ridge
    weight is the one of :data:`RIDGE_GRID` with the smallest leave-one-out RMS.

    Notes
    -----
    ``y = b0 + sum_j b_j z_j`` with ``z_j = (x_j - mean_j) / sd_j``, minimising
    ``sum_i w_i (y_i - X_i b)^2 + ridge |b_1..|^2``; leave-one-out residual ``e_i / (1 - H_ii)``,
    ``H = X (X'WX + ridge I)^-1 X'W``; leave-one-out RMS ``sqrt(sum w e_loo^2 / sum w)``.
    """
    x = np.asarray(features, dtype=float)
    y = np.asarray(y, dtype=float).reshape(-1)
    y_se = np.zeros_like(y) if y_se is None else np.asarray(y_se, dtype=float).reshape(-1)
    ok = np.isfinite(y) & np.all(np.isfinite(x), axis=1) & np.isfinite(y_se)
    x, y, w = x[ok], y[ok], 1.0 / (y_se[ok] ** 2 + NOISE_FLOOR ** 2)
    n, p = x.shape
    mean = x.mean(axis=0) if n else np.zeros(p)
    scale = x.std(axis=0) if n else np.ones(p)
    scale = np.where(scale > 0, scale, 1.0)
    z = (x - mean) / scale
    if n < 2:
        nan = np.full(p + 1, np.nan)
        return Correction(mean, scale, nan, np.full((p + 1, p + 1), np.nan), np.nan, np.inf, np.full(n, np.nan),
                          np.full(p, np.nan), np.full(p, np.nan), n)
    best = None
    for ridge in RIDGE_GRID:
        coef, gram_inv, loo = _ridge(_design(z), y, w, ridge)
        rms = float(np.sqrt(np.sum(w * loo ** 2) / np.sum(w)))
        if best is None or rms < best[0]:
            best = (rms, ridge, coef, gram_inv, loo)
    rms, ridge, coef, gram_inv, loo = best
    return Correction(mean, scale, coef, gram_inv, ridge, rms, loo, z.min(axis=0), z.max(axis=0), n)


def predict_correction(correction, features):
    """``(y, se, reached)`` at the points of ``features`` (points x features).

    ``se`` [1] is the leave-one-out RMS inflated by the leverage of the point,
    ``loo_rms sqrt(1 + x (X'X + ridge I)^-1 x')``; ``reached`` is false where a feature is outside the
    fitted range widened by :data:`REACH` (the correction would extrapolate) or not finite.
    """
    x = np.asarray(features, dtype=float)
    z = (x - correction.mean) / correction.scale
    d = _design(z)
    y = d @ correction.coef
    lev = np.einsum("ij,jk,ik->i", d, correction.gram_inv, d)
    se = correction.loo_rms * np.sqrt(1.0 + np.maximum(lev, 0.0))
    reached = np.all(np.isfinite(z), axis=1) & np.all((z >= correction.low - REACH) & (z <= correction.high + REACH),
                                                      axis=1)
    return y, se, reached & np.isfinite(y)


def linearization_promises(trust, low, high, target):
    """True where the trust rule promises the target: ``trusted`` and the predicted band within ``+-target``."""
    trust = np.asarray(trust)
    with np.errstate(invalid="ignore"):
        return (trust == int(Trust.trusted)) & (np.maximum(np.abs(low), np.abs(high)) <= target)


def best_estimates(sl_peak, status, trust, low, high, target, features, escalated, mc_peak, mc_se, mc_model):
    """Best estimate of a peak variance at every point: ``(value, se, method, correction)``.

    Parameters
    ----------
    sl_peak : linearization peak per point [rad2 or rad2 s-2].  status : :class:`PointStatus` codes.
    trust, low, high : ``sl_trust`` and its band per point.  target : relative error aimed at [1].
    features : (points x features) from :func:`point_features`.
    escalated : flat indices of the points with Monte Carlo; ``mc_peak``, ``mc_se`` [same units]
        and ``mc_model`` (:class:`EscalationModel`) there.

    Returns
    -------
    value, se : per point [units of ``sl_peak``]; ``se`` NaN where method is ``unreliable``.
    method : :class:`BestMethod` codes (int8), in this order of preference: Monte Carlo at the point
        (if it has a finite peak); the linearization where the rule promises the target (se: half the
        band); the corrected linearization ``SL exp(y)`` (se ``value x se_y``) where the correction is
        usable and reaches the point; else ``unreliable`` (value: SL's where it ran to the end, NaN
        where it stopped).
    correction : the fitted :class:`Correction`.
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
        y = np.log(mc_peak / sl[escalated])
        y_se = mc_se / mc_peak
    correction = fit_correction(np.asarray(features)[escalated], np.where(ok[escalated], y, np.nan), y_se)
    if correction.usable:
        y_hat, y_se, reached = predict_correction(correction, features)
        use = ok & ~promise & reached
        value[use] = sl[use] * np.exp(y_hat[use])
        se[use] = value[use] * y_se[use]
        method[use] = int(BestMethod.corrected_linearization)

    have = np.isfinite(mc_peak) & (mc_peak > 0)
    at = escalated[have]
    value[at], se[at] = mc_peak[have], mc_se[have]
    method[at] = np.where(np.asarray(mc_model)[have] == int(EscalationModel.condensed),
                          int(BestMethod.condensed_monte_carlo), int(BestMethod.coupled_monte_carlo))
    return value, se, method, correction
