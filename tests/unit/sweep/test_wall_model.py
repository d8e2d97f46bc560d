"""The accuracy stage's model of a Monte Carlo run's wall time (screening.sweep.accuracy.wall_model)."""

import numpy as np
import pytest

from screening.sweep.accuracy import PRIOR_WALL_PER_COST, wall_model


def test_a_fixed_part_per_run_is_not_read_as_a_slow_rate():
    """Runs of 0.3 s plus 1.2 wall seconds per cost-model second: the line is recovered, where the total ratio of
    the short runs alone would say 3.4."""
    costs = np.array([0.1, 0.1, 0.15, 0.2, 2.0, 5.0])
    walls = 0.3 + 1.2 * costs
    overhead, rate = wall_model(walls, costs)
    assert overhead == pytest.approx(0.3, rel=1e-9) and rate == pytest.approx(1.2, rel=1e-9)
    assert walls[:4].sum() / costs[:4].sum() > 3.3


def test_before_three_runs_of_two_costs_the_total_ratio_and_before_any_the_prior():
    assert wall_model([], []) == (0.0, PRIOR_WALL_PER_COST)
    assert wall_model([1.0, 3.0], [0.5, 1.0]) == (0.0, pytest.approx(4.0 / 1.5))
    assert wall_model([1.0, 1.0, 1.0], [0.5, 0.5, 0.5]) == (0.0, pytest.approx(2.0))


def test_the_fixed_part_stays_within_zero_and_the_shortest_run_and_the_total_is_kept():
    """A negative intercept (runs that scale faster than their cost) is 0; an intercept above the shortest run is
    cut to it; the slope then fits the total wall time."""
    costs = np.array([1.0, 2.0, 3.0])
    overhead, rate = wall_model(costs ** 2, costs)
    assert overhead == 0.0 and rate == pytest.approx(14.0 / 6.0)
    walls = np.array([0.2, 5.0, 5.1])
    overhead, rate = wall_model(walls, np.array([0.01, 0.02, 0.03]))
    assert 0.0 <= overhead <= 0.2
    assert overhead * 3 + rate * 0.06 == pytest.approx(walls.sum())
