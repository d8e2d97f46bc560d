"""Issue 13, "hold at every edge": each bug's reproducer and a neighbour.

Study-file bounds are checked at parse time: one line naming the key and the allowed range,
exit status 2, nothing written, and no allocation that depends on the size asked for
(``tracemalloc`` sees numpy's buffers: the peak must stay small).
"""

import os
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from helpers import one_line_error, study_text

from screening.cli import main
from screening.core import limits
from screening.sweep.study import StudyError, parse_study

ROOT = Path(__file__).resolve().parents[2]

STUDY = study_text({"title": '"edges"', "eps": "[-6e5, 6e7]",
                    "S0": "{start = 2e-5, stop = 2.4e-3, num = 3, log = true}", "excitation.T1": "4.0",
                    "excitation.T2": "2.0", "t_end": "2.0"}, "[mcs]\nsamples = 4\nseed = 0\n")

R1000 = "{start = 1.0, stop = 2.0, num = 1000}"
#: pins the paper's condensation in a study text (``.replace("[foundation]\n", PAPER_CONDENSATION)``)
PAPER_CONDENSATION = '[foundation]\ncondensation = "paper"\n'

# id, (old, new) replacements, needle of the one-line message
BOUNDS = [
    # B1: 4 ranges x 1000 values (1e12 points) and its neighbour just above the configured limit
    ("B1 grid 1e12 points", [("k = 2.89e7", f"k = {R1000}"), ("lam = 8.95e8", f"lam = {R1000}"),
                              ("eps = [-6e5, 6e7]", f"eps = {R1000}"),
                              ("S0 = {start = 2e-5, stop = 2.4e-3, num = 3, log = true}", f"S0 = {R1000}")],
     "the grid has 1000000000 points"),
    ("B1 neighbour: run.max_points", [("[mcs]", "[run]\nmax_points = 5\n[mcs]")],
     "excitation.S0: the grid has 6 points (eps 2 x S0 3); at most run.max_points = 5"),
    ("B1 max_points above the ceiling", [("[mcs]", "[run]\nmax_points = 1000000000000\n[mcs]")],
     "run.max_points: must be an integer in 1..100000000"),
    # B2
    ("B2 num = 1e9", [("num = 3", "num = 1000000000")], "excitation.S0.num: must be an integer in 1..1000000"),
    ("B2 num = 2**63-1", [("num = 3", f"num = {2**63 - 1}")], "excitation.S0.num: must be an integer in 1..1000000"),
    ("B2 dt = 1e-9", [("dt = 0.05", "dt = 1e-9")], "time.t_end / time.dt: t_end / dt = 2e+09 output steps"),
    ("B2 dt = 5e-324", [("dt = 0.05", "dt = 5e-324")], "output steps; at most 100000"),
    # B3, B10, B8
    ("B3 seed = 2**31", [("seed = 0", "seed = 2147483648")], "mcs.seed: must be an integer in 0..2147483647"),
    ("B3 neighbour seed = 2**64", [("seed = 0", "seed = 18446744073709551616")], "mcs.seed: must be an integer in 0.."),
    ("B10 samples = 1e9", [("samples = 4", "samples = 1000000000")], "mcs.samples: must be an integer in 2.."),
    ("B10 neighbour samples x times", [("samples = 4", "samples = 999999"), ("t_end = 2.0", "t_end = 200.0")],
     "mcs.samples: must be an integer in 2..12496 (at most 50000000 samples x 4001 output instants"),
    ("B8 t_end = 1e6", [("t_end = 2.0", "t_end = 1e6")], "output steps; at most 100000"),
    ("B8 neighbour t_end only", [("t_end = 2.0\ndt = 0.05", "t_end = 1e5")], "time.t_end: t_end / dt = 2e+06"),
    # B16
    # block lengths beyond float64 in the condensation (ZeroDivisionError / OverflowError in every batch)
    ("b = 1e-171", [("b = 0.035", "b = 1e-171")], "block.b: must be a finite number >= 1e-06 and <= 1000 (got 1e-171)"),
    ("b = 1e150", [("b = 0.035", "b = 1e150")], "block.b: must be a finite number >= 1e-06 and <= 1000"),
    ("h = 1e150", [("h = 0.21", "h = 1e150")], "block.h: must be a finite number >= 1e-06 and <= 1000"),
    ("h neighbour just above", [("h = 0.21", "h = 1000.5")], "block.h: must be a finite number >= 1e-06 and <= 1000"),
    ("B16 400-digit integer", [("m = 8.67", "m = " + "9" * 400)], "block.m: must be a finite number > 0 (got inf)"),
    ("B16 neighbour: 400-digit num", [("num = 3", "num = " + "9" * 400)],
     "excitation.S0.num: must be an integer in 1..1000000 (the grid limit run.max_points; got an integer of 400 digits)"),
    ("B16 inline tables 5000 deep", [("[mcs]", "x = " + "{a = " * 5000 + "1" + "}" * 5000 + "\n[mcs]")],
     "invalid TOML: arrays/tables nested 5000 deep"),
    ("B16 neighbour: arrays 5000 deep", [("eps = [-6e5, 6e7]", "eps = " + "[" * 5000 + "]" * 5000)],
     "invalid TOML: arrays/tables nested 5000 deep"),
]


