import numpy as np
import pytest
from scipy import integrate, stats

from screening import Block, Foundation, WhiteNoise, linearize
from screening.schema import PARAMETERS
from screening.analysis.fragility import (exceedance_probability_from_moments, fit_lognormal_fragility,
                                 lognormal_fragility, mcs_exceedance_probability,
                                 oscillator_bandwidth, upcrossing_rate, vanmarcke_factor)


def test_stationary_rate_is_rice():
    s, sv, a = 2e-3, 0.09, np.array([1e-3, 4e-3, 8e-3])
    nu = upcrossing_rate(s**2, sv**2, 0.0, a)
    np.testing.assert_allclose(nu, (sv / (np.pi * s)) * np.exp(-a**2 / (2 * s**2)), rtol=1e-13)


@pytest.mark.parametrize("rho", [-0.8, -0.2, 0.3, 0.9])
def test_correlated_rate_matches_quadrature_of_rice_integral(rho):
    s, sv, a = 1.5e-3, 0.07, 2.2e-3
    cov = np.array([[s * s, rho * s * sv], [rho * s * sv, sv * sv]])
    pdf = stats.multivariate_normal(mean=[0, 0], cov=cov).pdf
    up = integrate.quad(lambda v: v * pdf([a, v]), 0, np.inf, epsrel=1e-11)[0]
    down = integrate.quad(lambda v: -v * pdf([-a, v]), -np.inf, 0, epsrel=1e-11)[0]
    assert upcrossing_rate(s * s, sv * sv, rho * s * sv, a) == pytest.approx(up + down, rel=1e-8)


def test_rate_is_zero_before_motion_and_finite():
    assert upcrossing_rate(0.0, 0.0, 0.0, 1e-3) == 0.0
    assert np.isfinite(upcrossing_rate(1e-12, 1e-9, 0.0, 1.0))


def test_poisson_probability_for_a_stationary_record():
    t = np.linspace(0, 20, 2001)
    s, sv, a = 1e-3, 0.04, 3e-3
    p = exceedance_probability_from_moments(t, np.full_like(t, s * s), np.full_like(t, sv * sv),
                                            np.zeros_like(t), a, method="poisson")
    nu = sv / (np.pi * s) * np.exp(-a**2 / (2 * s * s))
    assert p == pytest.approx(-np.expm1(-nu * 20.0), rel=1e-10)


def test_bandwidth_of_linear_oscillator_matches_spectral_moments():
    for zeta in (0.02, 0.1, 0.4):
        H2 = lambda w: 1.0 / ((1 - w * w) ** 2 + (2 * zeta * w) ** 2)
        lam = [integrate.quad(lambda w: w**i * H2(w), 0, np.inf, limit=400, epsrel=1e-11, points=None)[0]
               for i in range(3)]
        delta = np.sqrt(1 - lam[1] ** 2 / (lam[0] * lam[2]))
        assert oscillator_bandwidth(zeta) == pytest.approx(delta, rel=1e-6)


def test_vanmarcke_factor_limits():
    assert vanmarcke_factor(1.0, 300.0, 0.3) == pytest.approx(1.0, rel=1e-12)  # high barrier: Poisson
    assert vanmarcke_factor(1.0, 30.0, 0.3) == pytest.approx(-np.expm1(-np.sqrt(np.pi / 2) * 0.3**1.2 * 30), rel=1e-12)
    assert 0 < vanmarcke_factor(1.0, 2.0, 0.2) < 1.0  # clumping of narrow-band crossings
    assert vanmarcke_factor(0.0, 1.0, 0.2) == 0.0


def test_lognormal_fit_recovers_parameters_from_probabilities():
    im = np.logspace(-5, -2, 25)
    median, beta = fit_lognormal_fragility(im, lognormal_fragility(im, 3e-4, 0.7))
    assert median == pytest.approx(3e-4, rel=1e-9) and beta == pytest.approx(0.7, rel=1e-9)


