"""Issue 13, "the first hour": small studies run in this process (no cluster), with the same results
and the same resume as on worker processes."""

import pytest

from helpers import GRID, compare_files, quiet

from screening.cli import main
from screening.sweep.execution import IN_PROCESS_MAX_POINTS, default_workers
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep


@pytest.fixture(scope="module")
def reference(client, tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "ref.nc"
    run_sweep(parse_study(GRID), out, client=client, batch_size=3, progress=False, log=quiet)
    return out


def test_workers_0_runs_in_process_with_the_same_results_and_resume(reference, tmp_path):
    out = tmp_path / "r.nc"

    def stop(batch, seen=[]):
        seen.append(batch.index)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(parse_study(GRID), out, workers=0, batch_size=3, progress=False, log=quiet, on_batch=stop)
    lines = []
    report = run_sweep(parse_study(GRID), out, workers=0, batch_size=3, progress=False, log=lines.append)
    assert report.n_workers == 1 and report.n_resumed_batches == 2
    assert any(line.startswith("resuming: 2 of") for line in lines)
    compare_files(reference, out)


def _study(points, spots=None):
    text = GRID.replace("S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}",
                        f"S0 = {{start = 1e-5, stop = 2.4e-3, num = {points // 4}, log = true}}")
    if spots is not None:
        text += f"[mcs]\npoints = \"auto\"\ncount = {spots}\nsamples = 10\n"
    return parse_study(text)


@pytest.mark.parametrize("points, spots, expected", [
    (20, None, 0), (IN_PROCESS_MAX_POINTS, 1, 0),             # small: in this process
    (IN_PROCESS_MAX_POINTS + 4, None, 2), (20, 2, 2)])        # neighbours: a larger grid, two spot checks
def test_default_workers_in_process_for_small_studies(points, spots, expected):
    assert default_workers(_study(points, spots)) == expected


def test_negative_workers_is_one_line(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(GRID)
    assert main(["run", str(study), "--workers", "-1", "--out", str(tmp_path / "r.nc")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--workers" in err[0] and "0..256" in err[0]
