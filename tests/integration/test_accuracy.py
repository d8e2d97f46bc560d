"""A sweep with ``[accuracy]`` escalates to Monte Carlo within its budget and stores consistent best estimates."""

import numpy as np
import pytest
import xarray as xr

from helpers import GRID

from screening.analysis.correction import linearization_promises
from screening.solvers.estimates import binomial_estimate
from screening.core.status import BestMethod, EscalationModel, PointStatus, TargetMet
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

TARGET = GRID.replace("t_end = 4.0", "t_end = 3.0") + """
[accuracy]
target = 0.15
budget_s = 10
"""
#: The same with a budget that does not bind: the whole plan runs, the same on every machine.
UNBOUNDED = TARGET.replace("budget_s = 10", "budget_s = 600000")


@pytest.mark.parametrize("suffix", [".nc", pytest.param(".zarr", marks=pytest.mark.slow)])   # .zarr: slow suite
def test_target_study_escalates_within_budget_and_labels_every_point(client, tmp_path, suffix):
    if suffix == ".zarr":
        pytest.importorskip("zarr")
    study = parse_study(TARGET)
    messages = []
    report = run_sweep(study, tmp_path / f"a{suffix}", client=client, progress=False, log=messages.append)
    info = report.accuracy
    assert info["n_escalated"] >= 1 and info["n_candidates"] >= info["n_escalated"]
    # the budget holds on the wall clock (within 10 %); cost model and measured CPU time are reported
    assert 0 < info["wall_s"] <= 1.1 * study.accuracy.budget_s
    assert info["cost_s"] > 0 and info["cpu_s"] > 0
    assert any(m.startswith("accuracy (target 0.15):") for m in messages)
    with xr.open_dataset(tmp_path / f"a{suffix}") as ds:
        assert float(ds.attrs["accuracy_wall_s"]) == pytest.approx(info["wall_s"])
        assert float(ds["esc_cpu_time"].sum()) == pytest.approx(float(ds.attrs["accuracy_cpu_s"]), rel=1e-9)
        assert float(ds["esc_cost"].sum()) == pytest.approx(float(ds.attrs["accuracy_cost_s"]), rel=1e-9)
        # the per-point flag says whether the standard error reached its target: 0.03 of P(overturn) where a
        # sample overturned (no [fragility] here: overturning is the only level), else target / 2 of the peak
        n_over, n_used = ds["esc_n_overturned"].values, ds["esc_n_used"].values + ds["esc_n_overturned"].values
        by_p = (ds["esc_transition"].values == 1) | (n_over > 0)
        met = np.where(by_p, binomial_estimate(n_over.astype(float), n_used)[1] <= 0.03,
                       ds["esc_peak_var_theta_se"].values <= 0.075 * ds["esc_peak_var_theta"].values)
        np.testing.assert_array_equal(ds["esc_target_met"].values == TargetMet.target_met, met)
        assert int(ds.attrs["accuracy_n_short_of_target"]) == int(np.sum(~met))
        method = ds["best_method"].values.reshape(-1)
        value = ds["best_peak_var_theta"].values.reshape(-1)
        se = ds["best_peak_var_theta_se"].values.reshape(-1)
        status = ds["status"].values.reshape(-1)
        # the escalated points carry their own Monte Carlo, with the model that ran there
        at = ds["esc_grid_index"].values
        mc = np.where(ds["esc_model"].values == EscalationModel.condensed, BestMethod.condensed_monte_carlo,
                      BestMethod.coupled_monte_carlo)
        np.testing.assert_array_equal(method[at], mc)
        np.testing.assert_array_equal(value[at], ds["esc_peak_var_theta"].values)
        sl_dot = ds["var_theta_dot"].values.reshape(-1, ds.sizes["t"])[at]
        np.testing.assert_array_equal(ds["esc_sl_peak_var_theta_dot"].values, np.nanmax(sl_dot, axis=1))
        assert np.all(ds["esc_samples"].values >= 64)
        assert np.all(ds["esc_n_used"].values + ds["esc_n_overturned"].values + ds["esc_n_diverged"].values
                      == ds["esc_samples"].values)
        # linearization only where the rule promises the target, never at a stopped point
        promised = linearization_promises(ds["sl_trust"].values.reshape(-1), ds["sl_error_low"].values.reshape(-1),
                                          ds["sl_error_high"].values.reshape(-1), 0.15)
        assert np.all(promised[method == BestMethod.linearization])
        assert np.all(status[method == BestMethod.linearization] == PointStatus.ok)
        # a standard error exactly where an estimate is vouched for
        reliable = method != BestMethod.unreliable
        assert np.all(np.isfinite(se[reliable]) & (se[reliable] > 0)) and np.all(np.isnan(se[~reliable]))
        assert ds["best_method"].attrs["flag_meanings"].split() == [m.name for m in BestMethod]
        assert ds["best_peak_var_theta_se"].attrs["units"] == "rad2"
        # info counts the best estimates by method
        from screening.report.text import describe

        counts = ", ".join(f"{m.name} {int(np.sum(method == m))}" for m in BestMethod if np.any(method == m))
        assert f"best estimates ([accuracy] target 0.15): {counts}; Monte Carlo at {at.size} point(s)" in describe(ds)



