"""A study's own fragility surface: the probability of overturning (or of exceeding a rotation) over the
swept inputs, fitted on the study's Monte Carlo points, and given only where it can be vouched for.

Near toppling the probability of overturning is the answer; the overturned counts at a sweep's few dozen
Monte Carlo points follow a smooth surface over the swept inputs.  Here: a binomial probit GLM over the
transformed, standardised inputs (:func:`study_surface`: the form by AIC, Fisher scoring, a leave-one-out
check and widening), used only inside the hull of the Monte Carlo points (:func:`inside_hull`).  Pure
numpy; ``docs/outputs_probabilities.md``, "Near toppling: the study's fragility surface".
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import special, stats
from scipy.spatial import Delaunay, QhullError

from screening.solvers.estimates import binomial_estimate

__all__ = []

#: Model forms, from the simplest: the probit of the probability linear in the standardised inputs, or
#: quadratic (squares and pairwise products added).
FORMS = ("linear", "quadratic")
#: At least this many Monte Carlo points in play (some samples overturned, or the surface expects one) for the
#: surface to be checked at all.
MIN_IN_PLAY = 5
#: Share of the held-out Monte Carlo points in play that must lie within :data:`LOO_Z` combined standard
#: errors of the surface fitted without them (one miss is allowed however few the points: at 2 SE a sound
#: surface misses 5 % of them, so 7 points pass all together only 70 % of the time).
LOO_PASS = 0.9
#: Combined standard errors of the leave-one-out check (about 95 % for a Gaussian error).
LOO_Z = 2.0
#: A form needs at least this many Monte Carlo points per term, and more points with ``0 < k < n`` than terms.
MIN_POINTS_PER_TERM = 2
#: Probabilities are clipped to ``[P_FLOOR, 1 - P_FLOOR]`` in the weights (never in the estimate).
P_FLOOR = 1e-12


class Surface(NamedTuple):
    """A fitted probit surface: its ``form``, coefficients ``coef`` [-] and their covariance ``cov`` (inflated
    by ``dispersion`` where > 1), the Pearson ``dispersion`` [-], the Monte Carlo ``points`` it was fitted on,
    whether the fit ``converged``, and (from :func:`study_surface`) the leave-one-out share ``loo_share`` [-]
    of the ``loo_in_play`` held-out points, whether it is ``vouched`` for and, if not, the ``reason``, and the
    factor ``loo_scale`` [-] (>= 1) by which the held-out errors widened the standard errors (``cov`` holds it)."""

    form: str
    coef: np.ndarray
    cov: np.ndarray
    dispersion: float
    points: int
    converged: bool
    loo_share: float = np.nan
    loo_in_play: int = 0
    vouched: bool = False
    reason: str = ""
    loo_scale: float = 1.0


def surface_inputs(columns):
    r"""``(z, names)``: the swept inputs ``(points, inputs)`` [-] as the surface reads them, and the names kept.

    Notes
    -----
    .. math:: z_j = (u_j - \bar u_j) / s_j, \qquad u_j = \ln x_j \text{ (positive, } \max/\min \ge 10)
       \text{ or } x_j

    An input with a single value is dropped.  A fragility curve is lognormal in the intensity [baker2015], a
    probit linear in ``ln S0``; an input swept over zero (the bed's ``eps``) stays linear.
    """
    cols, names = [], []
    for name, values in columns.items():
        x = np.asarray(values, dtype=float).reshape(-1)
        if x.size == 0 or np.ptp(x) == 0:
            continue
        if np.all(x > 0) and x.max() / x.min() >= 10.0:
            x = np.log(x)
        sd = x.std()
        cols.append((x - x.mean()) / sd)
        names.append(name)
    n = len(next(iter(columns.values()))) if columns else 0
    return (np.column_stack(cols) if cols else np.zeros((n, 0))), names


def surface_terms(z, form="linear"):
    r"""The design matrix ``(points, terms)`` of ``form`` over standardised inputs ``z``.

    Notes
    -----
    .. math:: \Phi^{-1}(p) = \beta_0 + \sum_j \beta_j z_j
       \;\Big[+ \sum_{j \le l} \gamma_{jl} z_j z_l\Big]  \quad\text{(quadratic)}
    """
    if form not in FORMS:
        raise ValueError(f"parameter 'form' must be one of {', '.join(FORMS)} (got {form!r})")
    z = np.atleast_2d(np.asarray(z, dtype=float))
    cols = [np.ones(z.shape[0])] + [z[:, j] for j in range(z.shape[1])]
    if form == "quadratic":
        cols += [z[:, j] * z[:, m] for j in range(z.shape[1]) for m in range(j, z.shape[1])]
    return np.column_stack(cols)


def _log_likelihood(eta, k, n):
    return float(np.sum(k * special.log_ndtr(eta) + (n - k) * special.log_ndtr(-eta)))


def _mills(eta):
    """``(phi / Phi, phi / (1 - Phi))`` at ``eta``, computed on the log scale (no 0 / 0 in the tails)."""
    log_pdf = stats.norm.logpdf(eta)
    return np.exp(log_pdf - special.log_ndtr(eta)), np.exp(log_pdf - special.log_ndtr(-eta))


def fit_probit_surface(x, k, n, form="linear", max_iter=100, tol=1e-10):
    """Maximum-likelihood fit of a binomial GLM with the probit link.

    Parameters
    ----------
    x : array_like
        ``(points, terms)`` design matrix [-] (:func:`surface_terms`).
    k : array_like
        Samples that reached the level (overturned, or exceeded the rotation) at each point [-].
    n : array_like
        Usable samples at each point (standing or overturned) [-], ``> 0``.
    form : str, default "linear"
        The form's name, kept in the result.
    max_iter : int, default 100
        Fisher-scoring iterations at most.
    tol : float, default 1e-10
        Convergence: the largest change of a coefficient [-].

    Returns
    -------
    Surface
        Coefficients, covariance (the inverse Fisher information, times the Pearson dispersion where it
        is > 1), dispersion, the number of points and whether the iteration converged (an ill-posed fit,
        e.g. separated counts, does not).

    Notes
    -----
    With :math:`\\eta_i = x_i^T\\beta` and :math:`p_i = \\Phi(\\eta_i)`, the log-likelihood is
    :math:`\\ell = \\sum_i k_i \\ln\\Phi(\\eta_i) + (n_i - k_i)\\ln\\Phi(-\\eta_i)`; Fisher scoring [1]_ steps
    :math:`\\beta \\leftarrow \\beta + (X^T W X)^{-1} X^T s` with the score
    :math:`s_i = k_i\\,\\phi/\\Phi - (n_i - k_i)\\,\\phi/(1 - \\Phi)` and the weight
    :math:`w_i = n_i\\,\\phi^2 / (\\Phi (1 - \\Phi))` (halved while the likelihood falls).  The covariance
    is :math:`(X^T W X)^{-1}` times the Pearson dispersion
    :math:`\\hat\\varphi = \\frac{1}{N - P}\\sum_i (k_i - n_i p_i)^2 / (n_i p_i (1 - p_i))` where
    :math:`\\hat\\varphi > 1` (quasi-binomial) [1]_.

    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    k, n = np.asarray(k, dtype=float).reshape(-1), np.asarray(n, dtype=float).reshape(-1)
    pts, terms = x.shape
    p0 = np.clip((k + 0.5) / (n + 1.0), 1e-3, 1 - 1e-3)        # start: weighted least squares on probit(p)
    sw = np.sqrt(n)
    beta = np.linalg.lstsq(x * sw[:, None], special.ndtri(p0) * sw, rcond=None)[0]
    ll = _log_likelihood(x @ beta, k, n)
    converged = False
    info = np.eye(terms)
    for _ in range(max_iter):
        eta = x @ beta
        r1, r0 = _mills(eta)
        score = x.T @ (k * r1 - (n - k) * r0)
        info = (x * (n * r1 * r0)[:, None]).T @ x
        try:
            step = np.linalg.solve(info, score)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(step)):
            break
        for _ in range(40):                                    # step halving: the likelihood never falls
            new = _log_likelihood(x @ (beta + step), k, n)
            if new >= ll - 1e-12 * abs(ll):
                break
            step = step / 2.0
        beta, ll = beta + step, new
        if np.max(np.abs(step)) < tol:
            converged = True
            break
    eta = x @ beta
    r1, r0 = _mills(eta)
    info = (x * (n * r1 * r0)[:, None]).T @ x
    try:
        cov = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        cov, converged = np.full((terms, terms), np.nan), False
    p = np.clip(special.ndtr(eta), P_FLOOR, 1 - P_FLOOR)
    dispersion = float(np.sum((k - n * p) ** 2 / (n * p * (1 - p))) / (pts - terms)) if pts > terms else np.nan
    converged = converged and bool(np.all(np.isfinite(beta)) and np.all(np.isfinite(np.diag(cov)))
                                   and np.all(np.diag(cov) > 0))
    inflate = dispersion if np.isfinite(dispersion) and dispersion > 1.0 else 1.0
    return Surface(form, beta, cov * inflate, dispersion, pts, converged)


