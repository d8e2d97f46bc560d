"""Nothing lost, nothing misread: the regressions of issue 36 that go through the command line and result
files, and the stopped points of the collection issue ("no stopped point reads as an answer").

Each test names its item; each failed before its fix."""

import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from helpers import study_text

from screening.cli import main
from screening.core.status import PointStatus, ProbabilitySource

ROOT = Path(__file__).resolve().parents[2]

#: The sweep grid up to S0 = 2e-2: the last column stops (k_eq_negative); [fragility] and two spot checks.
STOPPING = study_text({"excitation.S0": "{start = 1e-5, stop = 2e-2, num = 5, log = true}"},
                      append='[fragility]\nthresholds = [0.1, 0.5]\nrelative_to = "slenderness"\n'
                             '[mcs]\npoints = "auto"\ncount = 2\nsamples = 8\nmodel = "condensed"\n')


def _one_line_error(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("screening: error: "), err
    return err[0]


@pytest.fixture(scope="module")
def stopping(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stopping")
    (folder / "s.toml").write_text(STOPPING)
    assert main(["run", str(folder / "s.toml"), "--out", str(folder / "s.nc"), "--workers", "0", "--quiet",
                 "--no-plots"]) == 0
    return folder / "s.nc"


def test_stopped_points_hold_missing_probabilities_not_one(stopping):
    """Collection issue item 5 / issue 36 "also": p_overturn, p_exceed and their standard errors are NaN
    where the linearization stopped and no Monte Carlo ran, never 1.0."""
    with xr.open_dataset(stopping) as ds:
        stopped = ds["status"].isin([PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness])
        alone = stopped & (ds["p_source"] == ProbabilitySource.unreliable)
        assert int(alone.sum()) >= 2, "the grid needs stopped points without Monte Carlo"
        for name in ("p_overturn", "p_overturn_se", "p_exceed", "p_exceed_se"):
            assert bool(ds[name].where(alone).isnull().where(alone, True).all()), name
        assert not bool((ds["p_overturn"] == 1.0).any())


def test_mcs_model_is_an_integer_flag_variable(stopping):
    """Item 12: mcs_model read back as float32 (its -1 fill value); now int8 with flag_values for every value."""
    with xr.open_dataset(stopping) as ds:
        v = ds["mcs_model"]
        assert v.dtype == np.int8 and "_FillValue" not in v.encoding or v.encoding["_FillValue"] is None
        assert set(v.values.tolist()) <= set(v.attrs["flag_values"].tolist())
        assert v.attrs["flag_meanings"].split()[0] == "none"


@pytest.mark.parametrize("suffix", [".csv", ".xml", ".png"])
@pytest.mark.parametrize("im", [[], ["--im", "pga"]], ids=["grid", "im"])
def test_an_out_named_like_another_output_is_refused_before_any_work(stopping, tmp_path, capsys, suffix, im):
    """Item 2: fragility R.nc --out f.csv (.xml, .png) sent two files to one path and exited 0."""
    out = tmp_path / f"f{suffix}"
    args = ["fragility", str(stopping), "--threshold", "0.1", "--relative-to", "slenderness", *im]
    assert main(args + ["--out", str(out)]) == 2
    line = _one_line_error(capsys)
    assert str(out) in line and "--out" in line
    assert list(tmp_path.iterdir()) == []


def test_with_several_limit_states_the_fit_files_are_still_protected(stopping, tmp_path, capsys):
    assert main(["fragility", str(stopping), "--threshold", "0.1", "--threshold", "0.5", "--relative-to",
                 "slenderness", "--out", str(tmp_path / "f.csv")]) == 2
    _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []


def test_simulate_and_cloud_refuse_an_out_named_like_their_other_outputs(tmp_path, capsys, monkeypatch):
    """Item 2: simulate --out s.png, cloud --out c.csv or --out e_demand.csv."""
    from screening.core.model.excitation import Envelope
    from screening.core.excitations.kanai_tajimi import KanaiTajimi
    from screening.applications.cloud import synthesise_records

    synthesise_records(tmp_path / "rec", KanaiTajimi(1e-3, 15.6, 0.6, Envelope(1.0, 0.5), band_limit_hz=None), 2,
                       2.0, 100.0, [1.0, 2.0], seed=3)      # at 100 rad/s: no room for the 25-Hz band
    block = "[block]\nm = 8.67\nb = 0.035\nh = 0.21\n[foundation]\nk = 2.89e7\nlam = 8.95e8\n"
    (tmp_path / "c.toml").write_text(block + '[records]\nfiles = "rec"\nthreshold = 0.1\n')
    record = sorted((tmp_path / "rec").iterdir())[0]
    monkeypatch.chdir(tmp_path)
    for args in (["cloud", "c.toml", "--out", "c.csv"], ["cloud", "c.toml", "--out", "e_demand.csv"],
                 ["cloud", "c.toml", "--out", "c.xml"],
                 ["simulate", str(record), "--study", "c.toml", "--out", "s.png"]):
        assert main(args) == 2, args
        assert "--out" in _one_line_error(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml", "rec"]


def test_a_record_error_names_the_file_once(tmp_path, capsys):
    """Item 12: 'cannot read record R: R: the time column must increase strictly'."""
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3\nx y\n")
    (tmp_path / "s.toml").write_text("[block]\nm = 8.67\nb = 0.035\nh = 0.21\n[foundation]\nk = 2.89e7\nlam = 8.95e8\n")
    for target in (bad, tmp_path / "missing.txt"):
        assert main(["simulate", str(target), "--study", str(tmp_path / "s.toml"), "--dt", "0.01", "--units",
                     "g"]) == 2
        line = _one_line_error(capsys)
        assert line.count(str(target)) == 1, line


def test_simulate_writes_to_outputs_by_default_like_cloud(tmp_path, capsys, monkeypatch):
    """Item 12: simulate wrote to the current folder by default, cloud to outputs/."""
    t = np.arange(0.0, 1.0, 0.01)
    (tmp_path / "r.txt").write_text("\n".join(f"{x:.2f} {0.05 * np.sin(12 * x):.6f}" for x in t))
    (tmp_path / "s.toml").write_text("[block]\nm = 8.67\nb = 0.035\nh = 0.21\n[foundation]\nk = 2.89e7\nlam = 8.95e8\n")
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "r.txt", "--study", "s.toml", "--units", "g", "--no-plots"]) == 0
    assert (tmp_path / "outputs" / "r_simulation.nc").is_file()
    assert not (tmp_path / "r_simulation.nc").exists()


CLOUGH_PENZIEN = """
title = "a degenerate high-pass at one point"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = 6e7
[excitation]
kind = "clough_penzien"
S0 = [1e-4, 5e-4]
omega_g = 15.0
zeta_g = 0.6
omega_f = 1.5
zeta_f = [0.8, 1e-21]
[time]
t_end = 2.0
dt = 0.1
"""


def test_a_degenerate_clough_penzien_point_is_flagged_alone(tmp_path, capsys):
    """Item 4: zeta_f <= 1e-20 raised LinAlgError in the batch; every point of the batch ended task_failed
    and the worker's traceback was printed even with --workers 0."""
    (tmp_path / "cp.toml").write_text(CLOUGH_PENZIEN)
    assert main(["run", str(tmp_path / "cp.toml"), "--out", str(tmp_path / "cp.nc"), "--workers", "0",
                 "--quiet", "--no-plots", "--batch-size", "4"]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "LinAlgError" not in err
    with xr.open_dataset(tmp_path / "cp.nc") as ds:
        status = ds["status"].transpose("S0", "zeta_f").values
    assert (status[:, 0] == PointStatus.ok).all()
    assert (status[:, 1] == PointStatus.beyond_float_range).all()


def test_fragility_of_a_spots_only_result_uses_its_stored_probabilities(tmp_path, capsys):
    """Item 5: histories = "spots" with [fragility] gave KeyError: 'var_theta' in 'screening fragility'."""
    text = STOPPING + '[output]\nhistories = "spots"\n'
    (tmp_path / "h.toml").write_text(text)
    assert main(["run", str(tmp_path / "h.toml"), "--out", str(tmp_path / "h.nc"), "--workers", "0", "--quiet",
                 "--no-plots"]) == 0
    out = tmp_path / "f.nc"
    assert main(["fragility", str(tmp_path / "h.nc"), "--threshold", "0.5", "--relative-to", "slenderness",
                 "--out", str(out)]) == 0
    with xr.open_dataset(tmp_path / "h.nc") as ds, xr.open_dataset(out) as frag:
        stored = ds["p_exceed"].isel(threshold=1).where(ds["p_source"] != ProbabilitySource.unreliable)
        np.testing.assert_array_equal(frag["p_exceed"].transpose(*stored.dims).values, stored.values)
    capsys.readouterr()
    assert main(["fragility", str(tmp_path / "h.nc"), "--threshold", "0.3", "--relative-to", "slenderness",
                 "--out", str(tmp_path / "g.nc")]) == 2
    line = _one_line_error(capsys)
    assert "0.1, 0.5" in line and "histories" in line


def test_the_stiff_bed_tolerance_is_documented_as_the_code_has_it():
    """Item 10: docs/model_choice.md said the stiff-bed tolerance stays 1e-7; the code has 1e-5."""
    from screening.solvers.stiff_bed import StiffBedModel

    text = (ROOT / "docs" / "model_choice.md").read_text()
    assert "stays `1e-7`" not in text
    stated = re.search(r"the default\s+became `([0-9.e-]+)`", text)
    assert stated and float(stated.group(1)) == StiffBedModel.default_rtol


def test_distributed_doc_stops_processes_by_pid():
    """Item 12: 'kill %2 %1' works only in the shell that started the jobs."""
    text = (ROOT / "docs" / "distributed.md").read_text()
    commands = re.findall(r"^kill .*$", text, flags=re.M)
    assert commands and not any("%" in c for c in commands)
    assert "$!" in text


def test_the_quickstart_fragility_stands_on_vouched_points():
    """Collection issue item 5: the README's quickstart study gives its curve vouched-for points (Monte Carlo
    where the linearization is not trusted, and p_exceed stored at its threshold with p_source)."""
    from screening.sweep.study import load_study

    study = load_study(ROOT / "examples" / "collection.toml")
    assert study.accuracy is not None and study.fragility is not None
    assert list(study.fragility.thresholds) == [0.05, 0.1, 0.3]
    assert study.fragility.relative_to == "slenderness"
    readme = (ROOT / "README.md").read_text()
    assert "fragility outputs/collection.nc --limit-state overturn" in readme


def test_a_target_pga_point_with_a_filter_beyond_float_range_is_flagged_not_a_crash(tmp_path, capsys):
    """A neighbour of item 4 (one bad point sinks its batch): omega_g = 1e-300 at one point of a target-PGA
    study made QUADPACK crash the whole process (segmentation fault) while S0 was derived from the PGA."""
    text = CLOUGH_PENZIEN.replace('kind = "clough_penzien"\nS0 = [1e-4, 5e-4]\nomega_g = 15.0',
                                  'kind = "kanai_tajimi"\npga = [1.0, 2.0]\nomega_g = [15.0, 1e-300]')
    text = text.replace("omega_f = 1.5\nzeta_f = [0.8, 1e-21]\n", "")
    (tmp_path / "kt.toml").write_text(text)
    assert main(["run", str(tmp_path / "kt.toml"), "--out", str(tmp_path / "kt.nc"), "--workers", "0", "--quiet",
                 "--no-plots"]) == 0
    with xr.open_dataset(tmp_path / "kt.nc") as ds:
        status = ds["status"].transpose("pga", "omega_g").values
    assert (status[:, 1] == PointStatus.beyond_float_range).all() and (status[:, 0] != PointStatus.task_failed).all()
    assert "RuntimeWarning" not in capsys.readouterr().err
