"""Multi-fidelity Monte Carlo: a cheap model run on the same ground motions as the expensive one.

A cheap model (condensed, stiff-bed, or one whose expectation is known) on the *same* samples is
correlated with the coupled model sample by sample; as a control variate [peherstorfer2016] it removes the
part of the expensive estimate's sampling error it explains, at its own price.  Means of per-sample values
(:func:`control_variate_estimate`) and smooth functionals by the delta method [qian2018]
(:func:`control_variate_functional`); the sample split (:func:`optimal_ratio`, :func:`allocate`, with plain
Monte Carlo where the predicted gain is below :data:`MIN_GAIN`).  Pure numpy; ``docs/multifidelity.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = []


@dataclass(frozen=True)
class ControlVariateEstimate:
    """The result of :func:`control_variate_estimate`.

    Attributes
    ----------
    mean : the multi-fidelity estimate of ``E[Y]``.
    se : its standard error (same units as ``y``).
    plain_mean, plain_se : the estimate from the ``n`` expensive samples alone, and its standard error.
    weight : the control-variate weight ``alpha`` used.
    correlation : the sample correlation of ``y`` and ``x`` over the paired samples (NaN where either
        is constant).
    n_paired, n_cheap : expensive (paired) samples, and cheap samples behind the cheap mean
        (``math.inf`` where it is known exactly).
    """

    mean: float
    se: float
    plain_mean: float
    plain_se: float
    weight: float
    correlation: float
    n_paired: int
    n_cheap: float


def _influence_moments(psi_y, psi_x):
    """Sample variances and covariance (``ddof = 1``) of influence values along axis 0."""
    n = psi_y.shape[0]
    dy, dx = psi_y - psi_y.mean(axis=0), psi_x - psi_x.mean(axis=0)
    return (np.sum(dy * dy, axis=0) / (n - 1), np.sum(dx * dx, axis=0) / (n - 1), np.sum(dy * dx, axis=0) / (n - 1))


def control_variate_functional(value_y, influence_y, value_x, value_x_all, influence_x, n_cheap):
    r"""Control-variate estimate of a smooth functional of the expensive model's distribution (delta method).

    Parameters
    ----------
    value_y : float or ndarray
        The functional from the ``n`` expensive samples (e.g. their sample variance at each time).
    influence_y, influence_x : ndarray, shape (n, ...)
        The per-sample influence values of the expensive and of the cheap model on the paired samples.
    value_x, value_x_all : float or ndarray
        The cheap model's functional from its ``n`` paired samples and from all ``n_cheap`` of them.
    n_cheap : float
        Cheap samples behind ``value_x_all`` (``>= n``; ``math.inf`` where ``value_x_all`` is exact).

    Returns
    -------
    ControlVariateEstimate
        With array fields where the functional is an array (one estimate per trailing index).

    Notes
    -----
    A functional :math:`F` of the sample distribution is, to first order, the mean of its influence
    values :math:`\psi_i` (:math:`\hat F - F \approx \bar\psi`); a conditional mean
    :math:`F = E[v g] / E[v]` over the valid samples (``v`` = 1) has :math:`\psi_i = v_i (g_i - F) / \bar v`,
    a variance the same with :math:`g_i = (\theta_i - \mu)^2`.  The two-fidelity estimate and its variance
    are those of the mean (eq. (2.7) in [peherstorfer2016]) with the influence values in place of the samples ([qian2018], section 3):

    .. math:: \hat F = \hat F_y^{(n)} - \alpha (\hat F_x^{(n)} - \hat F_x^{(N)}), \quad
              \alpha = \frac{\widehat{\mathrm{cov}}(\psi_y, \psi_x)}{\widehat{\mathrm{var}}(\psi_x)}, \quad
              \mathrm{Var}\,\hat F \approx \frac{\mathrm{var}(\psi_y)}{n}\,[1 - (1 - n/N)\rho_\psi^2].

    Where ``influence_x`` or ``influence_y`` is constant (no information) the weight is 0 and the plain
    estimate is returned.
    """
    psi_y, psi_x = np.asarray(influence_y, dtype=float), np.asarray(influence_x, dtype=float)
    n = psi_y.shape[0]
    var_y, var_x, cov = _influence_moments(psi_y, psi_x)
    fraction = 1.0 if math.isinf(n_cheap) else 1.0 - n / n_cheap
    informative = (var_x > 0) & (var_y > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(informative, cov / np.where(informative, var_x, 1.0), 0.0)
        rho = np.where(informative, cov / np.sqrt(np.where(informative, var_x * var_y, 1.0)), np.nan)
    value_y = np.asarray(value_y, dtype=float)
    mean = value_y - alpha * (np.asarray(value_x, dtype=float) - np.asarray(value_x_all, dtype=float))
    plain_se = np.sqrt(var_y / n)
    rho2 = np.where(informative, np.minimum(np.nan_to_num(rho) ** 2, 1.0), 0.0)
    se = np.sqrt(np.maximum(var_y / n * (1.0 - fraction * rho2), 0.0))
    out = [mean, se, value_y, plain_se, alpha, rho]
    if value_y.ndim == 0:
        out = [float(a) for a in out]
    return ControlVariateEstimate(*out, n, n_cheap)


def conditional_mean_influence(g, valid=None):
    """``(value, influence)``: the mean of ``g`` ``(n, ...)`` over the ``valid`` samples (NaN without any) and ``psi_i = v_i (g_i - value) / mean(v)`` (section 3 of [qian2018])."""
    g = np.asarray(g, dtype=float)
    v = np.ones(g.shape[0], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    vv = v.reshape(v.shape + (1,) * (g.ndim - 1))
    k = int(v.sum())
    if k == 0:
        nan = np.full(g.shape[1:], np.nan)
        return nan, np.zeros_like(g)
    value = np.where(vv, g, 0.0).sum(axis=0) / k
    return value, np.where(vv, g - value, 0.0) * (g.shape[0] / k)


def variance_influence(theta, valid=None):
    r"""Ensemble variance [rad2] ``(n_t,)`` (``ddof = 1``, over the valid samples; NaN below two) of ``theta`` ``(n, n_t)`` and its influence values ``(n, n_t)``.

    Notes
    -----
    The influence of :math:`\sigma^2 = E[(\theta - \mu)^2]` is :math:`(\theta_i - \mu)^2 - \sigma^2` divided by
    the valid fraction [qian2018]: its variance over ``n`` is the engine's standard error to first order.
    """
    theta = np.asarray(theta, dtype=float)
    v = np.ones(theta.shape[0], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    k = int(v.sum())
    if k < 2:
        return np.full(theta.shape[1:], np.nan), np.zeros_like(theta)
    mu = theta[v].mean(axis=0)
    _, influence = conditional_mean_influence((theta - mu) ** 2, v)
    return np.sum((theta[v] - mu) ** 2, axis=0) / (k - 1), influence


def multifidelity_variance(theta_y, valid_y, theta_x, valid_x):
    """Two-fidelity estimate [rad2] ``(n_t,)`` of the expensive model's ensemble variance history.

    Notes
    -----
    :func:`control_variate_functional` with :func:`variance_influence` of the expensive histories ``theta_y``
    ``(n, n_t)`` and the cheap ``theta_x`` ``(N, n_t)`` (the first ``n`` rows on the same ground motions), each
    over its valid (neither overturned nor diverged) samples.
    """
    theta_y, theta_x = np.asarray(theta_y, dtype=float), np.asarray(theta_x, dtype=float)
    n = theta_y.shape[0]
    if theta_x.shape[0] < n or theta_x.shape[1:] != theta_y.shape[1:]:
        raise ValueError(f"parameter 'theta_x' must hold at least the {n} paired histories of 'theta_y' on the same "
                         f"times (got shape {theta_x.shape} against {theta_y.shape})")
    valid_x = np.asarray(valid_x, dtype=bool)
    value_y, psi_y = variance_influence(theta_y, valid_y)
    value_x, psi_x = variance_influence(theta_x[:n], valid_x[:n])
    value_x_all, _ = variance_influence(theta_x, valid_x)
    return control_variate_functional(value_y, psi_y, value_x, value_x_all, psi_x, theta_x.shape[0])


def multifidelity_probabilities(peak_y, overturned_y, valid_y, peak_x, overturned_x, valid_x, levels=()):
    """Two-fidelity ``[p_overturn, p_exceed(levels[0]), ...]`` [1] of the expensive model from paired per-sample peaks.

    Notes
    -----
    ``*_y`` ``(n,)``, ``*_x`` ``(N,)`` (the first ``n`` paired): peak ``|theta|`` [rad], overturned flags, valid
    samples.  Conditional means of the indicators over the valid samples (:func:`conditional_mean_influence`);
    an overturned sample exceeds every level.
    """
    peak_y, peak_x = np.asarray(peak_y, dtype=float), np.asarray(peak_x, dtype=float)
    n = peak_y.size
    if peak_x.size < n:
        raise ValueError(f"parameter 'peak_x' must hold at least the {n} paired samples of 'peak_y' "
                         f"(got {peak_x.size})")
    over_y, over_x = np.asarray(overturned_y, dtype=bool), np.asarray(overturned_x, dtype=bool)
    v_y, v_x = np.asarray(valid_y, dtype=bool), np.asarray(valid_x, dtype=bool)
    out = []
    for level in (None, *levels):
        with np.errstate(invalid="ignore"):
            g_y = over_y if level is None else over_y | (peak_y > level)
            g_x = over_x if level is None else over_x | (peak_x > level)
        value_y, psi_y = conditional_mean_influence(g_y.astype(float), v_y)
        value_x, psi_x = conditional_mean_influence(g_x[:n].astype(float), v_x[:n])
        value_x_all, _ = conditional_mean_influence(g_x.astype(float), v_x)
        out.append(control_variate_functional(value_y, psi_y, value_x, value_x_all, psi_x, peak_x.size))
    return out


def control_variate_estimate(y, x, x_extra=None, x_mean=None):
    r"""Control-variate (two-fidelity) estimate of the mean of the expensive model's quantity.

    Parameters
    ----------
    y, x : array_like, shape (n,)
        The expensive and the cheap model's per-sample values on the same ground motions.
    x_extra : array_like, shape (m,), optional
        The cheap model's values on further, independent ground motions (no expensive run).
    x_mean : float, optional
        The cheap model's exact expectation, where known; excludes ``x_extra``.

    Returns
    -------
    ControlVariateEstimate

    Notes
    -----
    With ``N = n + m`` cheap samples (mean :math:`\bar x_N`) the estimate is

    .. math:: \hat\mu = \bar y_n - \alpha (\bar x_n - \bar x_N),
              \qquad \alpha = \widehat{\mathrm{cov}}(x, y) / \widehat{\mathrm{var}}(x)

    with variance :math:`\sigma_y^2/n \, [1 - (1 - n/N) \rho^2]` at the optimal weight
    (eq. (2.7) in [peherstorfer2016]; :math:`N \to \infty` where ``x_mean`` is given: :math:`\sigma_y^2 (1-\rho^2)/n`,
    the classical control variate, section 4.1 of [glasserman2003]).  The weight is estimated from the same
    samples, which biases the estimate by O(1/n), far below its standard error at the sample counts
    used here (tested against the scatter over seeds).  Where the cheap values are constant over
    the paired samples (no information) the weight is 0 and the plain estimate is returned.
    """
    y = np.asarray(y, dtype=float).reshape(-1)
    x = np.asarray(x, dtype=float).reshape(-1)
    if y.size != x.size:
        raise ValueError(f"parameters 'y' and 'x' must be paired sample by sample (got {y.size} and {x.size} values)")
    if y.size < 3:
        raise ValueError(f"parameter 'y' must hold at least 3 paired samples (got {y.size})")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(x))):
        raise ValueError("parameters 'y' and 'x' must be finite (flag overturned or diverged samples by value first)")
    if x_mean is not None and x_extra is not None:
        raise ValueError("give either 'x_extra' (cheap samples) or 'x_mean' (the cheap model's exact mean), not both")
    n = y.size
    if x_mean is not None:
        mu_x, n_cheap = float(x_mean), math.inf
    else:
        extra = np.zeros(0) if x_extra is None else np.asarray(x_extra, dtype=float).reshape(-1)
        if not np.all(np.isfinite(extra)):
            raise ValueError("parameter 'x_extra' must be finite")
        n_cheap = n + extra.size
        mu_x = float((x.sum() + extra.sum()) / n_cheap)
    return control_variate_functional(y.mean(), y - y.mean(), x.mean(), mu_x, x - x.mean(), n_cheap)


#: Largest cheap-to-expensive sample ratio :func:`optimal_ratio` returns (a perfectly correlated
#: pilot would ask for infinitely many cheap samples; a pilot's correlation of 1 is never exact).
MAX_RATIO = 1000.0


def optimal_ratio(correlation, cost_expensive, cost_cheap, max_ratio=MAX_RATIO):
    r"""Cheap samples per expensive sample that minimise the variance at a fixed budget.

    Units: ``correlation`` in [-1, 1], ``cost_expensive``, ``cost_cheap`` [s].

    Returns: ``r = N / n`` in ``[1, max_ratio]``; ``1.0`` means the cheap model is not worth running beyond
    the paired samples (and :func:`speedup` then says whether it is worth running at all).

    Notes
    -----
    :math:`r^* = \sqrt{c_1 \rho^2 / (c_2 (1 - \rho^2))}` (eq. (3.11) in [peherstorfer2016] for two models), where
    :math:`c_1, c_2` are the costs of the expensive and the cheap model.
    """
    rho2 = min(float(correlation) ** 2, 1.0 - 1e-12)
    if not (cost_expensive > 0 and cost_cheap > 0):
        raise ValueError("parameters 'cost_expensive' and 'cost_cheap' must be > 0 [s]")
    return min(max_ratio, max(1.0, math.sqrt(cost_expensive * rho2 / (cost_cheap * (1.0 - rho2)))))


def speedup(correlation, cost_expensive, cost_cheap, ratio=None):
    r"""CPU of plain Monte Carlo over that of the two-fidelity estimate at equal standard error (> 1: the cheap model pays).

    Notes
    -----
    Per expensive sample the two-fidelity estimate costs :math:`c_1 + r c_2` for the variance
    :math:`\sigma^2 [1 - (1 - 1/r) \rho^2]` (``r``: ``ratio``, default :func:`optimal_ratio`); plain Monte
    Carlo costs :math:`c_1` for :math:`\sigma^2` [peherstorfer2016].
    """
    r = optimal_ratio(correlation, cost_expensive, cost_cheap) if ratio is None else float(ratio)
    rho2 = min(float(correlation) ** 2, 1.0)
    variance_factor = 1.0 - (1.0 - 1.0 / r) * rho2
    return cost_expensive / ((cost_expensive + r * cost_cheap) * variance_factor)


#: The cheap model runs beyond its paired pilot samples only where the predicted :func:`speedup` from
#: the pilot's correlation and costs is at least this (the margin covers the pilot's error in the
#: correlation: about ``(1 - rho^2) / sqrt(n)``, 0.024 at ``rho = 0.9`` and 64 pilot samples).
MIN_GAIN = 1.2


@dataclass(frozen=True)
class Allocation:
    """The result of :func:`allocate`.

    Attributes
    ----------
    estimator : ``"multifidelity"`` or ``"plain"`` (plain Monte Carlo of the expensive model).
    n_expensive, n_cheap : samples of each model (``n_cheap`` 0 for ``"plain"``; else ``>= n_expensive``,
        the first ``n_expensive`` paired).
    ratio : cheap samples per expensive one (1 for ``"plain"``).
    gain : predicted CPU of plain Monte Carlo over this allocation's at equal standard error.
    """

    estimator: str
    n_expensive: int
    n_cheap: int
    ratio: float
    gain: float


def allocate(correlation, cost_expensive, cost_cheap, n_plain, min_gain=MIN_GAIN, max_ratio=MAX_RATIO):
    r"""Samples of the expensive and the cheap model for the standard error of ``n_plain`` plain samples.

    Returns an :class:`Allocation` from the pilot ``correlation`` of the two models' influence values (in
    [-1, 1]; NaN: plain) and their costs per sample ``cost_expensive``, ``cost_cheap`` [s].

    Notes
    -----
    With ``r`` from :func:`optimal_ratio`, the two-fidelity variance per expensive sample is
    :math:`\sigma^2 [1 - (1 - 1/r) \rho^2]`, so ``n = ceil(n_plain [1 - (1 - 1/r) rho^2])`` expensive and
    ``ceil(r n)`` cheap samples give the plain standard error.  Rule: plain Monte Carlo (``n_plain``
    samples, no cheap run beyond the pilot) unless the predicted speed-up is at least ``min_gain``; the
    estimator is then never planned worse than plain Monte Carlo.
    """
    n_plain = int(n_plain)
    if not (cost_expensive > 0 and cost_cheap > 0):
        raise ValueError("parameters 'cost_expensive' and 'cost_cheap' must be > 0 [s]")
    if not math.isfinite(correlation):
        return Allocation("plain", n_plain, 0, 1.0, 1.0)
    r = optimal_ratio(correlation, cost_expensive, cost_cheap, max_ratio)
    gain = speedup(correlation, cost_expensive, cost_cheap, r)
    if gain < min_gain:
        return Allocation("plain", n_plain, 0, 1.0, 1.0)
    rho2 = min(float(correlation) ** 2, 1.0)
    n = max(3, math.ceil(n_plain * (1.0 - (1.0 - 1.0 / r) * rho2)))
    return Allocation("multifidelity", n, max(n, math.ceil(r * n)), r, gain)


def cost_ratio_needed(correlation, target_speedup):
    r"""Expensive-to-cheap cost ratio at which the two-fidelity estimate reaches ``target_speedup``.

    Units: ``correlation`` in [-1, 1].

    Returns: ``c_expensive / c_cheap`` [1]; ``math.inf`` where no cost ratio reaches it (``target_speedup >=
    1 / (1 - rho^2)``, the speed-up of free cheap samples).

    Notes
    -----
    At the optimal ratio the cost times the variance per expensive sample is
    :math:`(\sqrt{c_1 (1 - \rho^2)} + \rho \sqrt{c_2})^2` ([1], section 3.4), so the speed-up is
    :math:`S = 1 / (\sqrt{1 - \rho^2} + \rho / \sqrt{w})^2` with :math:`w = c_1 / c_2`, and
    :math:`w = \rho^2 / (S^{-1/2} - \sqrt{1 - \rho^2})^2`.  (Without the bound :data:`MAX_RATIO`
    and where the optimal ratio exceeds 1.)
    """
    rho = abs(float(correlation))
    if not target_speedup > 1:
        raise ValueError(f"parameter 'target_speedup' must be > 1 (got {target_speedup!r})")
    gap = 1.0 / math.sqrt(target_speedup) - math.sqrt(max(1.0 - rho * rho, 0.0))
    return math.inf if gap <= 0 else rho * rho / (gap * gap)
