"""Shared pieces of the sweep, CLI and robustness tests: a small study grid and file checks."""

import contextlib
import os
import subprocess
import sys
import time
from pathlib import Path

import xarray as xr

from screening.applications.tradeoff_study import EXAMPLE_TRADEOFF_STUDY

#: 4 eps x 5 S0 white-noise points, 4 s records: the sweep tests' standard grid.
GRID = """
title = "sweep test"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = [-6e5, 0.0, 3e7, 6e7]
[excitation]
kind = "white"
S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}
[time]
t_end = 4.0
dt = 0.05
"""


def study_text(edits=None, append="", base=GRID):
    """A study file derived from ``base`` (default :data:`GRID`): each ``key: value`` of ``edits`` (TOML
    source text) replaces the value on the line ``key = ...`` (``None`` drops the line); a ``"table.key"``
    whose key has no line yet is added at the end of ``[table]``; ``append`` (more tables) goes last."""
    lines = base.strip("\n").split("\n")
    for key, value in (edits or {}).items():
        table, _, name = key.rpartition(".")
        at = [i for i, line in enumerate(lines) if line.split(" = ", 1)[0] == name]
        if at and value is None:
            del lines[at[0]]
        elif at:
            lines[at[0]] = f"{name} = {value}"
        else:
            header = lines.index(f"[{table}]")
            end = next((i for i in range(header + 1, len(lines)) if lines[i].startswith("[")), len(lines))
            lines.insert(end, f"{name} = {value}")
    return "\n" + "\n".join(lines) + "\n" + append


#: A small speed-accuracy trade study: one white-noise family, 2 points, 2 s records (the package's example).
TRADE_STUDY = EXAMPLE_TRADEOFF_STUDY

#: Two cases (white noise on a hardening bed, Kanai-Tajimi on a softening one) x 3 S0: 6 points.
CASES = """
title = "cases test"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[excitation]
kind = "white"
S0 = [1e-4, 5e-4, 2.4e-3]
[time]
t_end = 3.0
dt = 0.1
[[case]]
name = "hard_white"
foundation.eps = 6e7
[[case]]
name = "soft_kt"
foundation.eps = -6e5
excitation = {kind = "kanai_tajimi", omega_g = 10.0, zeta_g = 0.4}
"""


#: Keep the scheduler's HTTP server off the default port 8787 (parallel test runs).
NO_HTTP_PORT_8787 = {"dashboard_address": "127.0.0.1:0"}


def quiet(*_):
    """A ``log`` callback that drops the messages."""


def stop_after(n, seen):
    """An ``on_batch`` callback that appends each batch index to ``seen`` and presses Ctrl-C at the ``n``-th."""
    def on_batch(batch):
        seen.append(batch.index)
        if len(seen) == n:
            raise KeyboardInterrupt
    return on_batch


def interrupted_run(study, out, client, batch_size, n=2):
    """Run ``study`` into ``out`` and press Ctrl-C after its ``n``-th finished batch; returns the
    indices of the batches finished by then."""
    import pytest

    from screening.sweep.run import run_sweep

    seen = []
    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, client=client, batch_size=batch_size, progress=False, log=quiet,
                  on_batch=stop_after(n, seen))
    return seen


def failed_result_file(study, path, zarr_batch_size=None):
    """A complete result of ``study`` (netCDF, or zarr with ``zarr_batch_size``) whose batches and spot
    checks all failed: the writer alone, no solver, no dask."""
    from screening.sweep._submit import failed_spot
    from screening.sweep.execution import failed_result
    from screening.sweep.grid import plan_batches, select_spots
    from screening.sweep.run import write_batch, write_spots
    from screening.io.writer import ResultFile, result_attributes

    result = ResultFile(path, study, result_attributes(study, "2024-01-01T00:00:00+00:00", 4),
                        zarr_batch_size=zarr_batch_size)
    try:
        for batch in plan_batches(study, 4):
            write_batch(result, study, batch, failed_result(batch.size, study.times.size))
        if study.mcs is not None:
            spots = select_spots(study, result.status, result.peak_p_uplift)
            write_spots(result, study, spots, [failed_spot(study.times.size, study.mcs.samples) for _ in spots],
                        [True] * len(spots), study.mcs)
    finally:
        result.close()
    return path


