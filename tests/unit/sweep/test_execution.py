"""The task functions of a sweep (screening.sweep.execution), called directly (no dask)."""

import os
import pickle

import numpy as np
import pytest
import xarray as xr

from helpers import GRID

from screening.analysis import escalation as esc
from screening.core import condensation
from screening.solvers.datasets import INTEGRATOR_TEXT
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.core.status import PointStatus, SampleState, Trust
from screening.sweep.execution import SPOT_HISTORIES
from screening.sweep import execution
from screening.sweep._submit import failed_spot
from screening.sweep.execution import failed_result, sample_state, solve_batch
from screening.sweep.grid import batch_models, plan_batches
from screening.sweep.study import parse_study


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


def test_local_workers_share_the_cores_among_numba_threads(monkeypatch):
    """Each local worker process is told the cores over the workers (at least one), and its tasks run numba's
    parallel loops on that many threads; outside such a worker nothing changes."""
    import numba

    assert execution.worker_environment(2, cores=2) == {execution.THREADS_VARIABLE: "1"}
    assert execution.worker_environment(1, cores=2) == {execution.THREADS_VARIABLE: "2"}
    assert execution.worker_environment(3, cores=8) == {execution.THREADS_VARIABLE: "2"}
    assert execution.worker_environment(4, cores=2) == {execution.THREADS_VARIABLE: "1"}
    before = numba.get_num_threads()
    monkeypatch.delenv(execution.THREADS_VARIABLE, raising=False)
    assert execution.task_threads() == before
    monkeypatch.setenv(execution.THREADS_VARIABLE, "1")
    try:
        assert execution.task_threads() == 1 and numba.get_num_threads() == 1
    finally:
        numba.set_num_threads(before)


@pytest.mark.slow
def test_local_worker_processes_run_tasks_on_their_share_of_numba_threads():
    """The share reaches the worker processes of a local cluster: a task there that applies it (as every spot check
    does) runs on that many threads."""
    def threads():
        import numba
        execution.task_threads()
        return numba.get_num_threads()

    with execution.dask_client(2) as c:
        got = c.gather([c.submit(threads, pure=False) for _ in range(4)])
    assert set(got) == {max(1, (os.cpu_count() or 1) // 2)}


def test_spot_arrays_carry_the_full_contact_share_the_stiff_bed_cost_model_reads():
    """A hand-made Monte Carlo dataset of 4 samples (one overturned): ``full_contact`` is the mean over
    time of 1 - p_uplift, scaled to the used samples, and the stiff-bed cost estimate changes with it."""
    t = np.linspace(0.0, 1.0, 5)
    p = np.array([0.0, 0.25, 0.5, 0.25, 0.0])
    histories = {name: ("t", np.zeros(t.size)) for name in SPOT_HISTORIES}
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


@pytest.mark.parametrize("integrator", ["dopri", "rodas", "exact"])
def test_the_spot_arrays_say_which_steps_the_run_took_and_the_cost_model_charges_them(integrator):
    t = np.linspace(0.0, 1.0, 5)
    ds = xr.Dataset({**{name: ("t", np.zeros(t.size)) for name in SPOT_HISTORIES},
                     "n_overturned": ((), 0), "n_diverged": ((), 0), "n_steps": ("sample", np.full(2, 1000)),
                     "peak_abs_theta": ("sample", np.ones(2)), "overturned": ("sample", np.zeros(2, bool)),
                     "diverged": ("sample", np.zeros(2, bool))},
                    coords={"t": t, "sample": np.arange(2)},
                    attrs={"input_grid_points": 64, "integrator": INTEGRATOR_TEXT[integrator]})
    out = execution.spot_arrays(ds)
    assert (bool(out["rodas"]), bool(out["exact"])) == (integrator == "rodas", integrator == "exact")
    coupled = esc.EscalationModel.coupled
    plain = esc.estimated_cost(2000, coupled, 0, False, 2)
    charged = esc.estimated_cost(2000, coupled, 0, bool(out["rodas"]), 2, exact=bool(out["exact"]))
    factor = {"dopri": 1.0, "rodas": esc.RODAS_STEP_FACTOR, "exact": esc.EXACT_RUN_FACTOR}[integrator]
    assert charged == pytest.approx(factor * plain, rel=1e-12)


def test_the_exact_contact_sampler_says_so_and_is_charged_as_exact():
    """A run of the stiff-bed model's exact-contact sampler records that integration (not the explicit pair's text,
    whose steps land on the outputs), and its spot arrays carry ``exact`` for the cost model."""
    import screening
    from screening.analysis.beds import lam_from_vertical_damping
    from screening.core.excitations.kanai_tajimi import KanaiTajimi
    from screening.core.model import Block, Foundation

    statue = Block(m=1200.0, b=0.25, h=0.9)
    bed = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, statue.m, statue.b, 0.05)))
    ds = screening.monte_carlo(statue, bed, KanaiTajimi(0.015, 15.6, 0.6), n_samples=2, t_end=1.0,
                               model="stiff_bed_fast", progress=False)
    assert ds.attrs["integrator"] == INTEGRATOR_TEXT["exact_contact"]
    out = execution.spot_arrays(ds)
    assert bool(out["exact"]) and not bool(out["rodas"])

