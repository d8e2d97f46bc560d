"""Bounds on what a study, a record or an API call may ask for (screening.core.limits)."""

import math

import pytest

from screening.core import limits


@pytest.mark.parametrize("text, depth", [("a = 1", 0), ("a = [1, [2, [3]]]", 3), ('a = "[[[["', 0),
                                         ("a = {b = {c = 1}}", 2), ("# [[[[\nx = [1]", 1)])
def test_nesting_depth_counts_brackets_outside_strings_and_comments(text, depth):
    assert limits.nesting_depth(text) == depth


def test_output_steps_is_a_float_and_infinite_instead_of_overflowing():
    assert limits.output_steps(20.0, 0.05) == pytest.approx(400.0)
    assert limits.output_steps(1e308, 1e-308) == math.inf and limits.output_steps(1.0, 0.0) == math.inf


@pytest.mark.parametrize("n_times, n_variables", [(401, 6), (100_001, 6), (1, 1), (10**9, 6)])
def test_batch_budget_is_the_most_points_whose_histories_fit_the_budget(n_times, n_variables):
    n = limits.batch_budget(n_times, n_variables)
    per_point = 8 * n_times * n_variables
    assert n >= 1
    if per_point <= limits.TASK_BYTES:
        assert n * per_point <= limits.TASK_BYTES < (n + 1) * per_point
    else:
        assert n == 1                                       # one point per task at least


def test_the_bounds_are_ordered():
    assert limits.DEFAULT_MAX_POINTS <= limits.MAX_POINTS_CEILING
    assert limits.MIN_RECORD_DT < limits.MAX_RECORD_DT and limits.SA_PERIOD_RANGE[0] < limits.SA_PERIOD_RANGE[1]
    assert limits.MAX_STUDY_BYTES >= limits.MAX_STUDY_CHARS