def predict_surface(surface, x):
    r"""``(p, se)``: :math:`\Phi(x^T\hat\beta)` at the design rows ``x`` and its delta-method standard error :math:`\phi(x^T\hat\beta)\sqrt{x^T \hat C x}`."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    eta = x @ surface.coef
    var = np.einsum("ij,jk,ik->i", x, surface.cov, x)
    return special.ndtr(eta), stats.norm.pdf(eta) * np.sqrt(np.maximum(var, 0.0))


def choose_form(z, k, n):
    r"""The form of :data:`FORMS` of lowest AIC :math:`2P - 2\ell(\hat\beta)` among those the points afford, or None.

    Notes
    -----
    A form of ``P`` terms qualifies where ``points >= MIN_POINTS_PER_TERM P``, more than ``P`` points have
    ``0 < k < n`` (``k`` samples reached the level of ``n`` usable), and its fit converged.
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    k, n = np.asarray(k, dtype=float).reshape(-1), np.asarray(n, dtype=float).reshape(-1)
    mixed = int(np.sum((k > 0) & (k < n)))
    best, best_aic = None, np.inf
    for form in FORMS:
        x = surface_terms(z, form)
        terms = x.shape[1]
        if z.shape[0] < MIN_POINTS_PER_TERM * terms or mixed <= terms:
            continue
        fit = fit_probit_surface(x, k, n, form)
        if not fit.converged:
            continue
        aic = 2 * terms - 2 * _log_likelihood(x @ fit.coef, k, n)
        if aic < best_aic:
            best, best_aic = form, aic
    return best


