"""The same study on a cluster (docs/distributed.md): dask-jobqueue's own local cluster, whose jobs are processes
of this machine, with workers that retire at their ``--lifetime`` (a fraction of the run), one killed, and new
jobs taking their place; the result equals the local run bit for bit, every batch reaches the file once, and
the workers never open the output's folder (netCDF).  The version handshake and bad input: one line, exit 2,
bounded in time."""

import contextlib
import os
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
from distributed.diagnostics.plugin import WorkerPlugin

from helpers import GRID, compare_files, dask_processes, one_line_error, quiet, study_text

from screening.cli import main
from screening.sweep import connect
from screening.sweep.config import cluster_table
from screening.sweep.run import run_sweep
from screening.sweep.study import load_study, parse_study

TESTS = Path(__file__).resolve().parents[1]

#: 4 eps x 10 S0 points, 4 s records, no histories: 40 one-point tasks.
CHURN = study_text({"S0": "{start = 1e-5, stop = 2.4e-3, num = 10, log = true}"},
                   append='[output]\nhistories = "none"\n')
#: The accuracy tests' grid (4 eps x 5 S0, 3 s) with a budget that does not bind (the same plan everywhere).
ACCURACY = GRID.replace("t_end = 4.0", "t_end = 3.0") + "[accuracy]\ntarget = 0.15\nbudget_s = 600000\n"
#: Worker lifetime and stagger [s] of the churn tests: a fraction of the run (which waits for the churn).
LIFETIME, STAGGER = 25, 4
#: Most seconds a run waits for a retired worker and a new one (then the test fails, never hangs).
CHURN_WAIT = 150


# ----------------------------------------------------------------------------- bad input (not slow)
def _study(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("table, needle", [
    ('kind = "local"\nmemory = "2GB"\ncpus = 2\n', "cluster.cpus: unknown key (allowed: kind, cores, memory"),
    ('kind = "slurm"\nmemory = "2GB"\nlifetime = "2h"\n', "cluster.lifetime: 7200 s + lifetime_stagger 180 s"),
])
def test_a_bad_cluster_table_is_one_line_exit_2_before_any_work(tmp_path, capsys, table, needle):
    study = _study(tmp_path, GRID + "[cluster]\n" + table)
    start = time.monotonic()
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--quiet", "--no-plots"]) == 2
    assert time.monotonic() - start < 10
    assert needle in one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_a_batch_queue_that_is_not_here_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    pytest.importorskip("dask_jobqueue")
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent))           # no sbatch on it
    study = _study(tmp_path, GRID + '[cluster]\nkind = "slurm"\nmemory = "2GB"\n')
    start = time.monotonic()
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--quiet", "--no-plots"]) == 2
    assert time.monotonic() - start < 30
    assert "submits jobs with sbatch, which is not on this machine's PATH" in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "r.nc").exists() and not (tmp_path / "r.nc.partial").exists()


def test_a_scheduler_that_cannot_be_reached_is_one_line_exit_2_in_bounded_time(tmp_path, capsys):
    import socket

    with socket.socket() as probe:                                           # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    study = _study(tmp_path, GRID + '[cluster]\nkind = "local"\nmemory = "2GB"\n')      # --scheduler wins
    start = time.monotonic()
    assert main(["run", str(study), "--scheduler", f"tcp://127.0.0.1:{port}", "--out", str(tmp_path / "r.nc"),
                 "--quiet", "--no-plots"]) == 2
    assert time.monotonic() - start < 30
    line = one_line_error(capsys.readouterr().err)
    assert f"cannot connect to the dask scheduler tcp://127.0.0.1:{port}" in line, line
    assert not (tmp_path / "r.nc").exists()


