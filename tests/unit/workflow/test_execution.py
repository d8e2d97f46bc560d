"""The task functions of a sweep (screening.workflow.execution), called directly (no dask)."""

import pickle

import numpy as np
import pytest

from helpers import GRID

from screening import condensation
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.status import PointStatus, SampleState
from screening.workflow import execution
from screening.workflow.execution import failed_result, failed_spot, sample_state, solve_batch
from screening.workflow.grid import batch_models, plan_batches
from screening.workflow.study import parse_study


@pytest.mark.parametrize("name", ["paper", "cubic"])
def test_condensation_objects_survive_pickling(name):
    cond = condensation.get(name)
    copy = pickle.loads(pickle.dumps(cond))
    assert type(copy) is type(cond) and copy.name == name


@pytest.mark.parametrize("name", ["paper", "cubic"])
def test_solve_batch_takes_the_condensation_object(name):
    study = parse_study(GRID.replace("t_end = 4.0", "t_end = 0.5"))
    batch = plan_batches(study, 7)[1]
    block, foundation, excitation = batch_models(study, batch)
    cond = condensation.get(name)
    out = solve_batch(block, foundation, excitation, cond, study.times, study.rtol, study.max_steps)
    direct = solve_moments(block, foundation, excitation, study.times, condensation=name)
    for key in HISTORY_VARIABLES:
        assert out[key].dtype == np.float32 and out[key].shape == (7, study.times.size)
        np.testing.assert_array_equal(out[key], direct[key].astype(np.float32))
    np.testing.assert_array_equal(out["status"], direct["status"])
    np.testing.assert_array_equal(out["theta_ul"], cond.uplift_threshold(block, foundation))
    np.testing.assert_array_equal(out["slenderness"], np.full(7, block.slenderness))


def test_failed_results_use_the_status_enums():
    part = failed_result(3, 5)
    assert np.all(part["status"] == PointStatus.task_failed) and part["status"].dtype == np.int8
    assert np.all(np.isnan(part["var_theta"])) and np.all(part["n_steps"] == 0)
    assert np.all(np.isnan(part["slenderness"]))
    spot = failed_spot(5, 4)
    assert np.all(spot["sample_state"] == SampleState.diverged_or_failed) and int(spot["n_used"]) == 0


def test_sample_state_codes():
    over = np.array([True, False, False, False])
    div = np.array([False, True, False, False])
    np.testing.assert_array_equal(sample_state(over, div), [SampleState.overturned, SampleState.diverged_or_failed,
                                                            SampleState.standing, SampleState.standing])


def test_the_local_client_is_never_made_dask_s_default():
    """A run's client is used by name only: inside and after the run, dask's default client and its
    scheduler setting are what they were (a closed default client breaks a caller's later xarray writes)."""
    import dask
    from distributed.client import _get_global_client

    before = (_get_global_client(), dask.config.get("scheduler", None))
    with execution.dask_client(0) as c:
        assert c.submit(sum, [1, 2]).result() == 3
        assert (_get_global_client(), dask.config.get("scheduler", None)) == before
    assert (_get_global_client(), dask.config.get("scheduler", None)) == before
