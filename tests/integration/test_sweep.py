"""Sweeps on dask (screening.sweep.run): exactness, failures, resume, reuse, spot checks, and a real
``dask scheduler`` + ``dask worker`` cluster.  The pure pieces are tested in tests/unit/workflow."""

import json

import netCDF4
import numpy as np
import pytest
import xarray as xr

from helpers import CASES, GRID, compare_files, dask_processes, interrupted_run, quiet

from screening.sweep import execution
from screening.core.condensation.api import uplift_threshold
from screening.solvers.moments import solve_moments
from screening.analysis.linearization import linearize
from screening.solvers.montecarlo import monte_carlo
from screening.core.status import PointStatus, ProbabilitySource
from screening.io.errors import SweepError
from screening.io.reader import result_key
from screening.io.store import PartialStore
from screening.sweep.study import build_models, parse_study
from screening.sweep.run import run_sweep


# ----------------------------------------------------------------------------- runs
def test_cases_with_both_excitations_match_direct_solves(client, tmp_path):
    study = parse_study(CASES)
    out = tmp_path / "cases.nc"
    report = run_sweep(study, out, client=client, batch_size=2, progress=False, log=quiet)
    assert report.n_batches == 4 and report.status_counts == {"ok": 6}
    assert not (tmp_path / "cases.nc.partial").exists()
    with xr.open_dataset(out) as ds:
        assert ds["var_theta"].dims == ("case", "S0", "t")
        assert list(ds["case_name"].values) == ["hard_white", "soft_kt"]
        np.testing.assert_array_equal(ds["eps"].values, [6e7, -6e5])        # per-case coordinate
        assert np.isnan(ds["omega_g"].values[0]) and ds["omega_g"].values[1] == 10.0
        assert list(ds["excitation"].values) == ["white", "kanai_tajimi"]
        for i, case in enumerate(study.cases):
            direct = solve_moments(*build_models(case, {"S0": study.sweeps["S0"]}), study.times)
            for name in ("var_theta", "k_eq", "p_uplift"):
                np.testing.assert_array_equal(ds[name].values[i], direct[name].astype(np.float32))
            for name in ("peak_var_theta", "min_k_eq", "t_stop", "n_steps"):
                np.testing.assert_array_equal(ds[name].values[i], direct[name])


def test_cubic_condensation_case_matches_direct_solves(client, tmp_path):
    text = GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = [-6e5, 6e7]") + """
