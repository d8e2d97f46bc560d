"""Fractions of Monte Carlo samples and their standard errors (screening.solvers.estimates)."""

import numpy as np
import pytest

from screening.solvers.estimates import binomial_estimate, sample_probabilities


def test_sample_probabilities_equal_a_direct_count_on_synthetic_peaks():
    """Every probability against a loop that counts sample by sample."""
    rng = np.random.default_rng(7)
    peaks = rng.exponential(0.02, size=(3, 400))
    overturned = rng.random((3, 400)) < 0.1
    valid = rng.random((3, 400)) > 0.05
    peaks[overturned] = 0.001          # an overturned sample counts whatever peak it recorded
    levels = np.array([0.005, 0.02, 0.06])
    got = sample_probabilities(peaks, overturned, valid, levels)
    for i in range(3):
        n = over = 0
        hits = np.zeros(3)
        for s in range(400):
            if not valid[i, s]:
                continue
            n += 1
            over += overturned[i, s]
            for j, a in enumerate(levels):
                hits[j] += overturned[i, s] or peaks[i, s] > a
        assert got["p_overturn"][i] == over / n
        np.testing.assert_array_equal(got["p_exceed"][i], hits / n)
    assert got["p_exceed"].shape == (3, 3) and got["p_exceed_se"].shape == (3, 3)
    assert np.all(np.diff(got["p_exceed"], axis=-1) <= 0)            # higher threshold, lower probability


def test_levels_may_differ_per_run_and_no_valid_sample_gives_nan():
    peaks = np.array([[0.1, 0.3], [0.1, 0.3]])
    got = sample_probabilities(peaks, np.zeros((2, 2), bool), np.array([[True, True], [False, False]]),
                               np.array([[0.2], [0.05]]))
    assert got["p_exceed"][0, 0] == 0.5 and np.isnan(got["p_exceed"][1, 0]) and np.isnan(got["p_overturn"][1])


def test_agresti_coull_standard_error():
    """se = sqrt(p~(1-p~)/(n+4)), p~ = (k+2)/(n+4); finite at k = 0 and k = n, Wald-like in between."""
    p, se = binomial_estimate(np.array([0, 250, 1000]), 1000)
    np.testing.assert_array_equal(p, [0.0, 0.25, 1.0])
    tilde = (np.array([0, 250, 1000]) + 2) / 1004
    np.testing.assert_allclose(se, np.sqrt(tilde * (1 - tilde) / 1004), rtol=1e-14)
    assert 1.0e-3 < se[0] < 2e-3 and se[2] == pytest.approx(se[0], rel=1e-12)
    assert abs(se[1] / np.sqrt(0.25 * 0.75 / 1000) - 1) < 0.01
    assert np.isnan(binomial_estimate(0, 0)[0])


@pytest.mark.slow
def test_sample_probabilities_are_unbiased_within_their_standard_error():
    """400 repetitions of 500 Bernoulli(0.03)-overturning samples with lognormal peaks: the mean estimate
    is within 4 standard errors of the mean (se / sqrt(400)) of the truth, and the mean reported SE
    matches the spread of the estimates within 10 % (the spread's own relative error is 1/sqrt(2 x 400))."""
    rng = np.random.default_rng(2024)
    reps, n, p_over, a = 400, 500, 0.03, 0.02
    peaks = rng.lognormal(np.log(0.01), 0.8, size=(reps, n))
    over = rng.random((reps, n)) < p_over
    got = sample_probabilities(peaks, over, np.ones((reps, n), bool), [a])
    from scipy import stats
    p_exc = p_over + (1 - p_over) * stats.norm.sf(np.log(a / 0.01) / 0.8)
    for est, se, truth in ((got["p_overturn"], got["p_overturn_se"], p_over),
                           (got["p_exceed"][:, 0], got["p_exceed_se"][:, 0], p_exc)):
        assert abs(est.mean() - truth) < 4 * est.std() / np.sqrt(reps)
        assert abs(se.mean() / est.std() - 1) < 0.1