def test_fragility_uses_monte_carlo_where_it_ran_and_the_band_elsewhere(client, tmp_path):
    from screening.analysis.fragility import fragility_dataset, sample_exceedance

    study = parse_study(TARGET)
    run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda m: None)
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        frag = fragility_dataset(ds, 0.05, "slenderness").load()
        at = np.unravel_index(ds["esc_grid_index"].values, ds["status"].shape)
        state = ds["esc_sample_state"].rename(esc_sample="sample")
        level = frag["threshold_rad"].values[at] if frag["threshold_rad"].ndim else float(frag["threshold_rad"])
        p_mc, se = sample_exceedance(ds["esc_peak_abs_theta"].rename(esc_sample="sample"), state == 1,
                                     (state == 0) | (state == 1), xr.DataArray(level, dims="escalation"))
    np.testing.assert_allclose(frag["best_p_exceed"].values[at], p_mc.values)
    np.testing.assert_allclose(frag["best_p_exceed_high"].values[at], np.clip(p_mc + 2 * se, 0, 1))
    reliable = frag["best_method"].values != BestMethod.unreliable
    p, lo, hi = (frag[n].values[reliable] for n in ("best_p_exceed", "best_p_exceed_low", "best_p_exceed_high"))
    assert np.all((lo <= p + 1e-12) & (p <= hi + 1e-12))
    assert frag["best_p_exceed"].attrs["units"] == "1"


def test_interrupted_escalation_resumes_from_its_record(client, tmp_path, monkeypatch):
    from screening.io.store import PartialStore
    from screening.sweep import _submit
    from screening.sweep.accuracy import ESCALATION_RECORD
    from screening.sweep.run import _SweepRun

    study = parse_study(TARGET)
    real_submit, real_save = _submit.submit_escalation, PartialStore.save_spot
    calls, recorded = [], {}

    def submit(*a, **k):                          # (plan position, phase) of every run submitted
        phase, j = k["key"].split("-")[1], int(k["key"].rsplit("-", 1)[1])
        calls.append((j, ("pilot", "full", "topup").index(phase)))
        return real_submit(*a, **k)

    def save(self, i, index, result):             # the phase each point's record holds
        if i >= ESCALATION_RECORD:
            recorded[i - ESCALATION_RECORD] = int(result["phase"])
        return real_save(self, i, index, result)

    monkeypatch.setattr(_submit, "submit_escalation", submit)
    monkeypatch.setattr(PartialStore, "save_spot", save)

    def interrupted(self):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:              # everything computed, the file never moved into place
        m.setattr(_SweepRun, "_finalize", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda msg: None)
    first = dict(recorded)
    calls.clear()
    report = run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda msg: None)
    # no recorded run is done again (a point may go on to its next phase with what is left of the budget;
    # which runs the first run finished depends on the machine's speed, so the record is read, not guessed)
    assert first and not [(j, what) for j, what in calls if j in first and what <= first[j]]
    assert report.accuracy["wall_s"] <= 1.1 * study.accuracy.budget_s      # the budget counts both runs
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        assert len(first) <= ds.sizes["escalation"]
        assert np.all(np.isfinite(ds["esc_peak_var_theta"].values))


