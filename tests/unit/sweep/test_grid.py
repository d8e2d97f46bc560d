"""Batches of a study grid (screening.sweep.grid): pure functions, no dask."""

import numpy as np
import pytest

from helpers import CASES, GRID

from screening.sweep import grid
from screening.sweep.grid import (batch_models, batch_values, default_batch_size, plan_batches, point_values,
                                  select_spots, swept_columns)
from screening.sweep.study import parse_study


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


def _history_free(rows, cols, extra=""):
    """A white-noise grid of ``rows`` eps x ``cols`` S0 without stored histories."""
    return parse_study(GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]", f"eps = {{start = -6e5, stop = 6e7, num = {rows}}}")
                       .replace("num = 5", f"num = {cols}") + '[output]\nhistories = "none"\n' + extra)


@pytest.mark.parametrize("rows, cols, workers", [(316, 316, 2), (100, 100, 2), (1000, 1000, 2), (200, 200, 4),
                                                 (30, 1000, 2), (7, 3001, 3), (316, 316, 1)])
def test_history_free_batches_are_few_large_whole_rows_that_end_evenly(rows, cols, workers):
    """No histories in a task: about BATCHES_PER_WORKER batches per worker of DEFAULT_BATCH ..
    HISTORY_FREE_BATCH points, whole rows where a row fits, and the busiest worker solves at most
    one row more (or 3 % more) than an even share."""
    study = _history_free(rows, cols)
    size = default_batch_size(study, workers)
    n_batches = len(plan_batches(study, size))
    assert size <= grid.HISTORY_FREE_BATCH + cols
    assert size >= min(grid.DEFAULT_BATCH, study.n_points / (2 * workers))
    assert n_batches <= max(2 * grid.BATCHES_PER_WORKER * workers, 2 * study.n_points / grid.HISTORY_FREE_BATCH)
    if cols <= size:
        assert size % cols == 0
    even = study.n_points / workers
    assert grid._makespan(study, size, workers) <= max(even + cols, 1.03 * even)


def test_batches_holding_histories_keep_the_ordinary_size():
    """Fragility needs the histories in memory even when none are stored: ordinary batches."""
    frag = _history_free(100, 100, "[fragility]\nthresholds = [0.01]\n")
    assert default_batch_size(frag, 2) == grid.DEFAULT_BATCH
    assert default_batch_size(_history_free(316, 316), 2) > grid.DEFAULT_BATCH
    assert grid.holds_histories(frag) and not grid.holds_histories(_history_free(2, 2))


def test_history_free_batches_fit_the_task_memory_budget():
    """One envelope value per point and output instant is the most a history-free task holds."""
    from screening.core import limits

    study = parse_study(_history_free(100, 100).text.replace("t_end = 4.0", "t_end = 5000.0"))
    size = default_batch_size(study, 2)
    assert size * len(study.times) * 8 <= limits.TASK_BYTES


def test_makespan_hands_batches_to_the_first_free_worker():
    study = _history_free(1, 10)                     # 10 points: batches 3, 3, 3, 1
    assert grid._makespan(study, 3, 2) == 6         # 3 + 3 | 3 + 1
    assert grid._makespan(study, 5, 2) == 5
    assert grid._makespan(study, 4, 3) == 4         # 4 | 4 | 2
    assert grid._makespan(study, 10, 1) == 10


def test_auto_spots_take_highest_uplift_among_ok_points_then_half_of_it():
    study = parse_study(GRID + '[mcs]\npoints = "auto"\ncount = 2\n')
    status = np.zeros(20, dtype=np.int8)
    upl = np.linspace(0.0, 0.5, 20)
    status[19] = 1                                  # the highest uplift point is not ok: skipped
    assert select_spots(study, status, upl) == [(3, 3), (1, 4)]       # upl 0.474, then the nearest to 0.237
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


@pytest.mark.parametrize("text", [GRID, CASES])
def test_swept_columns_give_every_points_values_and_case_as_point_values_does(text):
    """Independent: each flat point's grid index unravelled and read by point_values."""
    study = parse_study(text)
    columns, case = swept_columns(study)
    assert case.shape == (study.n_points,) and set(columns) == set(study.swept_dims)
    for flat in range(study.n_points):
        c, values = point_values(study, tuple(int(i) for i in np.unravel_index(flat, study.shape)))
        assert case[flat] == c and {name: columns[name][flat] for name in columns} == values


def test_auto_spots_also_visit_intermediate_uplift_on_other_beds():
    """The first spot at the highest uplift (where the linearization is closest to the truth), the others
    at intermediate uplift levels, each on a block/bed not yet visited when one is near its level."""
    study = parse_study(GRID + '[mcs]\npoints = "auto"\ncount = 3\n')      # eps (4) x S0 (5)
    upl = np.tile(np.linspace(0.0, 0.8, 5), 4) * np.repeat([1.0, 0.98, 0.96, 0.94], 5)
    status = np.zeros(20, dtype=np.int8)
    spots = select_spots(study, status, upl)
    assert spots[0] == (0, 4)                                           # the highest uplift first
    levels = [upl[np.ravel_multi_index(s, (4, 5))] for s in spots[1:]]
    assert levels[0] == pytest.approx(0.8 * 2 / 3, abs=0.1) and levels[1] == pytest.approx(0.8 / 3, abs=0.1)
    assert len({s[0] for s in spots}) == 3                              # three different beds (eps)
    one = parse_study(GRID + '[mcs]\npoints = "auto"\ncount = 1\n')
    assert select_spots(one, status, upl) == [(0, 4)]


def test_warm_up_excitations_are_one_per_moment_loop_a_run_compiles():
    """White noise and Kanai-Tajimi at the default band carry its four low-pass states (4 and 6), without a band
    none and two; each state size once, the case's own kind."""
    def states(text):
        return [int(e.filter().A.shape[-1]) for e in grid.warm_up_excitations(parse_study(text))]

    assert states(CASES) == [4, 6]
    assert states(GRID.replace('kind = "white"', 'kind = "white"\nband_limit_hz = "none"')) == [0]
    kt = GRID.replace('kind = "white"', 'kind = "kanai_tajimi"\nomega_g = 10.0\nzeta_g = 0.4\nband_limit_hz = "none"')
    (excitation,) = grid.warm_up_excitations(parse_study(kt))
    assert excitation.filter().A.shape[-1] == 2 and excitation.omega_g == 10.0 and excitation.S0 == 1e-5