def _listing(folder):
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob("*"))


@pytest.mark.parametrize("edits, needle", [b[1:] for b in BOUNDS], ids=[b[0] for b in BOUNDS])
def test_study_sizes_are_bounded_at_parse_time(tmp_path, capsys, edits, needle):
    text = STUDY
    for old, new in edits:
        assert old in text
        text = text.replace(old, new, 1)
    study = tmp_path / "bad.toml"
    study.write_text(text)
    before = _listing(tmp_path)
    tracemalloc.start()
    try:
        code = main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--quiet"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert code == 2
    line = one_line_error(capsys.readouterr().err)
    assert needle in line and str(study) in line
    assert len(line) < 400
    assert peak < 64 * 2**20                  # no array sized by the request
    assert _listing(tmp_path) == before


def test_limits_leave_ordinary_studies_alone():
    study = parse_study(STUDY.replace("[mcs]", "[run]\nmax_points = 6\n[mcs]"))
    assert study.n_points == 6 and study.mcs.seed == 0
    study = parse_study(STUDY.replace("seed = 0", f"seed = {2**31 - 1}"))
    assert study.mcs.seed == 2**31 - 1
    assert limits.nesting_depth('a = "[[[[" # {{{{\nb = [[1], [2]]') == 2


def test_default_batches_keep_one_task_within_its_memory_budget():
    """B8 neighbour: the longest record allowed gets batches whose histories fit the task budget."""
    from screening.solvers.moments import HISTORY_VARIABLES
    from screening.sweep.grid import default_batch_size

    study = parse_study(STUDY.replace("t_end = 2.0", "t_end = 5000.0")
                        .replace("num = 3", "num = 1000"))     # 100001 instants, 2000 points
    size = default_batch_size(study, 2)
    assert size * len(study.times) * len(HISTORY_VARIABLES) * 8 <= limits.TASK_BYTES
    assert size >= 1
    short = parse_study(STUDY.replace("num = 3", "num = 1000"))
    assert default_batch_size(short, 2) == 500                 # ordinary records: unchanged


@pytest.mark.parametrize("condensation", ["paper", "cubic"])
def test_equivalent_coefficients_keep_nan_moments_nan(condensation):
    """B9: NaN moments gave the finite sigma = 0 coefficients (reproducer: sigma_theta = NaN;
    neighbours: a NaN velocity, NaN inside an array, and the moment form)."""
    from screening.core.condensation.api import equivalent_coefficients, equivalent_coefficients_from_moments
    from screening.core.model import Block, Foundation

    block, bed = Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
    c, k = equivalent_coefficients(np.nan, 1.0, 0.5, block, bed, condensation)
    assert np.isnan(c) and np.isnan(k)
    c, k = equivalent_coefficients(np.array([np.nan, 0.01, 0.0]), 1.0, 0.5, block, bed, condensation)
    assert np.isnan(c[0]) and np.isnan(k[0]) and np.all(np.isfinite(c[1:])) and np.all(np.isfinite(k[1:]))
    c0, k0 = equivalent_coefficients(0.0, 1.0, 0.5, block, bed, condensation)
    assert c[2] == pytest.approx(c0) and k[2] == pytest.approx(k0)
    c, k = equivalent_coefficients(0.01, np.inf, 0.5, block, bed, condensation)
    assert np.isnan(c) and np.isnan(k)
    c, k = equivalent_coefficients_from_moments(np.array([np.nan, 1e-4, 1e-4]), np.array([0.0, np.nan, 0.0]),
                                                block, bed, condensation)
    assert np.isnan(c[:2]).all() and np.isnan(k[:2]).all() and np.isfinite(c[2]) and np.isfinite(k[2])


# ----------------------------------------------------------------------------- output paths, pipes, terminals
@pytest.fixture(scope="module")
def result_file(client, tmp_path_factory):
    """A small valid result (2 x 3 points), in a folder of its own."""
    from helpers import quiet
    from screening.sweep.run import run_sweep

    out = tmp_path_factory.mktemp("result") / "res.nc"
    run_sweep(parse_study(STUDY.replace("[mcs]\nsamples = 4\nseed = 0\n", "")), out, client=client,
              progress=False, log=quiet)
    return out


def _cli(args, cwd, **kw):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "screening.cli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120, **kw)


@pytest.mark.parametrize("spelling", ["same", "dotted", "symlink"])
def test_out_equal_to_the_study_file_is_refused(tmp_path, capsys, spelling):
    """B13: ``--out`` naming the study file (as given, as ./x, through a link) overwrote the study."""
    study = tmp_path / "s.nc"                  # a study named like a result: --out s.nc is plausible
    study.write_text(STUDY)
    out = {"same": study, "dotted": tmp_path / "." / "s.nc", "symlink": tmp_path / "link.nc"}[spelling]
    if spelling == "symlink":
        out.symlink_to(study)
    assert main(["run", str(study), "--out", str(out), "--quiet", "--no-plots"]) == 2
    assert "is the input file" in one_line_error(capsys.readouterr().err)
    assert study.read_text() == STUDY


