"""The two-fidelity (control-variate) estimator: exact algebra, unbiasedness and honest standard errors
over seeds, the allocation against a brute-force optimum, and paired coupled/condensed samples of the
Monte Carlo engine against an independent plain run."""

import math

import numpy as np
import pytest

from screening.analysis.multifidelity import control_variate_estimate, optimal_ratio, speedup

REPEATS = 400


def _pairs(rng, n, rho, mu_y=1.0, sigma_y=2.0):
    x = rng.normal(size=n)
    y = mu_y + sigma_y * (rho * x + math.sqrt(1 - rho * rho) * rng.normal(size=n))
    return y, x


def test_without_extra_cheap_samples_the_estimate_is_the_plain_one():
    y, x = _pairs(np.random.default_rng(1), 50, 0.9)
    est = control_variate_estimate(y, x)
    assert est.mean == pytest.approx(y.mean(), rel=1e-14)
    assert est.se == pytest.approx(np.std(y, ddof=1) / math.sqrt(50), rel=1e-12)
    assert est.correlation == pytest.approx(np.corrcoef(x, y)[0, 1], rel=1e-12)


@pytest.mark.parametrize("rho, n, m", [(0.95, 40, 360), (0.5, 60, 120), (0.0, 50, 200)])
def test_unbiased_and_its_standard_error_matches_the_scatter_over_seeds(rho, n, m):
    """400 independent repetitions: the mean of the estimates is within 4 of its own standard errors
    of the true mean 1.0; the scatter of the estimates matches the reported standard error (the
    relative sampling error of a standard deviation over 400 repetitions is 1/sqrt(800) = 3.5 %:
    bound 15 %), and both match the closed form sigma_y^2/n [1 - (1 - n/N) rho^2]."""
    rng = np.random.default_rng(7)
    means, ses = [], []
    for _ in range(REPEATS):
        y, x = _pairs(rng, n, rho)
        extra = rng.normal(size=m)
        est = control_variate_estimate(y, x, x_extra=extra)
        means.append(est.mean)
        ses.append(est.se)
    means = np.array(means)
    scatter = np.std(means, ddof=1)
    assert abs(means.mean() - 1.0) <= 4 * scatter / math.sqrt(REPEATS)
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.15)
    theory = 2.0 * math.sqrt((1 - (1 - n / (n + m)) * rho * rho) / n)
    assert scatter / theory == pytest.approx(1.0, abs=0.15)


def test_exceedance_indicators_are_estimated_without_bias():
    """Probabilities: indicators of a latent correlated pair exceeding a level (what paired models'
    peaks do); true P = P(Z > 1) = 0.1587 for the expensive one."""
    rng = np.random.default_rng(11)
    p_true = 0.5 * math.erfc(1 / math.sqrt(2))
    means, ses = [], []
    for _ in range(REPEATS):
        z_cheap = rng.normal(size=250)
        z = 0.95 * z_cheap[:50] + math.sqrt(1 - 0.95 ** 2) * rng.normal(size=50)
        cheap = (z_cheap > 0.9).astype(float)           # the cheap model exceeds a little more often
        est = control_variate_estimate((z > 1.0).astype(float), cheap[:50], x_extra=cheap[50:])
        means.append(est.mean)
        ses.append(est.se)
    means = np.array(means)
    scatter = np.std(means, ddof=1)
    assert abs(means.mean() - p_true) <= 4 * scatter / math.sqrt(REPEATS)
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.15)
    plain = math.sqrt(p_true * (1 - p_true) / 50)
    assert scatter < 0.8 * plain                        # the cheap samples pay


def test_a_known_cheap_mean_is_the_classical_control_variate():
    rng = np.random.default_rng(3)
    means = []
    for _ in range(REPEATS):
        y, x = _pairs(rng, 30, 0.9)
        means.append(control_variate_estimate(y, x, x_mean=0.0).mean)
    scatter = np.std(means, ddof=1)
    assert scatter / (2.0 * math.sqrt((1 - 0.81) / 30)) == pytest.approx(1.0, abs=0.15)


