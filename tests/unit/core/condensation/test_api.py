"""The name-or-object functions of the condensations (screening.core.condensation.api), with the condensation always
named: a name and its object give the same values, the restoring moment is ``K(theta) theta``, the uplift
probability is the Gaussian tail beyond ``theta_ul`` (scipy), and the equivalent coefficients of the cubic
condensation are the Gaussian expectations of eq. (31) computed here by adaptive quadrature:
``c_eq = E[C(theta)]`` and, for uncorrelated ``(theta, theta')``, ``k_eq = E[K(theta) theta^2] / sigma^2``
(Stein's lemma on ``E[d(K theta)/d theta]``)."""

import numpy as np
import pytest
from scipy import integrate, stats

from screening.core.condensation import api, get
from screening.core.model import Block, Foundation

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
THETA = np.array([-3e-3, -1e-4, 0.0, 5e-4, 1.1e-3, 4e-3])


@pytest.mark.parametrize("name", ["paper", "cubic"])
def test_a_name_and_its_condensation_give_the_same_values(name):
    cond = get(name)
    for func in (api.rocking_damping, api.rocking_stiffness, api.restoring_moment):
        np.testing.assert_array_equal(func(THETA, BLOCK, BED, name), func(THETA, BLOCK, BED, cond))
    assert api.uplift_threshold(BLOCK, BED, name) == api.uplift_threshold(BLOCK, BED, cond)


@pytest.mark.parametrize("name", ["paper", "cubic"])
def test_the_restoring_moment_is_the_secant_stiffness_times_the_angle(name):
    np.testing.assert_allclose(api.restoring_moment(THETA, BLOCK, BED, name),
                               api.rocking_stiffness(THETA, BLOCK, BED, name) * THETA, rtol=1e-14, atol=0)


def test_the_rocking_acceleration_of_a_block_at_rest_is_the_ground_term():
    """At ``theta = theta' = 0`` only ``m h x_g'' / m_sdof`` is left (eq. 23)."""
    acc = api.rocking_acceleration(0.0, 0.0, 1.5, BLOCK, BED, "cubic")
    assert float(acc) == pytest.approx(BLOCK.m * BLOCK.h * 1.5 / BLOCK.m_sdof, rel=1e-14)


@pytest.mark.parametrize("ratio", [0.2, 1.0, 3.0])
def test_the_uplift_probability_is_the_gaussian_tail_beyond_the_threshold(ratio):
    theta_ul = float(api.uplift_threshold(BLOCK, BED, "paper"))
    p = float(api.uplift_probability(ratio * theta_ul, BLOCK, BED, "paper"))
    assert p == pytest.approx(2 * stats.norm.sf(1.0 / ratio), rel=1e-9)


@pytest.mark.parametrize("ratio", [0.5, 1.5, 4.0])
def test_the_cubic_equivalent_coefficients_are_the_gaussian_expectations(ratio):
    theta_ul = float(api.uplift_threshold(BLOCK, BED, "cubic"))
    sigma = ratio * theta_ul
    density = stats.norm(scale=sigma).pdf

    def expectation(f):
        value = 0.0
        for lo, hi in ((0.0, theta_ul), (theta_ul, 12 * sigma)):
            if hi > lo:
                value += integrate.quad(lambda t: 2 * f(t) * density(t), lo, hi, epsabs=0.0, epsrel=1e-11,
                                        limit=200)[0]
        return value

    c_expected = expectation(lambda t: float(api.rocking_damping(t, BLOCK, BED, "cubic")))
    k_expected = expectation(lambda t: float(api.restoring_moment(t, BLOCK, BED, "cubic")) * t) / sigma ** 2
    c_eq, k_eq = api.equivalent_coefficients(sigma, 0.01, 0.0, BLOCK, BED, "cubic")
    assert float(c_eq) == pytest.approx(c_expected, rel=1e-6)
    assert float(k_eq) == pytest.approx(k_expected, rel=1e-6)
    c_m, k_m = api.equivalent_coefficients_from_moments(sigma ** 2, 0.0, BLOCK, BED, "cubic")
    assert (float(c_m), float(k_m)) == pytest.approx((float(c_eq), float(k_eq)), rel=1e-12)