def test_fragility_out_equal_to_the_result_is_refused(result_file, tmp_path, capsys):
    """B13 neighbour: ``fragility --out`` naming the result it reads."""
    before = result_file.read_bytes()
    assert main(["fragility", str(result_file), "--threshold", "0.01", "--out", str(result_file)]) == 2
    assert "is the input file" in one_line_error(capsys.readouterr().err)
    assert result_file.read_bytes() == before


@pytest.mark.parametrize("command", ["run", "fragility"])
def test_fifo_as_output_is_refused_without_blocking(result_file, tmp_path, capsys, command):
    """B17: a FIFO given as --out hung the run (opening it for writing blocks)."""
    fifo = tmp_path / "out.nc"
    os.mkfifo(fifo)
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    args = (["run", str(study), "--quiet", "--no-plots"] if command == "run"
            else ["fragility", str(result_file), "--threshold", "0.01"]) + ["--out", str(fifo)]
    assert main(args) == 2
    assert "is not a regular file" in one_line_error(capsys.readouterr().err)
    assert fifo.is_fifo()


def test_info_into_a_closed_pipe_is_quiet(result_file):
    """B19: ``screening info R.nc | head -1`` printed a BrokenPipeError traceback."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(f"'{sys.executable}' -m screening.cli info '{result_file}' | head -1",
                          shell=True, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and len(proc.stdout.splitlines()) == 1
    assert proc.stderr == "", proc.stderr
    # neighbour: --help into a closed pipe
    proc = subprocess.run(f"'{sys.executable}' -m screening.cli run --help | head -c 10", shell=True, cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.stderr == "", proc.stderr


def test_info_escapes_terminal_control_characters_of_a_title(result_file, tmp_path, capsys):
    """Control characters in a result's title (and other attributes) are shown escaped by info."""
    import xarray as xr

    forged = tmp_path / "forged.nc"
    with xr.open_dataset(result_file) as ds:
        ds = ds.load()
    ds.attrs["title"] = "nice\x1b[2J\x1b]0;owned\x07\rtitle\x9b"
    ds.attrs["study_text"] = ds.attrs.get("study_text", "") + "\x1b[31m"
    ds.to_netcdf(forged)
    assert main(["info", str(forged)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\r" not in out and "\x9b" not in out
    assert "\\x1b[2J" in out


# ----------------------------------------------------------------------------- the partial store (B11, B12, B14)
def _interrupted(client, study, out, after=2, batch_size=3):
    """Run ``study`` into ``out`` and stop after ``after`` saved batches (the partial folder stays)."""
    from helpers import quiet
    from screening.sweep.run import run_sweep

    def stop(batch, seen=[]):
        seen.append(batch.index)
        if len(seen) == after:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, client=client, batch_size=batch_size, progress=False, log=quiet, on_batch=stop)


@pytest.fixture(scope="module")
def reference_grid(client, tmp_path_factory):
    from helpers import GRID, quiet
    from screening.sweep.run import run_sweep

    out = tmp_path_factory.mktemp("ref") / "ref.nc"
    run_sweep(parse_study(GRID), out, client=client, batch_size=3, progress=False, log=quiet)
    return out


def test_planted_lock_symlink_does_not_truncate_its_target(client, tmp_path, reference_grid):
    """B11: ``<out>.partial/lock`` was opened with open(..., "w"), following a planted link."""
    from helpers import GRID, compare_files, quiet
    from screening.sweep.run import run_sweep

    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    partial = tmp_path / "r.nc.partial"
    partial.mkdir()
    (partial / "lock").symlink_to(victim)
    with pytest.raises(Exception, match="symbolic link"):
        run_sweep(parse_study(GRID), tmp_path / "r.nc", client=client, progress=False, log=quiet)
    assert victim.read_text() == "precious"
    # neighbour: a planted link at the manifest's temporary file is replaced, not followed
    (partial / "lock").unlink()
    (partial / "manifest.json.tmp").symlink_to(victim)
    run_sweep(parse_study(GRID), tmp_path / "r.nc", client=client, batch_size=3, progress=False, log=quiet)
    assert victim.read_text() == "precious"
    compare_files(reference_grid, tmp_path / "r.nc")


@pytest.mark.parametrize("kind", ["symlink", "file"])
def test_partial_folder_that_is_a_link_or_a_file_is_refused(client, tmp_path, capsys, kind):
    """B11 neighbours: a partial folder that is a symbolic link (to a folder elsewhere) or not a folder."""
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    partial = tmp_path / "r.nc.partial"
    if kind == "symlink":
        partial.symlink_to(elsewhere)
    else:
        partial.write_text("x")
    from screening.io.store import PartialStore
    from screening.io.errors import SweepError

    with pytest.raises(SweepError, match="symbolic link" if kind == "symlink" else "not a folder"):
        PartialStore(tmp_path / "r.nc").open("k", {"n_points": 1, "shape": [1], "batch_size": 1}, print)
    assert list(elsewhere.iterdir()) == []


@pytest.mark.skipif(os.geteuid() != 0, reason="needs root to make a folder owned by another user")
def test_partial_folder_of_another_user_is_refused(tmp_path):
    from screening.io.errors import SweepError
    from screening.io.store import PartialStore

    partial = tmp_path / "r.nc.partial"
    partial.mkdir()
    os.chown(partial, 12345, 12345)
    with pytest.raises(SweepError, match="owned by another user"):
        PartialStore(tmp_path / "r.nc").open("k", {"n_points": 1, "shape": [1], "batch_size": 1}, print)


def test_damaged_finished_result_is_recomputed_not_reused(client, tmp_path, reference_grid):
    """B12: a finished result with damaged data chunks was reused as up to date forever."""
    from helpers import GRID, compare_files, quiet
    from test_robustness import _corrupt_data
    from screening.sweep.run import run_sweep

    out = tmp_path / "r.nc"
    _corrupt_data(reference_grid, out)
    lines = []
    report = run_sweep(parse_study(GRID), out, client=client, batch_size=3, progress=False, log=lines.append)
    assert not report.reused and any("computing it again" in line for line in lines)
    compare_files(reference_grid, out)
    # neighbour: the intact file is reused
    report = run_sweep(parse_study(GRID), out, client=client, batch_size=3, progress=False, log=quiet)
    assert report.reused


def test_result_with_the_key_but_another_grid_is_not_reused(client, tmp_path, reference_grid):
    """B12 neighbour: a file carrying the study's key whose grid is not the study's (edited by hand)."""
    import netCDF4
    from helpers import GRID
    from screening.io.reader import verify_result

    other = tmp_path / "other.nc"
    study = parse_study(GRID.replace("num = 5", "num = 4"))
    with netCDF4.Dataset(reference_grid) as src:
        key = src.getncattr("study_sha256")
    assert verify_result(reference_grid, parse_study(GRID)) is None
    assert "dimension 'S0'" in verify_result(reference_grid, study)


def _part_edits():
    def shape(d):
        d["var_theta"] = d["var_theta"][:, :3]

    def missing(d):
        del d["p_uplift"]

    def dtype(d):
        d["status"] = np.array(["x"] * len(d["status"]))

    return {"wrong shape": shape, "missing variable": missing, "wrong dtype": dtype}


@pytest.mark.parametrize("edit", list(_part_edits()))
def test_damaged_part_files_are_recomputed_on_resume(client, tmp_path, reference_grid, edit):
    """B14: part files with the right key but a wrong shape / missing variable / wrong dtype gave a
    traceback on every resume."""
    from helpers import GRID, compare_files, quiet
    from screening.sweep.run import run_sweep

    study, out = parse_study(GRID), tmp_path / "r.nc"
    _interrupted(client, study, out)
    part = sorted((tmp_path / "r.nc.partial").glob("batch-*.npz"))[0]
    with np.load(part) as f:
        data = dict(f)
    _part_edits()[edit](data)
    with open(part, "wb") as fh:
        np.savez(fh, **data)
    report = run_sweep(study, out, client=client, batch_size=3, progress=False, log=quiet)
    assert report.n_resumed_batches == 1
    compare_files(reference_grid, out)


@pytest.mark.parametrize("batch_size", [0, -3, "3", True, None, 10**30])
def test_manifest_with_a_bad_batch_size_starts_again(client, tmp_path, reference_grid, batch_size):
    """B14: a manifest whose key matches but whose batch_size is nonsense gave a traceback on resume."""
    import json
    from helpers import GRID, compare_files, quiet
    from screening.sweep.run import run_sweep

    study, out = parse_study(GRID), tmp_path / "r.nc"
    _interrupted(client, study, out)
    manifest = tmp_path / "r.nc.partial" / "manifest.json"
    m = json.loads(manifest.read_text())
    m["batch_size"] = batch_size
    manifest.write_text(json.dumps(m))
    lines = []
    run_sweep(study, out, client=client, batch_size=3, progress=False, log=lines.append)
    assert any("damaged partial results" in line for line in lines)
    compare_files(reference_grid, out)


def test_huge_batch_size_option_is_one_line(tmp_path, capsys):
    """B14 neighbour: --batch-size 10**30 overflowed int32 when the file was created."""
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--batch-size", str(10**30),
                 "--quiet", "--no-plots"]) == 2
    assert "batch size must be an integer in 1..2147483647" in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "r.nc").exists()


