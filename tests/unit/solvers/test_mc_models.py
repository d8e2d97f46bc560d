"""The coupled and condensed Monte Carlo models (screening.solvers.mc_models): the coupled model's starting
indentation against the vertical balance of a linear bed written out (full contact: ``z = m g / (2 b k)``; in uplift,
contact over ``z + x sin(theta) > 0``: ``k (z + b s)^2 / (2 s) = m g`` with ``s = sin(theta)``), the uplift angle
that labels its samples (where the rest indentation lifts the far edge), and the error scales of its state.
Integration itself: test_mcs_kernels.py and test_montecarlo.py."""

import math

import pytest

from screening.core.condensation import get
from screening.core.model import Block, Foundation
from screening.solvers import mc_models

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8)
WEIGHT, Z_REST = BLOCK.m * BLOCK.g, BLOCK.m * BLOCK.g / (2 * BLOCK.b * BED.k)


def test_at_rest_upright_the_indentation_carries_the_weight_on_the_whole_base():
    assert mc_models.quasi_static_indentation(BLOCK, BED, 0.0) == pytest.approx(Z_REST, rel=1e-12)


@pytest.mark.parametrize("theta0", [5e-4, -8e-4])
def test_tilted_in_full_contact_the_mean_indentation_is_unchanged(theta0):
    """Full contact of a linear bed: the resultant is ``2 b k z`` whatever the tilt."""
    assert mc_models.quasi_static_indentation(BLOCK, BED, theta0) == pytest.approx(Z_REST, rel=1e-9)


@pytest.mark.parametrize("theta0", [2e-3, -5e-3, 2e-2])
def test_in_uplift_the_contact_left_carries_the_weight(theta0):
    s = abs(math.sin(theta0))
    expected = math.sqrt(2 * s * WEIGHT / BED.k) - BLOCK.b * s
    assert mc_models.quasi_static_indentation(BLOCK, BED, theta0) == pytest.approx(expected, rel=1e-5)


def test_the_samples_are_labelled_by_the_angle_where_the_far_edge_lifts():
    theta_ul, attrs = mc_models.exact_uplift_threshold(BLOCK, BED)
    assert theta_ul == pytest.approx(math.asin(Z_REST / BLOCK.b), rel=1e-6)
    assert attrs == {"theta_ul_condensation": "cubic"}
    assert theta_ul == pytest.approx(float(get("cubic").uplift_threshold(BLOCK, BED)), rel=1e-6)


def test_the_state_scales_are_the_uplift_angle_and_the_rest_indentation_and_their_rates():
    scales = mc_models.state_scales(BLOCK, BED)
    assert scales[0] == pytest.approx(float(get("paper").uplift_threshold(BLOCK, BED)), rel=1e-12)
    assert scales[2] == pytest.approx(Z_REST, rel=1e-12)
    assert scales[1] / scales[0] >= 1.0 and scales[3] / scales[2] >= 1.0          # rates: at least 1 rad/s