def test_lognormal_fit_recovers_parameters_from_binomial_samples():
    rng = np.random.default_rng(11)
    im = np.logspace(-5, -2, 15)
    n = 400
    k = rng.binomial(n, lognormal_fragility(im, 3e-4, 0.6))
    median, beta = fit_lognormal_fragility(im, n_exceed=k, n_total=n)
    # sampling error of the MLE with 15 x 400 trials is a few percent
    assert median == pytest.approx(3e-4, rel=0.1) and beta == pytest.approx(0.6, rel=0.15)


def test_mcs_exceedance_counts_overturned_samples():
    p, se = mcs_exceedance_probability([0.1, 0.3, 0.05, 0.2], 0.15, overturned=[False, False, True, False])
    assert p == 0.75 and se == pytest.approx(np.sqrt(0.75 * 0.25 / 4))


def test_accessor_on_a_linearization_result():
    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, -6e5)
    ds = linearize(block, bed, WhiteNoise(5e-4))
    p_small = float(ds.rocking.exceedance_probability(1e-3))
    p_large = float(ds.rocking.exceedance_probability(1e-2))
    assert 0 < p_large < p_small <= 1
    p_rel = float(ds.rocking.exceedance_probability(0.05, relative_to="slenderness"))
    p_abs = float(ds.rocking.exceedance_probability(0.05 * np.arctan(0.035 / 0.21)))
    assert p_rel == pytest.approx(p_abs, rel=1e-12)
    p_poisson = float(ds.rocking.exceedance_probability(5e-3, method="poisson"))
    p_vanm = float(ds.rocking.exceedance_probability(5e-3, method="vanmarcke"))
    assert p_vanm < p_poisson


def test_fragility_curve_over_s0_from_a_batch():
    S0 = np.logspace(-6, -3, 13)
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 0.0), WhiteNoise(S0))
    curve = ds.rocking.fragility_curve(0.5, dim="S0", relative_to="theta_ul")
    p, median, beta = curve["p_exceed"], curve["median"], curve["beta"]
    assert p.dims == ("S0",) and np.all(np.diff(p.values) >= 0)
    assert S0[0] < float(median) < S0[-1] and 0 < float(beta) < 5
    assert median.attrs["units"] == PARAMETERS["S0"]["units"] and beta.attrs["units"] == "1"


@pytest.mark.parametrize("S0, ratio", [(2e-6, 0.4), (5e-6, 0.4), (5e-6, 0.6)])
def test_gaussian_fragility_matches_monte_carlo_peaks_on_a_linear_case(S0, ratio):
    """No uplift (sigma_theta < theta_ul / 5), eps = 0: the condensed model is linear and Gaussian.

    Tolerance: 3 binomial standard errors of the 1000-sample estimate plus 0.03 for the
    Vanmarcke approximation itself (measured: 0.004-0.037 above the Monte Carlo value here,
    while the Poisson approximation is 0.1-0.2 above it).
    """
    from screening import Envelope, uplift_threshold
    from screening.solvers.montecarlo import monte_carlo

    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 0.0)
    exc = WhiteNoise(S0=S0, envelope=Envelope(T1=4.0, T2=2.0))
    ds = linearize(block, bed, exc)
    level = ratio * float(uplift_threshold(block, bed))
    assert float(ds["p_uplift"].max()) < 1e-5
    mc = monte_carlo(block, bed, exc, n_samples=1000, model="condensed", seed=1)
    p_mcs, se = mcs_exceedance_probability(mc["peak_abs_theta"].values, level, mc["overturned"].values)
    p_vanmarcke = float(ds.rocking.exceedance_probability(level, method="vanmarcke"))
    p_poisson = float(ds.rocking.exceedance_probability(level, method="poisson"))
    assert 0.05 < p_mcs < 0.95
    assert abs(p_vanmarcke - p_mcs) < 3 * se + 0.03
    assert p_poisson > p_vanmarcke                      # Poisson ignores clumping: conservative
