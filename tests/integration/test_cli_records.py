"""``screening simulate`` end to end on a record file written here."""

import numpy as np
import pytest
import xarray as xr

from screening.cli import main
from screening.core.records import Record, write_at2
from screening.sweep.config import StudyError

STUDY = """
title = "record CLI"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = [0.0, 6e7]
[excitation]
kind = "white"
S0 = 1e-3
"""


def _files(tmp_path):
    (tmp_path / "study.toml").write_text(STUDY)
    dt = 0.005
    t = np.arange(0.0, 4.0, dt)
    a = 2.0 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-((t - 1.5) / 0.6) ** 2)
    write_at2(tmp_path / "pulse.at2", Record(a, dt))
    return tmp_path / "study.toml", tmp_path / "pulse.at2"


def test_simulate_writes_netcdf_and_png(tmp_path, capsys):
    study, record = _files(tmp_path)
    out = tmp_path / "res.nc"
    assert main(["simulate", str(record), "--study", str(study), "--out", str(out), "--set", "eps=6e7"]) == 0
    assert out.exists() and out.with_suffix(".png").exists()
    with xr.open_dataset(out) as ds:
        assert ds["theta"].attrs["units"] == "rad"
        assert float(ds["eps"]) == 6e7
        assert ds.attrs["status"] in ("ok", "overturned")
        assert "sign_convention" in ds.attrs
        peak = float(ds["peak_abs_theta"])
    assert "PGA" in capsys.readouterr().err
    assert main(["info", str(out)]) == 0                 # info describes the file instead of refusing it
    text = capsys.readouterr().out
    assert "(simulation file)" in text and (f"peak |theta| {peak:.4g} rad" in text or "overturned at" in text)


