"""Multi-fidelity Monte Carlo: a cheap model run on the same ground motions as the expensive one.

The coupled model is the judge, and it is expensive; a cheap model (the condensed model, the
stiff-bed model, or any model whose expectation is known) run on the *same* ground-motion samples is
correlated with it sample by sample.  Used as a control variate it removes the part of the coupled
estimate's sampling error that the cheap model explains, at the cheap model's price:

* :func:`control_variate_estimate` — the estimate of ``E[Y]`` from ``n`` paired samples ``(y, x)``
  and the cheap model's mean from ``N >= n`` samples (or known exactly), with its standard error;
* :func:`optimal_ratio` — how many cheap samples per expensive one minimise the variance at a
  given cost (and whether the cheap model is worth running at all);
* :func:`speedup` — CPU saved at equal standard error against plain Monte Carlo of the expensive
  model alone.

Pure functions on numpy arrays; no model is run here.  The quantities are means of per-sample
values: an exceedance probability is the mean of the indicator ``peak |theta| > a`` (overturned
samples count as exceeding), the probability of overturning the mean of the overturned flags.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ControlVariateEstimate", "control_variate_estimate", "optimal_ratio", "speedup"]


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


def _moments(y, x):
    n = y.size
    ym, xm = y.mean(), x.mean()
    var_y = float(np.sum((y - ym) ** 2) / (n - 1))
    var_x = float(np.sum((x - xm) ** 2) / (n - 1))
    cov = float(np.sum((y - ym) * (x - xm)) / (n - 1))
    return float(ym), float(xm), var_y, var_x, cov


def control_variate_estimate(y, x, x_extra=None, x_mean=None):
    """Control-variate (two-fidelity) estimate of the mean of the expensive model's quantity.

    Parameters
    ----------
    y : array_like, shape (n,)
        The expensive model's per-sample values (e.g. ``1.0`` where sample ``i`` exceeds the level).
    x : array_like, shape (n,)
        The cheap model's values on the same ground motions, sample by sample.
    x_extra : array_like, shape (m,), optional
        The cheap model's values on further, independent ground motions (no expensive run).
    x_mean : float, optional
        The cheap model's exact expectation, where it is known (e.g. the linearization's Gaussian on
        a linear bed); excludes ``x_extra``.

    Returns
    -------
    ControlVariateEstimate

    Notes
    -----
    With ``N = n + m`` cheap samples (mean :math:`\\bar x_N`) the estimate is

    .. math:: \\hat\\mu = \\bar y_n - \\alpha (\\bar x_n - \\bar x_N),
              \\qquad \\alpha = \\widehat{\\mathrm{cov}}(x, y) / \\widehat{\\mathrm{var}}(x)

    with variance :math:`\\sigma_y^2/n \\, [1 - (1 - n/N) \\rho^2]` at the optimal weight
    (eq. (2.7) in [1]; :math:`N \\to \\infty` where ``x_mean`` is given: :math:`\\sigma_y^2 (1-\\rho^2)/n`,
    the classical control variate, section 4.1 of [2]).  The weight is estimated from the same
    samples, which biases the estimate by O(1/n), far below its standard error at the sample counts
    used here (tested against the scatter over seeds).  Where the cheap values are constant over
    the paired samples (no information) the weight is 0 and the plain estimate is returned.

    References
    ----------
    .. [1] B. Peherstorfer, K. Willcox, M. Gunzburger, "Optimal model management for multifidelity
       Monte Carlo estimation", SIAM J. Sci. Comput. 38(5), A3163-A3194, 2016.
    .. [2] P. Glasserman, "Monte Carlo Methods in Financial Engineering", Springer, 2003.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=200); y = x + 0.1 * rng.normal(size=200)
    >>> est = control_variate_estimate(y, x, x_mean=0.0)
    >>> bool(est.se < 0.2 * est.plain_se)
    True
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
    ym, xm, var_y, var_x, cov = _moments(y, x)
    plain_se = math.sqrt(var_y / n)
    if x_mean is not None:
        mu_x, n_cheap, fraction = float(x_mean), math.inf, 1.0
    else:
        extra = np.zeros(0) if x_extra is None else np.asarray(x_extra, dtype=float).reshape(-1)
        if not np.all(np.isfinite(extra)):
            raise ValueError("parameter 'x_extra' must be finite")
        n_cheap = n + extra.size
        mu_x = float((x.sum() + extra.sum()) / n_cheap)
        fraction = 1.0 - n / n_cheap
    if var_x <= 0.0 or var_y <= 0.0:
        return ControlVariateEstimate(ym, plain_se, ym, plain_se, 0.0, math.nan, n, n_cheap)
    alpha = cov / var_x
    rho = cov / math.sqrt(var_x * var_y)
    mean = ym - alpha * (xm - mu_x)
    var = var_y / n * (1.0 - fraction * rho * rho)
    return ControlVariateEstimate(mean, math.sqrt(max(var, 0.0)), ym, plain_se, alpha, rho, n, n_cheap)


