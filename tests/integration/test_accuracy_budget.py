"""``[accuracy] budget_s`` in wall seconds: measured on an injected clock (no sleeping), the transition points of
the fragility curves first, the line before any Monte Carlo, the interim result and the resume record after each
run, bad input."""

import numpy as np
import pytest
import xarray as xr

from helpers import GRID, one_line_error

from screening.analysis import escalation
from screening.core.status import EscalationModel
from screening.sweep import _submit, accuracy, run as sweep
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

#: Two beds x 5 intensities, 3 s records: P(overturn) and P(exceed 0.3 slenderness) go from 0 to 1 along S0.
BUDGET = GRID.replace("t_end = 4.0", "t_end = 3.0").replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = [0.0, 6e7]") + """
[fragility]
thresholds = [0.3]
relative_to = "slenderness"
[accuracy]
target = 0.15
budget_s = BUDGET_S
"""


def budget_study(budget):
    return parse_study(BUDGET.replace("BUDGET_S", str(budget)))
#: The fake clock's wall seconds per cost-model second of a run (one worker thread).
SLOW = 50.0


class FakeClock:
    """Wall time [s] that passes only as Monte Carlo runs end: a run of ``c`` cost-model seconds takes ``SLOW c``
    on the one worker thread (the runs of the stage are one at a time there)."""

    def __init__(self):
        self.now, self.runs, self.reads = 0.0, [], 0

    def submitted(self, future, model):
        self.runs.append((future, EscalationModel[model]))
        return future

    def __call__(self):
        self.reads += 1
        for item in [item for item in self.runs if item[0].done()]:
            self.runs.remove(item)
            future, model = item
            if future.status == "finished":
                r = future.result()
                self.now += SLOW * escalation.estimated_cost(r["n_steps"], model, r["n_grid"], bool(r["rodas"]),
                                                             int(r["samples"]), full_contact=r.get("full_contact"))
        return self.now


def run_with_clock(monkeypatch, study, out, client, clock, messages=None, calls=None):
    """``run_sweep`` of ``study`` into ``out`` with the accuracy stage on ``clock``; ``calls`` collects
    ``(position in the order, kind, samples)`` of the runs submitted."""
    real_stage, real_submit = sweep.Stage, _submit.submit_escalation

    def submit(client, study, flat, samples, model, key, **kw):
        if calls is not None:
            calls.append((int(key.rsplit("-", 1)[1]), key.split("-")[1], int(samples)))
        return clock.submitted(real_submit(client, study, flat, samples, model, key, **kw), model)

    with monkeypatch.context() as m:
        m.setattr(sweep, "Stage", lambda *a, **k: real_stage(*a, **k, clock=clock))
        m.setattr(_submit, "submit_escalation", submit)
        log = messages.append if messages is not None else (lambda msg: None)
        return run_sweep(study, out, client=client, progress=False, log=log)


@pytest.fixture(scope="module")
def unbounded(one_worker, tmp_path_factory):
    """The study with a budget that does not bind, on the fake clock: what the whole plan runs and costs."""
    mp = pytest.MonkeyPatch()
    clock, calls, messages = FakeClock(), [], []
    out = tmp_path_factory.mktemp("unbounded") / "a.nc"
    try:
        report = run_with_clock(mp, budget_study(600000), out, one_worker, clock, messages, calls)
    finally:
        mp.undo()
    with xr.open_dataset(out) as ds:
        esc = {k: ds[k].values.copy() for k in ("esc_grid_index", "esc_samples", "esc_peak_var_theta")}
    return report, clock.now, calls, messages, esc


def test_the_budget_in_wall_seconds_binds_on_the_clock(one_worker, tmp_path, monkeypatch, unbounded):
    report, whole, calls, _, esc = unbounded
    assert report.accuracy["n_cut"] == 0 and whole == pytest.approx(report.accuracy["wall_s"])
    assert len(esc["esc_grid_index"]) >= 4                       # enough points to cut
    budget = round(whole / 3, 1)
    clock, bound_calls = FakeClock(), []
    out = tmp_path / "b.nc"
    bound = run_with_clock(monkeypatch, budget_study(budget), out, one_worker, clock,
                           calls=bound_calls)
    info = bound.accuracy
    # the wall time of the stage on the clock: within 10 % of the budget, and most of it used
    assert info["wall_s"] == pytest.approx(clock.now)
    assert 0.5 * budget <= clock.now <= 1.1 * budget
    # pilots first: at a third of the budget every point has its first answer, and the refinements were cut
    assert info["n_cut"] >= 1 and info["n_escalated"] == len(esc["esc_grid_index"])
    with xr.open_dataset(out) as ds:
        assert float(ds.attrs["accuracy_wall_s"]) <= 1.1 * budget
        assert int(ds.attrs["accuracy_n_cut_by_budget"]) == info["n_cut"]
        assert ds["esc_transition"].values[0] == 1                 # the first point to run decides a curve
        got = dict(zip(ds["esc_grid_index"].values.tolist(), ds["esc_samples"].values.tolist()))
    # the runs that were not shortened are the unbounded plan's (what a point runs depends on its own runs)
    full = dict(zip(esc["esc_grid_index"].tolist(), esc["esc_samples"].tolist()))
    assert set(got) <= set(full)
    assert sum(got[i] == full[i] for i in got) >= 1
    assert sum(got.values()) < sum(full.values())
    # the points went in the order: no point started before one earlier in the order had its pilot
    pilots = [j for j, kind, _ in bound_calls if kind == "pilot"]
    assert pilots == sorted(pilots) == list(range(len(pilots)))


def test_transition_points_run_first(unbounded):
    report, _, calls, messages, esc = unbounded
    n = report.accuracy["n_transition"]
    assert 1 <= n < report.accuracy["n_escalated"]                # both kinds in this study
    line = next(m for m in messages if m.startswith("accuracy: Monte Carlo at up to"))
    assert f"the {n} in the transition of a fragility curve first" in line
    # the first n positions of the order are the transition points: their pilots were submitted first
    pilots = [j for j, kind, _ in calls if kind == "pilot"]
    assert pilots[:n] == list(range(n))
    with xr.open_dataset(report.path) as ds:
        flat = ds["esc_grid_index"].values
        assert ds["esc_transition"].values.tolist() == [1] * n + [0] * (flat.size - n)
        p = np.column_stack([ds["p_overturn"].values.reshape(-1), ds["p_exceed"].values.reshape(ds["status"].size, -1)])
        s0_axis = list(ds["status"].dims).index("S0")
        shape = ds["status"].shape
    # each transition point is in a curve that Monte Carlo (or the linearization) shows rising through the band
    first = flat[:n]
    grid = np.unravel_index(first, shape)
    for k in range(n):
        line_index = [grid[a][k] if a != s0_axis else slice(None) for a in range(len(shape))]
        curve = p.reshape(shape + (-1,))[tuple(line_index)]
        assert np.nanmin(curve) < escalation.TRANSITION_BAND[1] and np.nanmax(curve) > escalation.TRANSITION_BAND[0]


def test_the_run_says_before_any_monte_carlo_when_the_pilots_cannot_fit(one_worker, tmp_path, monkeypatch):
    messages, order = [], []
    real = _submit.submit_escalation
    monkeypatch.setattr(_submit, "submit_escalation", lambda *a, **k: order.append(len(messages)) or real(*a, **k))
    report = run_sweep(budget_study(0.01), tmp_path / "a.nc", client=one_worker, progress=False,
                       log=messages.append)
    said = [i for i, m in enumerate(messages) if "cannot hold even the pilots" in m]
    assert len(said) == 1 and "\n" not in messages[said[0]]
    assert "give [accuracy] budget_s >= " in messages[said[0]]
    need = float(messages[said[0]].split("budget_s >= ")[1].split()[0])
    assert need > 0.01
    assert not order or said[0] < order[0]                       # before any Monte Carlo
    assert report.accuracy["n_escalated"] == 0 and report.accuracy["n_cut"] >= 1
    with xr.open_dataset(tmp_path / "a.nc") as ds:                # still a complete result, saying so
        assert ds.sizes["escalation"] == 0 and "cut short by the budget" in ds.attrs["accuracy_note"]


def test_an_interim_result_and_the_record_after_each_run(one_worker, tmp_path, monkeypatch):
    from screening.io.store import PartialStore

    study = budget_study(600000)
    monkeypatch.setattr(accuracy, "INTERIM_INTERVAL_S", 0.0)
    clock = FakeClock()
    real_save = PartialStore.save_spot
    saved, calls = [], []

    def killed_after_three_runs(self, i, index, result):
        real_save(self, i, index, result)
        if i >= accuracy.ESCALATION_RECORD:
            saved.append(i)
            if len(saved) == 3:
                raise KeyboardInterrupt

    out = tmp_path / "a.nc"
    with monkeypatch.context() as m:
        m.setattr(PartialStore, "save_spot", killed_after_three_runs)
        with pytest.raises(KeyboardInterrupt):
            run_with_clock(monkeypatch, study, out, one_worker, clock, calls=calls)
    # the interim result of the first two runs is a complete, valid file at ``out``, saying what it is
    with xr.open_dataset(out) as ds:
        assert "interim_result" in ds.attrs and "accuracy_note" in ds.attrs
        assert 1 <= ds.sizes["escalation"] <= 2
        assert np.all(np.isfinite(ds["esc_peak_var_theta"].values))
        assert ds["best_method"].shape == ds["status"].shape and "p_source" in ds
    from screening.io.reader import verify_result

    assert "interim" in verify_result(out, study)
    first = [(j, kind) for j, kind, _ in calls]
    # resumed: no run that was kept runs again, and the final result replaces the interim one
    calls.clear()
    report = run_with_clock(monkeypatch, study, out, one_worker, FakeClock(), calls=calls)
    assert not set(first[:3]) & {(j, kind) for j, kind, _ in calls}
    with xr.open_dataset(out) as ds:
        assert "interim_result" not in ds.attrs
        assert ds.sizes["escalation"] == report.accuracy["n_escalated"] >= 2


@pytest.mark.parametrize("value", ["0", "-5", "nan"])
def test_a_budget_that_is_not_positive_is_one_line_and_exit_2(tmp_path, capsys, value):
    from screening.cli import main

    (tmp_path / "s.toml").write_text(BUDGET.replace("BUDGET_S", value))
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "r.nc")]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert "accuracy.budget_s" in line and "> 0" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]        # before any work