def test_simulate_needs_swept_value(tmp_path, capsys):
    study, record = _files(tmp_path)
    assert main(["simulate", str(record), "--study", str(study), "--out", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert "--set eps=VALUE" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.nc").exists()


def test_fit_excitation_prints_a_study_table(tmp_path, capsys):
    from screening.cli import main as run
    from screening.sweep.study import parse_study

    _, record = _files(tmp_path)
    assert run(["fit-excitation", str(record)]) == 0
    table = capsys.readouterr().out
    study = parse_study("[block]\nm = 1.0\nb = 0.1\nh = 0.3\n[foundation]\nk = 1e8\nlam = 1e9\n" + table)
    assert study.cases[0].excitation == "kanai_tajimi"
    assert run(["fit-excitation", str(record), "--kind", "white"]) == 2
    assert "cutoff" in capsys.readouterr().err


def test_fit_excitation_checks_its_inputs_in_one_line_and_draws_its_fit(tmp_path, capsys):
    """--cutoff 0 / -5 / nan, a constant record: exit 2 with one line before any work; --figure draws
    the Husid curve and the spectrum; the pulse record (a short harmonic burst) is flagged."""
    from helpers import one_line_error

    from screening.cli import main as run

    _, record = _files(tmp_path)
    for bad in ("0", "-5", "nan"):
        assert run(["fit-excitation", str(record), "--kind", "white", "--cutoff", bad]) == 2
        assert "--cutoff" in one_line_error(capsys.readouterr().err)
    flat = tmp_path / "flat.txt"
    flat.write_text("\n".join(["0.1"] * 500))
    assert run(["fit-excitation", str(flat), "--dt", "0.01", "--units", "m/s2"]) == 2
    assert "constant" in one_line_error(capsys.readouterr().err)
    png = tmp_path / "fit.png"
    assert run(["fit-excitation", str(record), "--figure", str(png)]) == 0
    captured = capsys.readouterr()
    assert png.stat().st_size > 10_000 and "# fit: Husid curves" in captured.out
    assert "warning:" in captured.err                     # a 2 Hz burst is no Kanai-Tajimi record
    assert [p.name for p in tmp_path.iterdir() if ".tmp" in p.name] == []


def test_simulate_accepts_a_study_without_excitation_or_with_records(tmp_path):
    _, record = _files(tmp_path)
    study = tmp_path / "bed.toml"
    study.write_text("[block]\nm = 8.67\nb = 0.035\nh = 0.21\n[foundation]\nk = 2.89e7\nlam = 8.95e8\n"
                     "[records]\nfiles = '*.at2'\n")
    assert main(["simulate", str(record), "--study", str(study), "--out", str(tmp_path / "s.nc"), "--no-plots"]) == 0


def _csv_in_g(tmp_path, pga_g=0.05, dt=0.005, columns=2):
    t = np.arange(0.0, 4.0, dt)
    a = pga_g * np.sin(2 * np.pi * 2.0 * t) * np.exp(-((t - 1.5) / 0.6) ** 2) / 0.9999
    rows = [f"{ti:.4f},{ai:.7f}" + (f",{-0.5 * ai:.7f}" if columns == 3 else "") for ti, ai in zip(t, a)]
    path = tmp_path / "rec.csv"
    path.write_text("\n".join(rows) + "\n")
    return path, float(np.max(np.abs(a)))


def _one_line(capsys):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


def test_simulate_reads_two_columns_as_time_and_acceleration_whatever_dt_says(tmp_path, capsys):
    study, _ = _files(tmp_path)
    record, pga_g = _csv_in_g(tmp_path)
    out = tmp_path / "s.nc"
    base = ["simulate", str(record), "--study", str(study), "--set", "eps=6e7", "--no-plots", "--units", "g"]
    assert main(base + ["--out", str(out), "--dt", "0.005"]) == 0
    said = capsys.readouterr().err
    assert f"PGA {pga_g:.3f} g" in said                     # not the time column read as accelerations
    with xr.open_dataset(out) as ds:
        assert ds.attrs["record_dt"] == 0.005 and ds.sizes["t"] == 800
    assert main(base + ["--out", str(tmp_path / "t.nc"), "--dt", "0.01"]) == 2
    assert "time column gives a step of 0.005 s but dt = 0.01" in _one_line(capsys)


def test_text_records_need_their_units(tmp_path, capsys):
    study, _ = _files(tmp_path)
    record, _ = _csv_in_g(tmp_path)
    assert main(["simulate", str(record), "--study", str(study), "--set", "eps=6e7", "--no-plots",
                 "--out", str(tmp_path / "x.nc")]) == 2
    assert "units are not stated; give --units (g, m/s2 or cm/s2)" in _one_line(capsys)
    assert main(["fit-excitation", str(record)]) == 2
    assert "give --units" in _one_line(capsys)
    assert not (tmp_path / "x.nc").exists()


@pytest.mark.parametrize("args,needle", [
    (["--scale", "nan"], "--scale must be a finite number with 0 < |scale| <= 1000 (got nan)"),
    (["--scale", "inf"], "--scale must be a finite number"),
    (["--scale", "1e308"], "--scale must be a finite number"),
    (["--t-end", "1e6"], "'--t-end': t_end / dt = 2e+08 steps; at most 1999999"),
    (["--t-end", "-1"], "'--t-end' must be a finite number > 0"),
])
def test_simulate_options_are_checked_before_any_work(tmp_path, capsys, args, needle):
    study, record = _files(tmp_path)
    assert main(["simulate", str(record), "--study", str(study), "--set", "eps=6e7", "--no-plots",
                 "--out", str(tmp_path / "x.nc")] + args) == 2
    err = _one_line(capsys)
    assert needle in err and "compiling" not in err


@pytest.mark.parametrize("kind", ["folder", "fifo", "loop"])
def test_a_record_path_says_what_it_is(tmp_path, capsys, kind):
    import os

    study, _ = _files(tmp_path)
    path = tmp_path / "r.csv"
    said = {"folder": "is a folder, not a file", "fifo": "is a FIFO (named pipe), not a file",
            "loop": "is a symbolic link loop"}[kind]
    if kind == "folder":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to(path)
    assert main(["simulate", str(path), "--study", str(study), "--units", "g", "--out", str(tmp_path / "x.nc")]) == 2
    assert said in _one_line(capsys)


CLOUD = STUDY + """
[records]
files = {files}
{extra}
"""


@pytest.mark.parametrize("files,extra,needle", [
    ("[]", "", "records.files: empty list"),
    ("'*.at2'", "scale = 1e308", "records.scale: must be a finite number with 0 < scale <= 1000"),
    ("'*.at2'", "scale = nan", "records.scale: must be a finite number"),
    ("'*.at2'", "im = 'sa'\nperiod = 1e-300", "records.period: must be a finite number >= 0.001 and <= 100"),
    ("'*.at2'", "im = 'sa'\nperiod = 1e300", "records.period: must be a finite number >= 0.001 and <= 100"),
    ("'*.at2'", "dt = 5.0", "records.dt: must be a number of seconds in [1e-06, 1]"),
    ("'*.at2'", "units = 'furlongs'", "records.units: must be one of"),
])
def test_cloud_records_table_is_checked(tmp_path, capsys, files, extra, needle):
    _files(tmp_path)
    path = tmp_path / "cloud.toml"
    path.write_text(CLOUD.format(files=files, extra=extra))
    assert main(["cloud", str(path), "--set", "eps=6e7", "--out", str(tmp_path / "c.nc")]) == 2
    assert needle in _one_line(capsys)


def test_cloud_reads_a_csv_beside_a_one_column_file_as_time_and_acceleration(tmp_path, capsys):
    from screening.applications.cloud import load_cloud_study, read_cloud_records

    _files(tmp_path)
    csv, pga_g = _csv_in_g(tmp_path, columns=3)
    (tmp_path / "one.txt").write_text("".join(f"{v:.6f}\n" for v in (0.01, -0.02, 0.03, 0.0)))
    path = tmp_path / "cloud.toml"
    path.write_text(CLOUD.format(files="['rec.csv', 'one.txt']", extra="dt = 0.005"))
    assert main(["cloud", str(path), "--set", "eps=6e7", "--out", str(tmp_path / "c.nc")]) == 2
    assert "give --units or records.units (g, m/s2 or cm/s2)" in _one_line(capsys)
    cloud = load_cloud_study(path, units="g")
    csv_rec, one = read_cloud_records(cloud)
    assert csv_rec.acceleration.size == 800 and csv_rec.pga / 9.80665 == pytest.approx(pga_g, rel=1e-6)
    assert csv_rec.vertical is not None and one.acceleration.size == 4
    path.write_text(CLOUD.format(files="['rec.csv']", extra="units = 'm/s2'"))
    assert main(["cloud", str(path), "--units", "g", "--set", "eps=6e7", "--out", str(tmp_path / "c.nc")]) == 2
    assert "records.units: 'm/s2', but --units 'g' was given" in _one_line(capsys)


@pytest.mark.parametrize("free,needle", [(0, "no space left on the device (0.0 MiB free; the netCDF library said: "
                                              "NetCDF: HDF error)"),
                                         (10 * 2**30, "NetCDF: HDF error (the netCDF library gives no reason; 10.0 GiB")])
def test_a_full_disk_is_said_as_such(tmp_path, capsys, monkeypatch, free, needle):
    import collections
    import shutil

    study, record = _files(tmp_path)

    def hdf_error(self, *args, **kwargs):
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(free + 1, 1, free))
    assert main(["simulate", str(record), "--study", str(study), "--set", "eps=6e7", "--no-plots",
                 "--out", str(tmp_path / "x.nc")]) == 2
    assert needle in _one_line(capsys)


@pytest.mark.parametrize("period", ["1e-300", "1e300", "0.0009"])
def test_fragility_period_of_sa_is_bounded_before_the_result_is_read(tmp_path, capsys, period):
    assert main(["fragility", str(tmp_path / "absent.nc"), "--threshold", "0.2", "--im", "sa",
                 "--period", period]) == 2
    assert "parameter '--period' must be a finite number >= 0.001 and <= 100" in _one_line(capsys)


def test_a_vertical_component_is_used_unless_left_out(tmp_path, capsys):
    """The record's vertical component (-0.5 x the horizontal, in g) drives the block unless --no-vertical:
    both files say which, and the vertical history is stored with its units where it was used."""
    study, _ = _files(tmp_path)
    record, pga_g = _csv_in_g(tmp_path, columns=3)
    peaks = {}
    for flag in ([], ["--no-vertical"]):
        out = tmp_path / f"v{len(flag)}.nc"
        assert main(["simulate", str(record), "--study", str(study), "--set", "eps=6e7", "--no-plots", "--units", "g",
                     "--out", str(out), *flag]) == 0
        err = capsys.readouterr().err
        assert f"PGA {pga_g:.3f} g" in err and "vertical component: " + ("left out" if flag else "used") in err
        with xr.open_dataset(out) as ds:
            assert ds.attrs["vertical_ground_motion"].startswith("left out" if flag else "used")
            assert ("vertical_ground_acceleration" in ds) is not bool(flag)
            if not flag:
                assert ds["vertical_ground_acceleration"].attrs["units"] == "m s-2"
                np.testing.assert_allclose(ds["vertical_ground_acceleration"], -0.5 * ds["ground_acceleration"],
                                           atol=1e-6)
                assert not bool(ds["lift_off"])
            peaks[bool(flag)] = ds["theta"].values
    assert not np.array_equal(peaks[True], peaks[False])        # the vertical component changed the response


def test_cloud_uses_vertical_components_unless_left_out(tmp_path):
    from screening.applications.cloud import load_cloud_study, run_cloud

    _files(tmp_path)
    _csv_in_g(tmp_path, columns=3)
    path = tmp_path / "cloud.toml"
    path.write_text(CLOUD.format(files="['rec.csv', 'pulse.at2']", extra="units = 'g'"))
    used, _ = run_cloud(load_cloud_study(path), overrides={"eps": 6e7})
    assert used.attrs["vertical_ground_motion"].startswith("used for the 1 of 2 record(s)")
    left, _ = run_cloud(load_cloud_study(path, vertical=False), overrides={"eps": 6e7})
    assert left.attrs["vertical_ground_motion"].startswith("left out")
    peak_used, peak_left = used["peak_abs_theta"].values, left["peak_abs_theta"].values
    assert peak_used[1] == peak_left[1]                          # the one-component AT2 record: no change
    assert peak_used[0] != peak_left[0]
    path.write_text(CLOUD.format(files="['rec.csv']", extra="units = 'g'\nvertical = false"))
    assert not load_cloud_study(path).vertical
    path.write_text(CLOUD.format(files="['rec.csv']", extra="units = 'g'\nvertical = 'yes'"))
    with pytest.raises(StudyError, match="records.vertical: must be true or false"):
        load_cloud_study(path)


@pytest.mark.parametrize("model,said", [("condensed", "stopped there (diverged: left out of the fit)"),
                                        ("coupled", "flew and landed")])
def test_a_record_that_lifts_the_block_off_is_one_warning_line(tmp_path, model, said):
    """A vertical pulse to -1.5 g: the record is flagged ``lift_off``; the condensed model stops it (diverged),
    the coupled block flies and lands; one warning line says which, never a crash."""
    from screening.applications.cloud import load_cloud_study, run_cloud

    _files(tmp_path)
    t = np.arange(0.0, 2.0, 0.002)
    a_v = np.where(np.abs(t - 1.0) < 0.05, -1.5 * np.cos(np.pi * (t - 1.0) / 0.1), 0.0)
    a_h = 0.01 * np.sin(2 * np.pi * 2.0 * t)
    (tmp_path / "up.csv").write_text("\n".join(f"{ti:.4f},{hi:.6f},{vi:.6f}" for ti, hi, vi in zip(t, a_h, a_v)) + "\n")
    path = tmp_path / "cloud.toml"
    path.write_text(CLOUD.format(files="['up.csv', 'pulse.at2']", extra=f"units = 'g'\nmodel = '{model}'"))
    ds, warnings = run_cloud(load_cloud_study(path), overrides={"eps": 0.0})
    assert ds["lift_off"].values.tolist() == [True, False]
    assert ds["diverged"].values.tolist() == [model == "condensed", False]
    assert [w for w in warnings if "lift the block off" in w] == [
        f"1 record(s) lift the block off (g + a_v < 0: up); the {model} model {said}"]