# ----------------------------------------------------------------------------- Ctrl-C (B18)
@pytest.mark.parametrize("moment", ["workers up", "batches saved"])
def test_ctrl_c_prints_one_line_and_no_worker_tracebacks(tmp_path, moment):
    """B18: Ctrl-C (SIGINT to the whole process group, as a terminal sends it) printed the one-line
    message plus the KeyboardInterrupt tracebacks of every worker."""
    import signal
    import time

    study = tmp_path / "long.toml"
    study.write_text(STUDY.replace("num = 3", "num = 400").replace("eps = [-6e5, 6e7]",
                                                                    "eps = [-6e5, 0.0, 3e7, 6e7]"))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "screening.cli", "run", str(study), "--out",
                             str(tmp_path / "r.nc"), "--no-plots", "--quiet", "--batch-size", "20"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 120
    partial = tmp_path / "r.nc.partial"
    while time.monotonic() < deadline and proc.poll() is None:
        if moment == "workers up" and partial.is_dir():      # cluster started, workers warmed up
            break
        if moment == "batches saved" and len(list(partial.glob("batch-*.npz"))) >= 2:
            break
        time.sleep(0.02)
    assert proc.poll() is None, proc.communicate()
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    if proc.returncode == 0:        # seen rarely under load: the run finished first (reported to the lead)
        assert lines[-1].startswith("wrote "), err
        return
    assert proc.returncode == 130, err
    assert lines == ["screening: interrupted; finished batches are kept, re-run the same command to resume"]


