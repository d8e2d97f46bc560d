"""Subset simulation (screening.solvers.tail): its bias on a closed form, its standard error, and the stiff-bed
model's small probabilities against crude Monte Carlo on the same model."""

import warnings

import numpy as np
import pytest
from scipy.stats import norm

from screening import Block, KanaiTajimi, monte_carlo
from screening.core.model import Foundation
from screening.solvers.tail import chain_correlation_factor, combine_runs, subset_simulation, tail_probability

STATUE = Block(m=1200.0, b=0.25, h=0.9)
BED = Foundation(k=1e10, lam=2.08e11)                  # 5 % vertical damping (benchmarks/tail_estimator.py)


def _linear(dim):
    return lambda u: u.sum(axis=1) / np.sqrt(dim)       # Y ~ N(0, 1): P(Y > y) = Phi(-y)


def test_chain_correlation_factor_is_zero_for_independent_chains_and_two_for_stuck_ones():
    rng = np.random.default_rng(3)
    iid = rng.random((10, 2000)) < 0.1
    # gamma of independent samples: a sum of 9 sample autocorrelations, each with SE ~ 1 / sqrt(N) = 0.007
    assert abs(chain_correlation_factor(iid)) < 2 * 9 * 3 / np.sqrt(iid.size)
    stuck = np.repeat(rng.random((1, 2000)) < 0.1, 10, axis=0)
    assert chain_correlation_factor(stuck) == pytest.approx(9.0)      # 2 sum_k (1 - k/10), k = 1..9
    assert chain_correlation_factor(iid[:1]) == 0.0


@pytest.mark.parametrize("sampler", ["acs", "mma"])
def test_no_bias_on_a_gaussian_limit_state_and_the_cov_is_the_spread(sampler):
    """200 independent runs at P = Phi(-3.09) = 1e-3: their mean within 3 standard errors of the mean (its
    empirical spread / sqrt(200), ~2.3 %) of the closed form; the reported CoV within the 3-sigma sampling error
    of the empirical one (~5 % for 200 runs) widened by Au & Beck's neglect of the correlation between levels."""
    dim, runs, exact = 20, 200, norm.sf([2.326, 3.09])
    est = [subset_simulation(_linear(dim), dim, [2.326, 3.09], n_per_level=500, seed=s, sampler=sampler)
           for s in range(runs)]
    p = np.array([e.p for e in est])
    cov = np.array([e.cov for e in est])
    spread = p.std(axis=0, ddof=1)
    assert np.all(np.abs(p.mean(axis=0) - exact) < 3 * spread / np.sqrt(runs))
    ratio = (spread / p.mean(axis=0)) / cov.mean(axis=0)
    assert np.all((0.8 < ratio) & (ratio < 1.5)), ratio
    assert est[0].n_calls <= 500 + 3 * 550       # 3 levels of chains after the first (ties may cost a longer chain)


def test_thresholds_reached_by_no_sample_are_nan_and_bad_input_is_refused():
    est = subset_simulation(_linear(5), 5, [1.0, 50.0], n_per_level=100, seed=0, max_levels=2)
    assert est.p[0] == pytest.approx(norm.sf(1.0), rel=4 * est.cov[0]) and np.isnan(est.p[1])
    with pytest.raises(ValueError, match="parameter 'p0'"):
        subset_simulation(_linear(5), 5, [1.0], n_per_level=100, p0=0.123)
    with pytest.raises(ValueError, match="parameter 'sampler'"):
        subset_simulation(_linear(5), 5, [1.0], sampler="gibbs")
    with pytest.raises(ValueError, match="parameter 'thresholds'"):
        tail_probability(STATUE, BED, KanaiTajimi(S0=0.01, omega_g=15.6, zeta_g=0.6), thresholds=[-0.1])


