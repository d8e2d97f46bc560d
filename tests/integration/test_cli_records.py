"""``screening simulate`` end to end on a record file written here."""

import numpy as np
import xarray as xr

from screening.cli import main
from screening.records import Record, write_at2

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
    from screening.workflow.study import parse_study

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