def leave_one_out(z, k, n, form):
    """``(p, se)``: every Monte Carlo point predicted by the surface of ``form`` fitted without it (NaN where that fit did not converge)."""
    z = np.atleast_2d(np.asarray(z, dtype=float))
    k, n = np.asarray(k, dtype=float).reshape(-1), np.asarray(n, dtype=float).reshape(-1)
    x = surface_terms(z, form)
    p, se = np.full(k.size, np.nan), np.full(k.size, np.nan)
    for i in range(k.size):
        keep = np.arange(k.size) != i
        fit = fit_probit_surface(x[keep], k[keep], n[keep], form)
        if fit.converged:
            p[i], se[i] = (v[0] for v in predict_surface(fit, x[i:i + 1]))
    return p, se


def loo_check(k, n, p_loo, se_loo):
    r"""Whether the held-out predictions agree with the Monte Carlo points they left out.

    Returns ``(share, in_play, passed)``: ``share`` share [-] of the points in play whose prediction is
    within :data:`LOO_Z` combined standard errors of the point (NaN when none is in play); ``in_play``
    points in play: some of their samples reached the level, or the prediction expects at least one (``n
    p_loo >= 1``), or the prediction is not finite (counted as a miss); ``passed`` ``in_play >=
    MIN_IN_PLAY`` and the misses at most ``max(1, floor((1 - LOO_PASS) in_play))``: a share of at least
    ``LOO_PASS``, one miss allowed below ten points.

    Notes
    -----
    A point holds when :math:`|\hat p_{(-i)} - k_i/n_i| \le z\sqrt{\mathrm{se}_{(-i)}^2 + \mathrm{se}_i^2}`,
    :math:`\mathrm{se}_i` the Agresti-Coull standard error of the point's fraction [agresti1998] and :math:`z` =
    :data:`LOO_Z`.  Points where neither the samples nor the surface expect the level to be reached are
    left out of the share: they would pass whatever the surface does elsewhere.
    """
    z, finite, play = _held_out_z(k, n, p_loo, se_loo)
    with np.errstate(invalid="ignore"):
        holds = finite & (np.abs(z) <= LOO_Z)
    in_play = int(play.sum())
    share = float(np.mean(holds[play])) if in_play else np.nan
    misses = in_play - int(np.sum(holds[play]))
    allowed = max(1, int(np.floor((1.0 - LOO_PASS) * in_play + 1e-9)))
    return share, in_play, bool(in_play >= MIN_IN_PLAY and misses <= allowed)


