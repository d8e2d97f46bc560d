"""Zarr results (``--out result.zarr``): written in place by the workers, resumed from the store's batch
markers, identical to the netCDF result when opened with xarray and when exported
(``screening export``); and a real ``dask scheduler`` + ``dask worker`` cluster writing one."""

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from helpers import CASES, GRID, assert_cdo_form_of, compare_files, dask_processes, interrupted_run, one_line_error, quiet

from screening.cli import main
from screening.core.status import PointStatus
from screening.sweep import _submit
from screening.io.reader import result_key
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

pytest.importorskip("zarr")

BIN = Path(sys.executable).parent
CHECKER = BIN / "compliance-checker"
SPOTS = "[mcs]\npoints = \"auto\"\ncount = 2\nsamples = 6\nmodel = \"condensed\"\n"
FRAGILITY = "[fragility]\nthresholds = [0.01, 0.02]\n"


def _same(nc, store, ignore=()):
    """The zarr store opens (xarray) to the values and attributes of the netCDF file."""
    with xr.open_dataset(nc) as a, xr.open_zarr(store) as b:
        a, b = a.load(), b.load()
    for ds in (a, b):
        for name in ("history", "date_created", *ignore):
            ds.attrs.pop(name, None)
    xr.testing.assert_identical(a, b)


PGA_GRID = GRID.replace("S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}", "pga = [0.5, 1.0, 2.0]")


@pytest.mark.parametrize("text", [GRID + SPOTS, CASES, GRID + FRAGILITY + '[output]\nhistories = "none"\n', PGA_GRID],
                         ids=["grid_spots", "cases", "no_histories_fragility", "pga_target"])
def test_the_zarr_result_is_the_netcdf_result(client, tmp_path, text):
    study = parse_study(text, name="s", source="s.toml")
    run_sweep(study, tmp_path / "r.nc", client=client, batch_size=5, progress=False, log=quiet)
    report = run_sweep(study, tmp_path / "r.zarr", client=client, batch_size=5, progress=False, log=quiet)
    assert report.status_counts.get("ok") == study.n_points
    assert not (tmp_path / "r.zarr.partial").exists()
    _same(tmp_path / "r.nc", tmp_path / "r.zarr")
    assert result_key(tmp_path / "r.zarr") == study.key


def test_workers_write_the_zarr_chunks_and_return_only_summaries(client, tmp_path, monkeypatch):
    """The client never receives the histories of a zarr run: it writes no batch region itself."""
    from screening.sweep import run

    study = parse_study(GRID)
    written = []
    monkeypatch.setattr(run, "write_batch", lambda result, study, batch, part: written.append(batch))
    run_sweep(study, tmp_path / "w.zarr", client=client, batch_size=5, progress=False, log=quiet)
    assert written == []
    with xr.open_zarr(tmp_path / "w.zarr") as ds:
        assert np.all(np.isfinite(ds["var_theta"].values[..., 1:]))
        assert ds["var_theta"].encoding["chunks"] == (1, 5, 81)     # one chunk per batch of a row


def test_an_interrupted_zarr_run_resumes_from_the_marked_batches(client, tmp_path):
    study = parse_study(GRID)
    ref = tmp_path / "ref.nc"
    run_sweep(study, ref, client=client, batch_size=5, progress=False, log=quiet)
    out = tmp_path / "run.zarr"
    seen = interrupted_run(study, out, client, batch_size=5)
    while any(client.processing().values()):     # tasks already running finish (and mark their batch)
        time.sleep(0.05)
    partial = tmp_path / "run.zarr.partial"
    assert not out.exists() and (partial / "result.zarr.building" / "zarr.json").is_file()
    markers = sorted(p.name for p in (partial / "done").glob("batch-*.json"))
    assert set(f"batch-{i:06d}.json" for i in seen) <= set(markers)
    marker = json.loads((partial / "done" / f"batch-{seen[0]:06d}.json").read_text())
    assert marker["key"] == study.key and all(size > 0 and len(digest) == 32
                                              for size, digest in marker["files"].values())

    # damage marked batches: a chunk file cut short, and one zeroed at its size (only the checksum sees it)
    building = partial / "result.zarr.building"
    chunk = building / "var_theta" / "c" / str(seen[1]) / "0" / "0"
    chunk.write_bytes(chunk.read_bytes()[:10])
    chunk = building / "status" / "c" / str(seen[0]) / "0"
    chunk.write_bytes(bytes(chunk.stat().st_size))
    messages = []
    report = run_sweep(study, out, client=client, batch_size=2, progress=False, log=messages.append)
    assert report.n_batches == 4                                   # the layout of the first attempt
    assert report.n_resumed_batches == len(markers) - 2
    assert not partial.exists()
    _same(ref, out)


