"""Probabilities of overturning and of exceedance (screening.analysis.probabilities)."""

import numpy as np
import pytest

from screening.analysis.probabilities import (binomial_estimate, choose_sources, monte_carlo_source,
                                              sample_probabilities, source_codes, uplift_acceleration)
from screening.status import BestMethod, ProbabilitySource, Trust


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


def test_every_monte_carlo_model_has_its_own_source_code():
    from screening.schema import attributes
    from screening.solvers.montecarlo import MODELS

    codes = source_codes()
    mc = [monte_carlo_source(m) for m in MODELS]
    assert len(set(codes.values())) == len(codes) and len(set(mc)) == len(MODELS)
    assert not set(mc) & {int(s) for s in ProbabilitySource}
    attrs = attributes("p_source")
    assert attrs["flag_meanings"].split() == sorted(codes, key=codes.get)
    assert [int(v) for v in attrs["flag_values"]] == sorted(codes.values())
    with pytest.raises(ValueError, match="parameter 'model'"):
        monte_carlo_source("no_such_model")
    # every model the [accuracy] escalation can run is a Monte Carlo model with a code
    from screening.status import EscalationModel
    assert {m.name for m in EscalationModel} <= set(MODELS)


def test_sources_before_monte_carlo():
    ok = np.array([True, True, True, False])
    trust = np.array([Trust.trusted, Trust.untrusted, Trust.trusted, Trust.trusted])
    band = np.array([True, True, False, True])
    np.testing.assert_array_equal(choose_sources(ok, trust, band),
                                  [ProbabilitySource.linearization_gaussian] + [ProbabilitySource.unreliable] * 3)
    best = np.array([BestMethod.linearization, BestMethod.corrected_linearization, BestMethod.unreliable,
                     BestMethod.corrected_linearization])
    np.testing.assert_array_equal(choose_sources(ok, trust, band, best),
                                  [ProbabilitySource.linearization_gaussian,
                                   ProbabilitySource.corrected_linearization_gaussian,
                                   ProbabilitySource.unreliable, ProbabilitySource.unreliable])


def test_uplift_acceleration_on_a_winkler_bed_is_the_kern_limit():
    """a_ul = g b / (3 h) - g theta_ul (pressure resultant at the kern edge b/3), from the paper condensation;
    the cubic condensation of the same linear bed (eps = 0) agrees."""
    from screening import condensation
    from screening.model import Block, Foundation

    block, bed = Block(1200.0, 0.25, 0.9), Foundation(1.0e10, 1e8, eps=0.0)
    theta_ul = block.m * block.g / (2 * block.b**2 * bed.k)
    expected = block.g * block.b / (3 * block.h) - block.g * theta_ul
    got = uplift_acceleration(block, bed, condensation.get("paper"))
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    np.testing.assert_allclose(uplift_acceleration(block, bed, condensation.get("cubic")), expected, rtol=1e-6)