#: Largest cheap-to-expensive sample ratio :func:`optimal_ratio` returns (a perfectly correlated
#: pilot would ask for infinitely many cheap samples; a pilot's correlation of 1 is never exact).
MAX_RATIO = 1000.0


def optimal_ratio(correlation, cost_expensive, cost_cheap, max_ratio=MAX_RATIO):
    """Cheap samples per expensive sample that minimise the variance at a fixed budget.

    Parameters
    ----------
    correlation : float
        Correlation of the two models' per-sample values (from a pilot), in [-1, 1].
    cost_expensive, cost_cheap : float
        CPU seconds per sample of each model [s], > 0.
    max_ratio : float
        Upper bound of the result (default :data:`MAX_RATIO`).

    Returns
    -------
    float
        ``r = N / n`` in ``[1, max_ratio]``; ``1.0`` means the cheap model is not worth running beyond the paired samples
        (and :func:`speedup` then says whether it is worth running at all).

    Notes
    -----
    :math:`r^* = \\sqrt{c_1 \\rho^2 / (c_2 (1 - \\rho^2))}` (eq. (3.11) in [1] for two models), where
    :math:`c_1, c_2` are the costs of the expensive and the cheap model.

    References
    ----------
    .. [1] B. Peherstorfer, K. Willcox, M. Gunzburger, SIAM J. Sci. Comput. 38(5), A3163-A3194, 2016.
    """
    rho2 = min(float(correlation) ** 2, 1.0 - 1e-12)
    if not (cost_expensive > 0 and cost_cheap > 0):
        raise ValueError("parameters 'cost_expensive' and 'cost_cheap' must be > 0 [s]")
    return min(max_ratio, max(1.0, math.sqrt(cost_expensive * rho2 / (cost_cheap * (1.0 - rho2)))))


def speedup(correlation, cost_expensive, cost_cheap, ratio=None):
    """CPU of plain Monte Carlo divided by the CPU of the two-fidelity estimate at equal standard error.

    Parameters
    ----------
    correlation : float
        Correlation of the two models' per-sample values, in [-1, 1].
    cost_expensive, cost_cheap : float
        CPU seconds per sample [s].
    ratio : float, optional
        Cheap samples per expensive sample (default :func:`optimal_ratio`).

    Returns
    -------
    float
        > 1 where the cheap model pays for itself; below 1 the plain estimate is the better buy.

    Notes
    -----
    Per expensive sample the two-fidelity estimate costs :math:`c_1 + r c_2` and has the variance
    :math:`\\sigma^2 [1 - (1 - 1/r) \\rho^2]`; plain Monte Carlo costs :math:`c_1` for :math:`\\sigma^2`.
    """
    r = optimal_ratio(correlation, cost_expensive, cost_cheap) if ratio is None else float(ratio)
    rho2 = min(float(correlation) ** 2, 1.0)
    variance_factor = 1.0 - (1.0 - 1.0 / r) * rho2
    return cost_expensive / ((cost_expensive + r * cost_cheap) * variance_factor)