def test_a_gaussian_probability_that_underflows_gets_a_standard_error_that_reaches_the_trust_limit():
    """A trusted point far below toppling: the up-crossing probability underflows to 0 at both ends of the trust
    band, which made its standard error 0 (certainty).  The trust rule vouches for points whose calibration Monte
    Carlo overturned up to OVERTURN_LIMIT of its samples, so ``p + 2 se`` reaches that limit; a large probability
    keeps the band's quarter (computed here from the up-crossing at the band's two ends)."""
    from screening.analysis.fragility import linearized_exceedance
    from screening.analysis.trust import OVERTURN_LIMIT
    from screening.sweep.study import EXAMPLE_STUDY

    study = parse_study(EXAMPLE_STUDY)
    block, foundation, excitation = batch_models(study, plan_batches(study, 2)[0])
    nt = study.times.size
    var = np.array([1e-7, 4e-3])[:, None]                      # sigma_theta: 3e-4 and 0.063 rad; atan(b/h) = 0.165
    res = {"status": np.zeros(2, np.int8), "var_theta": np.repeat(var, nt, 1),
           "var_theta_dot": np.repeat(100.0 * var, nt, 1), "cov_theta_theta_dot": np.zeros((2, nt)),
           "c_eq": np.full((2, nt), 5.0), "k_eq": np.full((2, nt), 1000.0)}
    slender = float(block.slenderness)
    out = {"status": np.zeros(2, np.int8), "slenderness": np.full(2, slender),
           "sl_trust": np.full(2, int(Trust.trusted), np.int8),
           "sl_error_low": np.full(2, -0.1), "sl_error_high": np.full(2, 0.1)}
    p = execution.batch_probabilities(res, block, foundation, excitation, out, study.times)
    assert p["p_overturn"][0] == 0.0                                                 # underflowed
    assert p["p_overturn_se"][0] > 0 and p["p_overturn"][0] + 2 * p["p_overturn_se"][0] == pytest.approx(OVERTURN_LIMIT)
    ends = [linearized_exceedance(study.times, res["var_theta"][1:] / (1 + e), res["var_theta_dot"][1:] / (1 + e),
                                  res["cov_theta_theta_dot"][1:], res["c_eq"][1:], res["k_eq"][1:],
                                  np.atleast_1d(block.m_sdof), np.zeros(1, np.int8), np.array([slender]))[0]
            for e in (0.1, -0.1)]
    assert p["p_overturn"][1] > 0.1
    assert p["p_overturn_se"][1] == pytest.approx((ends[1] - ends[0]) / 4, rel=1e-12)