def test_stiff_bed_tail_agrees_with_crude_monte_carlo_within_the_standard_errors():
    """A 5 s record where P(peak |theta| > 0.07 rad) ~ 0.03: subset simulation (2 x 150 samples a level, 2 levels)
    against 3,000 crude samples of the same model (binomial SE ~ 0.003); the difference within 3 standard errors
    of the difference (two runs of 150 a level: their combined standard error; the binomial one for crude Monte
    Carlo)."""
    quake = KanaiTajimi(S0=0.01, omega_g=15.6, zeta_g=0.6, band_limit_hz=None)   # the case as measured (idealized input)
    common = dict(model="stiff_bed", t_end=5.0, dt=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)        # the model's validity note, if any
        crude = monte_carlo(STATUE, BED, quake, n_samples=3000, seed=11, thresholds=[0.07], progress=False, **common)
        tail = tail_probability(STATUE, BED, quake, thresholds=[0.07], n_per_level=150, runs=2, seed=5,
                                max_levels=2, **common)
    p_c, se_c = float(crude.p_exceed[0]), float(crude.p_exceed_se[0])
    p_s, se_s = float(tail.p_exceed[0]), float(tail.p_exceed_se[0])
    assert 0.01 < p_c < 0.08, p_c                          # the case is where it is meant to be
    assert abs(p_s - p_c) < 3 * np.hypot(se_s, se_c), (p_s, se_s, p_c, se_c)
    assert tail.attrs["n_model_runs"] < 3000 / 3 and tail.attrs["model"] == "stiff_bed"


def test_overturned_samples_are_inf_and_samples_without_an_answer_never_exceed():
    """+inf (an overturned sample) exceeds every threshold, the largest float included; NaN (a diverged sample)
    none: P(Y = inf) = Phi(-3) (the NaN region u_0 < -2.5 meets z > 3 with a probability of about 1e-7)."""
    def response(u):
        z = u.sum(axis=1) / np.sqrt(u.shape[1])
        out = np.where(z > 3.0, np.inf, z)
        return np.where(u[:, 0] < -2.5, np.nan, out)

    est = subset_simulation(response, 10, [np.finfo(float).max, 2.0], n_per_level=1000, seed=2)
    assert abs(est.p[0] - norm.sf(3.0)) < 3 * est.cov[0] * norm.sf(3.0), (est.p, est.cov)
    assert est.n_missing > 0 and np.all(np.isfinite(est.level_threshold))


def test_runs_combine_to_their_mean_with_the_larger_standard_error():
    """The mean of the runs; the standard error the spread over sqrt(runs) where Au & Beck's is low, Au & Beck's
    combined where the spread is smaller; a threshold any run left unreached is NaN."""
    p = np.array([[1e-3, 0.02, np.nan], [3e-3, 0.02, 0.1]])
    se = np.array([[1e-4, 2e-3, np.nan], [1e-4, 2e-3, 0.01]])
    mean, err = combine_runs(p, se)
    assert np.allclose(mean[:2], [2e-3, 0.02]) and np.isnan(mean[2]) and np.isnan(err[2])
    assert np.isclose(err[0], np.std([1e-3, 3e-3], ddof=1) / np.sqrt(2))      # the spread: 1e-3
    assert np.isclose(err[1], np.sqrt(2 * 2e-3 ** 2) / 2)                     # Au & Beck's: equal runs


def test_combined_standard_error_covers_the_spread_of_independent_combined_estimates():
    """Gaussian limit state, P = Phi(-3.09) = 1e-3 in 20 dimensions: 60 combined estimates of 4 runs (250 a
    level) each.  Their spread must not exceed the mean reported standard error by more than its 3-sigma
    sampling error for 60 estimates (~27 %, i.e. a ratio below 1.3)."""
    dim, exact = 20, norm.sf(3.09)
    combined = []
    for k in range(60):
        est = [subset_simulation(_linear(dim), dim, [3.09], n_per_level=250, seed=1000 + 4 * k + r) for r in range(4)]
        combined.append(combine_runs([e.p for e in est], [e.se for e in est]))
    p = np.array([c[0][0] for c in combined])
    se = np.array([c[1][0] for c in combined])
    assert abs(p.mean() - exact) < 3 * p.std(ddof=1) / np.sqrt(len(p)), (p.mean(), exact)
    assert p.std(ddof=1) / se.mean() < 1.3, (p.std(ddof=1), se.mean())