LOCAL_WORKERS_PROBE = """
import signal, sys
from screening.sweep import _submit, execution

def probe():
    inherited = "state" in vars(sys.modules["__main__"])     # a forked worker has this script's functions
    return signal.getsignal(signal.SIGINT) == signal.SIG_IGN, inherited

def state():
    method = execution._worker_start_method()
    with execution.dask_client(2) as c:
        probes = list(c.run(probe).values())
        spot = c.submit(_submit.warm_up_monte_carlo, pure=False).result(timeout=120)
    return method, probes, spot > 0

print(state())
_submit.warm_up_monte_carlo()         # numba's parallel threads started in this process
print(state())
"""


def test_local_workers_ignore_ctrl_c_are_forked_while_safe_and_run_monte_carlo():
    """The workers of a local cluster ignore SIGINT (the client stops the run on a Ctrl-C).  On
    Linux they are forked (they start with the client's modules: issue 12) unless the client has
    started numba's parallel threads, which a forked worker could not use: then spawned, and a
    Monte Carlo task still runs on them."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", LOCAL_WORKERS_PROBE], env=env, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    first, second = (eval(line) for line in out.stdout.splitlines())   # noqa: S307 - our own printout
    linux = sys.platform.startswith("linux")
    assert first == ("fork" if linux else "spawn", [(True, linux)] * 2, True)
    assert second == ("spawn", [(True, False)] * 2, True)


def test_worker_start_method_set_for_dask_in_the_environment_is_used(monkeypatch):
    import dask

    from screening.sweep import execution

    monkeypatch.setenv(execution.START_METHOD_VARIABLE, "spawn")
    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}):   # as dask reads it at import
        assert execution._worker_start_method() == "spawn"
    monkeypatch.delenv(execution.START_METHOD_VARIABLE)
    import numba.np.ufunc.parallel as numba_parallel

    expected = "fork" if sys.platform.startswith("linux") and not numba_parallel._is_initialized else "spawn"
    assert execution._worker_start_method() == expected


# ----------------------------------------------------------------------------- readers and figures (B4, B6, B20)
def test_all_flagged_study_writes_its_figures(client, tmp_path, capsys, monkeypatch):
    """B4: a valid study whose points are all flagged (soft bed k = 1e4) wrote its result and then
    plotting crashed ("Data cannot be log-scaled")."""
    from helpers import quiet
    from screening.sweep import run as sweep

    study = tmp_path / "soft.toml"
    study.write_text(STUDY.replace("k = 2.89e7", "k = 1e4").replace("eps = [-6e5, 6e7]", "eps = [-6e5, 0.0]").replace("[mcs]\nsamples = 4\nseed = 0\n", "")
                     .replace("[foundation]\n", PAPER_CONDENSATION))   # the default cannot condense this bed
    real = sweep.run_sweep
    monkeypatch.setattr("screening.sweep.run.run_sweep",
                        lambda *a, **kw: real(*a, **{**kw, "client": client}))
    out = tmp_path / "soft.nc"
    assert main(["run", str(study), "--out", str(out), "--quiet"]) == 0, capsys.readouterr().err
    import xarray as xr
    with xr.open_dataset(out) as ds:
        assert (ds["status"].values != 0).all()
    assert (tmp_path / "soft_peaks.png").is_file() and (tmp_path / "soft_histories.png").is_file()


def _all_nan(src, dst):
    import xarray as xr

    with xr.open_dataset(src) as ds:
        ds = ds.load()
    for name in ds.data_vars:
        if ds[name].dtype.kind == "f":
            ds[name][...] = np.nan
    ds["status"][...] = 3
    ds.to_netcdf(dst)
    return dst


def test_plot_of_an_all_nan_result_writes_figures(result_file, tmp_path, capsys):
    """B4 neighbour: ``screening plot`` on any all-NaN result."""
    bad = _all_nan(result_file, tmp_path / "nan.nc")
    assert main(["plot", str(bad)]) == 0, capsys.readouterr().err
    assert (tmp_path / "nan_peaks.png").is_file()


def _foreign(result_file, path, edit):
    import xarray as xr

    with xr.open_dataset(result_file) as ds:
        ds = ds.load()
    ds = edit(ds)
    for name in ds.variables:
        ds[name].encoding = {}
    ds.to_netcdf(path)
    return path


def _drop_flags(ds):
    ds["status"].attrs.pop("flag_values")
    return ds


def _bad_flag_shape(ds):
    ds["status"].attrs["flag_values"] = np.array([0, 1], dtype=np.int8)
    return ds


FOREIGN = {
    "no flag_values": _drop_flags,
    "flag attributes of the wrong shape": _bad_flag_shape,
    "t of length 0": lambda ds: ds.isel(t=slice(0, 0)),
    "histories without t": lambda ds: ds.assign(var_theta=ds["var_theta"].isel(t=0)),
    "float status": lambda ds: ds.assign(status=ds["status"].astype(float)),
}


@pytest.mark.parametrize("command", [["info"], ["plot"], ["fragility", "--threshold", "0.1"]],
                         ids=["info", "plot", "fragility"])
@pytest.mark.parametrize("edit", list(FOREIGN))
def test_foreign_files_with_the_expected_names_are_one_line(result_file, tmp_path, capsys, command, edit):
    """B6: foreign netCDF files carrying the expected variable names crashed info/plot/fragility
    (KeyError flag_values, t of length 0, flag attributes of the wrong shape)."""
    bad = _foreign(result_file, tmp_path / "foreign.nc", FOREIGN[edit])
    before = _listing(tmp_path)
    assert main([command[0], str(bad), *command[1:]]) == 2
    assert "not a screening sweep result" in one_line_error(capsys.readouterr().err)
    assert _listing(tmp_path) == before


@pytest.mark.parametrize("command", ["info", "plot"])
def test_small_file_declaring_a_huge_grid_is_refused_without_allocating(tmp_path, capsys, command):
    """B20: a small file declaring a 2e8-point grid made info/plot allocate 1.5 GB."""
    import netCDF4

    from screening.solvers.moments import HISTORY_VARIABLES
    from screening.io.reader import REQUIRED_VARIABLES

    path = tmp_path / "huge.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("eps", 20000)
        nc.createDimension("S0", 10000)
        nc.createDimension("t", 2)
        nc.createVariable("t", "f8", ("t",))[:] = [0.0, 0.05]
        for name in REQUIRED_VARIABLES + HISTORY_VARIABLES:
            dims = ("eps", "S0", "t") if name in HISTORY_VARIABLES else ("eps", "S0")
            v = nc.createVariable(name, "i1" if name == "status" else "f4", dims, chunksizes=(1, 1, 1)[:len(dims)])
            if name == "status":
                v.flag_values = np.array([0, 1], dtype=np.int8)
                v.flag_meanings = "ok bad"
    assert path.stat().st_size < 100_000
    tracemalloc.start()
    try:
        code = main([command, str(path)])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert code == 2
    assert "declares 2e+08 points" in one_line_error(capsys.readouterr().err)
    assert peak < 64 * 2**20


def test_figures_and_fragility_do_not_write_through_planted_links(result_file, tmp_path, capsys):
    """B11 neighbour: the temporary files of figures and of the fragility file were ``<path>.tmp``,
    written through a link planted there."""
    import shutil

    res = tmp_path / "r.nc"
    shutil.copy(result_file, res)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    for name in ("r_histories.png.tmp", "r_peaks.png.tmp", "r_fragility.nc.tmp", "r_fragility.png.tmp"):
        (tmp_path / name).symlink_to(victim)
    assert main(["plot", str(res)]) == 0
    assert main(["fragility", str(res), "--threshold", "0.1"]) == 0
    assert victim.read_text() == "precious"
    assert (tmp_path / "r_fragility.nc").stat().st_mode & 0o044 == 0o044 & ~_umask()


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


# ----------------------------------------------------------------------------- --scheduler (B5, B15)
import contextlib
import socket
import threading


@contextlib.contextmanager
def _server(reply):
    """A TCP server on 127.0.0.1 that accepts and sends ``reply`` (nothing: stays silent), bounded in time."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    srv.settimeout(20)
    stop = threading.Event()
    conns = []

    def serve():
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except OSError:
                return
            conns.append(conn)
            if reply:
                with contextlib.suppress(OSError):
                    conn.sendall(reply)

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        stop.set()
        srv.close()
        for c in conns:
            c.close()


