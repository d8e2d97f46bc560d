"""Robustness (issue 6): stiff points, batch and worker independence, Monte Carlo at the edges,
bad input on the command line, and faults (killed worker, killed run, disk full, permissions).

The extremes of the core (item 1: coefficients and solver over the whole parameter ranges,
analytic limits) are property-tested in ``test_core_extremes.py``.
"""

import contextlib
import errno
import os
import resource
import shutil
import signal
import socket
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from helpers import GRID, NO_HTTP_PORT_8787, compare_files, one_line_error, quiet, study_text

from screening.sweep import execution
from screening.cli import main
from screening.core.model.excitation import ConstantEnvelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.condensation.paper import coefficient_constants
from screening.solvers.moments import DEFAULT_MAX_STEPS, HISTORY_VARIABLES, solve_moments
from screening.core.status import PointStatus
from screening.core.model import Block, Foundation
from screening.solvers.montecarlo import monte_carlo
from screening.sweep.study import build_models, parse_study
from screening.io.errors import SweepError
from screening.io.reader import open_result
from screening.io.store import PartialStore
from screening.sweep.run import run_sweep
from screening.sweep import run as sweep_run
from screening.solvers.timegrid import output_times

SCREENING = Path(sys.executable).parent / "screening"
#: Test clusters keep off the default HTTP port, so that `screening run` processes never find it taken.
PAPER = Block(8.67, 0.035, 0.21)
SLENDER = Block(8.67, 0.035, 1.75)          # b/h = 0.02
SQUAT = Block(8.67, 0.175, 0.035)           # b/h = 5
LIGHT_WIDE = Block(0.1, 2.0, 0.4)           # b/h = 5, 0.1 kg on a 4 m base
HEAVY_WIDE = Block(1e4, 2.0, 0.4)


#: A grid over the corners of the ranges: every status but non_finite_moments occurs (with the paper's
#: condensation: the default refuses the softest of these beds before any work).
EXTREME = study_text({"title": '"extreme corners"', "k": "[1e4, 2.89e7, 1e10]", "lam": "[0.0, 1e11]",
                      "eps": "[-1e7, 0.0, 1e9]", "S0": "[1e-12, 2.4e-3, 1e8]", "dt": "0.1",
                      "foundation.condensation": '"paper"'},
                     "[solver]\nmax_steps = 20000\n")


def listing(folder):
    """Every path below ``folder`` (relative), to check that nothing was written."""
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob("*"))


@pytest.fixture(scope="module")
def reference(client, tmp_path_factory):
    """The uninterrupted result of GRID (batch size 3: 7 batches)."""
    out = tmp_path_factory.mktemp("reference") / "grid.nc"
    run_sweep(parse_study(GRID), out, client=client, batch_size=3, progress=False, log=quiet)
    return out


@pytest.fixture
def cli_on_client(client, monkeypatch):
    """Make ``screening run`` use the in-process cluster instead of starting worker processes."""
    @contextlib.contextmanager
    def local(workers=2, scheduler=None, given=None, cluster=None, log=None):
        yield client

    monkeypatch.setattr(execution, "dask_client", local)
    return client


# ============================================================================ 2. solver: stiff points
STIFF = [
    # name, block, foundation, excitation, expected status (the idealized inputs: the budget and the step bound
    # are the solver's; the 25-Hz band's extra states cost 10-25x more steps, docs/models.md)
    ("paper_k1e10_lam1e11_white", PAPER, Foundation(1e10, 1e11), WhiteNoise(1e-4, band_limit_hz=None), PointStatus.ok),
    ("paper_k1e10_lam1e11_kt", PAPER, Foundation(1e10, 1e11), KanaiTajimi(1e-4, 200.0, 0.01, band_limit_hz=None),
     PointStatus.ok),
    ("heavy_wide_k1e10_lam1e11", HEAVY_WIDE, Foundation(1e10, 1e11), WhiteNoise(1e-4, band_limit_hz=None),
     PointStatus.ok),
    ("slender_k1e10_lam1e11", SLENDER, Foundation(1e10, 1e11, 1e9), WhiteNoise(1e-4, band_limit_hz=None),
     PointStatus.ok),
    ("squat_k1e4_lam1e11", SQUAT, Foundation(1e4, 1e11), WhiteNoise(1e-4, band_limit_hz=None),
     PointStatus.step_budget_exhausted),
    ("light_wide_k1e10_lam1e11_kt", LIGHT_WIDE, Foundation(1e10, 1e11),
     KanaiTajimi(1e-4, 200.0, 0.01, band_limit_hz=None),
     PointStatus.step_budget_exhausted),
    ("squat_winkler_k1e4_c1e7", SQUAT, Foundation(k=1e4, c=1e7), WhiteNoise(1e-4, band_limit_hz=None),
     PointStatus.step_budget_exhausted),
]