def test_a_failed_batch_is_flagged_in_the_zarr_result(client, tmp_path, monkeypatch):
    real = _submit.solve_and_store_batch

    def flaky(target, batch, *args):
        if batch.index == 1:
            raise FloatingPointError("synthetic failure")
        return real(target, batch, *args)

    monkeypatch.setattr(_submit, "solve_and_store_batch", flaky)
    report = run_sweep(parse_study(GRID), tmp_path / "f.zarr", client=client, batch_size=5, progress=False,
                       log=quiet)
    assert report.n_failed_batches == 1
    with xr.open_zarr(tmp_path / "f.zarr") as ds:
        assert np.all(ds["status"].values[1] == PointStatus.task_failed) and np.all(ds["status"].values[0] == 0)
        assert np.all(np.isnan(ds["var_theta"].values[1])) and int(ds.attrs["n_failed_points"]) == 5


def test_disk_full_in_the_zarr_store_keeps_the_marked_batches_and_resumes(client, tmp_path, monkeypatch):
    """No space for batch 2 on, on the workers and on the client: one line naming the cause and the
    kept batches; the same command then resumes."""
    import errno

    from screening.io.errors import SweepError

    study = parse_study(GRID)
    ref = tmp_path / "ref.nc"
    run_sweep(study, ref, client=client, batch_size=5, progress=False, log=quiet)
    original = _submit.write_region

    def full_from_batch_2(nc, shape, histories, batch, result):
        if batch.index >= 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "full.zarr.partial"))
        original(nc, shape, histories, batch, result)

    monkeypatch.setattr(_submit, "write_region", full_from_batch_2)
    with pytest.raises(SweepError) as info:
        run_sweep(study, tmp_path / "full.zarr", client=client, batch_size=5, progress=False, log=quiet)
    message = str(info.value)
    assert "\n" not in message and "No space left on device" in message and "re-run" in message
    # batches 0 and 1 run beside batch 2 on the two workers: when batch 2 fails, 0, 1 or 2 of them are done
    kept = re.search(r"the (\d+) finished batch\(es\) are kept in \S*full\.zarr\.partial", message)
    assert kept is not None and 0 <= int(kept.group(1)) <= 2, message
    assert not (tmp_path / "full.zarr").exists()
    monkeypatch.setattr(_submit, "write_region", original)
    report = run_sweep(study, tmp_path / "full.zarr", client=client, batch_size=5, progress=False, log=quiet)
    # what was kept is resumed (a batch still running at the failure may have finished since)
    assert int(kept.group(1)) <= report.n_resumed_batches <= 2 and report.n_failed_batches == 0
    _same(ref, tmp_path / "full.zarr")


def test_a_finished_zarr_result_is_reused_then_replaced_by_another_study(client, tmp_path):
    study = parse_study(GRID)
    out = tmp_path / "u.zarr"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    messages = []
    assert run_sweep(study, out, client=client, progress=False, log=messages.append).reused
    changed = parse_study(GRID.replace("t_end = 4.0", "t_end = 2.0"))
    assert not run_sweep(changed, out, client=client, progress=False, log=quiet).reused
    with xr.open_zarr(out) as ds:
        assert ds.sizes["t"] == 41 and ds.attrs["study_sha256"] == changed.key
    assert sorted(p.name for p in tmp_path.iterdir()) == ["u.zarr"]