def test_the_optimal_ratio_minimises_variance_times_cost_by_brute_force():
    for rho, c1, c2 in [(0.95, 1.0, 0.05), (0.9, 46.0, 1.5), (0.7, 1.0, 0.3), (0.99, 12.0, 0.4)]:
        r = np.linspace(1.0, 400.0, 400_001)
        work = (c1 + r * c2) * (1 - (1 - 1 / r) * rho ** 2)
        assert optimal_ratio(rho, c1, c2) == pytest.approx(r[np.argmin(work)], rel=1e-3, abs=2e-3)
        assert speedup(rho, c1, c2) == pytest.approx(c1 / work.min(), rel=1e-6)


def test_a_perfect_pilot_correlation_asks_for_a_bounded_number_of_cheap_samples():
    from screening.analysis.multifidelity import MAX_RATIO

    assert optimal_ratio(1.0, 10.0, 1.0) == MAX_RATIO
    assert optimal_ratio(1.0, 10.0, 1.0, max_ratio=50.0) == 50.0


def test_the_cheap_model_is_not_worth_it_when_uncorrelated_or_as_expensive():
    assert optimal_ratio(0.0, 1.0, 0.01) == 1.0
    assert speedup(0.0, 1.0, 0.01) < 1.0
    assert speedup(0.9, 1.0, 1.0) < 1.0
    assert speedup(0.95, 30.0, 1.0) > 3.0


@pytest.mark.parametrize("kwargs, word", [({"y": [1, 2], "x": [1, 2]}, "at least 3"),
                                          ({"y": [1, 2, 3], "x": [1, 2]}, "paired"),
                                          ({"y": [1, 2, np.nan], "x": [1, 2, 3]}, "finite"),
                                          ({"y": [1, 2, 3], "x": [1, 2, 3], "x_mean": 0.0, "x_extra": [1.0]}, "either")])
def test_bad_input_names_the_parameter(kwargs, word):
    with pytest.raises(ValueError, match=word):
        control_variate_estimate(**kwargs)


@pytest.mark.slow
def test_paired_condensed_samples_reduce_the_error_of_coupled_exceedance_without_bias():
    """The paper block (fig. 3 case): 64 coupled samples paired with condensed (virtual_work) ones, and
    448 more condensed samples, against an independent 512-sample plain coupled run (other seed):
    P(peak |theta| > a) agrees within 4 combined standard errors, and the paired estimate's standard
    error is never above the plain 64-sample one (at this heavy-uplift point the indicators of the
    two models correlate weakly, about 0.2: the weight follows and the estimate falls back towards
    the plain one, which is the "never worse" half of the contract)."""
    from screening.model import Block, Foundation, WhiteNoise
    from screening.model.cases import PAPER_BED, PAPER_BLOCK
    from screening.solvers.montecarlo import monte_carlo

    block, bed = Block(**PAPER_BLOCK), Foundation(eps=6e7, **PAPER_BED)
    excitation = WhiteNoise(S0=2.4e-3)
    kw = dict(t_end=20.0, dt=0.05)
    coupled = monte_carlo(block, bed, excitation, n_samples=64, model="coupled", seed=5, **kw)
    cheap = monte_carlo(block, bed, excitation, n_samples=512, model="condensed", condensation="virtual_work",
                        seed=5, **kw)
    reference = monte_carlo(block, bed, excitation, n_samples=512, model="coupled", seed=6, **kw)

    def exceeds(ds, level):
        return ((ds.peak_abs_theta.values > level) | ds.overturned.values).astype(float)

    level = 0.3 * math.atan(block.b / block.h)
    y, x = exceeds(coupled, level), exceeds(cheap, level)
    est = control_variate_estimate(y, x[:64], x_extra=x[64:])
    p_ref = exceeds(reference, level).mean()
    se_ref = math.sqrt(max(p_ref * (1 - p_ref), 1e-12) / 512)
    assert 0.05 < p_ref < 0.95                  # a level the test can resolve
    assert abs(est.mean - p_ref) <= 4 * math.hypot(est.se, se_ref)
    assert est.se <= est.plain_se * (1 + 1e-12)
    assert abs(est.weight * np.std(x, ddof=1) / np.std(y, ddof=1) - est.correlation) < 0.1