@pytest.mark.parametrize("reply, needle", [
    (b"", "did not answer like a dask scheduler within"),                  # B5: silent server
    (b"\xff" * 64, "is not a dask scheduler"),                             # B15: exabyte frame
    (b"HTTP/1.1 400 Bad Request\r\n\r\n", "is not a dask scheduler"),     # B15 neighbour: a web server
])
def test_scheduler_that_is_not_dask_is_one_line_in_bounded_time(tmp_path, capsys, monkeypatch, reply, needle):
    import time

    monkeypatch.setattr("screening.sweep.connect.HANDSHAKE_TIMEOUT", 1.0)
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    with _server(reply) as address:
        start = time.monotonic()
        assert main(["run", str(study), "--scheduler", address, "--out", str(tmp_path / "r.nc"), "--quiet"]) == 2
        assert time.monotonic() - start < 15
    assert needle in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "r.nc").exists() and not (tmp_path / "r.nc.partial").exists()


@pytest.mark.parametrize("content, needle", [
    ('{"address": 5}', 'has no "address" string'),
    ("[1, 2]", 'has no "address" string'),
    ("{not json", "is not valid JSON"),
    ("[" * 100000, "cannot read the scheduler file"),
])
def test_malformed_scheduler_file_is_one_line(tmp_path, capsys, content, needle):
    """B15: a malformed scheduler JSON gave AssertionError/TypeError tracebacks."""
    sched = tmp_path / "scheduler.json"
    sched.write_text(content)
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    assert main(["run", str(study), "--scheduler", str(sched), "--out", str(tmp_path / "r.nc"), "--quiet"]) == 2
    assert needle in one_line_error(capsys.readouterr().err)