def test_workers_that_do_not_see_the_output_folder_are_a_one_line_error(client, tmp_path, monkeypatch):
    from screening.io.errors import SweepError

    monkeypatch.setattr(_submit, "sees_folder", lambda path: False)
    with pytest.raises(SweepError, match=r"2 dask worker\(s\) .* do not see .*shared file system"):
        run_sweep(parse_study(GRID), tmp_path / "far.zarr", client=client, progress=False, log=quiet)
    assert not (tmp_path / "far.zarr").exists()


def test_a_folder_that_is_not_a_zarr_store_is_refused(tmp_path, capsys):
    (tmp_path / "x.zarr").mkdir()
    (tmp_path / "x.zarr" / "keep.txt").write_text("mine")
    study = tmp_path / "s.toml"
    study.write_text(GRID)
    assert main(["run", str(study), "--out", str(tmp_path / "x.zarr")]) == 2
    assert "not a zarr store" in capsys.readouterr().err
    assert (tmp_path / "x.zarr" / "keep.txt").read_text() == "mine"


def test_export_gives_the_netcdf_file_of_a_direct_run(client, tmp_path, capsys):
    study = parse_study(GRID.replace("k = 2.89e7", "k = [2.0e7, 2.89e7]") + SPOTS + FRAGILITY,
                        name="e", source="e.toml")
    run_sweep(study, tmp_path / "direct.nc", client=client, progress=False, log=quiet)
    run_sweep(study, tmp_path / "e.zarr", client=client, progress=False, log=quiet)
    assert main(["export", str(tmp_path / "e.zarr"), str(tmp_path / "exported.nc")]) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "exported.nc")
    compare_files(tmp_path / "direct.nc", tmp_path / "exported.nc")
    with xr.open_dataset(tmp_path / "exported.nc") as ds:
        assert "screening export" in ds.attrs["history"].splitlines()[-1]
        assert ds["status"].attrs["flag_values"].dtype == np.int8
    if CHECKER.exists():
        proc = subprocess.run([str(CHECKER), "--test=cf:1.8", "--criteria=strict", str(tmp_path / "exported.nc")],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0 and "All tests passed!" in proc.stdout, proc.stdout + proc.stderr
    # bad input: one line, exit 2, nothing written
    assert main(["export", str(tmp_path / "direct.nc"), str(tmp_path / "x.nc")]) == 2
    assert "not a zarr store" in capsys.readouterr().err and not (tmp_path / "x.nc").exists()
    # the CDO form (time first, p_exceed per threshold) from the zarr store and from the netCDF file
    for source in ("e.zarr", "direct.nc"):
        assert main(["export", str(tmp_path / source), str(tmp_path / f"{source}.cdo.nc"), "--layout", "cdo"]) == 0
        assert_cdo_form_of(tmp_path / source, tmp_path / f"{source}.cdo.nc")
    compare_files(tmp_path / "e.zarr.cdo.nc", tmp_path / "direct.nc.cdo.nc")
    with xr.open_dataset(tmp_path / "e.zarr.cdo.nc", decode_times=False) as ds:
        assert [float(ds[f"p_exceed_{i}"].attrs["threshold"]) for i in range(2)] == [0.01, 0.02]


def test_info_and_plot_read_a_zarr_result(client, tmp_path, capsys):
    run_sweep(parse_study(GRID), tmp_path / "i.zarr", client=client, progress=False, log=quiet)
    assert main(["info", str(tmp_path / "i.zarr")]) == 0
    assert "ok" in capsys.readouterr().out
    assert main(["plot", str(tmp_path / "i.zarr")]) == 0
    assert (tmp_path / "i_peaks.png").is_file()


# ----------------------------------------------------------------------------- a real cluster
@pytest.fixture
def scheduler_file(tmp_path):
    """``dask scheduler`` + two ``dask worker --nworkers 1 --nthreads 1`` (nanny) processes on 127.0.0.1,
    ports chosen by the system, found through a scheduler file (terminated afterwards)."""
    with dask_processes(tmp_path, ["--nworkers", "1", "--nthreads", "1", "--host", "127.0.0.1",
                                   "--no-dashboard"]) as sched_file:
        yield sched_file


def test_dask_scheduler_and_worker_processes_write_a_zarr_result(scheduler_file, client, tmp_path):
    from distributed import Client

    with Client(scheduler_file=str(scheduler_file), timeout="30s") as probe:
        probe.wait_for_workers(2, timeout=60)
        worker_pids = set(probe.run(os.getpid).values())
    assert os.getpid() not in worker_pids and len(worker_pids) == 2
    study = parse_study(CASES)
    report = run_sweep(study, tmp_path / "remote.zarr", scheduler=str(scheduler_file), batch_size=2, progress=False,
                       log=quiet)
    assert report.n_workers == 2 and report.status_counts == {"ok": 6}
    run_sweep(study, tmp_path / "local.nc", client=client, batch_size=3, progress=False, log=quiet)
    _same(tmp_path / "local.nc", tmp_path / "remote.zarr", ignore=("batch_size",))


def test_fragility_of_a_zarr_result_is_named_after_its_stem(client, tmp_path):
    study = parse_study(GRID, name="s", source="s.toml")
    run_sweep(study, tmp_path / "r.zarr", client=client, batch_size=5, progress=False, log=quiet)
    assert main(["fragility", str(tmp_path / "r.zarr"), "--threshold", "0.2", "--relative-to", "slenderness"]) == 0
    assert (tmp_path / "r_fragility.nc").exists() and not (tmp_path / "r.zarr_fragility.nc").exists()


@pytest.mark.parametrize("layout", ["cf", "cdo"])
def test_export_of_a_damaged_store_names_the_store_and_writes_nothing(client, tmp_path, capsys, layout):
    """A chunk of the result damaged after the run: the export says it cannot read the result (it
    used to say it could not write the output) and leaves no output behind."""
    run_sweep(parse_study(GRID), tmp_path / "d.zarr", client=client, progress=False, log=quiet)
    chunk = next(p for p in sorted((tmp_path / "d.zarr" / "var_theta").rglob("*")) if p.is_file()
                 and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[:10])
    out = tmp_path / "out.nc"
    assert main(["export", str(tmp_path / "d.zarr"), str(out), "--layout", layout]) == 2
    err = one_line_error(capsys.readouterr().err)
    assert f"cannot read {tmp_path / 'd.zarr'}: " in err and "nothing written" in err and "out.nc" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.zarr"]


def _status_chunk(store):
    return next(p for p in sorted((store / "status" / "c").rglob("*")) if p.is_file())


def test_a_finished_store_missing_a_chunk_is_neither_reused_nor_read_nor_exported(client, tmp_path, capsys):
    """A deleted chunk would read as zarr's fill value: it is damage, seen by reuse, info and export, and
    a never-written status chunk reads as task_failed, not ok."""
    study = parse_study(GRID)
    out = tmp_path / "m.zarr"
    run_sweep(study, out, client=client, batch_size=5, progress=False, log=quiet)
    chunk = _status_chunk(out)
    chunk.unlink()
    with xr.open_zarr(out) as ds:
        assert np.all(ds["status"].values[0] == PointStatus.task_failed)
    for argv in (["info", str(out)], ["export", str(out), str(tmp_path / "x.nc")],
                 ["export", str(out), str(tmp_path / "x.nc"), "--layout", "cdo"]):
        assert main(argv) == 2
        err = one_line_error(capsys.readouterr().err)
        assert "status/c/" in err and "missing" in err, err
    assert not (tmp_path / "x.nc").exists()
    messages = []
    report = run_sweep(study, out, client=client, batch_size=5, progress=False, log=messages.append)
    assert not report.reused and any("computing it again" in m and "missing" in m for m in messages)
    assert report.status_counts == {"ok": study.n_points}
    # a chunk zeroed at its size: only the checksum of the completion mark sees it
    chunk = _status_chunk(out)
    chunk.write_bytes(bytes(chunk.stat().st_size))
    assert main(["export", str(out), str(tmp_path / "x.nc")]) == 2
    assert "checksum" in one_line_error(capsys.readouterr().err)
    assert not run_sweep(study, out, client=client, batch_size=5, progress=False, log=quiet).reused


def test_the_store_of_an_interrupted_run_is_not_a_result(client, tmp_path, capsys):
    study = parse_study(GRID)
    interrupted_run(study, tmp_path / "i.zarr", client, batch_size=5)
    building = tmp_path / "i.zarr.partial" / "result.zarr.building"
    assert (building / "zarr.json").is_file()
    for argv in (["export", str(building), str(tmp_path / "x.nc")], ["info", str(building)]):
        assert main(argv) == 2
        assert "no completion mark" in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "x.nc").exists()


