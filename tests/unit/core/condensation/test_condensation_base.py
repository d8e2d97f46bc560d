"""The condensation interface (screening.core.condensation.base) with a linear toy subclass defined here (not
registered): the three abstract functions are required; the defaults give ``K(theta) theta``, ``C(0)``, ``K(0)``, no
capacity angle, the equivalent coefficients by quadrature (for constant ``C`` and ``K``: ``c_eq = C``,
``k_eq = K``) and a named refusal of the condensed Monte Carlo."""

import numpy as np
import pytest

from screening.core.condensation.base import Condensation
from screening.core.model import Block, Foundation

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8)
C0, K0 = 2.5, 900.0


class Linear(Condensation):
    name = "linear_toy"

    def uplift_threshold(self, block, foundation):
        return np.asarray(1e-3 * block.b / 0.035)[()]

    def rocking_damping(self, theta, block, foundation):
        return np.full(np.shape(theta), C0)[()]

    def rocking_stiffness(self, theta, block, foundation):
        return np.full(np.shape(theta), K0)[()]


def test_the_three_model_functions_are_required():
    class Incomplete(Condensation):
        name = "incomplete"

        def uplift_threshold(self, block, foundation):
            return 1e-3

    with pytest.raises(TypeError, match="rocking_damping"):
        Incomplete()


def test_the_defaults_follow_from_the_model_functions():
    cond = Linear()
    theta = np.array([-2e-3, 0.0, 5e-4])
    np.testing.assert_array_equal(cond.restoring_moment(theta, BLOCK, BED), K0 * theta)
    assert (float(cond.damping_at_rest(BLOCK, BED)), float(cond.stiffness_at_rest(BLOCK, BED))) == (C0, K0)
    assert float(cond.capacity_angle(BLOCK, BED)) == np.inf
    assert cond.check(BLOCK, BED) is None


@pytest.mark.parametrize("sigma", [1e-5, 1e-3, 2e-2])
def test_constant_coefficients_are_their_own_equivalent_coefficients(sigma):
    c_eq, k_eq = Linear().equivalent_coefficients(np.array([sigma]), np.array([0.3 * sigma]), BLOCK, BED)
    np.testing.assert_allclose(c_eq, C0, rtol=1e-9)
    np.testing.assert_allclose(k_eq, K0, rtol=1e-9)


def test_a_condensation_without_compiled_coefficients_cannot_run_the_condensed_monte_carlo():
    with pytest.raises(NotImplementedError, match="condensation 'linear_toy' has no compiled"):
        Linear().sdof_kernel(BLOCK, BED)
