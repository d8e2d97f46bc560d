"""The ``screening`` command line: run / plot / info end to end, errors, kill and resume."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from helpers import compare_files, in_process_client, one_line_error, quiet

from screening import __version__, linearize
from screening.cli import main
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.solvers.schema import LINEARIZATION as VARIABLES, PARAMETERS
from screening.sweep.study import build_models, parse_study

SCREENING = Path(sys.executable).parent / "screening"

STUDY = """
title = "CLI end-to-end"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
# the paper's condensation: the values are compared bit for bit with direct calls on another batch
# layout, and the default's uplift threshold (the cubic root, vectorised numpy) can differ in its
# last bit between array layouts
condensation = "paper"
k = 2.89e7
lam = 8.95e8
eps = [-6e5, 2e7, 6e7]
[excitation]
kind = "white"
S0 = {start = 2e-5, stop = 2.4e-3, num = 4, log = true}
[time]
t_end = 6.0
dt = 0.05
[mcs]
points = "auto"
count = 1
samples = 8
model = "condensed"
"""


# ----------------------------------------------------------------------------- end to end
@pytest.fixture(scope="module")
def cli_result(tmp_path_factory):
    """``screening run study.toml --workers 2`` from a fresh folder (default output path)."""
    folder = tmp_path_factory.mktemp("cli")
    (folder / "study.toml").write_text(STUDY)
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        code = main(["run", "study.toml", "--workers", "2", "--quiet"])
    finally:
        os.chdir(cwd)
    assert code == 0
    return folder


def test_run_writes_netcdf_and_pngs_at_the_default_place(cli_result):
    out = cli_result / "outputs"
    assert (out / "study.nc").is_file()
    for kind in ("histories", "peaks", "spots"):
        png = out / f"study_{kind}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert not (out / "study.nc.partial").exists()


def test_run_values_equal_direct_solver_calls(cli_result):
    study = parse_study(STUDY)
    with xr.open_dataset(cli_result / "outputs" / "study.nc") as ds:
        assert ds["var_theta"].dims == ("eps", "S0", "t")
        np.testing.assert_array_equal(ds["eps"].values, study.sweeps["eps"])
        np.testing.assert_array_equal(ds["S0"].values, study.sweeps["S0"])
        np.testing.assert_array_equal(ds["t"].values, study.times)
        assert ds["eps"].attrs["units"] == PARAMETERS["eps"]["units"]
        assert ds["S0"].attrs["units"] == PARAMETERS["S0"]["units"]
        assert ds["t"].attrs["units"] == "s"
        for name in HISTORY_VARIABLES:
            assert ds[name].attrs["units"] == VARIABLES[name]["units"]

        # the whole grid in one direct batched call
        eps = study.sweeps["eps"][:, None]
        s0 = study.sweeps["S0"][None, :]
        direct = solve_moments(*build_models(study.cases[0], {"eps": eps, "S0": s0}), study.times,
                               condensation=study.cases[0].condensation_model)
        for name in HISTORY_VARIABLES:
            np.testing.assert_array_equal(ds[name].values, direct[name].astype(np.float32), err_msg=name)
        for name in ("status", "t_stop", "n_steps", "n_rejected", "peak_var_theta", "t_peak_var_theta",
                     "peak_p_uplift", "min_k_eq"):
            np.testing.assert_array_equal(ds[name].values, direct[name], err_msg=name)

        # and single points through linearize()
        for e, s in ((6e7, study.sweeps["S0"][0]), (-6e5, study.sweeps["S0"][-1])):
            one = linearize(*build_models(study.cases[0], {"eps": e, "S0": s}), t_end=6.0, dt=0.05,
                            condensation=study.cases[0].condensation_model)
            point = ds.sel(eps=e, S0=s)
            np.testing.assert_array_equal(point["var_theta"].values, one["var_theta"].values.astype(np.float32))
            assert float(point["peak_var_theta"]) == float(one["peak_var_theta"])
            assert float(point["theta_ul"]) == float(one["theta_ul"])

        # the spot check sits at the highest peak uplift probability
        upl = np.where(ds["status"].values == 0, ds["peak_p_uplift"].values, -1.0)
        i, j = np.unravel_index(np.argmax(upl), upl.shape)
        assert (float(ds["spot_eps"][0]), float(ds["spot_S0"][0])) == (study.sweeps["eps"][i], study.sweeps["S0"][j])
        assert np.isfinite(float(ds["mcs_rel_error_peak_var_theta"][0]))


def test_rerun_reuses_the_result(cli_result, capsys):
    out = cli_result / "outputs" / "study.nc"
    stamp = out.stat().st_mtime_ns
    code = main(["run", str(cli_result / "study.toml"), "--out", str(out), "--quiet"])
    assert code == 0
    assert "up to date" in capsys.readouterr().err
    assert out.stat().st_mtime_ns == stamp


def test_info_describes_the_result(cli_result, capsys):
    assert main(["info", str(cli_result / "outputs" / "study.nc")]) == 0
    text = capsys.readouterr().out
    assert "dimensions: eps (3), S0 (4), t (121), spot (1), sample (8); 12 grid point(s)" in text
    assert "eps      3 values, -6e+05 .. 6e+07 m-2" in text
    assert "S0       4 values, 2e-05 .. 0.0024 m2 s-3" in text
    assert "status: ok 12" in text
    assert "peak_var_theta" in text and "min_k_eq" in text
    assert "Monte Carlo spot checks (condensed, 8 samples" in text


def test_plot_command_writes_pngs_into_out_dir(cli_result, tmp_path, capsys):
    assert main(["plot", str(cli_result / "outputs" / "study.nc"), "--out-dir", str(tmp_path)]) == 0
    printed = capsys.readouterr().out.split()
    assert sorted(Path(p).name for p in printed) == ["study_histories.png", "study_peaks.png",
                                                     "study_spot0_eps_-6e+05__S0_0.0024.png", "study_spots.png"]
    assert all(Path(p).stat().st_size > 10_000 for p in printed)


# ----------------------------------------------------------------------------- errors
def test_missing_output_folder_exits_2(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(STUDY)
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "missing" / "r.nc")]) == 2
    assert "output folder" in one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


@pytest.mark.parametrize("command", ["info", "plot"])
def test_unreadable_results_exit_2(tmp_path, capsys, command):
    corrupt = tmp_path / "corrupt.nc"
    corrupt.write_bytes(b"\x89HDF\r\n\x1a\n" + os.urandom(2000))
    assert main([command, str(corrupt)]) == 2
    assert "cannot read the result file" in one_line_error(capsys.readouterr().err)
    assert main([command, str(tmp_path / "absent.nc")]) == 2
    assert "no such result file" in one_line_error(capsys.readouterr().err)
    foreign = tmp_path / "foreign.nc"
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(foreign)
    assert main([command, str(foreign)]) == 2
    assert "not a screening sweep result" in one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["corrupt.nc", "foreign.nc"]   # nothing written


def test_plot_into_missing_folder_creates_it(cli_result, tmp_path, capsys):
    """The README's ``plot --out-dir figs``: a missing folder is created; one whose parent is missing
    too is one line, exit 2."""
    code = main(["plot", str(cli_result / "outputs" / "study.nc"), "--out-dir", str(tmp_path / "nope" / "deeper")])
    assert code == 2
    assert "output folder" in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "nope").exists()
    assert main(["plot", str(cli_result / "outputs" / "study.nc"), "--out-dir", str(tmp_path / "figs")]) == 0
    assert list((tmp_path / "figs").glob("*.png"))


@pytest.mark.parametrize("argv, needle", [(["run", "x.toml", "--workers", "-1"], "--workers"),
                                          (["run", "x.toml", "--workers", "2", "--scheduler", "a"], "not allowed"),
                                          (["launch"], "invalid choice"), ([], "required")])
def test_usage_errors_are_one_line(capsys, argv, needle):
    assert main(argv) == 2
    assert needle in one_line_error(capsys.readouterr().err)


def test_console_script_reports_errors_without_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(STUDY.replace("k = 2.89e7", "k = 0.0"))
    proc = subprocess.run([str(SCREENING), "run", str(bad)], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"screening: error: {bad}: foundation.k: must be a finite number > 0 (got 0.0)"]
    assert not (tmp_path / "outputs").exists()


# ----------------------------------------------------------------------------- kill and resume
@pytest.mark.parametrize("value, needle", [
    ("0", 'excitation.band_limit_hz: must be a number in (0, 1e+05] Hz or "none" (got 0)'),
    ("nan", 'excitation.band_limit_hz: must be a number in (0, 1e+05] Hz or "none" (got nan)'),
    ('"wide"', "excitation.band_limit_hz: must be a number in (0, 1e+05] Hz or \"none\" (got 'wide')"),
    ("5e4", 'excitation.band_limit_hz: must be a number in (0, 3.108e+04] Hz (what the synthesis of a 6 s record '
            'can carry) or "none" (got 50000.0)')])
def test_a_bad_band_exits_2_with_one_line_before_any_work(tmp_path, capsys, value, needle):
    bad = tmp_path / "band.toml"
    bad.write_text(STUDY.replace('kind = "white"', f'kind = "white"\nband_limit_hz = {value}'))
    assert main(["run", str(bad), "--out", str(tmp_path / "out" / "band.nc")]) == 2
    assert needle in one_line_error(capsys.readouterr().err)
    assert not (tmp_path / "out").exists()


BIG = STUDY.replace("eps = [-6e5, 2e7, 6e7]", "eps = {start = -6e5, stop = 6e7, num = 20}") \
           .replace("num = 4, log = true", "num = 150, log = true").replace("t_end = 6.0", "t_end = 20.0") \
           .split("[mcs]")[0]


@pytest.mark.slow
def test_killed_run_resumes_to_the_same_file(tmp_path):
    """SIGKILL a real `screening run` (and its workers) mid-way; the re-run resumes and matches."""
    from screening.sweep.run import run_sweep

    study_file = tmp_path / "big.toml"
    study_file.write_text(BIG)
    out = tmp_path / "big.nc"
    partial = tmp_path / "big.nc.partial"
    cmd = [str(SCREENING), "run", str(study_file), "--out", str(out), "--workers", "1", "--batch-size", "25",
           "--no-plots", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(partial.glob("batch-*.npz"))) < 5:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no batch finished in time"
            time.sleep(0.01)
        os.killpg(proc.pid, signal.SIGKILL)        # the CLI and its dask worker processes
    finally:
        proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists()
    done_before = len(list(partial.glob("batch-*.npz")))
    assert 5 <= done_before < 120

    resumed = subprocess.run(cmd[:-4] + ["--workers", "2", "--no-plots", "--quiet"], capture_output=True,
                             text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming: " in resumed.stderr and "of 120 batches were already done" in resumed.stderr
    assert not partial.exists()

    reference = tmp_path / "reference.nc"
    with in_process_client(2) as client:
        run_sweep(parse_study(BIG, name="big", source=str(study_file)), reference, client=client,
                  batch_size=25, progress=False, log=quiet)
    compare_files(out, reference)


# ----------------------------------------------------------------------------- fragility
def test_fragility_command_writes_probabilities_fit_and_mcs_side_by_side(cli_result, tmp_path, capsys):
    from screening.analysis.fragility import exceedance_probability, mcs_exceedance_probability, threshold_angle
    from screening.io.reader import open_result

    out = tmp_path / "frag.nc"
    assert main(["fragility", str(cli_result / "outputs" / "study.nc"), "--threshold", "5", "--relative-to", "theta_ul",
                 "--out", str(out)]) == 0
    assert out.is_file() and out.with_suffix(".png").stat().st_size > 10_000
    with open_result(cli_result / "outputs" / "study.nc") as res, xr.open_dataset(out) as frag:
        expected = exceedance_probability(res, 5.0, "theta_ul").values
        np.testing.assert_array_equal(frag["p_exceed"].values, expected)
        assert frag["p_exceed"].dims == ("eps", "S0") and frag["p_exceed"].attrs["units"] == "1"
        assert frag["fit_median"].dims == ("eps",) and frag["beta"].dims == ("eps",)
        assert frag["fit_median"].attrs["units"] == PARAMETERS["S0"]["units"]
        assert np.nanmin(expected) < 1e-6 and np.nanmax(expected) > 0.99
        # fitted on the vouched points only: a curve left with too few is flagged (untrusted), never fitted
        ok = frag["fit_flag"].values == 0
        assert ok.any() and np.all(np.isfinite(frag["fit_median"].values[ok]))
        assert np.all(np.isnan(frag["fit_median"].values[~ok])) and np.all(frag["fit_n_unvouched"].values[~ok] > 0)
        # the Monte Carlo spot point: same probability from its per-sample peaks
        i = int(np.argmin(np.abs(res["eps"].values - float(res["spot_eps"][0]))))
        j = int(np.argmin(np.abs(res["S0"].values - float(res["spot_S0"][0]))))
        level = float(threshold_angle(res, 5.0, "theta_ul").isel(eps=i, S0=j))   # theta_ul is stored per point
        state = res["mcs_sample_state"].values[0]
        p_mcs, se = mcs_exceedance_probability(res["mcs_peak_abs_theta"].values[0][state != 2], level,
                                               overturned=(state == 1)[state != 2])
        assert float(frag["mcs_p_exceed"][0]) == pytest.approx(p_mcs, abs=1e-15)
        assert float(frag["mcs_p_exceed_se"][0]) == pytest.approx(se, abs=1e-15)
        assert float(frag["p_exceed_at_spot"][0]) == expected[i, j]
        assert frag.attrs["Conventions"] == "CF-1.8" and frag.attrs["method"] == "vanmarcke"


def test_fragility_file_passes_the_cf_checker(cli_result, tmp_path):
    checker = Path(sys.executable).parent / "compliance-checker"
    if not checker.exists():
        pytest.skip("IOOS compliance-checker is not installed")
    out = tmp_path / "frag.nc"
    assert main(["fragility", str(cli_result / "outputs" / "study.nc"), "--threshold", "1e-3", "--out", str(out)]) == 0
    proc = subprocess.run([str(checker), "--test=cf:1.8", "--criteria=strict", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and "All tests passed!" in proc.stdout, proc.stdout + proc.stderr


@pytest.mark.parametrize("extra, needle", [
    (["--threshold", "-1"], "--threshold"),
    (["--threshold", "nan"], "--threshold"),
    (["--threshold", "abc"], "--threshold"),
    ([], "--threshold"),
    (["--threshold", "0.1", "--relative-to", "height"], "--relative-to"),
    (["--threshold", "0.1", "--dim", "lam"], "--dim"),
    (["--threshold", "0.1", "--out", "no/such/folder/f.nc"], "does not exist"),
])
def test_fragility_bad_input_exits_2_and_writes_nothing(cli_result, tmp_path, capsys, extra, needle):
    before = sorted(p.name for p in (cli_result / "outputs").iterdir())
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        code = main(["fragility", str(cli_result / "outputs" / "study.nc"), *extra])
    finally:
        os.chdir(cwd)
    assert code == 2
    assert needle in one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in (cli_result / "outputs").iterdir()) == before and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("content", [None, b"not a netCDF file"])
def test_fragility_of_unreadable_result_exits_2(tmp_path, capsys, content):
    path = tmp_path / "r.nc"
    if content is not None:
        path.write_bytes(content)
    assert main(["fragility", str(path), "--threshold", "0.1"]) == 2
    one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == (["r.nc"] if content else [])


def test_tradeoff_subcommand_delegates_with_one_line_errors(tmp_path, capsys):
    assert main(["tradeoff", str(tmp_path / "missing.toml")]) == 2
    assert "missing.toml" in one_line_error(capsys.readouterr().err)
    (tmp_path / "bad.toml").write_text("[block]\nm = -1\n")
    assert main(["tradeoff", str(tmp_path / "bad.toml"), "--out-dir", str(tmp_path)]) == 2
    one_line_error(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


# ----------------------------------------------------------------------------- the click parser
@pytest.mark.parametrize("argv, message", [
    (["fragility", "r.nc", "--threshold"], "argument --threshold: expected one argument (see 'screening fragility --help')"),
    (["run", "s.toml", "extra"], "unrecognized arguments: extra (see 'screening run --help')"),
    (["run", "s.toml", "--scheduler", "a", "--workers", "2"], "argument --workers: not allowed with argument --scheduler"),
    (["run", "s.toml", "--complevel", "x"], "argument --complevel: must be an integer in 0..9 (got 'x')"),
    (["fragility", "r.nc", "--threshold", "1", "--method", "x"],
     "argument --method: invalid choice: 'x' (choose from 'vanmarcke', 'poisson')"),
    (["launch"], "argument command: invalid choice: 'launch' (choose from 'run', 'plot', 'fragility', 'tradeoff', 'info'"),
    ([], "the following arguments are required: command (see 'screening --help')"),
    (["tradeoff"], "the following arguments are required: study (see 'screening tradeoff --help')"),
    (["tradeoff", "s.toml", "--bogus"], "unrecognized arguments: --bogus (see 'screening tradeoff --help')"),
    (["info", "--out-dir", "x", "r.nc"], "unrecognized arguments: --out-dir"),
])
def test_click_usage_errors_are_one_argparse_style_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert message in one_line_error(capsys.readouterr().err)
    assert list(tmp_path.iterdir()) == []


def test_help_and_version_exit_0(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"screening {__version__}"
    for argv in (["--help"], ["run", "--help"], ["fragility", "--help"], ["tradeoff", "--help"]):
        assert main(argv) == 0, argv
        out = capsys.readouterr().out
        assert out.startswith(f"Usage: screening {argv[0] if len(argv) > 1 else ''}".rstrip()), out


def test_ctrl_c_exits_130_with_one_line(tmp_path, capsys, monkeypatch):
    import screening.sweep.run

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(screening.sweep.run, "run_sweep", interrupted)
    (tmp_path / "s.toml").write_text(STUDY)
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "r.nc")]) == 130
    assert [line for line in capsys.readouterr().err.splitlines() if line.strip()] == [
        "screening: interrupted; finished batches are kept, re-run the same command to resume"]


def test_tradeoff_subcommand_runs_then_rerenders_from_its_netcdf(tmp_path, capsys):
    from golden import TRADEOFF_STUDY

    study = tmp_path / "tiny.toml"
    study.write_text(TRADEOFF_STUDY)
    assert main(["tradeoff", str(study), "--out-dir", str(tmp_path / "nowhere"), "--from-nc"]) == 2
    assert "--from-nc:" in one_line_error(capsys.readouterr().err) and not (tmp_path / "nowhere").exists()
    assert main(["tradeoff", str(study), "--out-dir", str(tmp_path / "out"), "--quiet"]) == 0
    captured = capsys.readouterr()
    assert "Recommended: " in captured.out and captured.err == ""
    assert captured.out.splitlines()[-1].startswith(f"wrote {tmp_path / 'out' / 'tiny.nc'}, ")
    (tmp_path / "out" / "tiny.md").unlink()
    assert main(["tradeoff", str(study), "--out-dir", str(tmp_path / "out"), "--from-nc"]) == 0
    out = capsys.readouterr().out
    assert "SL : condensed : coupled = 1 :" in out and "tiny.nc" not in out.splitlines()[-1]
    assert (tmp_path / "out" / "tiny.md").exists()