def test_a_valid_scheduler_file_of_several_megabytes_gives_its_address(tmp_path):
    """A scheduler with many workers writes a large file: a 2 MB one was read as 'JSONDecodeError'."""
    import json

    from screening.sweep.connect import MAX_SCHEDULER_FILE, scheduler_address
    from screening.io.errors import SweepError

    workers = {f"tcp://10.0.{i // 250}.{i % 250}:40000": {"name": f"w{i}", "memory_limit": 4e9} for i in range(40000)}
    sched = tmp_path / "scheduler.json"
    sched.write_text(json.dumps({"type": "Scheduler", "address": "tcp://127.0.0.1:8786", "workers": workers}))
    assert sched.stat().st_size > 1 << 21
    assert scheduler_address(sched) == "tcp://127.0.0.1:8786"
    with open(sched, "r+b") as fh:
        fh.truncate(MAX_SCHEDULER_FILE + 1)
    with pytest.raises(SweepError, match="at most"):
        scheduler_address(sched)


def test_a_real_scheduler_passes_the_check():
    import logging
    from distributed import LocalCluster
    from screening.sweep.connect import check_scheduler

    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster:
        assert check_scheduler(cluster.scheduler_address, timeout=5) == cluster.scheduler_address


def _handshake_length(n=58):
    import struct

    return struct.pack("<Q", n)


@pytest.mark.parametrize("reply, needle", [
    (_handshake_length(), "did not answer like a dask scheduler within"),        # a length, then silence
    (_handshake_length() + b"\x07" * 58, "is not a dask scheduler"),            # a length, then junk
    (_handshake_length(24) + _handshake_length(1) + _handshake_length(8) + b"\xc1" * 8,
     "is not a dask scheduler"),                                                # frames, not msgpack
])
@pytest.mark.parametrize("how", ["address", "file", "cloud"])
def test_a_scheduler_handshake_cut_short_or_junk_is_one_line_in_bounded_time(tmp_path, capsys, monkeypatch,
                                                                              reply, needle, how):
    import json
    import time

    monkeypatch.setattr("screening.sweep.connect.HANDSHAKE_TIMEOUT", 1.0)
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    with _server(reply) as address:
        if how == "file":
            (tmp_path / "scheduler.json").write_text(json.dumps({"address": address}))
            address = str(tmp_path / "scheduler.json")
        argv = (["cloud", str(study)] if how == "cloud" else ["run", str(study)]) + [
            "--scheduler", address, "--out", str(tmp_path / "r.nc"), "--quiet"]
        if how == "cloud":
            from screening.core.records import Record, write_at2

            (tmp_path / "rec").mkdir()
            write_at2(tmp_path / "rec" / "a.at2", Record(np.sin(np.arange(200) * 0.1), 0.01))
            study.write_text("[block]\nm = 8.67\nb = 0.035\nh = 0.21\n[foundation]\nk = 2.89e7\nlam = 8.95e8\n"
                             'eps = 6e7\n[records]\nfiles = "rec"\n')
        start = time.monotonic()
        code = main(argv)
        assert time.monotonic() - start < 15
    assert code == 2 and needle in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "r.nc").exists()