@pytest.mark.parametrize("name, block, foundation, excitation, expected", STIFF, ids=[s[0] for s in STIFF])
def test_stiff_points_finish_or_flag_with_bounded_work(name, block, foundation, excitation, expected):
    """Large k and lam: integrated to the end or stopped by the step budget (status 3) -- the work
    per point is bounded by max_steps (about 0.15 s at the default 200,000), and the step never
    collapses below the explicit stability bound of the no-uplift oscillator."""
    t = output_times(20.0, 0.05)
    solve_moments(PAPER, Foundation(2.89e7, 8.95e8), excitation, t[:3])      # compiled code loaded (its state size)
    start = time.perf_counter()
    res = solve_moments(block, foundation, excitation, t)
    elapsed = time.perf_counter() - start
    status, stop, n_steps = int(res["status"]), float(res["t_stop"]), int(res["n_steps"])
    assert status == expected
    assert n_steps <= DEFAULT_MAX_STEPS and elapsed < 3.0
    done = t <= stop
    assert np.all(np.isfinite(res["var_theta"][done])) and np.all(np.isnan(res["var_theta"][~done]))
    assert np.isfinite(res["peak_var_theta"]) and np.isfinite(res["min_k_eq"])
    if status == PointStatus.ok:
        assert stop == 20.0 and n_steps < 50_000
    else:
        assert n_steps == DEFAULT_MAX_STEPS and stop < 20.0
    # no step collapse: the mean accepted step is near the stability bound ~3.3 / (spectral radius)
    const = coefficient_constants(block, foundation)
    M = block.m_sdof
    radius = 2.0 * max(const["C1"] / M, np.sqrt(abs(const["K0"] - const["mgh"] + 0.5 * foundation.eps * const["E0"]) / M))
    accepted = n_steps - int(res["n_rejected"])
    assert accepted > 0 and stop / accepted > 0.2 * 3.3 / radius
    assert int(res["n_rejected"]) < 0.2 * n_steps


def test_step_budget_is_reported_in_the_result_file(client, tmp_path):
    """A stiff point in a sweep: its status, t_stop and work (n_steps, n_rejected) are in the file."""
    study = parse_study(GRID.replace("b = 0.035\nh = 0.21", "b = 0.175\nh = 0.035")      # squat, b/h = 5
                        .replace("k = 2.89e7", "k = 1e4").replace("lam = 8.95e8", "lam = 1e11")
                        .replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = [0.0, 1e5, 3e7, 6e7]")
                        .replace("[time]", "[solver]\nmax_steps = 5000\n[time]"))
    out = tmp_path / "stiff.nc"
    report = run_sweep(study, out, client=client, progress=False, log=quiet)
    assert report.status_counts == {"step_budget_exhausted": 20}
    with xr.open_dataset(out) as ds:
        budget = ds["status"].values == PointStatus.step_budget_exhausted
        assert budget.all()
        assert np.all(ds["n_steps"].values[budget] == 5000)
        assert np.all((ds["n_rejected"].values >= 0) & (ds["n_rejected"].values < ds["n_steps"].values))
        assert np.all(ds["t_stop"].values[budget] < 4.0)
        assert int(ds.attrs["max_steps"]) == 5000
        assert "step_budget_exhausted" in ds["status"].attrs["flag_meanings"].split()


# ============================================================================ 2. alone = batch = any workers
def _extreme_batch(kind):
    """Eight points of different kinds (ok, flagged at once or later, over the slenderness, budget,
    non-finite), as arrays for one batched call."""
    pts = [  # (m, b, h, k, lam, eps, S0)
        (8.67, 0.035, 0.21, 2.89e7, 8.95e8, 6e7, 2.4e-3),     # ok
        (8.67, 0.035, 0.21, 1e4, 8.95e8, 0.0, 1e-4),          # k_eq < 0 at the start
        (8.67, 0.035, 1.75, 2.89e7, 0.0, 0.0, 1e-4),          # k_eq reaches 0 later
        (8.67, 0.035, 0.21, 2.89e7, 0.0, 6e7, 1e8),           # sigma beyond the slenderness
        (8.67, 0.175, 0.035, 1e4, 1e11, 0.0, 1e-4),           # step budget
        (8.67, 0.035, 0.21, 1e10, 0.0, -1e7, 1e150),          # non-finite moments (absurd intensity)
        (8.67, 0.035, 0.21, 1e10, 1e11, 1e9, 1e-12),          # stiff, tiny input
        (1e4, 2.0, 0.4, 1e10, 1e11, 0.0, 1e-4),               # heavy and wide, stiff
    ]
    m, b, h, k, lam, eps, S0 = (np.array(col) for col in zip(*pts))
    if kind == "white":
        exc = lambda sel: WhiteNoise(S0[sel], band_limit_hz=None)
    else:
        wg = np.geomspace(0.5, 200.0, len(pts))
        zg = np.geomspace(0.01, 2.0, len(pts))[::-1]
        exc = lambda sel: KanaiTajimi(S0[sel], wg[sel], zg[sel], band_limit_hz=None)
    return lambda sel: (Block(m[sel], b[sel], h[sel]), Foundation(k[sel], lam[sel], eps[sel]), exc(sel)), len(pts)


@pytest.mark.parametrize("kind", ["white", "kanai_tajimi"])
def test_extreme_points_alone_equal_their_row_in_a_batch(kind):
    make, n = _extreme_batch(kind)
    t = output_times(20.0, 0.5)
    batch = solve_moments(*make(slice(None)), t, max_steps=20_000, condensation="paper")   # its statuses
    if kind == "white":
        assert set(batch["status"].tolist()) == {0, 1, 2, 3, 4}
    for i in range(n):
        alone = solve_moments(*make(slice(i, i + 1)), t, max_steps=20_000, condensation="paper")
        for key, value in alone.items():
            np.testing.assert_array_equal(batch[key][i], value[0], err_msg=f"{key} of point {i}")
    reverse = solve_moments(*make(slice(None, None, -1)), t, max_steps=20_000,       # order does not matter
                            condensation="paper")
    for key, value in batch.items():
        np.testing.assert_array_equal(reverse[key][::-1], value, err_msg=key)


