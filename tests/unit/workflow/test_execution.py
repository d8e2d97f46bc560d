"""The task functions of a sweep (screening.workflow.execution), called directly (no dask)."""

import pickle

import numpy as np
import pytest

from helpers import GRID

from screening import condensation
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.status import PointStatus, SampleState
from screening.workflow import execution
from screening.workflow._submit import failed_spot
from screening.workflow.execution import failed_result, sample_state, solve_batch
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


def test_spot_arrays_carry_the_full_contact_share_the_stiff_bed_cost_model_reads():
    """A hand-made Monte Carlo dataset of 4 samples (one overturned): ``full_contact`` is the mean over
    time of 1 - p_uplift, scaled to the used samples, and the stiff-bed cost estimate changes with it."""
    import xarray as xr

    from screening.analysis import escalation as esc

    t = np.linspace(0.0, 1.0, 5)
    p = np.array([0.0, 0.25, 0.5, 0.25, 0.0])
    histories = {name: ("t", np.zeros(t.size)) for name in execution.SPOT_HISTORIES}
    histories["p_uplift"] = ("t", p)
    ds = xr.Dataset({**histories,
                     "n_overturned": ((), 1), "n_diverged": ((), 0), "n_steps": ("sample", np.full(4, 1000)),
                     "peak_abs_theta": ("sample", np.ones(4)), "overturned": ("sample", [False, True, False, False]),
                     "diverged": ("sample", np.zeros(4, bool))},
                    coords={"t": t, "sample": np.arange(4)}, attrs={"input_grid_points": 64})
    out = execution.spot_arrays(ds)
    expected = (1.0 - p.mean()) * 3 / 4
    assert out["full_contact"] == pytest.approx(expected, rel=1e-12)
    assert out["full_contact"] == pytest.approx(esc.full_contact_share(p, 3, 4), rel=1e-12)
    model = esc.EscalationModel.stiff_bed
    with_share = esc.estimated_cost(out["n_steps"], model, out["n_grid"], False, 4, full_contact=out["full_contact"])
    without = esc.estimated_cost(out["n_steps"], model, out["n_grid"], False, 4)
    assert np.isfinite(with_share) and with_share > 0 and with_share != pytest.approx(without)
    # a run that did not keep p_uplift: the share is unknown (NaN), and the cost model falls back
    del ds["p_uplift"]
    unknown = execution.spot_arrays(ds)["full_contact"]
    assert np.isnan(unknown)
    assert esc.estimated_cost(out["n_steps"], model, out["n_grid"], False, 4, full_contact=unknown) == without