@pytest.mark.slow
def test_escalation_is_reproducible_for_a_study_and_seed(client, tmp_path, monkeypatch):
    # where the budget does not bind, what a point runs depends on its own runs only (their standard errors):
    # the same points run with the same samples, so the best estimates are identical
    from screening.sweep import accuracy

    study = parse_study(UNBOUNDED)
    waits = []
    real = accuracy.raise_if_interrupted
    monkeypatch.setattr(accuracy, "raise_if_interrupted", lambda: waits.append(1) or real())
    runs = []
    for name in ("a.nc", "b.nc"):
        run_sweep(study, tmp_path / name, client=client, progress=False, log=lambda m: None)
        with xr.open_dataset(tmp_path / name) as ds:
            runs.append({k: ds[k].values.copy() for k in ("esc_grid_index", "esc_samples", "esc_cost", "best_method",
                                                          "best_peak_var_theta", "best_peak_var_theta_se",
                                                          "best_peak_var_theta_dot")})
    for key, value in runs[0].items():
        np.testing.assert_array_equal(value, runs[1][key], err_msg=key)
    assert waits                                  # the waits for Monte Carlo results let a Ctrl-C through


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_accuracy_on_a_one_point_grid(client, tmp_path, suffix):
    """A study without swept parameters: its escalation has no grid coordinate to write."""
    if suffix == ".zarr":
        pytest.importorskip("zarr")
    text = TARGET.replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = 3e7").replace(
        "S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}", "S0 = 2.4e-3")
    study = parse_study(text)
    assert study.shape == ()
    report = run_sweep(study, tmp_path / f"one{suffix}", client=client, progress=False, log=lambda m: None)
    assert report.accuracy["n_escalated"] == 1
    with xr.open_dataset(tmp_path / f"one{suffix}") as ds:
        assert ds["esc_grid_index"].values.tolist() == [0]
        assert ds["best_method"].values.item() in (BestMethod.coupled_monte_carlo, BestMethod.condensed_monte_carlo)
        assert ds["best_peak_var_theta"].values.item() == ds["esc_peak_var_theta"].values.item()


@pytest.mark.slow
def test_a_run_killed_during_its_top_up_round_resumes_to_the_same_result(client, tmp_path, monkeypatch):
    """Every finished run is in the resume record at once (the point's latest result): the resumed run runs
    no kept run again and, where the budget does not bind, ends with the same points, samples and estimates."""
    from screening.analysis import escalation
    from screening.sweep import _submit, accuracy
    from screening.io.store import PartialStore

    # a top-up round whatever the models' errors: no point meets the target, a top-up asks for a few samples more
    real_needed = escalation.samples_needed
    monkeypatch.setattr(escalation, "meets_target", lambda *a, **k: False)
    monkeypatch.setattr(escalation, "samples_needed", lambda se, n0, *a, **k: n0 + 16 if n0 != escalation.PILOT_SAMPLES
                        else real_needed(se, n0, *a, **k))
    study = parse_study(UNBOUNDED)
    real_submit = _submit.submit_escalation
    keys = []
    monkeypatch.setattr(_submit, "submit_escalation",
                        lambda *a, **k: keys.append((k["key"].split("-")[1], k["key"].rsplit("-", 1)[1]))
                        or real_submit(*a, **k))
    run_sweep(study, tmp_path / "ref.nc", client=client, progress=False, log=lambda m: None)
    assert sum(kind == "topup" for kind, _ in keys) >= 1, keys     # the study has a top-up round to interrupt
    real_save = PartialStore.save_spot
    kept = []

    def killed_at_the_first_top_up(self, i, index, result):
        real_save(self, i, index, result)
        if i >= accuracy.ESCALATION_RECORD:
            kept.append((("pilot", "full", "topup")[int(result["phase"])], f"{i - accuracy.ESCALATION_RECORD:04d}"))
            if kept[-1][0] == "topup":
                raise KeyboardInterrupt

    keys.clear()
    with monkeypatch.context() as m:
        m.setattr(PartialStore, "save_spot", killed_at_the_first_top_up)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda m: None)
    keys.clear()
    run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda m: None)
    assert kept and not set(kept) & set(keys)                      # no kept run runs again
    with xr.open_dataset(tmp_path / "ref.nc") as ref, xr.open_dataset(tmp_path / "a.nc") as ds:
        for var in ("esc_grid_index", "esc_samples", "esc_cost", "esc_peak_var_theta", "esc_peak_var_theta_se",
                    "best_method", "best_peak_var_theta", "best_peak_var_theta_se"):
            np.testing.assert_array_equal(ds[var].values, ref[var].values, err_msg=var)