def test_a_store_with_files_screening_did_not_write_is_never_replaced(client, tmp_path, capsys):
    """``--out x.zarr`` over a finished store: replaced; over one holding a file of the user's: one line,
    exit 2, the folder untouched -- also when the file appears during the run."""
    study_file = tmp_path / "s.toml"
    study_file.write_text(GRID)
    out = tmp_path / "x.zarr"
    run_sweep(parse_study(GRID), out, client=client, batch_size=5, progress=False, log=quiet)
    (out / "notes.txt").write_text("mine")
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    assert main(["run", str(study_file), "--out", str(out), "--force", "--no-plots", "--workers", "0"]) == 2
    assert "notes.txt" in one_line_error(capsys.readouterr().err)
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert (out / "notes.txt").read_text() == "mine"
    # the user's file appears while the run computes: the finished result waits in the partial folder
    (out / "notes.txt").unlink()
    from screening.io.errors import SweepError

    def add_notes(batch):
        (out / "notes.txt").write_text("mine")

    changed = parse_study(GRID.replace("t_end = 4.0", "t_end = 2.0"))
    with pytest.raises(SweepError, match="notes.txt"):
        run_sweep(changed, out, client=client, batch_size=5, progress=False, log=quiet, on_batch=add_notes)
    assert (out / "notes.txt").read_text() == "mine"
    (out / "notes.txt").unlink()
    report = run_sweep(changed, out, client=client, batch_size=5, progress=False, log=quiet)
    assert report.n_resumed_batches == report.n_batches
    with xr.open_zarr(out) as ds:
        assert ds.attrs["study_sha256"] == changed.key


