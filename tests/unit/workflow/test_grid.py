"""Batches of a study grid (screening.workflow.grid): pure functions, no dask."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import CASES, GRID

from screening.workflow import grid
from screening.workflow.grid import (batch_models, batch_values, default_batch_size, hyperslabs, parameter_table,
                                     plan_batches, point_values, select_spots)
from screening.workflow.study import parse_study


@settings(max_examples=200, deadline=None)
@given(shape=st.lists(st.integers(1, 5), min_size=0, max_size=4), data=st.data())
def test_hyperslabs_cover_a_flat_range_exactly(shape, data):
    shape = tuple(shape)
    n = int(np.prod(shape, dtype=np.int64))
    lo = data.draw(st.integers(0, n - 1))
    hi = data.draw(st.integers(lo + 1, n))
    flat = np.arange(n).reshape(shape)
    pieces = hyperslabs(lo, hi, shape)
    got = np.concatenate([np.atleast_1d(flat[s] if s else flat).ravel() for s, _, _ in pieces])
    np.testing.assert_array_equal(got, np.arange(lo, hi))
    for s, a, b in pieces:
        np.testing.assert_array_equal(np.atleast_1d(flat[s] if s else flat).ravel(), np.arange(a, b))
    assert len(pieces) <= max(1, 2 * len(shape) - 1)


def test_batches_partition_the_grid_case_by_case():
    study = parse_study(CASES)
    batches = plan_batches(study, 2)
    assert [(b.case, b.lo, b.hi) for b in batches] == [(0, 0, 2), (0, 2, 3), (1, 3, 5), (1, 5, 6)]
    assert [b.index for b in batches] == list(range(4))
    with pytest.raises(ValueError, match="batch_size"):
        plan_batches(study, 0)


def test_default_batch_size_is_whole_rows_and_spreads_work():
    study = parse_study(GRID)                       # 4 x 5 = 20 points
    assert default_batch_size(study, 2) == 5        # ceil(20 / 4) = 5 = one row
    big = parse_study(GRID.replace("num = 5", "num = 300"))
    size = default_batch_size(big, 2)
    assert size == 300 and size <= grid.DEFAULT_BATCH
    huge = parse_study(GRID.replace("num = 5", "num = 7000"))
    assert default_batch_size(huge, 2) == grid.DEFAULT_BATCH


def test_auto_spots_take_highest_uplift_among_ok_points():
    study = parse_study(GRID + '[mcs]\npoints = "auto"\ncount = 2\n')
    status = np.zeros(20, dtype=np.int8)
    upl = np.linspace(0.0, 0.5, 20)
    status[19] = 1                                  # the highest uplift point is not ok: skipped
    assert select_spots(study, status, upl) == [(3, 3), (3, 2)]
    status[:] = 1
    assert select_spots(study, status, upl) == []


def test_batch_values_and_models_follow_the_flat_c_order():
    study = parse_study(GRID)                       # eps (4) x S0 (5)
    batch = plan_batches(study, 7)[1]               # points 7..13
    values = batch_values(study, batch)
    np.testing.assert_array_equal(values["eps"], study.sweeps["eps"][np.arange(7, 14) // 5])
    np.testing.assert_array_equal(values["S0"], study.sweeps["S0"][np.arange(7, 14) % 5])
    block, foundation, excitation = batch_models(study, batch)
    np.testing.assert_array_equal(foundation.eps, values["eps"])
    np.testing.assert_array_equal(excitation.S0, values["S0"])
    assert point_values(study, (1, 2)) == (0, {"eps": study.sweeps["eps"][1], "S0": study.sweeps["S0"][2]})
    cases = parse_study(CASES)
    assert point_values(cases, (1, 0)) == (1, {"S0": 1e-4})


def test_parameter_table_splits_constants_per_case_values_and_labels():
    constants, per_case, labels, case_labels = parameter_table(parse_study(CASES))
    assert constants["m"] == 8.67 and constants["I_cm"] == pytest.approx(8.67 * (0.035**2 + 0.21**2) / 3)
    np.testing.assert_array_equal(per_case["eps"], [6e7, -6e5])
    assert np.isnan(per_case["omega_g"][0]) and per_case["omega_g"][1] == 10.0
    assert "S0" not in constants and "S0" not in per_case                  # swept
    assert labels == {"contact": "hunt_crossley", "condensation": "paper", "envelope": "exponential"}
    assert case_labels == {"excitation": ["white", "kanai_tajimi"]}