def test_sweep_file_is_the_same_on_1_or_2_workers_and_any_batching(client, one_worker, tmp_path):
    study = parse_study(EXTREME)
    runs = [(one_worker, None), (client, 1), (client, 7), (one_worker, 54)]
    paths = []
    for i, (c, size) in enumerate(runs):
        out = tmp_path / f"run{i}.nc"
        report = run_sweep(study, out, client=c, batch_size=size, progress=False, log=quiet)
        assert report.n_failed_batches == 0
        paths.append(out)
    assert set(report.status_counts) >= {"ok", "k_eq_negative", "sigma_theta_beyond_slenderness",
                                         "step_budget_exhausted"}
    for p in paths[1:]:
        compare_files(paths[0], p)
    # and the file holds exactly what one direct batched call over the whole grid gives
    grid = np.meshgrid(*(study.sweeps[d] for d in study.dims), indexing="ij")
    direct = solve_moments(*build_models(study.cases[0], dict(zip(study.dims, grid))), study.times,
                           max_steps=20000, condensation=study.cases[0].condensation_model)
    with xr.open_dataset(paths[0]) as ds:
        for name in HISTORY_VARIABLES:
            np.testing.assert_array_equal(ds[name].values, direct[name].astype(np.float32), err_msg=name)
        for name in ("status", "t_stop", "n_steps", "n_rejected", "peak_var_theta", "min_k_eq"):
            np.testing.assert_array_equal(ds[name].values, direct[name], err_msg=name)


@pytest.mark.slow
def test_sweep_file_is_the_same_on_1_or_2_worker_processes(client, tmp_path):
    """Local clusters of worker processes (what `screening run` starts) vs the in-process one."""
    study = parse_study(EXTREME)
    run_sweep(study, tmp_path / "threads.nc", client=client, batch_size=5, progress=False, log=quiet)
    for workers in (1, 2):
        report = run_sweep(study, tmp_path / f"p{workers}.nc", workers=workers, batch_size=5, progress=False,
                           log=quiet)
        assert report.n_workers == workers
        compare_files(tmp_path / "threads.nc", tmp_path / f"p{workers}.nc")


# ============================================================================ 3. Monte Carlo at the edges
MC_CORNERS = [
    ("stiff_damped", PAPER, Foundation(1e10, 1e11, 0.0)),
    ("stiff_hardening_undamped", SQUAT, Foundation(1e10, 0.0, 1e9)),
    ("soft_heavily_damped", PAPER, Foundation(1e5, 1e11, 0.0)),
    ("slender_undamped", SLENDER, Foundation(2.89e7, 0.0, 0.0)),
    ("winkler_stiff", SQUAT, Foundation(k=1e10, c=0.0, eps=0.0)),
    ("softening", PAPER, Foundation(2.89e7, 8.95e8, -6e5)),
]


@pytest.mark.parametrize("model", ["condensed", "coupled"])
@pytest.mark.parametrize("name, block, foundation", MC_CORNERS, ids=[c[0] for c in MC_CORNERS])
@pytest.mark.parametrize("S0", [1e-12, 1e-2, 0.5])
def test_monte_carlo_at_the_corners_counts_samples_and_never_crashes(name, block, foundation, model, S0):
    n = 3
    ds = monte_carlo(block, foundation, WhiteNoise(S0, ConstantEnvelope()), n_samples=n, model=model, t_end=1.0,
                     dt=0.05, seed=1, progress=False, max_steps=20_000, chunk_size=n)
    n_over, n_div, n_used = int(ds.n_overturned), int(ds.n_diverged), int(ds.n_used)
    assert n_over + n_div + n_used == n
    over, div = ds.overturned.values, ds.diverged.values
    assert int(over.sum()) == n_over and int(div.sum()) == n_div and not np.any(over & div)
    assert np.all(np.isfinite(ds.peak_abs_theta))
    assert np.all(ds.peak_abs_theta.values[over] > block.slenderness)
    if n_used >= 2:
        assert ds.attrs["status"] == "ok"
        assert np.all(np.isfinite(ds.var_theta.values)) and np.all(ds.var_theta.values >= 0)
    else:
        assert ds.attrs["status"] != "ok" and np.all(np.isnan(ds.var_theta.values))
        if n_over == n:
            assert ds.attrs["status"] == "all samples overturned"
        elif n_div == n:
            assert ds.attrs["status"] == "all samples diverged"
    assert (ds.attrs["diverged_reasons"] == "none") == (n_div == 0)


ALL_OVERTURN = study_text({"title": None, "eps": "6e7", "excitation.envelope": '"constant"', "S0": "[1e-5, 0.5]"},
                          '[mcs]\npoints = [{S0 = 0.5}, {S0 = 1e-5}]\nsamples = 4\nmodel = "condensed"\n')


@pytest.fixture(scope="module")
def all_overturned(client, tmp_path_factory):
    out = tmp_path_factory.mktemp("mcs") / "over.nc"
    report = run_sweep(parse_study(ALL_OVERTURN), out, client=client, progress=False, log=quiet)
    assert report.n_spots == 2
    return out


def test_spot_check_with_every_sample_overturning_is_recorded_not_fatal(all_overturned, capsys):
    with xr.open_dataset(all_overturned) as ds:
        np.testing.assert_array_equal(ds["mcs_n_overturned"].values, [4, 0])
        np.testing.assert_array_equal(ds["mcs_n_used"].values, [0, 4])
        np.testing.assert_array_equal(ds["mcs_n_diverged"].values, [0, 0])
        np.testing.assert_array_equal(ds["mcs_status"].values, [0, 0])          # the check itself ran
        np.testing.assert_array_equal(ds["mcs_sample_state"].values, [[1] * 4, [0] * 4])
        assert np.all(np.isnan(ds["mcs_var_theta"].values[0]))
        assert np.isnan(ds["mcs_rel_error_peak_var_theta"].values[0])
        assert np.all(ds["mcs_peak_abs_theta"].values[0] > np.arctan2(0.035, 0.21))
        assert np.all(np.isfinite(ds["mcs_var_theta"].values[1])) and np.isfinite(ds["mcs_rel_error_peak_var_theta"][1])
        assert ds["status"].values[1] != PointStatus.ok                             # the linearization topples too
    assert main(["info", str(all_overturned)]) == 0
    spot_line = [line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("S0=0.5")]
    assert len(spot_line) == 1 and "all 4 samples overturned" in spot_line[0]


