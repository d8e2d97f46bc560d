"""Fragility post-processing: probability that |theta| exceeds a rotation during the record.

From the Gaussian moments of the linearization by the up-crossing approximation (Rice's rate of the
non-stationary pair ``(theta, theta')`` [rice1944], Poisson or Vanmarcke's clumping [vanmarcke1975]), from
Monte Carlo as the fraction of samples beyond the threshold, and a lognormal fragility curve
``P(IM) = Phi(ln(IM / median) / beta)`` fitted over a swept intensity [baker2015].  The xarray accessor
``ds.rocking`` works on every result the package returns and reads the stored ``theta_ul`` and
``slenderness``: nothing here recomputes the model.  Method and checks: ``docs/method.md#fragility``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import xarray as xr
from scipy import optimize, special

from screening.solvers import schema
from screening.core.model.block import Block
from screening.solvers.datasets import finish
from screening.solvers.outputs import OUTPUTS
from screening.solvers.schema import cf
from screening.analysis.trust import OVERTURN_LIMIT
from screening.core.status import BestMethod, FitFlag, PointStatus, SampleState, Trust, ProbabilitySource

__all__ = ["upcrossing_rate", "vanmarcke_factor", "exceedance_probability_from_moments", "linearized_exceedance",
           "mcs_exceedance_probability", "lognormal_fragility", "fit_binomial_fragility", "total_dispersion",
           "with_modelling_dispersion", "fit_lognormal_fragility", "fit_fragility_curve", "RELATIVE_TO",
           "threshold_angle", "exceedance_probability", "fragility_curve", "best_exceedance", "fragility_dataset",
           "RockingAccessor"]

#: The variables of a fragility dataset and of the sweep's best probabilities, declared here (found by name).
FRAGILITY = schema.declare("fragility", {
    "p_exceed": dict(OUTPUTS["p_exceed"].attrs),
    "p_exceed_at_spot": cf("1", "Gaussian probability that |theta| exceeds the threshold, at the spot point"),
    "mcs_p_exceed": cf("1", "probability that |theta| exceeds the threshold, from the Monte Carlo peaks"),
    "mcs_p_exceed_se": cf("1", "standard error of mcs_p_exceed (binomial)"),
    "threshold_rad": cf("rad", "rotation threshold"),
    "best_p_exceed": cf("1", "probability that |theta| exceeds the threshold from the best estimates (Monte Carlo "
                             "where it ran, else the Gaussian up-crossing of the corrected moments)"),
    "best_p_exceed_low": cf("1", "lower end of the band of best_p_exceed (2 standard errors)"),
    "best_p_exceed_high": cf("1", "upper end of the band of best_p_exceed (2 standard errors)"),
    "beta": cf("1", "lognormal dispersion beta of the fragility curve"),
    "fit_median": {"long_name": "median of the lognormal fragility curve (units of the intensity it is fitted over)"},
    "fit_flag": schema.FIT_FLAG,
    "fit_n_unvouched": cf("1", "points of the curve left out of the fit: nothing vouches for their value (untrusted "
                              "or stopped linearization without a best estimate or Monte Carlo)"),
    "fit_im_min": {"long_name": "lowest vouched intensity of the curve (units of the intensity it is fitted over)"},
    "fit_im_max": {"long_name": "highest vouched intensity of the curve (units of the intensity it is fitted over)"},
    "fit_median_se": {"long_name": "standard error of fit_median from the standard errors of the fitted points "
                                   "(units of the intensity it is fitted over)"},
    "beta_se": cf("1", "standard error of beta from the standard errors of the fitted points"),
}, prefix=None)

_SQRT_2PI = np.sqrt(2.0 * np.pi)

#: ``method`` of a probability a sweep stored with its ``p_source`` (:func:`stored_exceedance`).
STORED = "stored (p_source)"


def _phi(x):
    return np.exp(-0.5 * x * x) / _SQRT_2PI


def _Phi(x):
    return 0.5 * special.erfc(-x / np.sqrt(2.0))


def upcrossing_rate(var_theta, var_theta_dot, cov_theta_theta_dot, level):
    """Mean rate [s-1] of outward crossings of ``|theta| = level`` (Rice, both barriers).

    Parameters
    ----------
    var_theta : array_like
        Variance of the rotation [rad2].
    var_theta_dot : array_like
        Variance of the rotation rate [rad2 s-2].
    cov_theta_theta_dot : array_like
        Their covariance [rad2 s-1].
    level : array_like
        Barrier ``a`` [rad] > 0.

    Returns
    -------
    numpy.ndarray
        ``nu`` [s-1], broadcast over the arguments; zero where ``var_theta = 0``.

    Notes
    -----
    Rice's formula [2] for a zero-mean Gaussian ``(theta, theta')`` with the moments the linearization
    carries (eq. (44) in [1]): ``nu = 2 p(a) E[(theta')^+ | theta = a]`` with ``p(a)`` the Gaussian density of
    ``theta`` at ``a`` and the conditional velocity of mean ``a cov / var_theta`` and variance
    ``var_theta_dot - cov^2 / var_theta``.

    References
    ----------
    [1] [mitseas2026]; [2] [rice1944].

    Examples
    --------
    >>> nu = upcrossing_rate(1e-6, 1e-2, 0.0, 1e-3)
    >>> bool(np.isclose(nu, np.sqrt(1e-2 / 1e-6) / np.pi * np.exp(-0.5)))
    True
    """
    v = np.asarray(var_theta, dtype=float)
    vd = np.asarray(var_theta_dot, dtype=float)
    c = np.asarray(cov_theta_theta_dot, dtype=float)
    a = np.asarray(level, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        pos = v > 0
        vs = np.where(pos, v, 1.0)
        p_a = np.exp(-0.5 * a * a / vs) / (_SQRT_2PI * np.sqrt(vs))
        mu = a * c / vs
        s = np.sqrt(np.maximum(vd - c * c / vs, 0.0))
        ss = np.where(s > 0, s, 1.0)
        mean_outward = np.where(s > 0, s * _phi(mu / ss) + mu * _Phi(mu / ss), np.maximum(mu, 0.0))
        rate = 2.0 * p_a * mean_outward
    return np.where(pos, rate, 0.0) + 0.0 * a


def oscillator_bandwidth(zeta):
    """Spectral bandwidth ``delta`` [1] of a white-noise driven linear oscillator.

    Parameters
    ----------
    zeta : array_like
        Damping ratio [1], 0 < zeta < 1.

    Returns
    -------
    numpy.ndarray
        ``delta = sqrt(1 - lambda_1^2 / (lambda_0 lambda_2))`` [1] of the oscillator's response spectrum.

    Notes
    -----
    In closed form ``1 - delta^2 = (1 - (2/pi) atan(zeta / sqrt(1 - zeta^2)))^2 / (1 - zeta^2)`` [vanmarcke1975]; the
    bandwidth of the linearized rocking response (eq. (26) in [mitseas2026]) enters :func:`vanmarcke_factor`.
    """
    z = np.clip(np.asarray(zeta, dtype=float), 1e-12, 1 - 1e-12)
    q = np.sqrt(1.0 - z * z)
    ratio = (1.0 - 2.0 / np.pi * np.arctan(z / q)) ** 2 / (1.0 - z * z)
    return np.sqrt(np.clip(1.0 - ratio, 0.0, 1.0))


def vanmarcke_factor(var_theta, level, bandwidth):
    """Vanmarcke's clumping correction [3] to the double-barrier Poisson rate.

    Parameters
    ----------
    var_theta : array_like
        Variance of the rotation [rad2].
    level : array_like
        Barrier ``a`` [rad] > 0.
    bandwidth : array_like
        Spectral bandwidth ``delta`` [1] of the response (:func:`oscillator_bandwidth`).

    Returns
    -------
    numpy.ndarray
        ``(1 - exp(-sqrt(pi/2) delta^1.2 r)) / (1 - exp(-r^2 / 2))`` [1], ``r = a / sigma_theta``; zero where
        ``var_theta = 0``.

    Notes
    -----
    The factor of [3] that corrects the Poisson rate of :func:`upcrossing_rate` for crossings in clumps of
    a narrow-band response (the linearized rocking response of eq. (26) in [1]); ``delta^1.2`` is
    Vanmarcke's empirical exponent.

    References
    ----------
    [1] [mitseas2026]; [2] [rice1944]; [3] [vanmarcke1975].

    Examples
    --------
    >>> f"{float(vanmarcke_factor(1e-6, 2e-3, 0.2)):.4f}"
    '0.3523'
    """
    v = np.asarray(var_theta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.asarray(level, dtype=float) / np.sqrt(np.where(v > 0, v, np.nan))
        num = -np.expm1(-np.sqrt(np.pi / 2.0) * np.asarray(bandwidth, dtype=float) ** 1.2 * r)
        den = -np.expm1(-0.5 * r * r)
        factor = np.where(den > 0, num / den, 1.0)
    return np.where(v > 0, factor, 0.0)


def exceedance_probability_from_moments(t, var_theta, var_theta_dot, cov_theta_theta_dot, level,
                                        method="vanmarcke", bandwidth=None, axis=-1):
    """``P(max_t |theta| > level)`` [1] over the record sampled at times ``t`` [s].

    Parameters
    ----------
    t : array_like
        Output times [s], along ``axis``.
    var_theta, var_theta_dot, cov_theta_theta_dot : array_like
        Moments of the rotation [rad2], the rotation rate [rad2 s-2] and their covariance [rad2 s-1].
    level : array_like
        Barrier ``a`` [rad] > 0.
    method : {"vanmarcke", "poisson"}
        Clumped (Vanmarcke) or independent (Poisson) crossings.
    bandwidth : array_like, optional
        Bandwidth ``delta`` [1] of the equivalent oscillator; required with ``"vanmarcke"``.
    axis : int
        The time axis of the moments.

    Returns
    -------
    numpy.ndarray
        The probability [1]; ``ValueError`` for a bad ``method`` or a missing ``bandwidth``.

    Notes
    -----
    The hazard ``h(t) = nu(a, t)`` (Poisson) or ``nu(a, t) F_V(t)`` (Vanmarcke's clumping factor)
    is integrated by the trapezoidal rule: ``P = 1 - exp(-int_0^T h dt)``.

    References
    ----------
    [1] [mitseas2026]; [2] [vanmarcke1975].

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 11)
    >>> ones = np.ones_like(t)
    >>> p = exceedance_probability_from_moments(t, 1e-6 * ones, 1e-2 * ones, 0 * ones, 3e-3, method="poisson")
    >>> bool(np.isclose(p, -np.expm1(-10.0 * upcrossing_rate(1e-6, 1e-2, 0.0, 3e-3))))
    True
    """
    rate = upcrossing_rate(var_theta, var_theta_dot, cov_theta_theta_dot, level)
    if method == "vanmarcke":
        if bandwidth is None:
            raise ValueError("parameter 'bandwidth' is required with method='vanmarcke'")
        rate = rate * vanmarcke_factor(var_theta, level, bandwidth)
    elif method != "poisson":
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    return -np.expm1(-np.trapezoid(rate, np.asarray(t, dtype=float), axis=axis))


def band_standard_error(p, p_low, p_high):
    """Standard error [1] of a linearization's Gaussian probability from its values at the two ends of the
    point's trust band, bounded below where the trust rule cannot vouch for a smaller one.

    Parameters
    ----------
    p : array_like
        The probability at the point's moments [1].
    p_low, p_high : array_like
        The probability with the moments at the two ends of the band (standing for two standard errors
        each way) [1].

    Returns
    -------
    numpy.ndarray
        ``max(|p_high - p_low| / 4, (OVERTURN_LIMIT - p) / 2)`` [1]; NaN where an input is NaN.

    Notes
    -----
    The band's quarter alone vanishes where the Gaussian tail underflows (both ends 0), and is far below
    what the trust rule checked wherever the tail is small: a trusted cell admits calibration points whose
    Monte Carlo overturned up to :data:`screening.analysis.trust.OVERTURN_LIMIT` of its samples
    (``docs/outputs_probabilities.md``, ``docs/trust.md``), and an overturned sample exceeds every threshold.
    So the standard error is at least
    ``(OVERTURN_LIMIT - p) / 2``: ``p + 2 se`` reaches that fraction, as the Agresti-Coull ``p + 2 se`` of a
    Monte Carlo without an overturned sample reaches about ``3 / n``.
    """
    p, p_low, p_high = (np.asarray(a, dtype=float) for a in (p, p_low, p_high))
    return np.maximum(np.abs(p_high - p_low) / 4.0, (OVERTURN_LIMIT - p) / 2.0)


def linearized_exceedance(t, var_theta, var_theta_dot, cov_theta_theta_dot, c_eq, k_eq, m_sdof, status, level,
                          method="vanmarcke"):
    """``P(max_t |theta| > level)`` [1] of each point from the linearization's plain arrays.

    What :func:`exceedance_probability` gives on a dataset of the same points, without building one.

    Parameters
    ----------
    t : array_like
        Output times [s].
    var_theta, var_theta_dot, cov_theta_theta_dot : array_like
        The Gaussian moments on ``(points, t)`` [rad2, rad2 s-2, rad2 s-1]; NaN read as 0.
    c_eq, k_eq : array_like
        Equivalent damping [N m s rad-1] and stiffness [N m rad-1] on ``(points, t)``.
    m_sdof : array_like
        Rocking inertia per point [kg m2].
    status : array_like of int
        :class:`~screening.core.status.PointStatus` per point.
    level : array_like
        Threshold per point [rad].
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation; Vanmarcke's bandwidth follows from the equivalent damping ratio
        ``c_eq / (2 sqrt(k_eq m_sdof))`` (0.05 where undefined).

    Returns
    -------
    numpy.ndarray
        Probability per point [1]; NaN at every point that is not ``ok``: where the linearized model
        stopped near toppling (``k_eq_negative``, ``sigma_theta_beyond_slenderness``) nothing vouches for a
        number (only Monte Carlo answers there), and where it failed.

    Notes
    -----
    With the Poisson assumption, ``P = 1 - exp(-int_0^T 2 nu+(t) exp(-a^2 / (2 var_theta)) dt)``,
    ``nu+ = sqrt(var_theta_dot var_theta - cov^2) / (2 pi var_theta)`` [2]; the variances are those of
    the Lyapunov equation, eq. (45) in [1].

    References
    ----------
    [1] [mitseas2026]; [2] [vanmarcke1975].

    Examples
    --------
    Stationary moments (sigma 0.01 rad, sigma_dot 0.1 rad/s) over 10 s, level 3 sigma: Poisson gives
    ``1 - exp(-10 x 2 x 1.59 x exp(-4.5)) = 0.298``; a point with ``k_eq_negative`` gets NaN:

    >>> t = np.linspace(0.0, 10.0, 101)
    >>> ones = np.ones((2, t.size))
    >>> p = linearized_exceedance(t, 1e-4 * ones, 1e-2 * ones, 0 * ones, 0.1 * ones, 10.0 * ones,
    ...                           np.ones(2), [0, 1], np.full(2, 0.03), method="poisson")
    >>> np.round(p, 3).tolist()
    [0.298, nan]
    """
    if method not in ("poisson", "vanmarcke"):
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    moments = [np.where(np.isnan(a), 0.0, a) for a in (np.asarray(var_theta, dtype=float),
                                                      np.asarray(var_theta_dot, dtype=float),
                                                      np.asarray(cov_theta_theta_dot, dtype=float))]
    level = np.broadcast_to(np.asarray(level, dtype=float)[:, None], moments[0].shape)
    bandwidth = None
    if method == "vanmarcke":
        k_eq = np.asarray(k_eq, dtype=float)
        zeta = np.asarray(c_eq, dtype=float) / (2.0 * np.sqrt(np.where(k_eq > 0, k_eq, np.nan)
                                                               * np.asarray(m_sdof, dtype=float)[:, None]))
        bandwidth = oscillator_bandwidth(np.where(np.isnan(zeta), 0.05, zeta))
    p = exceedance_probability_from_moments(t, *moments, level, method=method, bandwidth=bandwidth)
    return np.where(np.asarray(status) == PointStatus.ok, p, np.nan)


def mcs_exceedance_probability(peak_abs_theta, level, overturned=None):
    """Fraction of Monte Carlo samples whose peak ``|theta|`` exceeds a level, with its standard error.

    Parameters
    ----------
    peak_abs_theta : array_like
        Per-sample peak ``|theta|`` [rad].
    level : float
        Rotation [rad].
    overturned : array_like, optional
        Per-sample overturning flags (bool); overturned samples count as exceedances.

    Returns
    -------
    p : float
        The fraction [1].
    standard_error : float
        Its binomial standard error ``sqrt(p (1 - p) / n)`` [1].

    Notes
    -----
    The Monte Carlo reference of :func:`exceedance_probability_from_moments`, from the samples of the
    equations of motion (eqs. (7)-(8) or (22) in [1]).

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> mcs_exceedance_probability([1e-3, 3e-3, 5e-3, 0.0], 2e-3, overturned=[False, False, False, True])
    (0.75, 0.21650635094610965)
    """
    peaks = np.asarray(peak_abs_theta, dtype=float)
    hit = peaks > level
    if overturned is not None:
        hit = hit | np.asarray(overturned, dtype=bool)
    n = hit.size
    p = hit.mean()
    return float(p), float(np.sqrt(max(p * (1 - p), 0.0) / n))


def lognormal_fragility(intensity, median, beta):
    """Lognormal fragility curve ``Phi(ln(intensity / median) / beta)`` [1].

    Parameters
    ----------
    intensity : array_like
        Intensity measure [its units] > 0.
    median : float or array_like
        Median capacity [units of the intensity].
    beta : float or array_like
        Logarithmic standard deviation (dispersion) [1].

    Returns
    -------
    numpy.ndarray
        Probability of exceedance [1].

    Notes
    -----
    The standard form of [2], eq. (1); fitted to the exceedance probabilities of the linearization
    (eqs. (44)-(45) of [1] through :func:`exceedance_probability_from_moments`) or of Monte Carlo.

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    >>> [f"{p:.4f}" for p in lognormal_fragility([0.5, 1.0, 2.0], 1.0, 0.4)]
    ['0.0416', '0.5000', '0.9584']
    """
    return _Phi(np.log(np.asarray(intensity, dtype=float) / median) / beta)


def binomial_nll(log_median, log_beta, intensity, n_exceed, n_total):
    """Negative log-likelihood [1] of stripes of exceedances under a lognormal fragility.

    Parameters
    ----------
    log_median : float
        ``ln median`` [ln of the intensity's units].
    log_beta : float
        ``ln beta`` [1].
    intensity : array_like
        Intensity of each stripe [its units] > 0.
    n_exceed : array_like
        Exceedances at each intensity [1].
    n_total : array_like
        Trials at each intensity [1].

    Returns
    -------
    float
        ``-sum(z ln p + (n - z) ln(1 - p))`` [1] with ``p`` of :func:`lognormal_fragility` (the binomial
        coefficients left out).

    Notes
    -----
    The likelihood of [baker2015], eq. (11), on the log scale of its parameters, minimised by
    :func:`fit_binomial_fragility`; the exceedances come from the samples of the equations of motion of [mitseas2026].
    """
    p = np.clip(lognormal_fragility(intensity, np.exp(log_median), np.exp(log_beta)), 1e-300, 1.0)
    q = np.clip(1.0 - lognormal_fragility(intensity, np.exp(log_median), np.exp(log_beta)), 1e-300, 1.0)
    return -float(np.sum(n_exceed * np.log(p) + (n_total - n_exceed) * np.log(q)))


#: Relative standard error of beta from which the data are said not to determine it.
BETA_UNIDENTIFIED = 1.0


def fit_flag_of(intensity, median, beta, beta_se=np.nan):
    """Whether a fitted lognormal fragility is one the data support: :class:`~screening.core.status.FitFlag`.

    Parameters
    ----------
    intensity : array_like
        The intensities of the points the curve was fitted to [IM units].
    median : float
        The fitted median [IM units].
    beta : float
        The fitted dispersion [1].
    beta_se : float, optional
        Its standard error [1] (NaN: unknown).

    Returns
    -------
    screening.core.status.FitFlag
        ``not_identified`` where median or beta is not finite or ``beta_se >= BETA_UNIDENTIFIED beta``,
        ``non_positive_beta`` where ``beta <= 0``, ``median_outside_data`` where the median lies outside
        the intensities, else ``ok``.
    """
    im = np.asarray(intensity, dtype=float).ravel()
    im = im[np.isfinite(im)]
    if not (np.isfinite(median) and np.isfinite(beta)) or (np.isfinite(beta_se) and beta_se >= BETA_UNIDENTIFIED
                                                              * abs(beta)):
        return FitFlag.not_identified
    if beta <= 0:
        return FitFlag.non_positive_beta
    if im.size == 0 or not im.min() <= median <= im.max():
        return FitFlag.median_outside_data
    return FitFlag.ok


def fit_binomial_fragility(intensity, n_exceed, n_total):
    """Maximum-likelihood lognormal fragility of stripes of trials, with standard errors.

    Parameters
    ----------
    intensity : array [units of the IM], > 0, the level of each stripe.
    n_exceed, n_total : arrays [1], exceedances and trials (records) at each level (``n_total``
        broadcasts).

    Returns
    -------
    dict with ``median`` [IM units], ``beta`` [1], their standard errors ``median_se``, ``beta_se``
    (NaN where the information matrix is singular: perfectly separated stripes), ``n_trials`` and
    ``flag`` (:class:`~screening.core.status.FitFlag`): ``separated`` where every stripe is all or nothing,
    ``not_identified`` with fewer than two levels or a beta the information does not determine,
    ``non_positive_beta``, ``median_outside_data`` (:func:`fit_flag_of`), else ``ok``: only an ``ok`` fit
    is an answer.

    Notes
    -----
    The likelihood is ``prod_j C(n_j, z_j) p_j^z_j (1 - p_j)^(n_j - z_j)``, ``p_j = Phi(ln(x_j / median)
    / beta)`` ([2], eq. (11)), maximised over ``(ln median, ln beta)`` by Nelder-Mead.  The standard
    errors come from the observed information: the inverse of the Hessian of the negative
    log-likelihood at the optimum (central differences in ``(ln median, ln beta)``), carried to
    ``median`` and ``beta`` by the delta method (``se(median) = median se(ln median)``).

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    >>> fit = fit_binomial_fragility([0.5, 1.0, 2.0], [1, 5, 9], 10)
    >>> f"{fit['median']:.3f} {fit['beta']:.3f} {fit['n_trials']} {fit['flag'].name}"
    '1.000 0.541 30 ok'
    >>> fit_binomial_fragility([1.0], [4], 10)["flag"].name          # one stripe: beta is not determined
    'not_identified'
    """
    x = np.asarray(intensity, dtype=float).ravel()
    k = np.asarray(n_exceed, dtype=float).ravel()
    n = np.broadcast_to(np.asarray(n_total, dtype=float), k.shape)
    if x.size != k.size or not (np.all(np.isfinite(x)) and np.all(x > 0)):
        raise ValueError("parameter 'intensity' must hold one finite value > 0 per stripe")
    if not (np.all(k >= 0) and np.all(k <= n)):
        raise ValueError("parameter 'n_exceed' must lie in 0..n_total at every stripe")
    if k.sum() == 0 or k.sum() == n.sum():
        raise ValueError("every trial exceeds, or none does: the fragility is not identified")

    def nll(v):
        return binomial_nll(v[0], v[1], x, k, n)

    start = [math.log(float(np.exp(np.average(np.log(x), weights=np.maximum(k, 1e-9))))), math.log(0.4)]
    best = optimize.minimize(nll, start, method="Nelder-Mead",
                             options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 8000}).x
    h = 1e-4
    hess = np.empty((2, 2))
    for i in range(2):
        for j in range(2):
            ei, ej = np.eye(2)[i] * h, np.eye(2)[j] * h
            hess[i, j] = (nll(best + ei + ej) - nll(best + ei - ej) - nll(best - ei + ej) + nll(best - ei - ej)) \
                / (4 * h * h)
    try:
        cov = np.linalg.inv(hess)
        se = np.sqrt(np.diag(cov)) if np.all(np.diag(cov) > 0) else np.full(2, np.nan)
    except np.linalg.LinAlgError:
        se = np.full(2, np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        median, beta = float(np.exp(best[0])), float(np.exp(best[1]))
        median_se, beta_se = median * float(se[0]), beta * float(se[1])
    if np.all((k == 0) | (k == n)):
        flag = FitFlag.separated
    elif np.unique(x).size < 2:
        flag = FitFlag.not_identified
    else:
        flag = fit_flag_of(x, median, beta, beta_se if np.isfinite(beta_se) else np.inf)
    return {"median": median, "beta": beta, "median_se": median_se, "beta_se": beta_se, "n_trials": int(n.sum()),
            "flag": flag}


def total_dispersion(beta, modelling):
    """A fitted dispersion combined with a modelling dispersion, ``sqrt(beta^2 + beta_m^2)`` [1].

    Parameters
    ----------
    beta : float, array_like or xarray.DataArray
        Fitted (record-to-record) dispersion [1].
    modelling : float
        Modelling dispersion ``beta_m`` [1].

    Returns
    -------
    numpy.ndarray or xarray.DataArray
        The total dispersion [1], like ``beta``.

    Notes
    -----
    The square root of the sum of squares of FEMA P-58 [2]: the two sources taken independent and
    lognormal.  The modelling dispersion stands for the linearization's error against the equations of
    motion of [1].

    References
    ----------
    [1] [mitseas2026]; [2] [fema2012].

    Examples
    --------
    >>> f"{float(total_dispersion(0.3, 0.4)):.2f}"
    '0.50'
    """
    beta = beta if isinstance(beta, xr.DataArray) else np.asarray(beta, dtype=float)
    return np.sqrt(beta * beta + float(modelling) ** 2)


def with_modelling_dispersion(frag, modelling):
    """A fragility dataset whose ``beta`` combines the fitted and the modelling dispersion.

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility result with ``beta`` [1].
    modelling : float or None
        Modelling dispersion ``beta_m`` [1]; None or 0 returns ``frag`` unchanged.

    Returns
    -------
    xarray.Dataset
        ``beta`` = :func:`total_dispersion` of the fitted one and ``modelling``; the fitted one kept as
        ``beta_fit``; attribute ``modelling_dispersion``.

    Notes
    -----
    ``beta = sqrt(beta_fit^2 + beta_m^2)`` (square root of the sum of squares) [2].

    References
    ----------
    [1] [mitseas2026]; [2] [fema2012].

    Examples
    --------
    >>> out = with_modelling_dispersion(xr.Dataset({"beta": 0.3}), 0.4)
    >>> float(out["beta"]), float(out["beta_fit"])
    (0.5, 0.3)
    """
    if modelling is None or modelling == 0:
        return frag
    out = frag.assign(beta_fit=frag["beta"].assign_attrs(long_name="fitted (record-to-record) dispersion"))
    out["beta"] = total_dispersion(frag["beta"], modelling).assign_attrs(
        frag["beta"].attrs, note=f"SRSS of beta_fit and the modelling dispersion {float(modelling):g}")
    return out.assign_attrs(modelling_dispersion=float(modelling))


def fit_lognormal_fragility(intensity, probability=None, n_exceed=None, n_total=None):
    """Fit ``(median, beta)`` of a lognormal fragility curve to probabilities or to counts.

    Parameters
    ----------
    intensity : array_like
        Intensity measure of each point [its units] > 0.
    probability : array_like, optional
        Exceedance probabilities [1] (least squares on the probit scale where ``0 < p < 1``).
    n_exceed : array_like, optional
        Exceedances per intensity [1] (binomial maximum likelihood instead).
    n_total : array_like, optional
        Samples per intensity [1], with ``n_exceed``.

    Returns
    -------
    median : float
        [units of the intensity].
    beta : float
        [1].

    Raises
    ------
    ValueError
        With fewer than two probabilities strictly between 0 and 1.

    Notes
    -----
    Probit regression ``Phi^-1(p) = (ln x - ln median) / beta`` or the binomial likelihood of [2], eq. (11);
    the probabilities come from the linearization of [1] or from Monte Carlo.

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    >>> p = lognormal_fragility([0.5, 1.0, 2.0], 1.2, 0.5)
    >>> median, beta = fit_lognormal_fragility([0.5, 1.0, 2.0], p)
    >>> f"{median:.4f} {beta:.4f}"
    '1.2000 0.5000'
    """
    im = np.asarray(intensity, dtype=float).ravel()
    if n_exceed is not None:
        k = np.asarray(n_exceed, dtype=float).ravel()
        n = np.asarray(n_total, dtype=float).ravel() * np.ones_like(k)

        def nll(x):
            p = np.clip(lognormal_fragility(im, np.exp(x[0]), np.exp(x[1])), 1e-15, 1 - 1e-15)
            return -np.sum(k * np.log(p) + (n - k) * np.log1p(-p))

        x0 = [np.log(np.median(im)), np.log(0.5)]
        x = optimize.minimize(nll, x0, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-12,
                                                                      "maxiter": 4000}).x
        return float(np.exp(x[0])), float(np.exp(x[1]))
    p = np.asarray(probability, dtype=float).ravel()
    use = np.isfinite(p) & (p > 1e-6) & (p < 1 - 1e-6) & (im > 0)
    if use.sum() < 2:
        raise ValueError("need at least two intensities with 0 < probability < 1 to fit a fragility curve")
    z = special.ndtri(p[use])
    slope, intercept = np.polyfit(np.log(im[use]), z, 1)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        beta = 1.0 / slope
        return float(np.exp(-intercept * beta)), float(beta)


# ------------------------------------------------------------------ xarray layer
def parameter(ds, name):
    """A model parameter of a dataset: its coordinate.

    A swept ``k`` of a sweep file is stored as ``k_value``
    (:data:`screening.sweep.run.AUX_GRID_COORDINATES`); both names are looked up.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization, sweep or Monte Carlo result.
    name : str
        The parameter (``S0`` [m2 s-3], ``k`` [N m-2], ...).

    Returns
    -------
    xarray.DataArray
        Its values in SI units; ``KeyError`` when the dataset does not record it.
    """
    for var in (name, f"{name}_value"):
        if var in ds.variables:
            return ds[var]
    raise KeyError(f"the dataset does not record the parameter '{name}'")


#: Derived quantities that :func:`model_quantity` rebuilds from the parameters when a dataset does
#: not store them: name -> (parameters, property of :class:`~screening.core.model.Block` evaluated on them).
_FROM_PARAMETERS = {
    "slenderness": (("b", "h"), Block.slenderness),
    "m_sdof": (("I_cm", "m", "h"), Block.m_sdof),
}


def model_quantity(ds, name):
    """A derived model quantity of a dataset (``theta_ul``, ``slenderness``, ``m_sdof``), broadcast by name.

    Datasets store ``theta_ul`` and ``slenderness`` as data variables; they are read, never
    recomputed.  Fallback for files written before ``slenderness`` was stored (and for ``m_sdof``,
    which no dataset stores): the :class:`~screening.core.model.Block` property evaluated on the
    parameter coordinates.  ``theta_ul`` depends on the condensation and has no fallback.

    Parameters
    ----------
    ds : xarray.Dataset
        A result dataset.
    name : str
        ``"theta_ul"`` [rad], ``"slenderness"`` [rad] or ``"m_sdof"`` [kg m2].

    Returns
    -------
    xarray.DataArray
        The quantity; ``KeyError`` naming what is missing.

    Notes
    -----
    ``slenderness = atan(b / h)`` and ``m_sdof = I_cm + m h^2`` (the rocking inertia about the
    base centre, eq. (23) in [mitseas2026]).
    """
    if name in ds.variables:
        return ds[name]
    if name in _FROM_PARAMETERS:
        names, prop = _FROM_PARAMETERS[name]
        missing = [n for n in names if n not in ds.variables]
        if not missing:
            return prop.fget(SimpleNamespace(**{n: ds[n] for n in names})).rename(name)
        raise KeyError(f"the dataset stores neither '{name}' nor the parameters it is computed from "
                       f"(missing {', '.join(missing)})")
    raise KeyError(f"the dataset does not store '{name}'")


RELATIVE_TO = (None, "slenderness", "theta_ul")


def threshold_angle(ds, threshold, relative_to=None):
    """The rotation [rad] meant by ``threshold``.

    Absolute, or a fraction of the slenderness angle ``atan(b/h)`` (``relative_to="slenderness"``)
    or of the uplift angle ``theta_ul`` of the condensation that produced the dataset
    (``"theta_ul"``), both read from the dataset (per point where they vary).

    Parameters
    ----------
    ds : xarray.Dataset
        A result dataset.
    threshold : float
        The threshold: [rad] when absolute, else a fraction [1].
    relative_to : {None, "slenderness", "theta_ul"}
        What ``threshold`` is a fraction of.

    Returns
    -------
    xarray.DataArray
        The rotation [rad]; ``ValueError`` for another ``relative_to``.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> ds = xr.Dataset({"slenderness": 0.16515})
    >>> f"{float(threshold_angle(ds, 0.5, 'slenderness')):.5f}", float(threshold_angle(ds, 0.01))
    ('0.08257', 0.01)
    """
    if relative_to not in RELATIVE_TO:
        raise ValueError(f"parameter 'relative_to' must be None, 'slenderness' or 'theta_ul' (got {relative_to!r})")
    if relative_to is None:
        return xr.DataArray(float(threshold))
    return float(threshold) * model_quantity(ds, relative_to)


def equivalent_damping_ratio(ds):
    """The damping ratio of the equivalent linear oscillator along the record.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization result with ``c_eq`` [N m s rad-1] and ``k_eq`` [N m rad-1].

    Returns
    -------
    xarray.DataArray
        ``zeta_eq(t)`` [1]; NaN where ``k_eq <= 0``.

    Notes
    -----
    ``zeta_eq = c_eq / (2 sqrt(k_eq M))`` with ``M = I_cm + m h^2``, the equivalent linear system of
    eq. (42) in [mitseas2026].
    """
    k_eq = ds["k_eq"].where(ds["k_eq"] > 0)
    return ds["c_eq"] / (2.0 * np.sqrt(k_eq * model_quantity(ds, "m_sdof")))


def is_monte_carlo(ds):
    """True for a :func:`screening.monte_carlo` result (per-sample peaks on ``sample``).

    Parameters
    ----------
    ds : xarray.Dataset
        A result dataset.

    Returns
    -------
    bool
        Whether ``peak_abs_theta`` [rad] is stored per sample.
    """
    return "peak_abs_theta" in ds.variables and "sample" in ds["peak_abs_theta"].dims


def sample_exceedance(peaks, overturned, valid, level):
    """The fraction of the valid samples whose peak ``|theta|`` exceeds ``level``, with its standard error.

    Parameters
    ----------
    peaks : xarray.DataArray
        Peak ``|theta|`` [rad] per sample (dimension ``sample``).
    overturned : xarray.DataArray of bool
        Overturned samples (they count as exceedances).
    valid : xarray.DataArray of bool
        Samples that count at all.
    level : float or xarray.DataArray
        The rotation [rad].

    Returns
    -------
    p, standard_error : xarray.DataArray
        Over the other dimensions [1]; NaN where no sample is valid.

    Notes
    -----
    ``p = n_exceed / n_valid`` and the binomial standard error ``sqrt(p (1 - p) / n_valid)``.
    """
    n = valid.sum("sample")
    n = n.where(n > 0)
    p = (((peaks > level) | overturned) & valid).sum("sample") / n
    se = np.sqrt(p * (1 - p) / n)
    p.attrs, se.attrs = {}, {}                  # not the flags of a sample-state input
    return p, se


def _monte_carlo_exceedance(ds, level):
    p, se = sample_exceedance(ds["peak_abs_theta"], ds["overturned"], ~ds["diverged"], level)
    return (p.assign_coords(mcs_p_exceed_se=se.assign_attrs(schema.attributes("mcs_p_exceed_se")))
            .assign_attrs(schema.attributes("mcs_p_exceed"), method="monte_carlo").rename("mcs_p_exceed"))


def exceedance_probability(ds, threshold, relative_to=None, method="vanmarcke"):
    """Probability [1] that ``|theta|`` exceeds the threshold during the record, on the dims of the dataset.

    Linearization results and sweeps: the up-crossing approximation ``method`` on the Gaussian
    moments; NaN at every point that is not ``ok`` (where the linearization stopped near toppling,
    ``k_eq_negative`` or ``sigma_theta_beyond_slenderness``, nothing vouches for a number; elsewhere it
    failed).  A sweep that stores ``p_exceed`` at this threshold without the moments (``[output]
    histories = "spots"``): the stored value, NaN where its ``p_source`` is ``unreliable``.  Monte Carlo results: the fraction of the samples that did not diverge whose peak
    ``|theta|`` exceeds the threshold (overturned samples count), named ``mcs_p_exceed``, with its
    binomial standard error as the coordinate ``mcs_p_exceed_se`` (``method`` is not used).

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization, sweep or Monte Carlo result.
    threshold, relative_to : float, {None, "slenderness", "theta_ul"}
        The threshold [rad], or a fraction [1] of ``relative_to`` (:func:`threshold_angle`).
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation (:func:`exceedance_probability_from_moments`).

    Returns
    -------
    xarray.DataArray
        ``p_exceed`` (or ``mcs_p_exceed``) [1].

    Notes
    -----
    ``P = 1 - exp(-int_0^T h(t) dt)`` with the Rice rate of eq. (44) in [1] times, for
    ``"vanmarcke"``, Vanmarcke's factor [2] at the bandwidth of :func:`equivalent_damping_ratio`.

    References
    ----------
    [1] [mitseas2026]; [2] [vanmarcke1975].

    Examples
    --------
    The paper's block and bed under five white-noise intensities ``S0`` [m2 s-3]:

    >>> from screening import Block, Foundation, WhiteNoise, linearize
    >>> ds = linearize(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...                WhiteNoise(np.array([3e-4, 4e-4, 6e-4, 8e-4, 1.2e-3]), band_limit_hz=None), t_end=10.0, dt=0.5, trust=False,
    ...                condensation="paper")
    >>> [f"{p:.4f}" for p in exceedance_probability(ds, 0.01).values]
    ['0.0062', '0.1035', '0.6853', '0.9558', '0.9997']
    """
    level = threshold_angle(ds, threshold, relative_to)
    if is_monte_carlo(ds):
        return _monte_carlo_exceedance(ds, level)
    if method not in ("poisson", "vanmarcke"):
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    if "var_theta" not in ds.variables:
        return stored_exceedance(ds, threshold, relative_to)
    moments = [ds[name].fillna(0.0) for name in ("var_theta", "var_theta_dot", "cov_theta_theta_dot")]
    along_t = [xr.broadcast(level, ds["t"])[0]]
    if method == "vanmarcke":
        along_t.append(xr.apply_ufunc(oscillator_bandwidth, equivalent_damping_ratio(ds).fillna(0.05)))

    def _prob(t, v, vd, c, a, *bandwidth):
        return exceedance_probability_from_moments(t, v, vd, c, a, method=method,
                                                   bandwidth=bandwidth[0] if bandwidth else None)

    p = xr.apply_ufunc(_prob, ds["t"], *moments, *along_t, input_core_dims=[["t"]] * (4 + len(along_t)))
    if "status" in ds.variables:
        p = p.where(ds["status"] == PointStatus.ok)
    return p.rename("p_exceed").assign_attrs(schema.attributes("p_exceed"), method=method)


def _stored_base(ds):
    """What the stored thresholds are fractions of (``p_exceed``'s attribute ``relative_to``), ``"None"``."""
    return str(ds["p_exceed"].attrs.get("relative_to", ds["threshold"].attrs.get("relative_to", "None")))


def has_stored_exceedance(ds, threshold, relative_to=None):
    """Whether a sweep stored ``p_exceed`` with ``p_source`` at this ``[fragility]`` threshold (the sweep's best
    answer there: :func:`stored_exceedance`).

    Parameters
    ----------
    ds : xarray.Dataset
        A result.
    threshold : float
        The threshold, [rad] or a fraction [1].
    relative_to : {None, "slenderness", "theta_ul"}
        What ``threshold`` is a fraction of.

    Returns
    -------
    bool
        True where the result holds ``p_exceed`` at ``threshold`` relative to the same angle, with ``p_source``.
    """
    if not ("p_exceed" in ds.variables and "p_source" in ds.variables and "threshold" in ds["p_exceed"].dims):
        return False
    if _stored_base(ds) != str(relative_to):
        return False
    return bool(np.any(np.isclose(np.asarray(ds["threshold"].values, dtype=float), float(threshold), rtol=1e-9,
                                  atol=0.0)))


def stored_exceedance(ds, threshold, relative_to=None):
    """The ``p_exceed`` a sweep stored at a ``[fragility]`` threshold, NaN where ``p_source`` is ``unreliable``.

    What :func:`exceedance_probability` gives on a result without the moments' histories (``[output]
    histories = "spots"``): the sweep's own probabilities (Monte Carlo, trusted or corrected
    linearization, or the study's fragility surface, by ``p_source``).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with ``p_exceed`` over ``threshold`` (a ``[fragility]`` table).
    threshold : float
        One of the stored thresholds, [rad] or a fraction [1].
    relative_to : {None, "slenderness", "theta_ul"}
        As the study's ``[fragility] relative_to``.

    Returns
    -------
    xarray.DataArray
        ``p_exceed`` [1] over the grid.

    Raises
    ------
    ValueError
        One line: the result stores no moments and no probabilities at this threshold.
    """
    stored = ds["p_exceed"] if "p_exceed" in ds.variables and "threshold" in ds["p_exceed"].dims else None
    have = [] if stored is None else [float(t) for t in ds["threshold"].values]
    same_base = stored is not None and _stored_base(ds) == str(relative_to)
    match = [i for i, t in enumerate(have) if np.isclose(t, float(threshold), rtol=1e-9, atol=0.0)]
    if not (same_base and match):
        base = _stored_base(ds) if stored is not None else None
        offer = (f"its [fragility] thresholds {', '.join(f'{t:g}' for t in have)} (relative to {base})"
                 if have else "no [fragility] thresholds")
        raise ValueError(f"the result stores no histories of the moments ([output] histories = \"spots\"): only "
                         f"{offer} have probabilities; give one of them, or run the study with histories")
    p = stored.isel(threshold=match[0], drop=True)
    if "p_source" in ds.variables:
        p = p.where(ds["p_source"] != ProbabilitySource.unreliable)
    return p.rename("p_exceed").assign_attrs(schema.attributes("p_exceed"), method=STORED)


def fit_fragility_curve(intensity, probability):
    """``(median, beta, flag)`` of the lognormal fragility curve of one set of points.

    Parameters
    ----------
    intensity : array_like
        Intensity measure [units of the IM], 1-d.
    probability : array_like
        Exceedance probability [1] at each intensity.

    Returns
    -------
    median : float
        [units of the IM]; NaN where ``flag`` is not ``ok``.
    beta : float
        Lognormal dispersion [1]; NaN where ``flag`` is not ``ok``.
    flag : screening.core.status.FitFlag
        ``ok``, or why there is no fit (no finite value, never or always exceeded, fewer than two
        points strictly between, ``beta <= 0``, a median outside the intensities, a slope the points do
        not determine: :func:`fit_flag_of`).

    Notes
    -----
    :func:`fit_lognormal_fragility`: least squares of ``Phi^-1(P) = (ln IM - ln median) / beta``.

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    >>> median, beta, flag = fit_fragility_curve([0.5, 1.0, 2.0], lognormal_fragility([0.5, 1.0, 2.0], 1.2, 0.5))
    >>> f"{median:.3f} {beta:.3f} {flag.name}"
    '1.200 0.500 ok'
    >>> fit_fragility_curve([0.5, 1.0], [0.0, 0.0])[2].name
    'never_exceeded'
    >>> fit_fragility_curve([1.0, 1.1, 1.2, 1.3], [0.30, 0.31, 0.29, 0.30])[2].name     # flat: noise only
    'not_identified'
    """
    im = np.asarray(intensity, dtype=float).ravel()
    p = np.asarray(probability, dtype=float).ravel()
    finite = np.isfinite(p) & np.isfinite(im) & (im > 0)
    if not finite.any():
        return np.nan, np.nan, FitFlag.no_values
    if np.all(p[finite] <= 1e-6):
        return np.nan, np.nan, FitFlag.never_exceeded
    if np.all(p[finite] >= 1 - 1e-6):
        return np.nan, np.nan, FitFlag.always_exceeded
    try:
        median, beta = fit_lognormal_fragility(im[finite], p[finite])
    except ValueError:
        return np.nan, np.nan, FitFlag.no_fit
    flag = fit_flag_of(im[finite], median, beta, _probit_beta_se(im[finite], p[finite], beta))
    return (median, beta, flag) if flag == FitFlag.ok else (np.nan, np.nan, flag)


def _probit_beta_se(im, p, beta):
    """Standard error [1] of the least-squares ``beta`` of :func:`fit_lognormal_fragility` from the scatter
    of the probits about the line (NaN with two points: an exact line)."""
    use = np.isfinite(p) & (p > 1e-6) & (p < 1 - 1e-6) & (im > 0)
    x, z = np.log(im[use]), special.ndtri(p[use])
    if x.size < 3 or not np.isfinite(beta) or beta == 0:
        return np.nan
    slope, intercept = np.polyfit(x, z, 1)
    resid = z - (slope * x + intercept)
    sxx = float(np.sum((x - x.mean()) ** 2))
    if sxx <= 0:
        return np.inf
    slope_se = math.sqrt(float(np.sum(resid ** 2)) / (x.size - 2) / sxx)
    return abs(beta) * slope_se / abs(slope) if slope != 0 else np.inf


def fit_standard_errors(intensity, probability, standard_error):
    """Standard errors of the probit fit of :func:`fit_fragility_curve` from those of its points.

    Parameters
    ----------
    intensity, probability
        As in :func:`fit_fragility_curve`.
    standard_error : array_like
        Its standard error [1] at each intensity (NaN: unknown).

    Returns
    -------
    median_se : float
        [units of the IM]; NaN where a point of the fit has no standard error or the fit is undefined.
    beta_se : float
        [1].

    Notes
    -----
    The fit regresses ``z_i = Phi^-1(p_i)`` on ``u_i = ln x_i`` (``z = a + b u``, points with
    ``1e-6 < p < 1 - 1e-6``) by ordinary least squares; with independent point errors
    ``se(z_i) = se(p_i) / phi(z_i)`` (delta method) its covariance is the sandwich [white1980]
    ``(X'X)^-1 X' diag(se(z)^2) X (X'X)^-1``; ``beta = 1/b``, ``ln median = -a/b`` carry it by the delta
    method: ``se(beta) = se(b) / b^2``, ``se(median) = median se(ln median)``.
    """
    x = np.asarray(intensity, dtype=float).ravel()
    p = np.asarray(probability, dtype=float).ravel()
    se = np.asarray(standard_error, dtype=float).ravel()
    use = np.isfinite(p) & (p > 1e-6) & (p < 1 - 1e-6) & np.isfinite(x) & (x > 0)
    if use.sum() < 2 or not np.all(np.isfinite(se[use])):
        return math.nan, math.nan
    z = special.ndtri(p[use])
    X = np.column_stack([np.ones(int(use.sum())), np.log(x[use])])
    se_z = se[use] / np.exp(-0.5 * z * z) * math.sqrt(2 * math.pi)
    try:
        xtx = np.linalg.inv(X.T @ X)
    except np.linalg.LinAlgError:
        return math.nan, math.nan
    a, b = xtx @ X.T @ z
    if not b > 0:
        return math.nan, math.nan
    cov = xtx @ (X.T * se_z**2) @ X @ xtx
    grad = np.array([-1.0 / b, a / b**2])
    median = math.exp(-a / b)
    return median * math.sqrt(max(float(grad @ cov @ grad), 0.0)), math.sqrt(max(cov[1, 1], 0.0)) / b**2


def fitted_standard_error(frag):
    """The standard error of :func:`fitted_probability` where it is known (``docs/trust.md``), NaN elsewhere.

    A quarter of the band ``best_p_exceed_low..high`` (two standard errors either side) where
    ``[accuracy]`` vouches for the best estimate; ``p_exceed_se`` where the dataset has it; else NaN
    (the linearization's own probabilities carry none).

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset.

    Returns
    -------
    xarray.DataArray
        [1], on the grid of ``p_exceed``.
    """
    p = frag["p_exceed"]
    se = frag["p_exceed_se"] if "p_exceed_se" in frag else xr.full_like(p, np.nan, dtype=float)
    if "best_p_exceed" in frag and "best_p_exceed_low" in frag:
        vouched = (frag["best_method"] != BestMethod.unreliable) & np.isfinite(frag["best_p_exceed"])
        se = xr.where(vouched, (frag["best_p_exceed_high"] - frag["best_p_exceed_low"]) / 4, np.nan)
    return se


def fit_curves(p, intensity, dim):
    """The lognormal fit of every curve of ``p`` along ``dim``.

    Parameters
    ----------
    p : xarray.DataArray
        Exceedance probability [1] with dimension ``dim``.
    intensity : xarray.DataArray or array_like
        The intensity [units of the IM]: a DataArray broadcast against ``p``, or the values along ``dim``.
    dim : str
        The swept intensity dimension.

    Returns
    -------
    xarray.Dataset
        ``fit_median`` [units of the IM], ``beta`` [1] and ``fit_flag``
        (:class:`~screening.core.status.FitFlag`) over the other dimensions.

    Notes
    -----
    Each curve is fitted by :func:`fit_fragility_curve`, ``P(IM) = Phi(ln(IM / median) / beta)``.
    """
    x = intensity if isinstance(intensity, xr.DataArray) else xr.DataArray(np.asarray(intensity), dims=dim)
    x, p = xr.broadcast(x, p)

    def _fit(xv, pv):
        return np.array(fit_fragility_curve(xv, pv), dtype=float)

    fit = xr.apply_ufunc(_fit, x, p, input_core_dims=[[dim], [dim]], output_core_dims=[["fit"]], vectorize=True)
    fit = fit.drop_vars([c for c in fit.coords if dim in fit[c].dims or c == dim], errors="ignore")
    return xr.Dataset({"fit_median": fit.isel(fit=0, drop=True), "beta": fit.isel(fit=1, drop=True),
                       "fit_flag": fit.isel(fit=2, drop=True).astype(np.int8)})


def unvouched_points(ds, stored=True):
    """Grid points whose value nobody vouches for: a fit leaves them out.

    Where the result stores ``p_source``: for its stored probabilities (``stored``) the points whose source
    is ``unreliable``; for another threshold (a Gaussian value, ``stored`` false) every point whose source is
    not the trusted or corrected linearization (a best estimate of ``[accuracy]`` still counts, by
    :func:`fitted_probability`).  Otherwise the
    points whose ``sl_trust`` is ``untrusted`` with status ``ok``, and those where the linearization
    stopped near toppling (``k_eq_negative``, ``sigma_theta_beyond_slenderness``), without a best
    estimate (no ``[accuracy]``, or ``best_method`` ``unreliable``).  All False where the dataset stores
    neither ``p_source`` nor ``sl_trust``.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization or sweep result.
    stored : bool, default True
        Whether the fitted probability is the one the result stored with ``p_source``.

    Returns
    -------
    xarray.DataArray of bool
        ``unvouched`` [-] over the grid.
    """
    if "p_source" in ds.variables:
        bad = (ds["p_source"] == ProbabilitySource.unreliable) if stored else ~ds["p_source"].isin(
            [ProbabilitySource.linearization_gaussian, ProbabilitySource.corrected_linearization_gaussian])
        bad = bad.drop_vars([c for c in bad.coords if c not in bad.dims]).rename("unvouched")
        return bad.drop_attrs()                          # not p_source's flag attributes
    if "sl_trust" not in ds.variables:
        return xr.zeros_like(ds["status"] if "status" in ds.variables else xr.DataArray(False), dtype=bool)
    bad = ds["sl_trust"] == Trust.untrusted
    if "status" in ds.variables:
        bad = (bad & (ds["status"] == PointStatus.ok)) | ds["status"].isin(
            [PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness])
    if "best_method" in ds.variables:
        bad = bad & (ds["best_method"] == BestMethod.unreliable)
    return bad.drop_vars([c for c in bad.coords if c not in bad.dims]).rename("unvouched")


def fitted_probability(frag, unvouched=None):
    """The probability a fragility fit uses.

    ``best_p_exceed`` where ``[accuracy]`` vouches for it (``best_method`` not ``unreliable``), else
    ``p_exceed``; NaN (left out) at the ``unvouched`` points without a vouched best estimate.

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset with ``p_exceed`` [1] (and optionally ``best_p_exceed`` [1], ``best_method``).
    unvouched : xarray.DataArray of bool, optional
        :func:`unvouched_points` of the result.

    Returns
    -------
    xarray.DataArray
        The probability [1].
    """
    p = frag["p_exceed"] if unvouched is None else frag["p_exceed"].where(~unvouched)
    if "best_p_exceed" not in frag:
        return p
    vouched = (frag["best_method"] != BestMethod.unreliable) & np.isfinite(frag["best_p_exceed"])
    return xr.where(vouched, frag["best_p_exceed"], p)


def _left_out(frag, unvouched):
    """The unvouched points a fit leaves out: those without a vouched best estimate."""
    out = unvouched
    if "best_p_exceed" in frag:
        out = out & ~((frag["best_method"] != BestMethod.unreliable) & np.isfinite(frag["best_p_exceed"]))
    return out


def vouched_range(frag, ds, intensity, dim):
    """The intensity range each curve's fit stands on: its lowest and highest vouched point.

    A point is vouched when its fitted probability is finite and it is not unvouched
    (:func:`screening.analysis.fragility.unvouched_points`).  Outside this range the curve is an
    extrapolation: the NRML's ``minIML`` / ``maxIML`` and the risk integral's split
    (``screening risk``) use it.

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset with ``p_exceed`` [1].
    ds : xarray.Dataset
        The result it was computed from.
    intensity : xarray.DataArray
        The intensity [IM units] along ``dim``.
    dim : str
        The swept intensity dimension.

    Returns
    -------
    xarray.Dataset
        ``fit_im_min``, ``fit_im_max`` [IM units] over the curves (NaN where no point is vouched).
    """
    p = fitted_probability(frag)
    good = np.isfinite(p)
    if "sl_trust" in ds.variables:
        good = good & ~unvouched_points(ds)
    if not isinstance(intensity, xr.DataArray):
        intensity = xr.DataArray(np.asarray(intensity, dtype=float), dims=dim)
    x = intensity.drop_vars([c for c in intensity.coords if c not in intensity.dims]).broadcast_like(p).where(good)
    units = intensity.attrs.get("units", "")
    return xr.Dataset({
        "fit_im_min": x.min(dim).assign_attrs(units=units, long_name="lowest vouched intensity of the curve"),
        "fit_im_max": x.max(dim).assign_attrs(units=units, long_name="highest vouched intensity of the curve")}
    ).drop_vars([c for c in p.coords if dim in p[c].dims or c == dim], errors="ignore")


def add_fit(out, ds, intensity, dim):
    """A fragility Dataset with the lognormal fit of every curve along ``dim``.

    Parameters
    ----------
    out : xarray.Dataset
        A fragility Dataset with ``p_exceed`` [1].
    ds : xarray.Dataset
        The result it was computed from (for :func:`unvouched_points`).
    intensity : xarray.DataArray or array_like
        The intensity [units of the IM] along ``dim``.
    dim : str
        The swept intensity dimension.

    Returns
    -------
    xarray.Dataset
        ``out`` with :func:`fit_curves` of :func:`fitted_probability` (``fit_median``, ``beta``,
        ``fit_flag``) and ``fit_n_unvouched``, the number of the curve's points left out of the fit because
        nothing vouches for them (:func:`unvouched_points`); a curve whose vouched points alone are too few
        (no value, fewer than two between 0 and 1, never or always exceeded) while points were left out is
        flagged ``untrusted``; the vouched range ``fit_im_min``, ``fit_im_max`` (:func:`vouched_range`) and,
        where the points have standard errors, ``fit_median_se``, ``beta_se`` (:func:`fit_standard_errors`).
    """
    unvouched = unvouched_points(ds, stored=out["p_exceed"].attrs.get("method") == STORED)
    probability = fitted_probability(out, unvouched)
    fit = fit_curves(probability, intensity, dim)
    se = fitted_standard_error(out)
    if bool(np.isfinite(se).any()):
        x = intensity if isinstance(intensity, xr.DataArray) else xr.DataArray(np.asarray(intensity), dims=dim)
        x, p, se = xr.broadcast(x, probability, se)
        errors = xr.apply_ufunc(lambda *a: np.array(fit_standard_errors(*a)), x, p, se,
                                input_core_dims=[[dim]] * 3, output_core_dims=[["se"]], vectorize=True)
        errors = errors.drop_vars([c for c in errors.coords if dim in errors[c].dims or c == dim], errors="ignore")
        fit["fit_median_se"] = errors.isel(se=0, drop=True)
        fit["beta_se"] = errors.isel(se=1, drop=True)
    left_out = _left_out(out, unvouched)
    count = left_out.sum(dim) if dim in left_out.dims else xr.zeros_like(fit["fit_flag"], dtype=np.int32)
    count = count.astype(np.int32).broadcast_like(fit["fit_flag"])
    count.attrs = {}                                     # not p_source's flag attributes
    fit["fit_n_unvouched"] = count
    too_few = fit["fit_flag"].isin([FitFlag.no_values, FitFlag.no_fit, FitFlag.never_exceeded, FitFlag.always_exceeded])
    untrusted = too_few & (fit["fit_n_unvouched"] > 0)
    fit["fit_flag"] = xr.where(untrusted, np.int8(FitFlag.untrusted), fit["fit_flag"]).astype(np.int8)
    out = out.drop_vars([n for n in fit.data_vars if n in out]).merge(fit, compat="override")
    out = out.drop_vars(["fit_im_min", "fit_im_max"], errors="ignore").merge(vouched_range(out, ds, intensity, dim))
    return out.assign_attrs(fit_source="best_p_exceed where [accuracy] vouches for it, else p_exceed"
                            if "best_p_exceed" in out else "p_exceed")


def _finish(out, dim, threshold, relative_to, method):
    """The schema's metadata, the fit's ``intensity``, and the attributes."""
    out = finish(out, table=FRAGILITY)
    if "fit_median" in out:
        out["fit_median"].attrs.update(intensity=dim, units=grid_units_of(out, dim))
        for name in ("fit_im_min", "fit_im_max", "fit_median_se"):
            if name in out:
                out[name].attrs.update(units=grid_units_of(out, dim))
    out.attrs.update(threshold=float(threshold), relative_to=str(relative_to), method=method,
                     title="Probability that |theta| exceeds a rotation during the record")
    return out


def grid_units_of(ds, dim):
    """CF units of the grid dimension or model parameter ``dim`` of the result ``ds`` (``"m2 s-3"`` for ``S0``):
    its coordinate's ``units``, else the schema's for a model parameter, else ``""``."""
    if dim in ds.variables and "units" in ds[dim].attrs:
        return ds[dim].attrs["units"]
    return schema.PARAMETERS.get(dim, {}).get("units", "")


def fragility_curve(ds, threshold, dim="S0", relative_to=None, method="vanmarcke"):
    """Exceedance probability along the intensity ``dim`` and its lognormal fit.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization, sweep or Monte Carlo result swept over ``dim``.
    threshold : float
        The threshold, [rad] or a fraction [1] (:func:`threshold_angle`).
    dim : str
        The swept intensity (default ``S0`` [m2 s-3]); ``ValueError`` if not a dimension.
    relative_to : {None, "slenderness", "theta_ul"}
        What ``threshold`` is a fraction of.
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation.

    Returns
    -------
    xarray.Dataset
        ``p_exceed`` [1] over the dims of the dataset (at a ``[fragility]`` threshold of a sweep, its stored
        value: :func:`stored_exceedance`), and ``fit_median`` (in the units of ``dim``;
        ``fit_median.attrs["intensity"]`` names it), ``beta`` [1] and ``fit_flag`` over the other dims, fitted
        on the vouched points (``fit_n_unvouched`` left out).

    Notes
    -----
    ``P(IM) = Phi(ln(IM / median) / beta)`` fitted to :func:`exceedance_probability`.

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    A lognormal curve over the same five intensities as :func:`exceedance_probability`:

    >>> from screening import Block, Foundation, WhiteNoise, linearize
    >>> ds = linearize(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...                WhiteNoise(np.array([3e-4, 4e-4, 6e-4, 8e-4, 1.2e-3]), band_limit_hz=None), t_end=10.0, dt=0.5, trust=False,
    ...                condensation="paper")
    >>> curve = fragility_curve(ds, 0.01)
    >>> f"{float(curve['fit_median']):.3e} {float(curve['beta']):.3f}", curve["fit_median"].attrs["units"]
    ('5.381e-04 0.235', 'm2 s-3')
    """
    p = (stored_exceedance(ds, threshold, relative_to) if has_stored_exceedance(ds, threshold, relative_to)
         else exceedance_probability(ds, threshold, relative_to, method))
    if dim not in p.dims:
        raise ValueError(f"parameter 'dim' must be a swept dimension of the dataset (got {dim!r}; have {list(p.dims)})")
    out = add_fit(xr.Dataset({"p_exceed": p}), ds, parameter(ds, dim), dim)
    return _finish(out, dim, threshold, relative_to, method)


@xr.register_dataset_accessor("rocking")
class RockingAccessor:
    """``ds.rocking.exceedance_probability(...)``, ``ds.rocking.fragility_curve(...)`` and
    ``ds.rocking.fragility_dataset(...)`` on linearization, sweep and Monte Carlo results."""

    def __init__(self, ds):
        self._ds = ds

    def threshold_angle(self, threshold, relative_to=None):
        return threshold_angle(self._ds, threshold, relative_to)

    def exceedance_probability(self, threshold, relative_to=None, method="vanmarcke"):
        return exceedance_probability(self._ds, threshold, relative_to, method)

    def fragility_curve(self, threshold, dim="S0", relative_to=None, method="vanmarcke"):
        return fragility_curve(self._ds, threshold, dim, relative_to, method)

    def fragility_dataset(self, threshold, relative_to=None, method="vanmarcke", dim="S0"):
        return fragility_dataset(self._ds, threshold, relative_to, method, dim)


def spot_positions(ds):
    """Integer positions of the Monte Carlo spot points along each grid dimension.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with ``status`` on the grid and ``spot_<dim>`` coordinates (``spot_case`` holds
        the case index; other ones the parameter value in SI units).

    Returns
    -------
    dict of str to xarray.DataArray
        ``{dim: positions over spot}`` for a pointwise ``ds.isel(...)``.
    """
    positions = {}
    for dim in ds["status"].dims:
        spot = ds[f"spot_{dim}"].values
        if dim == "case":
            idx = spot.astype(int)
        else:
            grid = parameter(ds, dim).values
            idx = np.abs(grid[None, :] - spot[:, None]).argmin(axis=1)
        positions[dim] = xr.DataArray(idx, dims="spot")
    return positions


def mcs_exceedance_at_spots(ds, level):
    """Probability [1] that ``|theta|`` exceeds ``level`` from the Monte Carlo spot checks of a sweep.

    From the per-sample peaks ``mcs_peak_abs_theta`` and ``mcs_sample_state``.  Overturned samples
    count as exceedances; diverged or failed samples are left out.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with spot checks (:func:`spot_positions`).
    level : xarray.DataArray
        The rotation [rad]; may vary over the grid (it is taken at each spot point).

    Returns
    -------
    p, standard_error : xarray.DataArray
        Over ``spot`` [1] (:func:`sample_exceedance`).
    """
    level = level.isel({d: i for d, i in spot_positions(ds).items() if d in level.dims})
    peaks = ds["mcs_peak_abs_theta"]
    state = ds["mcs_sample_state"] if "mcs_sample_state" in ds else xr.zeros_like(peaks, dtype=np.int8)
    return sample_exceedance(peaks, state == SampleState.overturned, state != SampleState.diverged_or_failed, level)


def best_exceedance(ds, threshold, relative_to=None, method="vanmarcke"):
    """Exceedance probability from the best estimates of a sweep with ``[accuracy]``, and its band.

    At escalated points the Monte Carlo fraction of samples beyond the threshold
    (``esc_peak_abs_theta``; overturned samples count, diverged ones are left out) with the band
    ``p +- 2 x`` its binomial standard error; elsewhere the up-crossing probability of the linearized
    moments rescaled to the best estimates (``var_theta`` by ``best_peak_var_theta / peak_var_theta``,
    ``var_theta_dot`` likewise, the covariance by the geometric mean), with the band of the estimates
    at ``+-2`` standard errors.  Where ``best_method`` is ``unreliable`` the probability is the
    linearization's and the band NaN.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with the moments, ``peak_var_theta`` [rad2] and the best estimates
        ``best_peak_var_theta`` [rad2], ``best_peak_var_theta_dot`` [rad2 s-2], their standard errors
        and ``best_method``.
    threshold, relative_to : float, {None, "slenderness", "theta_ul"}
        The threshold [rad], or a fraction [1] of ``relative_to`` (:func:`threshold_angle`).
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation.

    Returns
    -------
    p, low, high : xarray.DataArray
        The probability [1] and its band [1] on the grid.
    source : xarray.DataArray
        ``best_method`` (:class:`~screening.core.status.BestMethod`).

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    Best estimates 10 % above the linearization, with a 5 % standard error:

    >>> from screening import Block, Foundation, WhiteNoise, linearize
    >>> ds = linearize(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...                WhiteNoise(np.array([3e-4, 4e-4, 6e-4, 8e-4, 1.2e-3]), band_limit_hz=None), t_end=10.0, dt=0.5, trust=False,
    ...                condensation="paper")
    >>> best, best_dot = 1.1 * ds["peak_var_theta"], 1.1 * ds["var_theta_dot"].max("t")
    >>> ds = ds.assign(best_peak_var_theta=best, best_peak_var_theta_se=0.05 * best,
    ...                best_peak_var_theta_dot=best_dot, best_peak_var_theta_dot_se=0.05 * best_dot,
    ...                best_method=("S0", np.zeros(5, dtype=np.int8)))
    >>> p, low, high, source = best_exceedance(ds, 0.01)
    >>> bool((p >= exceedance_probability(ds, 0.01)).all()), bool(((low <= p) & (p <= high)).all())
    (True, True)
    """
    sl_dot = ds["var_theta_dot"].max("t")
    ratio = ds["best_peak_var_theta"] / ds["peak_var_theta"]
    ratio_dot = (ds["best_peak_var_theta_dot"] / sl_dot).fillna(ratio)

    def scaled(k):
        r = ratio * (1 + k * ds["best_peak_var_theta_se"] / ds["best_peak_var_theta"])
        rd = ratio_dot * (1 + k * (ds["best_peak_var_theta_dot_se"] / ds["best_peak_var_theta_dot"]).fillna(
            ds["best_peak_var_theta_se"] / ds["best_peak_var_theta"]))
        r, rd = r.clip(min=0.0), rd.clip(min=0.0)
        return exceedance_probability(ds.assign(var_theta=ds["var_theta"] * r, var_theta_dot=ds["var_theta_dot"] * rd,
                                                cov_theta_theta_dot=ds["cov_theta_theta_dot"] * np.sqrt(r * rd)),
                                      threshold, relative_to, method)

    source = ds["best_method"]
    p, low, high = scaled(0.0), scaled(-2.0), scaled(2.0)
    unreliable = source == BestMethod.unreliable
    p = xr.where(unreliable, exceedance_probability(ds, threshold, relative_to, method), p)
    low, high = low.where(~unreliable), high.where(~unreliable)
    if "escalation" in ds.dims and ds.sizes["escalation"]:
        level = threshold_angle(ds, threshold, relative_to)
        grid = ds["status"].dims
        at = np.unravel_index(ds["esc_grid_index"].values.astype(np.int64), ds["status"].shape)
        where = {d: xr.DataArray(i, dims="escalation") for d, i in zip(grid, at)}
        state = ds["esc_sample_state"].rename(esc_sample="sample")
        p_mc, se = sample_exceedance(ds["esc_peak_abs_theta"].rename(esc_sample="sample"),
                                     state == SampleState.overturned,
                                     (state == SampleState.standing) | (state == SampleState.overturned),
                                     level.isel({d: i for d, i in where.items() if d in level.dims}))
        p, low, high = (a.transpose(*grid).copy() for a in xr.broadcast(p, low, high))
        idx = tuple(at)
        p.values[idx] = p_mc.values
        low.values[idx] = np.clip(p_mc.values - 2 * se.values, 0.0, 1.0)
        high.values[idx] = np.clip(p_mc.values + 2 * se.values, 0.0, 1.0)
    return p, low, high, source


def fragility_dataset(ds, threshold, relative_to=None, method="vanmarcke", dim="S0"):
    """The fragility result of a dataset.

    ``p_exceed`` over its dims (at a threshold the sweep stored with ``p_source``, its own best answer,
    :func:`stored_exceedance`; else the linearization's), the rotation ``threshold_rad`` and, when ``dim``
    is swept with at least two points, the lognormal ``fit_median`` and ``beta`` of the vouched points.  At Monte Carlo spot points of a
    sweep (``spot`` dimension with per-sample ``mcs_peak_abs_theta``), the same probability from the
    sample peaks (``mcs_p_exceed`` and its standard error ``mcs_p_exceed_se``) is put beside the
    Gaussian one (``p_exceed_at_spot``).  For a Monte Carlo result: ``mcs_p_exceed`` and
    ``mcs_p_exceed_se``.

    Parameters
    ----------
    ds, threshold, relative_to, method, dim
        As in :func:`fragility_curve`.

    Returns
    -------
    xarray.Dataset
        The variables of the schema's fragility table, with CF attributes.

    References
    ----------
    [1] [mitseas2026]; [2] [baker2015].

    Examples
    --------
    What ``screening fragility`` writes, here of one linearization:

    >>> from screening import Block, Foundation, WhiteNoise, linearize
    >>> ds = linearize(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...                WhiteNoise(np.array([3e-4, 4e-4, 6e-4, 8e-4, 1.2e-3]), band_limit_hz=None), t_end=10.0, dt=0.5, trust=False,
    ...                condensation="paper")
    >>> frag = fragility_dataset(ds, 0.01)
    >>> float(frag["threshold_rad"]), [f"{p:.4f}" for p in frag["p_exceed"].values[:2]]
    (0.01, ['0.0062', '0.1035'])
    """
    level = threshold_angle(ds, threshold, relative_to)
    if is_monte_carlo(ds):
        p = exceedance_probability(ds, threshold, relative_to, method)
        out = xr.Dataset({"mcs_p_exceed": p.drop_vars("mcs_p_exceed_se"), "mcs_p_exceed_se": p["mcs_p_exceed_se"]})
    else:
        stored = has_stored_exceedance(ds, threshold, relative_to)
        p = (stored_exceedance(ds, threshold, relative_to) if stored
             else exceedance_probability(ds, threshold, relative_to, method))
        out = xr.Dataset({"p_exceed": p})
        if "mcs_peak_abs_theta" in ds and "spot" in ds.dims:
            out["mcs_p_exceed"], out["mcs_p_exceed_se"] = mcs_exceedance_at_spots(ds, level)
            out["p_exceed_at_spot"] = p.isel(spot_positions(ds)) if p.ndim else p.expand_dims(spot=ds.sizes["spot"])
        if not stored and "best_method" in ds and all(n in ds for n in ("var_theta", "var_theta_dot",
                                                                          "cov_theta_theta_dot")):
            best = best_exceedance(ds, threshold, relative_to, method)
            for name, value in zip(("best_p_exceed", "best_p_exceed_low", "best_p_exceed_high", "best_method"), best):
                out[name] = value.drop_vars([c for c in value.coords if c not in value.dims and c not in out.coords])
    if "p_exceed" in out and dim in out["p_exceed"].dims and out.sizes[dim] >= 2:
        out = add_fit(out, ds, parameter(ds, dim), dim)
    out["threshold_rad"] = level
    return _finish(out, dim, threshold, relative_to, "monte_carlo" if is_monte_carlo(ds) else
                   STORED if out["p_exceed"].attrs.get("method") == STORED else method)