# ----------------------------------------------------------------------------- the handshake (slow: processes)
@pytest.mark.slow
def test_a_worker_of_another_version_is_refused_with_both_versions(tmp_path, capsys, monkeypatch):
    """The client's numba version faked: the worker process (real versions) is refused in one line."""
    real = connect.software_versions()
    monkeypatch.setattr(connect, "software_versions", lambda: {**real, "numba": "0.0.0+fake"})
    study = _study(tmp_path, GRID)
    with dask_processes(tmp_path, ["--nworkers", "1", "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
                        n_workers=1) as sched_file:
        start = time.monotonic()
        assert main(["run", str(study), "--scheduler", str(sched_file), "--out", str(tmp_path / "r.nc"), "--quiet",
                     "--no-plots"]) == 2
        took = time.monotonic() - start
    line = one_line_error(capsys.readouterr().err)
    assert f"runs numba {real['numba']}; this client runs numba 0.0.0+fake" in line, line
    assert took < 300 and not (tmp_path / "r.nc").exists()


# ----------------------------------------------------------------------------- workers that come and go (slow)
def _watch_opens(folder, log):
    """On a worker: append to ``log`` every path under ``folder`` this process opens from Python (audit events)."""
    folder = os.path.abspath(folder)

    def hook(event, args):
        if event == "open" and args and isinstance(args[0], (str, bytes, os.PathLike)):
            path = os.path.abspath(os.fsdecode(args[0]))
            if path.startswith(folder) and not path.startswith(log):
                with open(log, "a") as fh:
                    fh.write(f"{os.getpid()} {path}\n")

    sys.addaudithook(hook)


def _open_files(pid, folder):
    """The paths under ``folder`` that process ``pid`` holds open (C libraries included)."""
    found = []
    with contextlib.suppress(OSError):
        for fd in os.listdir(f"/proc/{pid}/fd"):
            with contextlib.suppress(OSError):
                target = os.readlink(f"/proc/{pid}/fd/{fd}")
                if target.startswith(str(folder)):
                    found.append(target)
    return found


class Churn:
    """``on_batch`` of a run on ``client``: records each batch, kills one busy worker (SIGKILL; its nanny
    starts a new one) at the ``kill_at``-th batch, then at the ``wait_at``-th waits (at most
    :data:`CHURN_WAIT` s) until a worker retired at its lifetime and a new one joined, so that the run spans
    them; ``watch``: a folder no worker may hold open."""

    def __init__(self, client, kill_at=3, wait_at=8, watch=None):
        self.client, self.kill_at, self.wait_at, self.watch = client, kill_at, wait_at, watch
        self.batches, self.killed, self.held = [], None, []
        self.first = set(self._workers())
        self.seen = set(self.first)

    def _workers(self):
        return set(self.client.scheduler_info(n_workers=-1)["workers"])

    def _look(self):
        now = self._workers()
        self.seen |= now
        if self.watch is not None:
            for pid in connect.run_on_workers(self.client, os.getpid).values():
                self.held += _open_files(pid, self.watch)
        return now

    @property
    def gone(self):
        return self.seen - self._workers()

    def __call__(self, batch):
        self.batches.append(batch.index)
        now = self._look()
        if len(self.batches) == self.kill_at:
            busy = sorted(w for w, keys in self.client.processing().items() if keys and w in now)
            pids = connect.run_on_workers(self.client, os.getpid)
            self.killed = next((w for w in busy if w in pids), sorted(pids)[0])
            os.kill(pids[self.killed], signal.SIGKILL)
        if len(self.batches) == self.wait_at:
            deadline = time.monotonic() + CHURN_WAIT
            while not (len(self.gone - {self.killed}) >= 1 and len(self.seen - self.first) >= 2):
                assert time.monotonic() < deadline, f"no worker retired or joined within {CHURN_WAIT} s"
                time.sleep(1.0)
                self._look()


@pytest.fixture
def jobqueue_client(tmp_path, monkeypatch):
    """A client of dask-jobqueue's local cluster (two jobs of one worker each, kept by adapt, retiring at
    :data:`LIFETIME` +- :data:`STAGGER` s), built from a ``[cluster]`` table like ``screening run`` does."""
    pytest.importorskip("dask_jobqueue")
    from distributed import Client

    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(TESTS / "integration"), str(TESTS),
                                                      os.environ.get("PYTHONPATH", "")]))   # the jobs import this
    monkeypatch.setenv("NUMBA_NUM_THREADS", "1")
    spec = cluster_table({"cluster": {"kind": "local", "memory": "4GB", "jobs": 2, "lifetime": f"{LIFETIME}s",
                                      "lifetime_stagger": f"{STAGGER}s", "local_directory": str(tmp_path / "jobs")}})
    with connect.jobqueue_cluster(spec) as cluster:
        cluster.adapt(minimum_jobs=2, maximum_jobs=2)
        with Client(cluster, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=120)
            yield client


def _local(study, path):
    return run_sweep(study, path, workers=0, batch_size=1, progress=False, log=quiet)


@pytest.mark.slow
def test_a_sweep_survives_workers_that_retire_die_and_join_without_opening_its_folder(jobqueue_client, tmp_path):
    client = jobqueue_client
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    log = str(tmp_path / "opens.log")
    client.register_plugin(_OpenAudit(str(out_dir), log))       # every worker, also those that join later
    connect.run_on_workers(client, _probe_open, str(out_dir / "probe"))     # the audit sees an open there
    assert Path(log).read_text().count("probe") == 2
    Path(log).unlink()

    study = parse_study(CHURN)
    churn = Churn(client, watch=out_dir)
    report = run_sweep(study, out_dir / "r.nc", client=client, batch_size=1, progress=False, log=quiet,
                       on_batch=churn)
    _local(study, tmp_path / "local.nc")
    compare_files(tmp_path / "local.nc", out_dir / "r.nc")                  # bit for bit
    assert sorted(churn.batches) == list(range(report.n_batches)) == list(range(40))   # each batch once
    assert report.n_failed_batches == 0 and report.n_resumed_batches == 0
    assert churn.killed in churn.gone and len(churn.gone) >= 2 and len(churn.seen - churn.first) >= 2
    assert not Path(log).exists() and churn.held == []                      # no worker opened the folder
    print(f"\nchurn (netCDF): {len(churn.seen)} workers in all, {len(churn.gone)} gone (1 killed), "
          f"{len(churn.seen - churn.first)} joined; lifetime {LIFETIME} +- {STAGGER} s")