def test_info_says_plainly_that_every_spot_sample_overturned(all_overturned, capsys):
    assert main(["info", str(all_overturned)]) == 0
    spot_line = [line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("S0=0.5")][0]
    assert "all 4 samples overturned" in spot_line and "nan" not in spot_line


# ============================================================================ 4. bad input on the CLI
STUDY = study_text({"title": '"bad input"', "eps": "[-6e5, 6e7]", "kind": '"kanai_tajimi"',
                    "excitation.omega_g": "10.0", "excitation.zeta_g": "0.4",
                    "S0": "{start = 2e-5, stop = 2.4e-3, num = 3, log = true}", "excitation.T1": "4.0",
                    "excitation.T2": "2.0", "t_end": "2.0"},
                   "[solver]\nrtol = 1e-7\nmax_steps = 200000\n[mcs]\nsamples = 4\n")

BAD_STUDIES = [
    # id, (old, new), what the message must name
    ("zero mass", ("m = 8.67", "m = 0.0"), "block.m: must be a finite number > 0"),
    ("negative h", ("h = 0.21", "h = -0.21"), "block.h: must be a finite number >= 1e-06 and <= 1000"),
    ("zero k", ("k = 2.89e7", "k = 0"), "foundation.k: must be a finite number > 0"),
    ("negative k", ("k = 2.89e7", "k = -1.0"), "foundation.k: must be a finite number > 0"),
    ("nan k", ("k = 2.89e7", "k = nan"), "foundation.k"),
    ("inf lam", ("lam = 8.95e8", "lam = inf"), "foundation.lam"),
    ("negative lam", ("lam = 8.95e8", "lam = -1.0"), "foundation.lam: must be a finite number >= 0"),
    ("-inf in a list", ("eps = [-6e5, 6e7]", "eps = [-6e5, -inf]"), "foundation.eps[1]"),
    ("nan in a range", ("start = 2e-5", "start = nan"), "excitation.S0.start"),
    ("zero S0", ("S0 = {start = 2e-5, stop = 2.4e-3, num = 3, log = true}", "S0 = 0.0"), "excitation.S0"),
    ("zero zeta_g", ("zeta_g = 0.4", "zeta_g = 0.0"), "excitation.zeta_g"),
    ("negative omega_g", ("omega_g = 10.0", "omega_g = -10.0"), "excitation.omega_g"),
    ("inf omega_g", ("omega_g = 10.0", "omega_g = inf"), "excitation.omega_g"),
    ("string for a number", ("m = 8.67", 'm = "8.67"'), "block.m: must be a number (got the string '8.67')"),
    ("string in a list", ("eps = [-6e5, 6e7]", 'eps = [-6e5, "6e7"]'), "foundation.eps[1]: must be a number"),
    ("string for num", ("num = 3", 'num = "3"'), "excitation.S0.num"),
    ("boolean for a number", ("b = 0.035", "b = true"), "block.b: must be a number"),
    ("T2 = T1", ("T2 = 2.0", "T2 = 4.0"), "excitation.T2: must be smaller than excitation.T1"),
    ("T2 > T1", ("T2 = 2.0", "T2 = 9.0"), "excitation.T2: must be smaller than excitation.T1"),
    ("unknown key", ("h = 0.21", "h = 0.21\ncolour = 1"), "block.colour: unknown key"),
    ("unknown table", ("[time]", "[outputs]\nformat = 1\n[time]"), "outputs: unknown key"),
    ("unknown range key", ("num = 3", "number = 3"), "excitation.S0.number: unknown key"),
    ("unknown solver key", ("rtol = 1e-7", "tol = 1e-7"), "solver.tol: unknown key"),
    ("empty list", ("eps = [-6e5, 6e7]", "eps = []"), "foundation.eps: empty list"),
    ("range num = 0", ("num = 3", "num = 0"), "excitation.S0.num: must be an integer >= 1"),
    ("range num < 0", ("num = 3", "num = -2"), "excitation.S0.num: must be an integer >= 1"),
    ("zero dt", ("dt = 0.05", "dt = 0.0"), "time.dt"),
    ("nan t_end", ("t_end = 2.0", "t_end = nan"), "time.t_end"),
    ("nan rtol", ("rtol = 1e-7", "rtol = nan"), "solver.rtol"),
    ("zero max_steps", ("max_steps = 200000", "max_steps = 0"), "solver.max_steps"),
    ("zero samples", ("samples = 4", "samples = 0"), "mcs.samples"),
    ("TOML syntax", ("[block]", "[block"), "invalid TOML"),
]


@pytest.mark.parametrize("old_new, needle", [b[1:] for b in BAD_STUDIES], ids=[b[0] for b in BAD_STUDIES])
def test_bad_study_values_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, monkeypatch, old_new, needle):
    assert old_new[0] in STUDY
    study = tmp_path / "bad.toml"
    study.write_text(STUDY.replace(*old_new, 1))
    before = listing(tmp_path)
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--quiet"]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert needle in line and str(study) in line
    monkeypatch.chdir(tmp_path)                        # default output place: no outputs/ folder either
    assert main(["run", "bad.toml", "--quiet"]) == 2
    assert needle in one_line_error(capsys.readouterr().err)
    assert listing(tmp_path) == before