@pytest.mark.parametrize("entry", ["done", "result.zarr.building"])
def test_links_planted_in_the_partial_folder_are_not_followed(client, tmp_path, entry):
    study = parse_study(GRID)
    out = tmp_path / "l.zarr"
    interrupted_run(study, out, client, batch_size=5)
    while any(client.processing().values()):     # tasks already running finish first
        time.sleep(0.05)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "keep.txt").write_text("mine")
    planted = tmp_path / "l.zarr.partial" / entry
    import shutil

    shutil.rmtree(planted)
    planted.symlink_to(elsewhere, target_is_directory=True)
    report = run_sweep(study, out, client=client, batch_size=5, progress=False, log=quiet)
    assert report.status_counts == {"ok": study.n_points}
    assert sorted(p.name for p in elsewhere.iterdir()) == ["keep.txt"]


def test_export_into_its_own_store_is_refused(client, tmp_path, capsys):
    out = tmp_path / "r.zarr"
    run_sweep(parse_study(GRID), out, client=client, progress=False, log=quiet)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    for target in (out / "zarr.json", out / "status" / "x.nc"):
        assert main(["export", str(out), str(target)]) == 2
        assert "inside the input" in one_line_error(capsys.readouterr().err)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert main(["info", str(out)]) == 0


def test_a_damaged_store_is_one_line_without_asyncio_noise(client, tmp_path):
    """Chunks damaged at their size (the cheap check of info/plot cannot see them): zarr's abandoned
    concurrent reads must not print pages of asyncio reports after the one-line error."""
    out = tmp_path / "n.zarr"
    run_sweep(parse_study(GRID), out, client=client, batch_size=1, progress=False, log=quiet)
    for chunk in (out / "status" / "c").rglob("*"):
        if chunk.is_file():
            chunk.write_bytes(b"\x01" * chunk.stat().st_size)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    for command in ("info", "plot"):
        proc = subprocess.run([sys.executable, "-m", "screening.cli", command, str(out)], capture_output=True,
                              text=True, env=env, timeout=300)
        assert proc.returncode == 2
        assert "damaged" in one_line_error(proc.stderr)