@pytest.mark.slow
def test_a_zarr_result_in_a_shared_folder_survives_the_same_churn(jobqueue_client, tmp_path):
    pytest.importorskip("zarr")
    study = parse_study(CHURN)
    churn = Churn(jobqueue_client)
    report = run_sweep(study, tmp_path / "r.zarr", client=jobqueue_client, batch_size=1, progress=False, log=quiet,
                       on_batch=churn)
    _local(study, tmp_path / "local.nc")
    with xr.open_dataset(tmp_path / "local.nc") as a, xr.open_zarr(tmp_path / "r.zarr") as b:
        a, b = a.load(), b.load()
    for ds in (a, b):
        for name in ("history", "date_created"):
            ds.attrs.pop(name, None)
    xr.testing.assert_identical(a, b)                                        # bit for bit
    assert sorted(churn.batches) == list(range(report.n_batches)) and report.n_failed_batches == 0
    assert churn.killed in churn.gone and len(churn.gone) >= 2 and len(churn.seen - churn.first) >= 2
    print(f"\nchurn (zarr): {len(churn.seen)} workers in all, {len(churn.gone)} gone (1 killed), "
          f"{len(churn.seen - churn.first)} joined")


@pytest.mark.slow
def test_an_accuracy_run_survives_the_churn_and_keeps_its_budget(jobqueue_client, tmp_path):
    study = parse_study(ACCURACY)
    churn = Churn(jobqueue_client, kill_at=2, wait_at=5)
    report = run_sweep(study, tmp_path / "r.nc", client=jobqueue_client, batch_size=1, progress=False, log=quiet,
                       on_batch=churn)
    linearized = set(churn.seen)                    # the workers seen while the batches came back
    churn._look()
    gone_in_accuracy, joined_in_accuracy = len(linearized - churn._workers()), len(churn.seen - linearized)
    local = run_sweep(study, tmp_path / "local.nc", workers=0, batch_size=1, progress=False, log=quiet)
    # the CPU and wall times of two runs differ; every value and every other attribute is the same
    with xr.open_dataset(tmp_path / "local.nc") as a, xr.open_dataset(tmp_path / "r.nc") as b:
        a, b = (ds.load().drop_vars("esc_cpu_time") for ds in (a, b))
    for ds in (a, b):
        for name in ("history", "date_created", "accuracy_cpu_s", "accuracy_wall_s", "accuracy_note"):
            ds.attrs.pop(name, None)
    xr.testing.assert_identical(a, b)
    assert report.accuracy["n_escalated"] == local.accuracy["n_escalated"] >= 1
    assert report.accuracy["wall_s"] <= study.accuracy.budget_s and report.accuracy.get("n_cut", 0) == 0
    assert sorted(churn.batches) == list(range(report.n_batches)) and report.n_failed_batches == 0
    assert churn.killed in churn.gone and len(churn.seen - churn.first) >= 2
    print(f"\nchurn ([accuracy]): {len(linearized)} workers during the linearization ({len(linearized - churn.first)} "
          f"joined, 1 killed); of them {gone_in_accuracy} gone by the end, {joined_in_accuracy} more seen at the end; "
          f"{report.accuracy['n_escalated']} escalated points in {report.accuracy['wall_s']:.0f} s")


@pytest.mark.slow
def test_screening_run_builds_the_cluster_of_the_study_table(tmp_path, capsys, monkeypatch):
    """``[cluster] kind = "local"``: `screening run` submits the jobs, waits for a worker, checks its versions
    and writes the same file as the local run."""
    pytest.importorskip("dask_jobqueue")
    monkeypatch.setenv("NUMBA_NUM_THREADS", "1")
    text = CHURN + '[cluster]\nkind = "local"\nmemory = "4GB"\njobs = 1\ncores = 2\nlifetime = "10m"\nbatch_size = 7\n'
    study = _study(tmp_path, text)
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--quiet", "--no-plots"]) == 0
    err = capsys.readouterr().err
    assert "submitted 1 local job(s) of 2 worker(s) each (workers retire after 600 +- 180 s" in err, err
    _local(load_study(study), tmp_path / "local.nc")                      # the same study, in this process
    compare_files(tmp_path / "local.nc", tmp_path / "r.nc", ignore=("batch_size",))
    with xr.open_dataset(tmp_path / "r.nc") as ds:
        assert int(ds.attrs["batch_size"]) == 7                              # [cluster] batch_size bounds the tasks
    # the same study with --workers: the table is not used, and the result (same key) is reused
    assert main(["run", str(study), "--out", str(tmp_path / "r.nc"), "--workers", "0", "--quiet", "--no-plots"]) == 0
    assert "is up to date" in capsys.readouterr().err


def _probe_open(path):
    with open(path, "w"):
        pass
    os.remove(path)



class _OpenAudit(WorkerPlugin):
    """Installs :func:`_watch_opens` on every worker (those that join later too)."""

    name = "test-open-audit"

    def __init__(self, folder, log):
        self.folder, self.log = folder, log

    def setup(self, worker):
        _watch_opens(self.folder, self.log)