@pytest.fixture(scope="module")
def result_file(client, tmp_path_factory):
    """A small valid result (2 x 3 points with a spot check), in a folder of its own."""
    out = tmp_path_factory.mktemp("result") / "res.nc"
    run_sweep(parse_study(STUDY.replace("samples = 4", "samples = 4\ncount = 1\nmodel = \"condensed\"")),
              out, client=client, progress=False, log=quiet)
    return out


def _bad_arguments(tmp, result):
    study = tmp / "ok.toml"
    study.write_text(STUDY)
    (tmp / "latin1.toml").write_bytes(STUDY.replace("bad input", "b\xe9d").encode("latin-1"))
    (tmp / "a_file").write_text("x")
    return [
        (["run", str(study), "--workers", "-1"], "--workers"),
        (["run", str(study), "--workers", "two"], "--workers"),
        (["run", str(study), "--workers", "1.5"], "--workers"),
        (["run", str(study), "--batch-size", "0"], "--batch-size"),
        (["run", str(study), "--batch-size", "nan"], "--batch-size"),
        (["run", str(study), "--complevel", "10"], "--complevel"),
        (["run", str(study), "--complevel", "-1"], "--complevel"),
        (["run", str(study), "--out", str(tmp / "missing" / "r.nc")], "output folder"),
        (["run", str(study), "--out", str(tmp)], "is a directory"),
        (["run", str(tmp / "absent.toml")], "cannot read the study file"),
        (["run", str(tmp)], "cannot read the study file"),
        (["run", str(tmp / "latin1.toml")], "cannot read the study file"),
        (["plot", str(result), "--out-dir", str(tmp / "missing" / "deeper")], "output folder"),   # parent missing
        (["plot", str(result), "--out-dir", str(tmp / "a_file")], "output folder"),
        (["fragility", str(result), "--threshold", "0"], "--threshold"),
        (["fragility", str(result), "--threshold", "inf"], "--threshold"),
        (["fragility", str(result), "--threshold", "1e-3", "--out", str(tmp / "missing" / "f.nc")], "does not exist"),
        (["fragility", str(result), "--threshold", "1e-3", "--out", str(tmp)], "is a directory"),
        (["fragility", str(result), "--threshold", "1e-3", "--dim", "S"], "--dim"),
        (["info"], "required"),
        (["info", str(result), "--verbose"], "unrecognized arguments"),
    ]


def test_bad_command_line_arguments_exit_2_with_one_line_and_write_nothing(tmp_path, result_file, capsys,
                                                                            monkeypatch):
    monkeypatch.chdir(tmp_path)
    cases = _bad_arguments(tmp_path, result_file)
    before, before_result = listing(tmp_path), listing(result_file.parent)
    for argv, needle in cases:
        assert main(argv) == 2, argv
        assert needle in one_line_error(capsys.readouterr().err), argv
    assert listing(tmp_path) == before and listing(result_file.parent) == before_result