def test_export_of_foreign_attributes(client, tmp_path, capsys):
    """A JSON object as a variable attribute and a null global attribute (zarr holds both, netCDF neither)
    are exported as JSON text / left out; ragged flag_values are one line, exit 2."""
    import zarr

    from screening.io._zarr_store import write_completion_mark

    out = tmp_path / "f.zarr"
    run_sweep(parse_study(GRID), out, client=client, progress=False, log=quiet)
    group = zarr.open_group(out, mode="r+")
    group["peak_var_theta"].attrs["provenance"] = {"tool": "other", "n": [1, 2]}
    group.attrs["empty"] = None
    zarr.consolidate_metadata(out)
    write_completion_mark(out)                   # as if the foreign tool had finished the store
    for layout in ("cf", "cdo"):
        target = tmp_path / f"{layout}.nc"
        assert main(["export", str(out), str(target), "--layout", layout]) == 0, capsys.readouterr().err
        with xr.open_dataset(target, decode_times=False) as ds:
            assert json.loads(ds["peak_var_theta"].attrs["provenance"]) == {"tool": "other", "n": [1, 2]}
            assert "empty" not in ds.attrs
    capsys.readouterr()
    group["sl_trust"].attrs["flag_values"] = [[0, 1], [2]]
    zarr.consolidate_metadata(out)
    write_completion_mark(out)
    for layout in ("cf", "cdo"):
        assert main(["export", str(out), str(tmp_path / "x.nc"), "--layout", layout]) == 2
        assert "flag_values of sl_trust" in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "x.nc").exists()


def test_export_of_an_accuracy_result_keeps_the_integer_fill_values(client, tmp_path, capsys):
    """Issue 36 item 6: export dropped esc_sample_state's _FillValue (its padding read -1, outside its
    flag_values); the exported file equals a direct netCDF run, variable by variable."""
    # a budget that does not bind: the two runs escalate the same points (a binding wall-clock budget may not)
    text = GRID.replace("k = 2.89e7", "k = [2.0e7, 2.89e7]") + "[accuracy]\ntarget = 0.15\nbudget_s = 600000\n"
    study = parse_study(text, name="a", source="a.toml")
    run_sweep(study, tmp_path / "direct.nc", client=client, progress=False, log=quiet)
    run_sweep(study, tmp_path / "a.zarr", client=client, progress=False, log=quiet)
    assert main(["export", str(tmp_path / "a.zarr"), str(tmp_path / "exported.nc")]) == 0
    with xr.open_dataset(tmp_path / "direct.nc") as a, xr.open_dataset(tmp_path / "exported.nc") as b:
        a, b = (ds.load().drop_vars("esc_cpu_time") for ds in (a, b))      # CPU times of two runs differ
        for ds in (a, b):
            for name in ("history", "date_created", "batch_size", "accuracy_cpu_s", "accuracy_wall_s", "accuracy_note"):
                ds.attrs.pop(name, None)
        xr.testing.assert_identical(a, b)
        assert a["esc_sample_state"].encoding.get("_FillValue") == -1 == b["esc_sample_state"].encoding["_FillValue"]
    import netCDF4

    with netCDF4.Dataset(tmp_path / "direct.nc") as a, netCDF4.Dataset(tmp_path / "exported.nc") as b:
        assert a["esc_sample_state"].dimensions == b["esc_sample_state"].dimensions
        for name in a.variables:
            assert getattr(a[name], "_FillValue", None) is not None or getattr(b[name], "_FillValue", None) is None, name
            if hasattr(a[name], "_FillValue"):
                assert np.array_equal(np.asarray(a[name]._FillValue), np.asarray(b[name]._FillValue),
                                      equal_nan=a[name].dtype.kind == "f"), name