def loo_scale(k, n, p_loo, se_loo):
    r"""The factor by which the held-out errors say the surface's standard errors are too small.

    Returns: ``max(1, sqrt(mean(z_i^2)))`` [-] over the points in play with a finite prediction (1 when
    fewer than :data:`MIN_IN_PLAY`).

    Notes
    -----
    :math:`z_i = (\hat p_{(-i)} - k_i/n_i) / \sqrt{\mathrm{se}_{(-i)}^2 + \mathrm{se}_i^2}` is
    standard normal where the surface's form is right and its standard error honest; a root mean square above
    1 means the form misses part of the surface (a bias the delta method does not see), and the standard
    errors are widened by it, as a normalised cross-validation residual calibrates a predictive interval [1]_.
    It never narrows them.  Points in play as in :func:`loo_check`.
    """
    z, finite, play = _held_out_z(k, n, p_loo, se_loo)
    use = finite & play
    if use.sum() < MIN_IN_PLAY:
        return 1.0
    return float(max(1.0, np.sqrt(np.mean(z[use] ** 2))))


def _held_out_z(k, n, p_loo, se_loo):
    """z-scores of the held-out predictions against the Monte Carlo fractions, which are finite, and which
    points are in play (some samples reached the level, the prediction expects one, or it is not finite)."""
    k, n = np.asarray(k, dtype=float).reshape(-1), np.asarray(n, dtype=float).reshape(-1)
    p_loo, se_loo = np.asarray(p_loo, dtype=float).reshape(-1), np.asarray(se_loo, dtype=float).reshape(-1)
    frac, se = binomial_estimate(k, n)
    finite = np.isfinite(p_loo) & np.isfinite(se_loo)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = (p_loo - frac) / np.sqrt(se_loo ** 2 + se ** 2)
        play = (k > 0) | ~finite | (n * p_loo >= 1.0)
    return z, finite, play


def inside_hull(z_points, z):
    """Boolean: the points ``z`` inside (or on) the convex hull of the Monte Carlo points ``z_points`` (Qhull Delaunay simplices).

    Notes
    -----
    With fewer Monte Carlo points than ``inputs + 1`` or a flat hull, the box of their ranges; with no input, True.
    """
    zp = np.atleast_2d(np.asarray(z_points, dtype=float))
    z = np.atleast_2d(np.asarray(z, dtype=float))
    if z.shape[1] == 0:
        return np.ones(z.shape[0], dtype=bool)
    lo, hi = zp.min(axis=0), zp.max(axis=0)
    tol = 1e-9 * np.maximum(hi - lo, 1.0)
    box = np.all((z >= lo - tol) & (z <= hi + tol), axis=1)
    if z.shape[1] == 1 or zp.shape[0] < z.shape[1] + 1:
        return box
    try:
        return box & (Delaunay(zp).find_simplex(z, tol=1e-9) >= 0)
    except QhullError:
        return box


def study_surface(z, k, n):
    """The study's surface for one level: the form the points afford, its fit and whether it is vouched for.

    Returns: the fit on every point with its leave-one-out share and ``vouched`` (the fit converged and
    :func:`loo_check` passed); None when no form qualifies (:func:`choose_form`: too few points, or too few
    with ``0 < k < n``).

    Notes
    -----
    The steps: :func:`choose_form`, :func:`fit_probit_surface` on every point, :func:`leave_one_out`,
    :func:`loo_check`, and the covariance widened by :func:`loo_scale` squared.  The points where the surface may be used are those :func:`inside_hull` finds (the
    caller's step).
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    k, n = np.asarray(k, dtype=float).reshape(-1), np.asarray(n, dtype=float).reshape(-1)
    form = choose_form(z, k, n)
    if form is None:
        return None
    fit = fit_probit_surface(surface_terms(z, form), k, n, form)
    held_out = leave_one_out(z, k, n, form)
    share, in_play, passed = loo_check(k, n, *held_out)
    scale = loo_scale(k, n, *held_out)
    vouched = fit.converged and passed
    reason = "" if vouched else (
        "the fit did not converge" if not fit.converged else
        f"leave-one-out: {share:.0%} of {in_play} held-out Monte Carlo points within {LOO_Z:g} combined SE "
        f"(needs {LOO_PASS:.0%}, one miss allowed, of at least {MIN_IN_PLAY})")
    return fit._replace(cov=fit.cov * scale ** 2, loo_scale=scale, loo_share=share, loo_in_play=in_play,
                        vouched=vouched, reason=reason)