def _unreadable_results(folder, good):
    """Result files that cannot be used, by kind: {name: (path, what the message says)}."""
    data = good.read_bytes()
    made = {
        "absent": (folder / "absent.nc", "no such result file"),
        "directory": (folder / "dir.nc", "no such result file"),
        "empty": (folder / "empty.nc", "cannot read the result file"),
        "text": (folder / "text.nc", "cannot read the result file"),
        "hdf5 signature + garbage": (folder / "garbage.nc", "cannot read the result file"),
        "truncated to half": (folder / "half.nc", "cannot read the result file"),
        "truncated to its first 4 kB": (folder / "head.nc", "cannot read the result file"),
        "foreign netCDF": (folder / "foreign.nc", "not a screening sweep result"),
    }
    made["directory"][0].mkdir()
    made["empty"][0].write_bytes(b"")
    made["text"][0].write_text("time,var_theta\n0,0\n")
    made["hdf5 signature + garbage"][0].write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8)
    made["truncated to half"][0].write_bytes(data[: len(data) // 2])
    made["truncated to its first 4 kB"][0].write_bytes(data[:4096])
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(made["foreign netCDF"][0])
    return made


@pytest.mark.parametrize("command", [["info"], ["plot"], ["fragility", "--threshold", "0.1"]],
                         ids=["info", "plot", "fragility"])
def test_unreadable_result_files_exit_2_with_one_line_and_write_nothing(tmp_path, result_file, capsys, command):
    bad = _unreadable_results(tmp_path, result_file)
    before = listing(tmp_path)
    for kind, (path, needle) in bad.items():
        assert main([command[0], str(path), *command[1:]]) == 2, kind
        line = one_line_error(capsys.readouterr().err)
        assert needle in line and str(path) in line, kind
    assert listing(tmp_path) == before                      # no PNG, no fragility file, nothing


@pytest.mark.slow
def test_run_output_stays_clean_when_the_default_dask_port_is_taken(tmp_path):
    """Another dask cluster (or another run) holds port 8787: `screening run` must not print
    distributed's multi-line 'Port 8787 is already in use' warning on stderr."""
    study = tmp_path / "tiny.toml"
    study.write_text(GRID.replace("num = 5", "num = 2"))
    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        holder.bind(("0.0.0.0", 8787))
        holder.listen(1)
    except OSError:
        pass                                        # taken already: the situation under test anyway
    try:
        proc = subprocess.run([str(SCREENING), "run", str(study), "--out", str(tmp_path / "tiny.nc"), "--workers", "1",
                               "--no-plots", "--quiet"], capture_output=True, text=True, timeout=300)
    finally:
        holder.close()
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"wrote {tmp_path / 'tiny.nc'}: 8 points"), proc.stderr


def test_console_script_errors_have_no_library_noise_on_stderr(tmp_path, result_file):
    """The real process: exit 2 and one stderr line, no HDF5 diagnostics from C or warnings."""
    bad = _unreadable_results(tmp_path, result_file)
    for argv in (["info", str(bad["truncated to half"][0])],
                 ["fragility", str(bad["hdf5 signature + garbage"][0]), "--threshold", "0.1"]):
        proc = subprocess.run([str(SCREENING), *argv], capture_output=True, text=True, timeout=120, cwd=tmp_path)
        assert proc.returncode == 2, proc.stderr
        assert "cannot read the result file" in one_line_error(proc.stderr)
        assert proc.stdout == ""


def _corrupt_data(good, path):
    """A result file whose header reads fine but whose compressed data chunks do not: every complete
    zlib stream in the file (HDF5 stores each deflated chunk as one) gets its deflate data damaged."""
    data = bytearray(good.read_bytes())
    damaged, start = 0, 0
    while (off := data.find(b"\x78\x01", start)) >= 0:              # zlib header of level 1
        stream = zlib.decompressobj()
        try:
            stream.decompress(bytes(data[off:off + (1 << 22)]))
            complete = stream.eof                                    # adler-32 checked: a real chunk
        except zlib.error:
            complete = False
        if not complete:
            start = off + 1
            continue
        end = off + len(data[off:off + (1 << 22)]) - len(stream.unused_data)
        for i in range(off + 2, end - 4):
            data[i] ^= 0x5A
        damaged += 1
        start = end
    assert damaged >= 10
    path.write_bytes(bytes(data))
    return path


def test_corrupt_data_chunks_are_a_corrupt_file_not_a_foreign_one(tmp_path, result_file):
    """Precondition of the test below: such a file opens (header intact) but its data cannot be read."""
    path = _corrupt_data(result_file, tmp_path / "chunks.nc")
    with open_result(path) as ds:
        with pytest.raises(RuntimeError, match="NetCDF: HDF error"):
            ds["var_theta"].values
        with pytest.raises(RuntimeError, match="NetCDF: HDF error"):
            ds["status"].values


@pytest.mark.parametrize("command", [["info"], ["plot"], ["fragility", "--threshold", "0.1"]],
                         ids=["info", "plot", "fragility"])
def test_result_with_corrupt_data_chunks_exits_2_with_one_line(tmp_path, result_file, capsys, command):
    path = _corrupt_data(result_file, tmp_path / "chunks.nc")
    before = listing(tmp_path)
    try:
        assert main([command[0], str(path), *command[1:]]) == 2
        assert "chunks.nc" in one_line_error(capsys.readouterr().err)
    finally:
        assert listing(tmp_path) == before


# ============================================================================ 5. faults
def _enospc(path):
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


def test_disk_full_while_saving_a_batch_keeps_earlier_batches_and_resumes(client, reference, tmp_path, monkeypatch):
    study = parse_study(GRID)
    out = tmp_path / "full.nc"
    original, saved = PartialStore.save_batch, []

    def save_until_full(self, batch, result):
        if len(saved) == 2:
            raise _enospc(self.batch_path(batch).with_suffix(".npz.tmp"))
        original(self, batch, result)
        saved.append(batch.index)

    monkeypatch.setattr(PartialStore, "save_batch", save_until_full)
    with pytest.raises(SweepError) as info:
        run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    message = str(info.value)
    assert "\n" not in message and "No space left on device" in message
    assert "the 2 finished batch(es) are kept in" in message and "full.nc.partial" in message and "re-run" in message
    assert not out.exists()
    partial = tmp_path / "full.nc.partial"
    assert sorted(p.name for p in partial.glob("batch-*.npz")) == [f"batch-{i:06d}.npz" for i in sorted(saved)]

    monkeypatch.setattr(PartialStore, "save_batch", original)
    messages = []
    report = run_sweep(study, out, client=client, batch_size=3, progress=False, log=messages.append)
    assert report.n_resumed_batches == 2 and any(m.startswith("resuming: 2 of 7 batches") for m in messages)
    assert not partial.exists()
    compare_files(reference, out)


def test_netcdf_write_error_keeps_the_saved_batches_and_resumes(client, reference, tmp_path, monkeypatch):
    study = parse_study(GRID)
    out = tmp_path / "hdf.nc"
    original, written = sweep_run.write_batch, []

    def write_until_error(result, study, batch, part):
        if len(written) == 3:
            raise RuntimeError("NetCDF: HDF error")
        original(result, study, batch, part)
        written.append(batch.index)

    monkeypatch.setattr(sweep_run, "write_batch", write_until_error)
    with pytest.raises(SweepError, match=r"NetCDF: HDF error; the 4 finished batch\(es\) are kept"):
        run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    assert not out.exists()
    monkeypatch.setattr(sweep_run, "write_batch", original)
    report = run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    assert report.n_resumed_batches == 4
    compare_files(reference, out)


@pytest.mark.parametrize("error", [RuntimeError("not a disk problem"), ConnectionResetError(errno.ECONNRESET, "reset")],
                         ids=["programming error", "network error"])
def test_other_errors_are_not_disguised_as_disk_errors(client, tmp_path, monkeypatch, error):
    def broken(result, study, batch, part):
        raise error

    monkeypatch.setattr(sweep_run, "write_batch", broken)
    with pytest.raises(type(error)):
        run_sweep(parse_study(GRID), tmp_path / "x.nc", client=client, batch_size=3, progress=False, log=quiet)


@pytest.fixture
def read_only(tmp_path_factory):
    """``read_only(folder)`` makes a folder refuse changes to its entries: chmod for an ordinary
    user, ``chattr +i`` for root (which ignores permission bits); skips if neither works here."""
    undo = []

    def probe(folder):
        try:
            (folder / ".probe").touch()
        except OSError:
            return True
        (folder / ".probe").unlink()
        return False

    def make(folder):
        folder = Path(folder)
        folder.chmod(0o555)
        undo.append(lambda: folder.chmod(0o755))
        if probe(folder):
            return
        if shutil.which("chattr") and subprocess.run(["chattr", "+i", str(folder)],
                                                     capture_output=True).returncode == 0:
            undo.append(lambda: subprocess.run(["chattr", "-i", str(folder)], check=True))
            if probe(folder):
                return
        raise RuntimeError(f"cannot make {folder} read-only here")

    def release():
        while undo:
            undo.pop()()

    scratch = tmp_path_factory.mktemp("read-only-probe")
    try:
        make(scratch)
    except RuntimeError:
        release()
        scratch.rmdir()
        pytest.skip("cannot make a folder read-only (root without chattr +i)")
    release()
    scratch.rmdir()
    make.release = release
    yield make
    release()


@pytest.mark.parametrize("which", ["output folder", "partial folder"])
def test_permission_error_mid_run_is_one_line_and_the_run_resumes(client, reference, tmp_path, read_only, which):
    """The output folder (the final rename fails) or the partial folder (the next batch cannot be
    saved) becomes read-only during the run."""
    study = parse_study(GRID)
    folder = tmp_path / "ro"
    folder.mkdir()
    out = folder / "r.nc"
    partial = folder / "r.nc.partial"
    seen = []

    def lock_after_two(batch):
        seen.append(batch.index)
        if len(seen) == 2:
            read_only(folder if which == "output folder" else partial)

    try:
        with pytest.raises(SweepError) as info:
            run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet, on_batch=lock_after_two)
    finally:
        read_only.release()
    message = str(info.value)
    assert "\n" not in message and ("Permission denied" in message or "Operation not permitted" in message)
    kept = 7 if which == "output folder" else 2
    assert f"the {kept} finished batch(es) are kept in {partial}" in message
    assert not out.exists()
    assert len(list(partial.glob("batch-*.npz"))) == kept
    report = run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    assert report.n_resumed_batches == kept
    compare_files(reference, out)