def one_line_error(err):
    """The single stderr line of a CLI error (``screening: error: ...``), no traceback."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("screening: error: "), err
    assert "Traceback" not in err
    return lines[0]


def compare_files(a, b, ignore=()):
    """Two result files hold identical data and metadata (creation stamps, batch size and the
    attributes in ``ignore`` aside)."""
    with xr.open_dataset(a) as da, xr.open_dataset(b) as db:
        for ds in (da, db):
            for name in ("history", "date_created", "batch_size", *ignore):
                ds.attrs.pop(name, None)
        xr.testing.assert_identical(da.load(), db.load())


def assert_cdo_form_of(result, cdo_file):
    """``cdo_file`` (``screening export --layout cdo``) holds every number of ``result``: the same values
    with ``t`` first, ``p_exceed`` (and every variable on ``threshold``) as ``p_exceed_<i>``, the strings as
    attributes (JSON lists); a variable without values (on a dimension of length 0) is named in ``left_out``."""
    import json

    import numpy as np

    from screening.io.reader import open_result

    with open_result(result) as ds, xr.open_dataset(cdo_file, decode_times=False) as cdo:
        for name, v in ds.variables.items():
            if 0 in v.shape:
                assert name not in cdo.variables and name in cdo.attrs["left_out"].split(":")[0].split(", "), name
            elif v.dtype.kind in "OSU":
                where = cdo.attrs.get(name) or next(c.attrs[name] for c in cdo.variables.values() if name in c.attrs)
                assert json.loads(where) == [str(s) for s in np.atleast_1d(v.values)], name
            elif "threshold" in v.dims and name != "threshold":
                for i in range(v.sizes["threshold"]):
                    np.testing.assert_array_equal(cdo[f"{name}_{i}"].values, v.isel(threshold=i).values)
            else:
                assert cdo[name].dims == (("t",) if "t" in v.dims else ()) + tuple(d for d in v.dims if d != "t")
                np.testing.assert_array_equal(cdo[name].transpose(*v.dims).values, v.values, err_msg=name)
                assert cdo[name].attrs.get("units") == v.attrs.get("units") or name == "t", name
        assert cdo["t"].attrs["units"].startswith("seconds since") and cdo.attrs["layout"].startswith("CDO")


@contextlib.contextmanager
def in_process_client(n_workers=2):
    """A dask client on an in-process cluster (threads, no dashboard): fast, and monkeypatches
    reach the tasks. Never made dask's default, as the package's own clients are not: with
    distributed 2025.10 a closed default client stays the default and a later xarray write fails
    ("IOLoop is closed")."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=False, dashboard_address=None,
                      scheduler_kwargs=NO_HTTP_PORT_8787) as cluster, \
            Client(cluster, set_as_default=False) as client:
        yield client


@contextlib.contextmanager
def dask_processes(folder, worker_args, n_workers=2):
    """``dask scheduler`` on 127.0.0.1 (port chosen by the system) + ``n_workers`` ``dask worker``
    processes (with ``worker_args``) found through a scheduler file in ``folder``; yields that file,
    then terminates them (killed if they do not stop within 20 s)."""
    import pytest

    bin_dir = Path(sys.executable).parent
    sched_file = folder / "scheduler.json"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    procs = [subprocess.Popen([str(bin_dir / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(sched_file)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)]
    try:
        deadline = time.monotonic() + 60
        while not sched_file.exists():
            if time.monotonic() > deadline or procs[0].poll() is not None:
                pytest.fail("dask scheduler did not start")
            time.sleep(0.1)
        for i in range(n_workers):
            procs.append(subprocess.Popen([str(bin_dir / "dask"), "worker", "--scheduler-file", str(sched_file),
                                           *worker_args, "--local-directory", str(folder / f"worker{i}")],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env))
        yield sched_file
    finally:
        # the workers first, while their scheduler still answers (a worker stopping after its scheduler
        # waits for it until a timeout), then the scheduler
        for group in (procs[1:], procs[:1]):
            for p in group:
                p.terminate()
            for p in group:
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
