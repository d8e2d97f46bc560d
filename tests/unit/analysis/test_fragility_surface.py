"""The study's fragility surface (screening.analysis.fragility_surface): a probit GLM fitted on the study's
Monte Carlo points, checked against independent computations and against synthetic binomial data drawn from
known surfaces (fixed seeds)."""

import numpy as np
import pytest
from scipy import optimize, special
from scipy.spatial import ConvexHull

from screening.analysis import fragility_surface as fs

#: A surface the linear form follows: probit(p) = -0.5 + 1.5 z0 - 0.8 z1 (a lognormal fragility in S0 whose
#: median moves with a second input).
TRUE = np.array([-0.5, 1.5, -0.8])


def _synthetic(seed, points=40, samples=800, coef=TRUE):
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1.5, 1.5, size=(points, 2))
    n = np.full(points, samples, dtype=float)
    k = rng.binomial(samples, special.ndtr(fs.surface_terms(z) @ coef)).astype(float)
    return z, k, n


def test_the_fit_is_the_maximum_of_the_likelihood_and_its_covariance_the_inverse_hessian():
    """Independent: scipy's minimiser of the negative log-likelihood, and a finite-difference Hessian."""
    z, k, n = _synthetic(1)
    x = fs.surface_terms(z)
    fit = fs.fit_probit_surface(x, k, n)

    def nll(b):
        eta = x @ b
        return -np.sum(k * special.log_ndtr(eta) + (n - k) * special.log_ndtr(-eta))

    ref = optimize.minimize(nll, np.zeros(3), method="Nelder-Mead", options=dict(xatol=1e-10, fatol=1e-12,
                                                                                 maxiter=20000))
    assert fit.converged
    np.testing.assert_allclose(fit.coef, ref.x, atol=1e-5)
    h = 1e-4
    hess = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            e_i, e_j = np.eye(3)[i] * h, np.eye(3)[j] * h
            hess[i, j] = (nll(fit.coef + e_i + e_j) - nll(fit.coef + e_i - e_j) - nll(fit.coef - e_i + e_j)
                          + nll(fit.coef - e_i - e_j)) / (4 * h * h)
    inflate = max(fit.dispersion, 1.0)
    # Fisher information and the observed one agree at the MLE up to the sampling noise of the counts
    np.testing.assert_allclose(fit.cov / inflate, np.linalg.inv(hess), rtol=0.05, atol=1e-6)


def test_the_fit_recovers_a_known_probit_surface_within_its_standard_errors():
    """40 points x 800 samples from TRUE (seed 3): every coefficient within 3 SE (a 3-SE miss has odds
    0.3 % per coefficient), and the surface within 3 of its SE at >= 90 % of 200 new points."""
    z, k, n = _synthetic(3)
    fit = fs.study_surface(z, k, n)
    assert fit is not None and fit.vouched and fit.form in fs.FORMS
    linear = fs.fit_probit_surface(fs.surface_terms(z), k, n)
    se = np.sqrt(np.diag(linear.cov))
    assert np.all(np.abs(linear.coef - TRUE) <= 3 * se)
    znew = np.random.default_rng(4).uniform(-1.4, 1.4, size=(200, 2))
    p, p_se = fs.predict_surface(fit, fs.surface_terms(znew, fit.form))
    truth = special.ndtr(fs.surface_terms(znew) @ TRUE)
    assert np.mean(np.abs(p - truth) <= 3 * p_se) >= 0.9
    # and its dispersion is that of binomial counts: near 1 (chi2 with 37 dof / 37: sd 0.23)
    assert 0.4 < linear.dispersion < 1.7


def test_the_delta_method_standard_error_is_that_of_draws_of_the_coefficients():
    """Independent: the spread of Phi(x b) over 20,000 coefficient draws from N(b_hat, cov) (seed 5);
    the draws' SE of a standard deviation is ~0.5 %, the delta method's linearization ~1 % here."""
    z, k, n = _synthetic(2)
    fit = fs.fit_probit_surface(fs.surface_terms(z), k, n)
    at = fs.surface_terms(np.array([[0.3, -0.4], [1.0, 1.0], [-1.0, 0.5]]))
    _, se = fs.predict_surface(fit, at)
    draws = np.random.default_rng(5).multivariate_normal(fit.coef, fit.cov, size=20000)
    spread = special.ndtr(draws @ at.T).std(axis=0)
    np.testing.assert_allclose(se, spread, rtol=0.05)


def test_overdispersed_counts_inflate_the_covariance_by_the_pearson_factor():
    """Beta-binomial counts (seed 6, intra-point correlation 0.05 at 800 samples: variance x ~41) give a
    dispersion far above 1, and the covariance is the Fisher one times it."""
    rng = np.random.default_rng(6)
    z, _, n = _synthetic(6)
    p = special.ndtr(fs.surface_terms(z) @ TRUE)
    rho = 0.05
    a, b = p * (1 / rho - 1), (1 - p) * (1 / rho - 1)
    k = rng.binomial(n.astype(int), rng.beta(a, b)).astype(float)
    fit = fs.fit_probit_surface(fs.surface_terms(z), k, n)
    x = fs.surface_terms(z)
    eta = x @ fit.coef
    pdf, cdf = np.exp(-eta ** 2 / 2) / np.sqrt(2 * np.pi), special.ndtr(eta)
    fisher = np.linalg.inv((x * (n * pdf ** 2 / (cdf * (1 - cdf)))[:, None]).T @ x)
    chi2 = np.sum((k - n * cdf) ** 2 / (n * cdf * (1 - cdf))) / (z.shape[0] - 3)
    assert fit.dispersion == pytest.approx(chi2, rel=1e-9) and fit.dispersion > 10
    np.testing.assert_allclose(fit.cov, fisher * fit.dispersion, rtol=1e-6)


