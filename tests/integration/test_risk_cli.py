"""``screening risk``: a fragility file and a site's hazard curve in, the ranked annual frequencies out (CSV and
figure); bad hazard curves refused in one line naming the file, line and field, exit 2, nothing written."""

import csv
import math

import numpy as np
import pytest
import xarray as xr

from screening.cli import main

G = 9.80665


@pytest.fixture()
def fragility_file(tmp_path):
    frag = xr.Dataset(
        {"fit_median": (("limit_state", "case"), [[2.0, 4.0], [3.0, 6.0]], {"units": "m s-2", "intensity": "pga"}),
         "beta": (("limit_state", "case"), [[0.4, 0.3], [0.4, 0.3]]),
         "fit_flag": (("limit_state", "case"), np.int8([[0, 0], [0, 3]])),
         "fit_n_unvouched": (("limit_state", "case"), np.int32([[0, 0], [0, 0]])),
         "fit_im_min": (("limit_state", "case"), [[1.0, 1.0], [1.0, 1.0]], {"units": "m s-2"}),
         "fit_im_max": (("limit_state", "case"), [[8.0, 8.0], [8.0, 8.0]], {"units": "m s-2"}),
         "threshold_rad": ((), 0.1)},
        coords={"limit_state": ["theta_0.1_slenderness", "theta_0.5_slenderness"], "case": [0, 1],
                "case_name": ("case", ["vase-tall", "bust"]), "pga": ("pga", [1.0, 8.0], {"units": "m s-2"})})
    path = tmp_path / "frag.nc"
    frag.to_netcdf(path)
    return path


def _hazard(tmp_path, rows, header="PGA [g], annual_rate [1/yr]"):
    path = tmp_path / "hazard.csv"
    path.write_text(header + "\n" + "".join(f"{x:g}, {h:g}\n" for x, h in rows))
    return path


def test_risk_writes_ranked_rates_with_the_case_names(tmp_path, fragility_file, capsys):
    x = np.geomspace(0.005, 5.0, 30)
    hazard = _hazard(tmp_path, zip(x, 1e-4 * x**-2.0))
    out = tmp_path / "risk.csv"
    assert main(["risk", str(fragility_file), "--hazard", str(hazard), "--years", "50", "--out", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert [(r["object"], r["limit_state"]) for r in rows[:3]] == [
        ("vase-tall", "theta_0.1_slenderness"), ("vase-tall", "theta_0.5_slenderness"), ("bust", "theta_0.1_slenderness")]
    # closed form inside the hazard table (k = 2): lambda = k0 (median / g)^-k exp(k^2 beta^2 / 2)
    assert float(rows[0]["annual_rate"]) == pytest.approx(1e-4 * (2.0 / G) ** -2 * math.exp(2 * 0.16), rel=2e-3)
    assert float(rows[0]["probability"]) == pytest.approx(1 - math.exp(-50 * float(rows[0]["annual_rate"])), rel=1e-5)
    assert 0 < float(rows[0]["share_outside_vouched"]) < 1          # vouched over 1..8 m s-2 only
    assert rows[-1]["object"] == "bust" and rows[-1]["annual_rate"] == "" and "never_exceeded" in rows[-1]["note"]
    assert out.with_suffix(".png").stat().st_size > 5_000
    assert "highest: vase-tall theta_0.1_slenderness" in capsys.readouterr().err


@pytest.mark.parametrize("rows, header, where", [
    ([(0.1, 1e-2), (0.2, 2e-2)], "PGA [g], annual_rate [1/yr]", "hazard.csv:3: annual_rate [1/yr]: the hazard curve is not decreasing"),
    ([(0.1, 1e-2), (0.2, 1e-3)], "SA(0.3) [g], annual_rate [1/yr]", "hazard.csv:1: imt: the hazard curve is for SA(0.3), the fragility for PGA"),
    ([(0.1, 1e-2), (0.2, 1e-3)], "PGA [m/s], annual_rate [1/yr]", "hazard.csv:1: units: the hazard curve is in m s-1"),
])
def test_bad_hazard_is_one_line_exit_2_and_nothing_written(tmp_path, fragility_file, capsys, rows, header, where):
    hazard = _hazard(tmp_path, rows, header)
    out = tmp_path / "risk.csv"
    assert main(["risk", str(fragility_file), "--hazard", str(hazard), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and where in err
    assert not out.exists() and not out.with_suffix(".png").exists()
