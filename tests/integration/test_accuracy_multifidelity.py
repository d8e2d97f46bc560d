"""``[accuracy] multifidelity = true``: coupled escalated points paired with the condensed model where the pilot
says it pays, the estimator recorded per point, the cost charged for both models, and a resumable plan."""

import numpy as np
import pytest
import xarray as xr

from helpers import GRID

from screening.analysis import escalation as esc
from screening.analysis.multifidelity import allocate
from screening.core.status import EscalationEstimator, EscalationModel
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

ONE_POINT = GRID.replace("t_end = 4.0", "t_end = 3.0").replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = 0.0").replace(
    "S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}", "S0 = 2.4e-3") + """
[accuracy]
target = 0.15
budget_s = 600000
multifidelity = true
"""


@pytest.fixture
def forced(monkeypatch):
    """The pilot's allocation with the gain threshold at 0 (today's condensed model costs ~1/3 of the coupled
    one and never pays on its own): the multi-fidelity path runs; the plans seen are recorded."""
    plans = []

    def plan(pilot, model, pilot_samples, n_plain):
        c = esc.estimated_cost(pilot["n_steps"], model, pilot["n_grid"]) / pilot_samples
        c_lo = esc.estimated_cost(pilot["cheap_n_steps"], esc.PAIRED_MODEL[2], pilot["cheap_n_grid"]) / pilot_samples
        out = allocate(float(pilot["correlation"]), c, c_lo, max(n_plain, 128), min_gain=0.0, max_ratio=4.0)
        plans.append(out)
        return out

    monkeypatch.setattr(esc, "paired_plan", plan)
    return plans


@pytest.mark.slow
def test_a_multifidelity_point_records_its_estimator_and_pays_for_both_models(client, tmp_path, forced):
    study = parse_study(ONE_POINT)
    assert study.accuracy.multifidelity
    messages = []
    report = run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=messages.append)
    assert forced and forced[0].estimator == "multifidelity"
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        assert ds["esc_model"].values.tolist() == [EscalationModel.coupled]
        assert ds["esc_estimator"].values.tolist() == [EscalationEstimator.multifidelity]
        assert ds["esc_estimator"].attrs["flag_meanings"].split() == [m.name for m in EscalationEstimator]
        n, n_cheap = int(ds["esc_samples"].values[0]), int(ds["esc_cheap_samples"].values[0])
        assert n_cheap > n >= esc.PILOT_SAMPLES
        assert -1.0 <= float(ds["esc_correlation"].values[0]) <= 1.0
        assert float(ds["esc_cost"].sum()) == pytest.approx(float(ds.attrs["accuracy_cost_s"]), rel=1e-9)
        se, peak = float(ds["esc_peak_var_theta_se"].values[0]), float(ds["esc_peak_var_theta"].values[0])
        assert np.isfinite(peak) and peak > 0 and 0 < se
        assert ds["best_peak_var_theta"].values.item() == peak
        assert ds["p_source"].values.item() == ds["p_source"].attrs["flag_values"][
            ds["p_source"].attrs["flag_meanings"].split().index("monte_carlo_coupled")]
        assert 0.0 <= float(ds["p_overturn"].values) <= 1.0 and np.isfinite(float(ds["p_overturn_se"].values))
    assert report.accuracy["n_multifidelity"] == 1
    assert any("1 multi-fidelity" in m for m in messages)


def test_the_pilot_decides_by_the_fallback_rule(client, tmp_path, monkeypatch):
    """Unforced: the paired pilot's allocation (costs from the cost model, correlation at the peak) decides; the
    point's estimator is multi-fidelity exactly where the predicted gain reaches MIN_GAIN."""
    from screening.analysis.multifidelity import MIN_GAIN, speedup

    real, plans = esc.paired_plan, []
    monkeypatch.setattr(esc, "paired_plan", lambda *a: plans.append((a[0], real(*a))) or plans[-1][1])
    study = parse_study(ONE_POINT)
    run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda m: None)
    pilot, plan = plans[0]
    c_hi = esc.estimated_cost(pilot["n_steps"], EscalationModel.coupled, pilot["n_grid"]) / esc.PILOT_SAMPLES
    c_lo = (esc.estimated_cost(pilot["cheap_n_steps"], EscalationModel.condensed, pilot["cheap_n_grid"])
            / esc.PILOT_SAMPLES)
    gain = speedup(float(pilot["correlation"]), c_hi, c_lo)
    print(f"pilot: rho {float(pilot['correlation']):.3f}, cost ratio {c_hi / c_lo:.2f}, predicted gain {gain:.2f}, "
          f"plan {plan}")
    assert (plan.estimator == "multifidelity") == (gain >= MIN_GAIN)
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        code = EscalationEstimator.multifidelity if gain >= MIN_GAIN else EscalationEstimator.plain_monte_carlo
        assert ds["esc_estimator"].values.tolist() == [code]
        if code == EscalationEstimator.plain_monte_carlo:     # the paired pilot's 64 cheap samples, none beyond
            assert int(ds["esc_cheap_samples"].values[0]) in (0, esc.PILOT_SAMPLES)


def test_an_interrupted_multifidelity_escalation_resumes_to_the_same_result(client, tmp_path, forced, monkeypatch):
    from screening.sweep import _submit
    from screening.sweep.run import _SweepRun

    study = parse_study(ONE_POINT)
    real = _submit.submit_escalation
    calls = []
    monkeypatch.setattr(_submit, "submit_escalation", lambda *a, **k: calls.append(k.get("cheap")) or real(*a, **k))

    def interrupted(self):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(_SweepRun, "_finalize", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda msg: None)
    assert calls and all(c is not None for c in calls)          # every run of the point paired
    first = list(calls)
    calls.clear()
    run_sweep(study, tmp_path / "a.nc", client=client, progress=False, log=lambda msg: None)
    assert not calls, f"resumed run ran again: {calls} (first run: {first})"
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        assert ds["esc_estimator"].values.tolist() == [EscalationEstimator.multifidelity]
        assert int(ds["esc_cheap_samples"].values[0]) == first[-1][2]


def test_multifidelity_is_a_boolean_checked_when_the_study_is_read():
    from screening.sweep.study import StudyError

    assert not parse_study(ONE_POINT.replace("multifidelity = true\n", "")).accuracy.multifidelity
    with pytest.raises(StudyError, match=r"accuracy\.multifidelity: must be true or false"):
        parse_study(ONE_POINT.replace("multifidelity = true", "multifidelity = 1"))