def test_the_leave_one_out_check_passes_on_the_model_form_and_fails_on_a_surface_it_cannot_follow():
    z, k, n = _synthetic(7)
    share, in_play, passed = fs.loo_check(k, n, *fs.leave_one_out(z, k, n, "linear"))
    assert passed and share >= fs.LOO_PASS and in_play >= 30
    # probit(p) = 2 sin(3 z0): three swings over the range, beyond a linear or quadratic probit
    wavy = np.random.default_rng(8)
    k_wavy = wavy.binomial(800, special.ndtr(2 * np.sin(3 * z[:, 0]))).astype(float)
    fit = fs.study_surface(z, k_wavy, n)
    assert fit is not None and not fit.vouched and fit.loo_share < fs.LOO_PASS
    assert "leave-one-out" in fit.reason


def test_held_out_errors_widen_the_standard_errors_by_their_rms_z_and_never_narrow_them():
    """Independent: the z-scores written out from the held-out predictions and Agresti-Coull errors."""
    z, k, n = _synthetic(7)
    p, se = fs.leave_one_out(z, k, n, "linear")
    frac, tilde = k / n, (k + 2) / (n + 4)
    se_mc = np.sqrt(tilde * (1 - tilde) / (n + 4))
    play = (k > 0) | (n * p >= 1)
    rms = np.sqrt(np.mean(((p - frac) / np.hypot(se, se_mc))[play] ** 2))
    assert fs.loo_scale(k, n, p, se) == pytest.approx(max(1.0, rms), rel=1e-12)
    # a surface the linear form follows only roughly: the held-out errors exceed the delta method's
    rng = np.random.default_rng(3)
    k_bent = rng.binomial(800, special.ndtr(fs.surface_terms(z) @ TRUE + 0.4 * z[:, 0] ** 2)).astype(float)
    fit = fs.study_surface(z, k_bent, n)
    plain = fs.fit_probit_surface(fs.surface_terms(z, fit.form), k_bent, n, fit.form)
    scale = fs.loo_scale(k_bent, n, *fs.leave_one_out(z, k_bent, n, fit.form))
    assert fit.loo_scale == pytest.approx(scale, rel=1e-12) and fit.loo_scale >= 1.0
    np.testing.assert_allclose(fit.cov, plain.cov * scale ** 2, rtol=1e-12)
    # the form right and the errors honest: the factor stays near 1 (20-40 points in play: RMS z within ~0.35)
    assert fs.study_surface(z, k, n).loo_scale < 1.35


def test_leave_one_out_predicts_each_point_from_the_others():
    z, k, n = _synthetic(9, points=12)
    p, se = fs.leave_one_out(z, k, n, "linear")
    x = fs.surface_terms(z)
    for i in (0, 5, 11):
        keep = np.arange(12) != i
        q, s = fs.predict_surface(fs.fit_probit_surface(x[keep], k[keep], n[keep]), x[i:i + 1])
        assert (p[i], se[i]) == (pytest.approx(q[0], rel=1e-12), pytest.approx(s[0], rel=1e-12))


def test_too_few_points_with_some_overturned_give_no_surface():
    z = np.linspace(-1, 1, 10)[:, None]
    n = np.full(10, 500.0)
    k = np.zeros(10)
    k[-2:] = [3, 40]                       # two points with 0 < k < n: fewer than the linear form's terms + 1
    assert fs.choose_form(z, k, n) is None and fs.study_surface(z, k, n) is None


def test_the_hull_against_the_half_spaces_of_scipys_convex_hull():
    rng = np.random.default_rng(10)
    pts = rng.normal(size=(25, 2))
    ask = rng.uniform(-3, 3, size=(2000, 2))
    eq = ConvexHull(pts).equations
    inside = np.all(ask @ eq[:, :2].T + eq[:, 2] <= 1e-12, axis=1)
    np.testing.assert_array_equal(fs.inside_hull(pts, ask), inside)
    # one input: the range; too few points for a hull: the box of their ranges
    np.testing.assert_array_equal(fs.inside_hull([[0.0], [2.0]], [[-0.1], [1.0], [2.0], [2.1]]),
                                  [False, True, True, False])
    np.testing.assert_array_equal(fs.inside_hull([[0.0, 0.0], [1.0, 1.0]], [[0.5, 0.9], [1.5, 0.5]]), [True, False])


def test_inputs_are_logged_where_they_span_a_decade_and_standardised():
    z, names = fs.surface_inputs({"S0": [1e-5, 1e-4, 1e-3, 1e-2], "eps": [-6e5, 0.0, 3e7, 6e7],
                                  "k": [2.0, 2.0, 2.0, 2.0], "h": [1.0, 1.5, 2.0, 2.5]})
    assert names == ["S0", "eps", "h"]
    u = np.log10([1e-5, 1e-4, 1e-3, 1e-2])
    np.testing.assert_allclose(z[:, 0], (u - u.mean()) / u.std())
    eps = np.array([-6e5, 0.0, 3e7, 6e7])
    np.testing.assert_allclose(z[:, 1], (eps - eps.mean()) / eps.std())
    h = np.array([1.0, 1.5, 2.0, 2.5])                 # positive, but within a factor 10: linear
    np.testing.assert_allclose(z[:, 2], (h - h.mean()) / h.std())
    with pytest.raises(ValueError, match="parameter 'form'"):
        fs.surface_terms(z, "cubic")