def test_cli_disk_full_exits_2_with_one_line_then_resumes(cli_on_client, reference, tmp_path, capsys, monkeypatch):
    study = tmp_path / "grid.toml"
    study.write_text(GRID)
    out = tmp_path / "grid.nc"
    argv = ["run", str(study), "--out", str(out), "--batch-size", "3", "--no-plots", "--quiet"]
    original, calls = PartialStore.save_batch, []

    def save_until_full(self, batch, result):
        calls.append(batch.index)
        if len(calls) == 4:
            raise _enospc(self.batch_path(batch))
        original(self, batch, result)

    monkeypatch.setattr(PartialStore, "save_batch", save_until_full)
    assert main(argv) == 2
    line = one_line_error(capsys.readouterr().err)
    assert "No space left on device" in line and "re-run the same command to resume" in line
    assert not out.exists() and len(list((tmp_path / "grid.nc.partial").glob("batch-*.npz"))) == 3

    monkeypatch.setattr(PartialStore, "save_batch", original)
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "resuming: 3 of 7 batches were already done" in err and "Traceback" not in err
    compare_files(reference, out, ignore=("study_file", "study_name"))


def test_cli_run_figure_write_failure_keeps_the_complete_result(cli_on_client, reference, tmp_path, capsys,
                                                                 monkeypatch):
    """The sweep finished and its file is in place; the disk fills while the PNGs are written:
    one line saying the result is complete, exit 2, no partial PNG."""
    from screening.report import figures as plots

    study = tmp_path / "grid.toml"
    study.write_text(GRID)
    out = tmp_path / "grid.nc"
    original, calls = plots.save_figure, []

    def full_after_one(fig, path):
        calls.append(path)
        if len(calls) == 2:
            raise _enospc(path)
        return original(fig, path)

    monkeypatch.setattr(plots, "save_figure", full_after_one)
    assert main(["run", str(study), "--out", str(out), "--batch-size", "3", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"wrote {out}: 20 points")                   # the sweep's own report, then
    line = one_line_error(err.split("\n", 1)[1])                       # one line for the failure
    assert "No space left on device" in line and f"the result {out} is complete" in line
    compare_files(reference, out, ignore=("study_file", "study_name"))
    assert sorted(p.name for p in tmp_path.glob("*.png*")) == []       # the first figure was removed too

def test_disk_full_while_saving_a_spot_record_keeps_the_spot_result(client, tmp_path, monkeypatch):
    """The Monte Carlo result is computed; only its resume record cannot be written: the spot
    check is kept in the file (not turned into a failed one) and a warning says what was lost."""
    text = GRID + "[mcs]\npoints = [{eps = 6e7, S0 = 2.4e-3}]\nsamples = 4\nmodel = \"condensed\"\n"
    study = parse_study(text)
    messages = []

    def no_space(self, i, index, result):
        raise _enospc(self.spot_path(i))

    monkeypatch.setattr(PartialStore, "save_spot", no_space)
    run_sweep(study, tmp_path / "s.nc", client=client, progress=False, log=messages.append)
    assert any("cannot save the resume record of spot check 0" in m and "No space left" in m for m in messages)
    monkeypatch.undo()
    run_sweep(study, tmp_path / "ref.nc", client=client, progress=False, log=quiet)
    with xr.open_dataset(tmp_path / "s.nc") as ds, xr.open_dataset(tmp_path / "ref.nc") as ref:
        assert int(ds["mcs_status"].values[0]) == 0
        np.testing.assert_array_equal(ds["mcs_var_theta"].values, ref["mcs_var_theta"].values)

def test_corrupt_part_file_is_recomputed_on_resume(client, reference, tmp_path):
    """A part file damaged while the run was down (e.g. a disk error) is computed again, not trusted."""
    study = parse_study(GRID)
    out = tmp_path / "r.nc"

    def stop_after_three(batch, seen=[]):
        seen.append(batch.index)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet, on_batch=stop_after_three)
    parts = sorted((tmp_path / "r.nc.partial").glob("batch-*.npz"))
    assert len(parts) == 3
    parts[0].write_bytes(parts[0].read_bytes()[:1000])              # truncated
    parts[1].write_bytes(b"PK\x03\x04" + b"\0" * 64)                   # garbage zip
    report = run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    assert report.n_resumed_batches == 1
    compare_files(reference, out)


