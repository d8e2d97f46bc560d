"""Binomial (multiple-stripe) fragility fits with standard errors, the modelling dispersion, and the
per-curve fit flags."""

import numpy as np
import pytest

from screening.analysis.fragility import (fit_binomial_fragility, fit_fragility_curve, lognormal_fragility,
                                          total_dispersion)
from screening.core.status import FitFlag

MEDIAN, BETA = 0.8, 0.45
LEVELS = np.geomspace(0.2, 3.0, 8)
RECORDS = 40


def _stripes(seed):
    rng = np.random.default_rng(seed)
    return rng.binomial(RECORDS, lognormal_fragility(LEVELS, MEDIAN, BETA))


def test_binomial_fit_recovers_median_and_beta_within_their_standard_errors():
    fit = fit_binomial_fragility(LEVELS, _stripes(11), RECORDS)
    assert fit["n_trials"] == RECORDS * LEVELS.size
    # a fixed seed: each within 2 of its own standard errors (a 95 % statement)
    assert abs(fit["median"] - MEDIAN) < 2 * fit["median_se"]
    assert abs(fit["beta"] - BETA) < 2 * fit["beta_se"]


@pytest.mark.slow
def test_standard_errors_match_the_scatter_of_replicated_fits():
    """The observed-information standard errors against the scatter of 200 independent replicates:
    the standard deviation of 200 estimates has a sampling error of about 1/sqrt(2 x 199) = 5 %, so
    they agree within 20 % (the information-matrix errors are asymptotic: ~320 trials here)."""
    fits = [fit_binomial_fragility(LEVELS, _stripes(seed), RECORDS) for seed in range(200)]
    for key in ("median", "beta"):
        scatter = np.std([f[key] for f in fits], ddof=1)
        se = np.median([f[f"{key}_se"] for f in fits])
        assert se == pytest.approx(scatter, rel=0.2)
        # and the estimates are unbiased within the error of their mean (scatter / sqrt(200)) x 3,
        # plus the MLE's small-sample bias of beta (a few per cent at 320 trials)
        assert np.mean([f[key] for f in fits]) == pytest.approx(MEDIAN if key == "median" else BETA,
                                                                abs=3 * scatter / np.sqrt(200) + 0.03 * BETA)


def test_binomial_fit_refuses_what_it_cannot_identify():
    with pytest.raises(ValueError, match="none does"):
        fit_binomial_fragility(LEVELS, np.zeros(LEVELS.size), RECORDS)
    with pytest.raises(ValueError, match="n_exceed"):
        fit_binomial_fragility(LEVELS, np.full(LEVELS.size, RECORDS + 1), RECORDS)
    with pytest.raises(ValueError, match="intensity"):
        fit_binomial_fragility(-LEVELS, _stripes(1), RECORDS)


def test_total_dispersion_is_the_srss():
    assert total_dispersion(0.3, 0.4) == pytest.approx(0.5, rel=1e-15)
    np.testing.assert_allclose(total_dispersion(np.array([0.3, 0.0]), 0.0), [0.3, 0.0])


@pytest.mark.parametrize("p, flag", [
    ([0.0, 1e-9, 0.0], FitFlag.never_exceeded),
    ([1.0, 1.0, 1.0], FitFlag.always_exceeded),
    ([np.nan, np.nan, np.nan], FitFlag.no_values),
    ([0.0, 0.3, 1.0], FitFlag.no_fit),
    ([0.9, 0.5, 0.1], FitFlag.non_positive_beta),
    ([0.1, 0.5, 0.9], FitFlag.ok),
])
def test_every_curve_gets_a_flag_saying_why_it_has_no_fit(p, flag):
    median, beta, got = fit_fragility_curve([1.0, 2.0, 4.0], p)
    assert got == flag
    assert np.isfinite(median) == (flag == FitFlag.ok) and np.isfinite(beta) == (flag == FitFlag.ok)
