"""Probabilities of overturning and of exceedance (screening.analysis.probabilities)."""

import numpy as np
import pytest

from screening.analysis.probabilities import (binomial_estimate, choose_sources, monte_carlo_source,
                                              sample_probabilities, source_codes, uplift_acceleration)
from screening.core.status import BestMethod, ProbabilitySource, Trust


def test_the_sample_estimates_are_those_of_the_solvers():
    """The sweep's probabilities and a Monte Carlo run's come from the same functions."""
    from screening.solvers import estimates

    assert sample_probabilities is estimates.sample_probabilities and binomial_estimate is estimates.binomial_estimate


def test_every_monte_carlo_model_has_its_own_source_code():
    from screening.solvers.schema import attributes
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
    from screening.core.status import EscalationModel
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
    from screening.core import condensation
    from screening.core.model import Block, Foundation

    block, bed = Block(1200.0, 0.25, 0.9), Foundation(1.0e10, 1e8, eps=0.0)
    theta_ul = block.m * block.g / (2 * block.b**2 * bed.k)
    expected = block.g * block.b / (3 * block.h) - block.g * theta_ul
    got = uplift_acceleration(block, bed, condensation.get("paper"))
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    np.testing.assert_allclose(uplift_acceleration(block, bed, condensation.get("cubic")), expected, rtol=1e-6)


def test_which_quantity_answers_a_point():
    from screening.analysis.probabilities import HEAVY_UPLIFT, answer_quantities, reliable_answer
    from screening.core.status import AnswerQuantity as A, PointStatus as S

    status = [S.k_eq_negative, S.sigma_theta_beyond_slenderness, S.ok, S.ok, S.ok, S.ok, S.ok, S.task_failed,
              S.step_budget_exhausted]
    p = [np.nan, 0.5, 0.10, 0.10, 0.3, 0.3, 0.01, np.nan, np.nan]
    se = [np.nan, 0.1, 0.02, 0.03, np.nan, np.nan, 0.01, np.nan, np.nan]
    low = [np.nan, np.nan, -0.1, -0.1, -0.6, -1.0, -0.6, np.nan, np.nan]
    high = [np.nan, np.nan, 0.1, 0.1, np.inf, 0.5, np.inf, np.nan, np.nan]
    uplift = [0.99, 0.99, 0.5, 0.5, HEAVY_UPLIFT, 0.95, HEAVY_UPLIFT - 1e-9, 0.99, 0.99]
    got = answer_quantities(status, p, se, low, high, uplift)
    # stopped near toppling; 0.10 - 2 x 0.02 >= 0.05 but 0.10 - 2 x 0.03 is not; an unvouched p (NaN SE) never
    # counts; open intervals in heavy uplift (either end); not below HEAVY_UPLIFT; other failures keep the variance
    assert got.tolist() == [A.probabilities_stopped, A.probabilities_stopped, A.probabilities_overturning,
                            A.variance, A.probabilities_open_interval, A.probabilities_open_interval, A.variance,
                            A.variance, A.variance]
    vouched = np.array([False, False, True, True, False, False, True, False, False])
    # in heavy uplift a variance nothing vouches for (a finite but too wide interval) is no answer either
    heavy = answer_quantities([S.ok, S.ok, S.ok], [0.01] * 3, [0.01] * 3, [-0.5] * 3, [1.8] * 3,
                              [0.95, 0.95, 0.5], [False, True, False])
    assert heavy.tolist() == [A.probabilities_open_interval, A.variance, A.variance]
    source = np.array([3, 0, 2, 2, 3, 0, 1, 0, 0])
    assert reliable_answer(got, vouched, source).tolist() == [True, False, True, True, True, False, True, False,
                                                              False]
