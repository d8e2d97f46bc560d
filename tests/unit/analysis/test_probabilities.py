"""Probabilities of overturning and of exceedance (screening.analysis.probabilities)."""

import numpy as np
import pytest

from screening.analysis.probabilities import (binomial_estimate, choose_sources, monte_carlo_source,
                                              sample_probabilities, source_codes, uplift_acceleration)
from screening.status import BestMethod, ProbabilitySource, Trust


def test_the_sample_estimates_are_those_of_the_solvers():
    """The sweep's probabilities and a Monte Carlo run's come from the same functions."""
    from screening.solvers import estimates

    assert sample_probabilities is estimates.sample_probabilities and binomial_estimate is estimates.binomial_estimate


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