def _limited_file_size(limit):
    def apply():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


@pytest.mark.slow
@pytest.mark.parametrize("command", ["plot", "fragility"])
def test_write_failure_of_plot_or_fragility_is_one_line_and_leaves_nothing(tmp_path, result_file, command):
    out = tmp_path / "out"
    out.mkdir()
    argv = {"plot": ["plot", str(result_file), "--out-dir", str(out)],
            "fragility": ["fragility", str(result_file), "--threshold", "0.1", "--out", str(out / "f.nc")]}[command]
    proc = subprocess.run([str(SCREENING), *argv], capture_output=True, text=True, timeout=120,
                          preexec_fn=_limited_file_size(2000))
    try:
        assert proc.returncode == 2, proc.stderr[-300:]
        assert "File too large" in one_line_error(proc.stderr) or "HDF error" in proc.stderr
    finally:
        leftovers = [p.name for p in out.iterdir() if p.suffix in (".tmp", ".nc") or p.stat().st_size <= 2000]
        assert leftovers == [], leftovers


BIG = GRID.replace("num = 5", "num = 40").replace("t_end = 4.0", "t_end = 20.0")


@pytest.mark.slow
def test_worker_process_killed_mid_sweep_the_batch_is_retried(tmp_path):
    """SIGKILL one worker process of a local cluster while it computes: the scheduler reruns its
    batches elsewhere (and on the restarted worker); the file equals direct solver calls."""
    from distributed import Client, LocalCluster

    study = parse_study(BIG)
    killed = {}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=50, scheduler_kwargs=NO_HTTP_PORT_8787) as cluster, \
            Client(cluster, set_as_default=False) as c:
        def kill_a_busy_worker(batch):
            if killed:
                return
            busy = {w: list(keys) for w, keys in c.processing().items() if keys}
            if not busy:
                return
            victim = sorted(busy)[0]
            pid = c.run(os.getpid)[victim]
            killed.update(worker=victim, pid=pid, tasks=busy[victim], after=batch.index)
            os.kill(pid, signal.SIGKILL)

        report = run_sweep(study, tmp_path / "r.nc", client=c, batch_size=5, progress=False, log=quiet,
                           on_batch=kill_a_busy_worker)
        assert killed and killed["tasks"], "no worker was busy when the first batch came back"
        assert killed["pid"] not in c.run(os.getpid).values()
    eps, s0 = np.meshgrid(study.sweeps["eps"], study.sweeps["S0"], indexing="ij")
    direct = solve_moments(*build_models(study.cases[0], {"eps": eps, "S0": s0}), study.times)
    codes, counts = np.unique(np.asarray(direct["status"]), return_counts=True)
    assert report.n_failed_batches == 0
    assert report.status_counts == {PointStatus(int(c)).name: int(n) for c, n in zip(codes, counts)}   # as direct calls
    assert report.status_counts.get("ok", 0) >= 0.9 * study.n_points      # the grid is mostly ordinary points
    with xr.open_dataset(tmp_path / "r.nc") as ds:
        for name in HISTORY_VARIABLES:
            np.testing.assert_array_equal(ds[name].values, direct[name].astype(np.float32), err_msg=name)
        for name in ("status", "n_steps", "peak_var_theta"):
            np.testing.assert_array_equal(ds[name].values, direct[name], err_msg=name)


@pytest.mark.slow
@pytest.mark.parametrize("limit, kept, reason", [(300_000, 16, "NetCDF: HDF error"), (50_000, 0, "File too large")],
                         ids=["result_file_too_large", "part_file_too_large"])
def test_real_write_failure_file_size_limit(tmp_path, limit, kept, reason):
    """A real failing write (RLIMIT_FSIZE: writes past the limit fail with EFBIG, like a full disk):
    `screening run` exits 2 with one line, keeps the finished batches, and the re-run resumes to the
    same file as an uninterrupted run."""
    from distributed import Client, LocalCluster

    study_file = tmp_path / "big.toml"
    study_file.write_text(BIG)
    out = tmp_path / "big.nc"
    cmd = [str(SCREENING), "run", str(study_file), "--out", str(out), "--workers", "1", "--batch-size", "10",
           "--no-plots", "--quiet"]

    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, preexec_fn=_limited_file_size(limit))
    assert proc.returncode == 2, proc.stderr
    line = one_line_error(proc.stderr)
    assert reason in line and f"the {kept} finished batch(es) are kept" in line
    assert not out.exists()
    assert len(list((tmp_path / "big.nc.partial").glob("batch-*.npz"))) == kept

    resumed = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert ("resuming: 16 of 16 batches" in resumed.stderr) == (kept == 16)
    reference = tmp_path / "reference.nc"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                      scheduler_kwargs=NO_HTTP_PORT_8787) as cluster, \
            Client(cluster, set_as_default=False) as client:
        run_sweep(parse_study(BIG, name="big", source=str(study_file)), reference, client=client, batch_size=10,
                  progress=False, log=quiet)
    compare_files(reference, out)
