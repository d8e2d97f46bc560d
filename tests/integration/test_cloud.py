"""Cloud analysis end to end on records synthesised here (no download)."""

import numpy as np
import pytest
import xarray as xr

from screening.cli import main
from screening.core.model.excitation import Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.applications.cloud import load_cloud_study, run_cloud, synthesise_records
from screening.sweep.config import StudyError
from screening.core.status import FitFlag

STUDY = """
title = "cloud test"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = 6e7
[records]
files = "rec"
period = 0.5
threshold = 0.1
im = "{im}"
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("cloud")
    synthesise_records(root / "rec", KanaiTajimi(1e-3, 15.6, 0.6, Envelope(2.0, 1.0), band_limit_hz=None), 8, 8.0, 100.0,
                       np.geomspace(0.4, 2.5, 8), seed=15)
    return root


def test_cloud_dataset_and_fit(folder):
    (folder / "s.toml").write_text(STUDY.format(im="sa"))
    ds, warnings = run_cloud(load_cloud_study(folder / "s.toml"))
    assert ds.sizes["record"] == 8
    for name in ("peak_abs_theta", "overturned", "exceed", "pga", "sa", "arias_intensity", "pgv", "avgsa",
                 "fit_median", "beta"):
        assert name in ds
    assert ds["sa"].attrs["period"] == 0.5 and ds["avgsa"].attrs["period"] == 0.5
    assert ds["pgv"].attrs["units"] == "m s-1" and ds["avgsa"].attrs["units"] == "m s-2"
    exceed = ds["exceed"].values
    if 0 < exceed.sum() < exceed.size:
        assert np.isfinite(float(ds["fit_median"])) or ds["fit_flag"] != 0
    # the exceedance definition: peak above the threshold or overturned
    level = float(ds["threshold_rad"])
    np.testing.assert_array_equal(exceed, (ds["peak_abs_theta"].values > level) | ds["overturned"].values)


def test_cloud_study_errors(folder):
    (folder / "bad.toml").write_text(STUDY.format(im="pgd"))
    with pytest.raises(StudyError, match="records.im"):
        load_cloud_study(folder / "bad.toml")
    (folder / "bad3.toml").write_text(STUDY.format(im="avgsa").replace("period = 0.5\n", ""))
    with pytest.raises(StudyError, match="records.period: required with im = 'avgsa'"):
        load_cloud_study(folder / "bad3.toml")
    (folder / "bad2.toml").write_text(STUDY.format(im="pga").replace('files = "rec"', 'files = "nothing/*.at2"'))
    with pytest.raises(StudyError, match="records.files"):
        load_cloud_study(folder / "bad2.toml")


def test_cloud_cli_writes_all_files(folder, capsys):
    (folder / "p.toml").write_text(STUDY.format(im="pgv"))
    out = folder / "cloud.nc"
    assert main(["cloud", str(folder / "p.toml"), "--out", str(out), "--quiet"]) == 0
    for suffix in (".nc", ".png", ".csv"):
        assert out.with_suffix(suffix).exists()
    with xr.open_dataset(out) as ds:
        assert ds.attrs["intensity_variable"] == "pgv"
        peaks, pga, names = ds["peak_abs_theta"].values, ds["pga"].values, ds["record_name"].values
    assert "records:" in capsys.readouterr().err
    # the per-record demands, one row per record, as stored
    import csv
    rows = list(csv.DictReader(folder.joinpath("cloud_demand.csv").open()))
    assert [r["record_name"] for r in rows] == [str(n) for n in names]
    np.testing.assert_allclose([float(r["peak_abs_theta [rad]"]) for r in rows], peaks, rtol=1e-7)
    np.testing.assert_allclose([float(r["pga [m s-2]"]) for r in rows], pga, rtol=1e-7)
    # and `info` describes the file instead of refusing it
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "(cloud file)" in text and f"{len(rows)} record(s):" in text


def test_shipped_cloud_example_is_valid():
    from pathlib import Path
    cloud = load_cloud_study(Path(__file__).parents[2] / "studies" / "cloud_example.toml")
    assert len(cloud.files) == 20 and cloud.im == "pga" and cloud.period == 0.5


def test_cloud_on_dask_equals_the_serial_run(folder, client):
    (folder / "d.toml").write_text(STUDY.format(im="pga"))
    cloud = load_cloud_study(folder / "d.toml")
    serial, _ = run_cloud(cloud)
    parallel, warnings = run_cloud(cloud, client=client)
    assert parallel.attrs["execution"].startswith("dask, one task per record")
    xr.testing.assert_identical(serial.drop_attrs(), parallel.drop_attrs())
    assert ("; ".join(warnings) or "none") == serial.attrs["warnings"]


def test_a_failed_record_task_is_kept_as_nan_and_left_out_of_the_fit(folder, client):
    from screening.core.model import Block, Foundation
    from screening.core.records import Record, read_record
    from screening.applications.cloud import cloud_dataset, _record_rows

    cloud = load_cloud_study(folder / "d.toml") if (folder / "d.toml").exists() else None
    if cloud is None:
        (folder / "d.toml").write_text(STUDY.format(im="pga"))
        cloud = load_cloud_study(folder / "d.toml")
    good = [read_record(path) for path in cloud.files]
    bad = Record(np.array([0.0, 1.0, 0.0]), 0.01, "bad")
    object.__setattr__(bad, "dt", -1.0)         # the reader refuses this; here a task meets it and fails
    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, lam=8.95e8, eps=6e7)
    rows, failures = _record_rows(block, bed, [bad, *good], "coupled", "paper", None, client=client)
    assert len(failures) == 1 and failures[0].startswith("record bad failed: ValueError")
    assert rows[0]["diverged"] and np.isnan(rows[0]["peak_abs_theta"]) and np.isnan(rows[0]["pga"])
    ds, _ = cloud_dataset(cloud, block, bed, rows, ["bad"] + [r.name for r in good])
    without, _ = cloud_dataset(cloud, block, bed, rows[1:], [r.name for r in good])
    assert float(ds["fit_median"]) == float(without["fit_median"]) or np.isnan(float(without["fit_median"]))


def test_cloud_cli_runs_on_workers_and_checks_the_worker_count(folder, capsys):
    (folder / "w.toml").write_text(STUDY.format(im="pga"))
    assert main(["cloud", str(folder / "w.toml"), "--out", str(folder / "w.nc"), "--workers", "300"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--workers" in err[0] and "0..256" in err[0]
    assert not (folder / "w.nc").exists()
    assert main(["cloud", str(folder / "w.toml"), "--out", str(folder / "w.nc"), "--workers", "1", "--quiet"]) == 0
    with xr.open_dataset(folder / "w.nc") as ds:
        assert ds.attrs["execution"] == "dask, one task per record on 1 worker(s)"
        assert ds["fit_median"].attrs["units"] == "m s-2" and ds["peak_abs_theta"].attrs["units"] == "rad"


@pytest.mark.slow
def test_multiple_stripe_analysis_scales_every_record_to_every_level(folder, capsys):
    """[records] levels: each record scaled to each PGA level (its PGA is then the level), the
    exceedances counted per stripe and fitted by the binomial likelihood with standard errors."""
    import csv

    from screening.analysis.fragility import fit_binomial_fragility

    levels = [0.5, 1.5, 4.5]
    (folder / "msa.toml").write_text(STUDY.format(im="pga") + f"levels = {levels}\n")
    out = folder / "msa.nc"
    assert main(["cloud", str(folder / "msa.toml"), "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "3 stripes x 8 records" in err
    with xr.open_dataset(out) as ds:
        np.testing.assert_allclose(ds["pga"].values, np.repeat(np.array(levels)[:, None], 8, axis=1), rtol=1e-9)
        k, n = ds["n_exceed"].values, ds["n_used"].values
        assert np.all(np.diff(k) >= 0)                  # stronger shaking, no fewer exceedances
        np.testing.assert_array_equal(k, (ds["exceed"].values & ~ds["diverged"].values).sum(axis=1))
        if 0 < k.sum() < n.sum():
            fit = fit_binomial_fragility(levels, k, n)
            assert int(ds["fit_flag"]) == fit["flag"]
            if fit["flag"] == FitFlag.ok:
                assert float(ds["fit_median"]) == pytest.approx(fit["median"], rel=1e-12)
                assert float(ds["beta_se"]) == pytest.approx(fit["beta_se"], rel=1e-12, nan_ok=True)
            else:                                   # e.g. separated stripes: no fit is given as good
                assert np.isnan(float(ds["fit_median"])) and np.isnan(float(ds["beta"]))
            rows = list(csv.DictReader(out.with_suffix(".csv").open()))
            assert len(rows) == 1 and rows[0]["intensity_measure"] == "stripe_pga"
            assert rows[0]["fit_flag"] == FitFlag(fit["flag"]).name
    assert out.with_suffix(".png").stat().st_size > 10_000
    assert main(["info", str(out)]) == 0
    assert "8 record(s) x 3 stripe(s) (stripe_pga levels)" in capsys.readouterr().out
    demand = list(csv.DictReader(folder.joinpath("msa_demand.csv").open()))
    assert len(demand) == 24 and [float(r["level [m s-2]"]) for r in demand[::8]] == levels
    np.testing.assert_allclose([float(r["pga [m s-2]"]) for r in demand], np.repeat(levels, 8), rtol=1e-7)


def test_levels_must_be_increasing_positive(folder):
    (folder / "bad_levels.toml").write_text(STUDY.format(im="pga") + "levels = [2.0, 1.0]\n")
    with pytest.raises(StudyError, match="records.levels: must be a list of 2..100 increasing"):
        load_cloud_study(folder / "bad_levels.toml")


def test_cloud_with_model_auto_runs_the_fallback_on_records(folder):
    """No validity rule is measured on records: model = "auto" runs the coupled model (same peaks)."""
    (folder / "auto.toml").write_text(STUDY.format(im="pga").replace('files = "rec"', 'files = "rec"\nmodel = "auto"'))
    (folder / "coupled.toml").write_text(STUDY.format(im="pga"))
    auto, _ = run_cloud(load_cloud_study(folder / "auto.toml"))
    coupled, _ = run_cloud(load_cloud_study(folder / "coupled.toml"))
    np.testing.assert_array_equal(auto["peak_abs_theta"].values, coupled["peak_abs_theta"].values)
    # issue 36 item 9: the result records the model that ran, and that "auto" chose it
    assert auto.attrs["model"] == "coupled" and auto.attrs["model_requested"] == "auto"
    assert coupled.attrs["model"] == "coupled" and "model_requested" not in coupled.attrs
    (folder / "rigid.toml").write_text(STUDY.format(im="pga").replace('files = "rec"', 'files = "rec"\nmodel = "rigid"'))
    with pytest.raises(StudyError, match="records.model: must be one of .*auto"):
        load_cloud_study(folder / "rigid.toml")


@pytest.mark.parametrize("im, levels", [("pgv", [0.05, 0.15]), ("avgsa", [1.0, 3.0])])
def test_multiple_stripes_over_every_documented_im(folder, im, levels):
    """Issue 36 item 1: [records] im = "pgv" (or "avgsa") with levels gave KeyError: 'pgv' while the study
    was read; every IM the docs list works in every place that takes an IM."""
    (folder / f"msa_{im}.toml").write_text(STUDY.format(im=im) + f"levels = {levels}\n")
    cloud = load_cloud_study(folder / f"msa_{im}.toml")
    assert cloud.levels == tuple(levels)
    from screening.applications.cloud import run_stripes

    ds, _ = run_stripes(cloud)
    name = {"pgv": "pgv", "avgsa": "avgsa"}[im]
    np.testing.assert_allclose(ds[name].values, np.repeat(np.array(levels)[:, None], 8, axis=1), rtol=1e-6)
    assert ds[f"stripe_{name}"].attrs["units"] == {"pgv": "m s-1", "avgsa": "m s-2"}[im]
    (folder / f"bad_{im}.toml").write_text(STUDY.format(im=im) + "levels = [2.0, 1.0]\n")
    with pytest.raises(StudyError, match=r"\[m s-1\]" if im == "pgv" else r"\[m s-2\]"):
        load_cloud_study(folder / f"bad_{im}.toml")


def test_every_im_of_the_cli_is_one_the_fits_know():
    """The --im choices and [records] im are the IMs of screening.applications.im_fragility (one list)."""
    from screening.applications.im_fragility import IMS as FIT_IMS
    from screening.cli.commands import cmd_fragility
    from screening.applications.cloud import IMS as CLOUD_IMS

    choices = next(p for p in cmd_fragility.params if p.name == "im").type.choices
    assert set(choices) == set(FIT_IMS) and set(CLOUD_IMS) == set(FIT_IMS) - {"s0"}