[[case]]
name = "paper"
foundation.condensation = "paper"
[[case]]
name = "cubic"
foundation.condensation = "cubic"
[mcs]
points = [{case = "cubic", eps = 6e7, S0 = 2.4e-3}]
samples = 6
model = "condensed"
seed = 3
"""
    study = parse_study(text)
    out = tmp_path / "cubic.nc"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    with xr.open_dataset(out) as ds:
        assert list(ds["condensation"].values) == ["paper", "cubic"]
        eps, s0 = np.meshgrid(study.sweeps["eps"], study.sweeps["S0"], indexing="ij")
        for i, case in enumerate(study.cases):
            models = build_models(case, {"eps": eps, "S0": s0})
            direct = solve_moments(*models, study.times, condensation=case.condensation)
            for name in ("var_theta", "c_eq", "k_eq"):
                np.testing.assert_array_equal(ds[name].values[i], direct[name].astype(np.float32))
            np.testing.assert_array_equal(ds["status"].values[i], direct["status"])
            np.testing.assert_allclose(ds["theta_ul"].values[i],
                                       uplift_threshold(*models[:2], condensation=case.condensation))
        # the condensed spot check ran the cubic condensation, not the paper's
        mc = monte_carlo(*build_models(study.cases[1], {"eps": 6e7, "S0": 2.4e-3}), n_samples=6,
                         model="condensed", condensation="cubic", t_end=study.t_end, dt=study.dt, seed=3,
                         progress=False)
        np.testing.assert_allclose(ds["mcs_var_theta"].values[0], mc["var_theta"].values, rtol=1e-12)
        # the hardening bed's cubic threshold sits below the paper's (z0 < z_lin)
        assert ds["theta_ul"].values[1, 1, 0] < 0.99 * ds["theta_ul"].values[0, 1, 0]


def test_a_failing_batch_is_retried_then_flagged(client, tmp_path, monkeypatch):
    calls = []

    def flaky(block, foundation, excitation, t_out, **kw):
        eps = np.atleast_1d(foundation.eps)
        calls.append(float(eps[0]))
        if np.any(eps == 3e7):
            raise FloatingPointError("injected failure")
        return solve_moments(block, foundation, excitation, t_out, **kw)

    monkeypatch.setattr(execution, "solve_moments", flaky)
    messages = []
    study = parse_study(GRID)
    report = run_sweep(study, tmp_path / "f.nc", client=client, batch_size=5, progress=False,
                       log=messages.append)
    assert report.n_failed_batches == 1
    assert calls.count(3e7) == 1 + execution.TASK_RETRIES
    assert any("failed after" in m and "injected failure" in m for m in messages)
    with xr.open_dataset(tmp_path / "f.nc") as ds:
        status = ds["status"].values
        assert np.all(status[2] == PointStatus.task_failed) and np.all(status[[0, 1, 3]] == 0)
        assert np.all(np.isnan(ds["var_theta"].values[2])) and np.all(ds["n_steps"].values[2] == 0)
        assert np.all(np.isfinite(ds["peak_var_theta"].values[[0, 1, 3]]))
        assert int(ds.attrs["n_failed_points"]) == 5
        assert "task_failed" in ds["status"].attrs["flag_meanings"].split()


def test_interrupted_run_resumes_to_the_same_file(client, tmp_path):
    study = parse_study(GRID)
    ref = tmp_path / "ref.nc"
    run_sweep(study, ref, client=client, batch_size=3, progress=False, log=quiet)

    out = tmp_path / "run.nc"
    seen = interrupted_run(study, out, client, batch_size=3)
    partial = tmp_path / "run.nc.partial"
    assert not out.exists()
    assert sorted(p.name for p in partial.glob("batch-*.npz")) == sorted(
        f"batch-{i:06d}.npz" for i in seen)
    assert json.loads((partial / "manifest.json").read_text())["key"] == study.key

    messages = []
    report = run_sweep(study, out, client=client, batch_size=50, progress=False, log=messages.append)
    assert report.n_resumed_batches == 2 and report.n_batches == 7      # layout of the first attempt
    assert any(m.startswith("resuming: 2 of 7 batches") for m in messages)
    assert not partial.exists()
    compare_files(ref, out)


def test_the_local_scheduler_keeps_few_messages_per_worker(tmp_path, monkeypatch):
    """Its log of the messages sent to a worker holds task arguments: a few only, whatever the number
    of batches (1,000 by default: client memory grew with the grid).  The run's client is not dask's
    default, so the test takes it from the local-cluster factory."""
    import contextlib

    logged, clients, real = [], [], execution._local_client

    @contextlib.contextmanager
    def capture(workers):
        with real(workers) as c:
            clients.append(c)
            yield c

    monkeypatch.setattr(execution, "_local_client", capture)

    def look(batch):
        scheduler = clients[0].cluster.scheduler
        logged.append(max(len(s.recent_message_log) for s in scheduler.stream_comms.values()))

    run_sweep(parse_study(GRID), tmp_path / "r.nc", workers=0, batch_size=1, progress=False, log=quiet,
              on_batch=look)
    cap = execution.LOCAL_CLUSTER_CONFIG["distributed.admin.low-level-log-length"]
    assert len(logged) == 20 and max(logged) == cap < 20


def test_unchanged_study_is_reused_and_changed_one_recomputed(client, tmp_path):
    study = parse_study(GRID)
    out = tmp_path / "r.nc"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    stamp = out.stat().st_mtime_ns
    messages = []
    report = run_sweep(study, out, client=client, progress=False, log=messages.append)
    assert report.reused and out.stat().st_mtime_ns == stamp
    assert "reusing" in messages[0]
    changed = parse_study(GRID.replace("t_end = 4.0", "t_end = 2.0"))
    report = run_sweep(changed, out, client=client, progress=False, log=quiet)
    assert not report.reused
    with xr.open_dataset(out) as ds:
        assert ds.sizes["t"] == 41 and ds.attrs["study_sha256"] == changed.key
    report = run_sweep(changed, out, client=client, progress=False, log=quiet, force=True)
    assert not report.reused


def test_partial_results_of_another_study_are_discarded(client, tmp_path):
    out = tmp_path / "s.nc"
    first = parse_study(GRID)

    def stop(batch):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(first, out, client=client, batch_size=4, progress=False, log=quiet, on_batch=stop)
    second = parse_study(GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = [0.0, 1e7]"))
    messages = []
    report = run_sweep(second, out, client=client, progress=False, log=messages.append)
    assert report.n_resumed_batches == 0
    assert any("discarding partial results" in m for m in messages)
    with xr.open_dataset(out) as ds:
        np.testing.assert_array_equal(ds["eps"].values, [0.0, 1e7])


def test_a_second_concurrent_run_is_refused(client, tmp_path):
    study = parse_study(GRID)
    out = tmp_path / "l.nc"
    holder = PartialStore(out)
    holder.open(study.key, {"batch_size": 5}, quiet)
    try:
        with pytest.raises(SweepError, match="another run is writing"):
            run_sweep(study, out, client=client, progress=False, log=quiet)
    finally:
        holder.close()
    assert not out.exists()


def test_bad_arguments_are_refused_before_any_work(tmp_path):
    with pytest.raises(SweepError, match="output folder .* does not exist"):
        run_sweep(parse_study(GRID), tmp_path / "nope" / "x.nc", client=object(), log=quiet)
    with pytest.raises(SweepError, match="number of workers"):
        run_sweep(parse_study(GRID), tmp_path / "x.nc", workers=-1, log=quiet)
    with pytest.raises(SweepError, match="zlib level"):
        run_sweep(parse_study(GRID), tmp_path / "x.nc", client=object(), complevel=12, log=quiet)
    with pytest.raises(SweepError, match="batch size"):
        run_sweep(parse_study(GRID), tmp_path / "x.nc", client=object(), batch_size=0, log=quiet)
    assert list(tmp_path.iterdir()) == []


def fake_monte_carlo(block, foundation, excitation, n_samples=1000, model="coupled", t_end=20.0, dt=0.05,
                     seed=0, **kw):
    """Stand-in with the documented API: var = 2 x S0-scaled ramp, so the values are known."""
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    scale = float(excitation.S0) * (1.0 + float(foundation.eps) * 1e-9)
    data = {"var_theta": ("t", scale * t), "var_theta_dot": ("t", 10 * scale * t),
            "var_theta_se": ("t", 0.1 * scale * t), "var_theta_dot_se": ("t", scale * t),
            "peak_abs_theta": ("sample", scale * np.arange(n_samples)),
            "overturned": ("sample", np.arange(n_samples) < 3), "diverged": ("sample", np.arange(n_samples) == 3),
            "n_steps": ("sample", np.full(n_samples, 100)), "n_overturned": ((), 3), "n_diverged": ((), 1)}
    return xr.Dataset(data, coords={"t": t}, attrs={"input_grid_points": 1024, "model": str(model)})


def test_spot_checks_store_monte_carlo_on_the_spot_dimension(client, tmp_path, monkeypatch):
    import screening.solvers.montecarlo

    monkeypatch.setattr(screening.solvers.montecarlo, "monte_carlo", fake_monte_carlo)
    study = parse_study(GRID + "[mcs]\npoints = [{eps = 6e7, S0 = 2.4e-3}, {index = {eps = 0, S0 = 1}}]\n"
                               "samples = 7\nmodel = \"condensed\"\nseed = 4\n")
    out = tmp_path / "m.nc"
    report = run_sweep(study, out, client=client, progress=False, log=quiet)
    assert report.n_spots == 2
    with xr.open_dataset(out) as ds:
        np.testing.assert_array_equal(ds["spot_eps"].values, [6e7, -6e5])
        np.testing.assert_array_equal(ds["spot_S0"].values, [2.4e-3, study.sweeps["S0"][1]])
        assert ds["mcs_var_theta"].dims == ("spot", "t")
        t = ds["t"].values
        for i, (eps, s0) in enumerate([(6e7, 2.4e-3), (-6e5, study.sweeps["S0"][1])]):
            scale = s0 * (1.0 + eps * 1e-9)
            np.testing.assert_allclose(ds["mcs_var_theta"].values[i], scale * t, rtol=1e-15)
            lin = ds["var_theta"].sel(eps=eps, S0=s0).values.astype(float)
            expected = (np.nanmax(lin) - scale * t[-1]) / (scale * t[-1])
            assert ds["mcs_rel_error_peak_var_theta"].values[i] == pytest.approx(expected, rel=1e-12)
        np.testing.assert_array_equal(ds["mcs_n_overturned"].values, [3, 3])
        np.testing.assert_array_equal(ds["mcs_n_used"].values, [3, 3])
        np.testing.assert_array_equal(ds["mcs_status"].values, [0, 0])
        assert ds["mcs_peak_abs_theta"].dims == ("spot", "sample") and ds.sizes["sample"] == 7
        np.testing.assert_allclose(ds["mcs_peak_abs_theta"].values[0], 2.4e-3 * 1.06 * np.arange(7), rtol=1e-15)
        np.testing.assert_array_equal(ds["mcs_sample_state"].values, [[1, 1, 1, 2, 0, 0, 0]] * 2)
        assert ds["mcs_sample_state"].attrs["flag_meanings"].split()[:2] == ["standing", "overturned"]
        assert ds.attrs["mcs_model"] == "condensed" and int(ds.attrs["mcs_samples"]) == 7
        assert "explicit" in ds.attrs["mcs_selection"]
        assert set(ds["mcs_var_theta"].coords) >= {"spot_eps", "spot_S0", "t"}


def test_auto_spot_check_with_the_real_monte_carlo(client, tmp_path):
    study = parse_study(GRID + '[mcs]\npoints = "auto"\ncount = 1\nsamples = 8\nmodel = "condensed"\n')
    out = tmp_path / "a.nc"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    with xr.open_dataset(out) as ds:
        ok = ds["status"].values == 0
        best = np.unravel_index(np.argmax(np.where(ok, ds["peak_p_uplift"].values, -1)), ok.shape)
        assert ds["spot_eps"].values[0] == ds["eps"].values[best[0]]
        assert ds["spot_S0"].values[0] == ds["S0"].values[best[1]]
        assert np.isfinite(ds["mcs_rel_error_peak_var_theta"].values[0])
        assert np.all(ds["mcs_var_theta"].values[0, 1:] > 0)
        assert int(ds["mcs_n_used"].values[0]) + int(ds["mcs_n_overturned"].values[0]) \
            + int(ds["mcs_n_diverged"].values[0]) == 8
        assert "auto" in ds.attrs["mcs_selection"]


# ----------------------------------------------------------------------------- a real cluster
@pytest.fixture
def dask_cluster(tmp_path):
    """``dask scheduler`` + two ``dask worker`` processes on 127.0.0.1 (torn down afterwards)."""
    with dask_processes(tmp_path, ["--nthreads", "1", "--no-nanny", "--no-dashboard"]) as sched_file:
        yield sched_file


def test_existing_scheduler_with_two_worker_processes(dask_cluster, client, tmp_path):
    address = json.loads(dask_cluster.read_text())["address"]
    assert address.startswith("tcp://127.0.0.1:")
    from distributed import Client

    with Client(address, timeout="30s") as probe:
        probe.wait_for_workers(2, timeout=60)
    study = parse_study(GRID)
    out = tmp_path / "remote.nc"
    report = run_sweep(study, out, scheduler=address, batch_size=4, progress=False, log=quiet)
    assert report.n_workers == 2 and report.n_batches == 5
    ref = tmp_path / "local.nc"
    run_sweep(study, ref, client=client, batch_size=4, progress=False, log=quiet)
    compare_files(ref, out)
    # the scheduler file is accepted too
    report = run_sweep(study, tmp_path / "file.nc", scheduler=str(dask_cluster), progress=False, log=quiet)
    assert report.status_counts == {"ok": 20}


def test_unreachable_scheduler_is_a_sweep_error(tmp_path, monkeypatch):
    monkeypatch.setattr(execution, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(SweepError, match="cannot connect to the dask scheduler"):
        run_sweep(parse_study(GRID), tmp_path / "x.nc", scheduler="tcp://127.0.0.1:9", progress=False,
                  log=quiet)
    assert list(tmp_path.iterdir()) == []
    with netCDF4.Dataset(tmp_path / "y.nc", "w"):
        pass
    assert result_key(tmp_path / "y.nc") is None


def test_complevel_changes_storage_not_values(client, tmp_path):
    study = parse_study(GRID)
    run_sweep(study, tmp_path / "z1.nc", client=client, progress=False, log=quiet)
    run_sweep(study, tmp_path / "z0.nc", client=client, progress=False, log=quiet, complevel=0)
    with netCDF4.Dataset(tmp_path / "z0.nc") as nc0, netCDF4.Dataset(tmp_path / "z1.nc") as nc1:
        assert not nc0["var_theta"].filters()["zlib"] and nc1["var_theta"].filters()["zlib"]
    compare_files(tmp_path / "z1.nc", tmp_path / "z0.nc")


# ----------------------------------------------------------------------------- [output]
def test_history_free_result_has_the_summaries_and_spot_checks_of_the_full_one(client, tmp_path):
    """histories = "none": no history variable, every summary identical, spot checks still compared."""
    spots = '[mcs]\npoints = [{eps = 6e7, S0 = 2.4e-3}]\nsamples = 4\nmodel = "condensed"\n'
    full, bare = tmp_path / "full.nc", tmp_path / "bare.nc"
    run_sweep(parse_study(GRID + spots), full, client=client, progress=False, log=quiet)
    run_sweep(parse_study(GRID + '[output]\nhistories = "none"\n' + spots), bare, client=client, progress=False,
              log=quiet)
    with xr.open_dataset(full) as f, xr.open_dataset(bare) as b:
        assert "var_theta" in f and not {"var_theta", "p_uplift", "c_eq"} & set(b.data_vars)
        assert b.attrs["output_histories"] == "none" and b.attrs["output_history_variables"] == ""
        for name in ("status", "peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq", "n_steps",
                     "mcs_var_theta", "mcs_peak_var_theta"):
            np.testing.assert_array_equal(b[name].values, f[name].values, err_msg=name)
        # the full file compares against float32 histories, the bare one against float64 ones
        np.testing.assert_allclose(b["mcs_rel_error_peak_var_theta"].values, f["mcs_rel_error_peak_var_theta"].values,
                                   rtol=1e-5)
        assert np.all(np.isfinite(b["mcs_rel_error_peak_var_theta_dot"].values))
        from screening.report.figures import plot_result

        names = sorted(p.name for p in plot_result(b, "bare", tmp_path))
        assert names == ["bare_peaks.png", "bare_spots.png"]           # no history figures to draw


def test_chosen_history_variables_only(client, tmp_path):
    out = tmp_path / "some.nc"
    run_sweep(parse_study(GRID + '[output]\nvariables = ["p_uplift"]\n'), out, client=client, progress=False,
              log=quiet)
    with xr.open_dataset(out) as ds:
        assert "p_uplift" in ds and not {"var_theta", "k_eq"} & set(ds.data_vars)
        assert ds["p_uplift"].dims == ("eps", "S0", "t") and ds.attrs["output_history_variables"] == "p_uplift"


def test_fragility_on_the_workers_matches_the_analysis_of_the_full_histories(client, tmp_path):
    """[fragility] with histories = "none": p_exceed stored per point and threshold, equal to
    ds.rocking.exceedance_probability on a result that has the histories (float32 there)."""
    frag = '[fragility]\nthresholds = [0.5, 2.0]\nrelative_to = "theta_ul"\n'
    full, bare = tmp_path / "full.nc", tmp_path / "bare.nc"
    run_sweep(parse_study(GRID), full, client=client, progress=False, log=quiet)
    run_sweep(parse_study(GRID + '[output]\nhistories = "none"\n' + frag), bare, client=client, progress=False,
              log=quiet)
    with xr.open_dataset(full) as f, xr.open_dataset(bare) as b:
        assert "var_theta" not in b and b["p_exceed"].dims == ("eps", "S0", "threshold")
        np.testing.assert_array_equal(b["threshold"].values, [0.5, 2.0])
        assert b["p_exceed"].attrs["units"] == "1" and b["p_exceed"].attrs["relative_to"] == "theta_ul"
        vouched = b["p_source"].values != ProbabilitySource.unreliable       # elsewhere missing values
        assert vouched.any()
        for j, thr in enumerate((0.5, 2.0)):
            ref = f.rocking.exceedance_probability(thr, relative_to="theta_ul").values
            got = b["p_exceed"].values[..., j]
            np.testing.assert_allclose(got[vouched], ref[vouched], rtol=1e-4, atol=1e-12)
            assert np.all(np.isnan(got[~vouched]))
        p = b["p_exceed"].values[vouched]
        assert np.all(p[..., 0] >= p[..., 1]) and np.nanmax(p[..., 0]) > 0.1      # higher threshold, lower p


def test_a_narrow_submission_window_gives_the_same_file(client, tmp_path, monkeypatch):
    """Batches are submitted a few per worker at a time: one in flight gives the same result."""
    import screening.sweep.run as sweep_module

    study = parse_study(GRID)
    run_sweep(study, tmp_path / "wide.nc", client=client, batch_size=3, progress=False, log=quiet)
    monkeypatch.setattr(sweep_module, "IN_FLIGHT_PER_WORKER", 1)
    seen = []
    in_flight = []
    report = run_sweep(study, tmp_path / "narrow.nc", client=client, batch_size=3, progress=False, log=quiet,
                       on_batch=lambda b: (seen.append(b.index), in_flight.append(len(client.futures))))
    assert sorted(seen) == list(range(report.n_batches)) and report.n_batches == 7
    assert max(in_flight) <= len(client.nthreads()) + 1      # the window plus the next one being topped up
    compare_files(tmp_path / "wide.nc", tmp_path / "narrow.nc")


def test_spot_histories_are_those_of_the_full_result_at_the_spot(client, tmp_path):
    """histories = "spots": no grid histories; the chosen ones at each spot point (float64)."""
    spots = '[mcs]\npoints = [{eps = 6e7, S0 = 2.4e-3}]\nsamples = 4\nmodel = "condensed"\n'
    full, some = tmp_path / "full.nc", tmp_path / "spots.nc"
    run_sweep(parse_study(GRID + spots), full, client=client, progress=False, log=quiet)
    run_sweep(parse_study(GRID + '[output]\nhistories = "spots"\nvariables = ["var_theta", "k_eq"]\n' + spots),
              some, client=client, progress=False, log=quiet)
    with xr.open_dataset(full) as f, xr.open_dataset(some) as s:
        assert "var_theta" not in s and {"spot_var_theta", "spot_k_eq"} <= set(s.data_vars)
        assert "spot_p_uplift" not in s and s["spot_k_eq"].dims == ("spot", "t")
        assert s["spot_var_theta"].attrs["units"] == "rad2"
        for name in ("var_theta", "k_eq"):
            ref = f[name].sel(eps=6e7, S0=2.4e-3).values.astype(float)
            np.testing.assert_allclose(s[f"spot_{name}"].values[0], ref, rtol=1e-6, equal_nan=True)


def test_every_point_carries_the_trust_flag_of_the_linearization(tmp_path, one_worker):
    """sl_trust and its error band on the workers equal add_trust on the same points solved directly."""
    from screening.analysis.trust import add_trust
    from screening.core.status import Trust
    from screening.io.reader import open_result

    study = parse_study(GRID, name="trust")
    out = tmp_path / "trust.nc"
    report = run_sweep(study, out, client=one_worker, progress=False, log=quiet)
    assert sum(report.trust_counts.values()) == study.n_points
    with open_result(out) as ds:
        ds = ds.load()
    assert ds["sl_trust"].attrs["flag_meanings"] == "trusted check untrusted"
    block, foundation, excitation = build_models(study.cases[0], {
        "eps": study.sweeps["eps"], "S0": study.sweeps["S0"]})           # 1-d: dims eps and S0
    direct = add_trust(linearize(block, foundation, excitation, t_end=study.t_end, dt=study.dt, rtol=study.rtol))
    direct = direct.transpose("eps", "S0", ...)
    np.testing.assert_array_equal(ds["sl_trust"].values, direct["sl_trust"].values)
    for name in ("sl_error_low", "sl_error_high"):
        np.testing.assert_allclose(ds[name].values, direct[name].values, rtol=1e-12, equal_nan=True)
    assert set(np.unique(ds["sl_trust"].values)) <= {int(t) for t in Trust}
    assert np.any(ds["sl_trust"].values != Trust.trusted)          # the heavy-uplift points are not trusted