@pytest.mark.parametrize("address, needle", [
    ("tls://127.0.0.1:8786", "needs TLS settings"),
    ("ucx://127.0.0.1:8786", "is not supported"),
    ("tcp://127.0.0.1:" + "9" * 20, "port in 1..65535"),
    ("127.0.0.1:\u00b2", "port in 1..65535"),
    ("tcp://" + "a" * 100_000 + ":8786", "host name"),
])
def test_scheduler_addresses_dask_cannot_use_are_one_line(tmp_path, capsys, address, needle):
    study = tmp_path / "s.toml"
    study.write_text(STUDY)
    assert main(["run", str(study), "--scheduler", address, "--out", str(tmp_path / "r.nc"), "--quiet"]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert needle in line and len(line) < 400, line[:400]


# ----------------------------------------------------------------------------- B7: a point beyond float64
#: reproducers of the issue (field, extreme value, an ordinary value): the point's scales under- or
#: overflow float64
B7_POINTS = {"k 1e200": ("k", 1e200, 2.89e7), "m 1e-200": ("m", 1e-200, 8.67),
             "omega_g 1e-150": ("omega_g", 1e-150, 15.0)}


def _b7_models(field, value):
    from screening import Block, Foundation, KanaiTajimi, WhiteNoise

    given = {field: value}
    blk = Block(**{"m": 8.67, "b": 0.035, "h": 0.21, **{k: v for k, v in given.items() if k == "m"}})
    bed = Foundation(**{"k": 2.89e7, "lam": 8.95e8, "eps": 6e7, **{k: v for k, v in given.items() if k == "k"}})
    if field != "omega_g":
        return blk, bed, WhiteNoise(S0=2.4e-5)
    return blk, bed, KanaiTajimi(S0=2.4e-5, omega_g=value, zeta_g=0.6)


@pytest.mark.parametrize("name", list(B7_POINTS))
def test_a_point_beyond_float_range_is_flagged_and_keeps_its_batch(name):
    """B7: one extreme point raised ZeroDivisionError in the compiled kernel and took its batch down."""
    from screening.solvers.moments import solve_moments
    from screening.core.status import PointStatus

    field, extreme, ordinary = B7_POINTS[name]
    t = np.linspace(0.0, 2.0, 41)
    alone = solve_moments(*_b7_models(field, extreme), t)
    assert alone["status"] == PointStatus.beyond_float_range
    assert np.isnan(alone["peak_var_theta"]) and np.all(np.isnan(alone["var_theta"]))
    # beside an ordinary point (neighbour): that point is bit for bit its solo result
    both = solve_moments(*_b7_models(field, np.array([ordinary, extreme])), t)
    solo = solve_moments(*_b7_models(field, ordinary), t)
    np.testing.assert_array_equal(both["status"], [PointStatus.ok, PointStatus.beyond_float_range])
    for var in ("var_theta", "peak_var_theta", "n_steps"):
        np.testing.assert_array_equal(both[var][0], solo[var])


@pytest.mark.parametrize("b, h", [(1e-6, 0.21), (1e3, 0.21), (0.035, 1e-6), (0.035, 1e3), (1e-6, 1e3), (1e3, 1e-6)])
def test_blocks_at_the_ends_of_the_length_range_finish_with_a_status(b, h):
    """Neighbours of b <= ~1e-170 (ZeroDivisionError) and b, h >= ~1e150 (OverflowError), now refused:
    the extreme lengths allowed are integrated or flagged, through the whole batch task."""
    from screening.core.status import PointStatus
    from screening.sweep.execution import solve_batch
    from screening.sweep.grid import batch_models, plan_batches

    study = parse_study(STUDY.replace("b = 0.035", f"b = {b!r}").replace("h = 0.21", f"h = {h!r}")
                        .replace("[foundation]\n", PAPER_CONDENSATION))    # the paper's closed forms at the extremes
    batch = plan_batches(study, study.n_points)[0]
    with np.errstate(all="ignore"):
        out = solve_batch(*batch_models(study, batch), study.cases[0].condensation_model, study.times, study.rtol,
                          study.max_steps)
    assert set(out["status"].tolist()) <= {int(s) for s in PointStatus if s >= PointStatus.ok}
    ok = out["status"] == PointStatus.ok
    assert np.all(np.isfinite(out["peak_var_theta"][ok]))


@pytest.mark.parametrize("field, value", [("k", 1e100), ("k", 1e150), ("m", 1e-100), ("omega_g", 1e-100)])
def test_points_near_the_float_range_are_integrated_or_flagged(field, value):
    """B7 neighbours: extreme but representable points finish with a status (no exception)."""
    from screening import linearize
    from screening.core.status import PointStatus

    ds = linearize(*_b7_models(field, value), t_end=2.0)
    assert int(ds["status"]) in {int(s) for s in PointStatus if s >= PointStatus.ok}


def test_a_sweep_batch_with_a_point_beyond_float_range_keeps_its_other_points(client, tmp_path):
    """B7 through a sweep: the extreme point is flagged in the file, its batch's other points are ok."""
    import xarray as xr
    from helpers import quiet
    from screening.core.status import PointStatus
    from screening.sweep.run import run_sweep

    text = STUDY.replace("k = 2.89e7", "k = [2.89e7, 1e200]").replace("[mcs]\nsamples = 4\nseed = 0\n", "")
    out = tmp_path / "b7.nc"
    run_sweep(parse_study(text), out, client=client, progress=False, log=quiet)
    with xr.open_dataset(out) as ds:
        status = ds["status"].transpose("k", ...).values
    assert (status[1] == PointStatus.beyond_float_range).all()
    assert (status[0] == PointStatus.ok).all()
