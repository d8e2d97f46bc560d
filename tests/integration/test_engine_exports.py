"""The fragility exports load in the engines others use: pelicun's own loader and DamageModel read the
pelicun collection, OpenQuake's own NRML reader the fragility model (issue #35 item 4).

The engines live in their own environment (``make engines`` -> ``.venv-engines``; pelicun pins scipy and
pandas below screening's): the exports are written here and read there by ``tests/engines/load_exports.py``.
"""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from screening.applications.im_fragility import write_csv, write_nrml, write_pelicun_csv, write_pelicun_json
from screening.core.status import FitFlag

ROOT = Path(__file__).resolve().parents[2]
G = 9.80665


def engines_python():
    """The Python of the engines' environment: $SCREENING_ENGINES_PYTHON, else .venv-engines of this checkout
    or of the checkout the venv of this Python belongs to."""
    for candidate in (os.environ.get("SCREENING_ENGINES_PYTHON"), ROOT / ".venv-engines/bin/python",
                      Path(sys.prefix).parent / ".venv-engines/bin/python"):
        if candidate and Path(candidate).exists():
            return str(candidate)
    return None


pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(engines_python() is None, reason="no engines environment (pelicun, OpenQuake): "
                                 "run `make engines` or set SCREENING_ENGINES_PYTHON")]

#: Four objects x two limit states: two fitted and vouched (one of them with points left out of its fit), one
#: whose vouched points are too few for a fit (``untrusted``), one without a fit at the second limit state.  Names with '-' (pelicun splits ids on it) and a negative eps.
NAMES = ["bust-wood", "vase_stone", "clock-case", "lamp"]
MEDIAN = np.array([[1.2, 2.5, np.nan, 1.8], [2.0, 4.0, np.nan, np.nan]])      # m s-2, limit_state x case
BETA = np.array([[0.3, 0.4, np.nan, 0.5], [0.3, 0.45, np.nan, np.nan]])
FLAG = np.array([[0, 0, int(FitFlag.untrusted), 0], [0, 0, int(FitFlag.untrusted), int(FitFlag.never_exceeded)]])
UNVOUCHED = np.array([[0, 2, 3, 0], [0, 2, 3, 0]])


def fragility():
    pga = np.geomspace(0.5, 8.0, 6)
    x = xr.DataArray(np.tile(pga, (4, 1)), dims=("case", "pga"), attrs={"units": "m s-2"})
    frag = xr.Dataset(
        {"fit_median": (("limit_state", "case"), MEDIAN, {"units": "m s-2", "intensity": "pga_median"}),
         "beta": (("limit_state", "case"), BETA), "fit_flag": (("limit_state", "case"), FLAG.astype(np.int8)),
         "fit_n_unvouched": (("limit_state", "case"), UNVOUCHED.astype(np.int32)),
         "fit_im_min": (("limit_state", "case"), np.full((2, 4), 0.5), {"units": "m s-2"}),
         "fit_im_max": (("limit_state", "case"), np.full((2, 4), 4.0), {"units": "m s-2"}),
         "threshold_rad": (("limit_state",), [0.01, 0.05]), "pga_median": x},
        coords={"limit_state": ["theta_0.1_slenderness", "theta_0.5_slenderness"], "case": np.arange(4),
                "case_name": ("case", NAMES), "m": ("case", [8.67, 20.0, 35.0, 2.0], {"units": "kg"}),
                "eps": ("case", [-6e5, 6e7, 0.0, 0.0], {"units": "m-2"}), "pga": pga,
                "h": ((), 0.21, {"units": "m"})})
    return frag


@pytest.fixture(scope="module")
def read_back(tmp_path_factory):
    folder = tmp_path_factory.mktemp("engines")
    frag = fragility()
    paths = {"csv": write_csv(frag, folder / "f.csv"), "pelicun": write_pelicun_csv(frag, folder / "f_pelicun.csv"),
             "json": write_pelicun_json(frag, folder / "f_pelicun.json"), "nrml": write_nrml(frag, folder / "f.xml")}
    run = subprocess.run([engines_python(), str(ROOT / "tests/engines/load_exports.py"), str(paths["pelicun"]),
                          str(paths["nrml"])], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return paths, json.loads(run.stdout.strip().splitlines()[-1])


def test_pelicun_loads_the_collection_with_its_own_loader_and_damage_model(read_back):
    paths, got = read_back
    ids = ["screening_case=bust_wood", "screening_case=vase_stone", "screening_case=clock_case",
           "screening_case=lamp"]
    assert sorted(got["pelicun"]["loaded_ids"]) == sorted(ids)   # one level each: no '-' left for pelicun to split on
    params = got["pelicun"]["damage_params"]
    # the complete objects reach the damage model with their betas and their medians, written in g and
    # converted back to pelicun's base units (m s-2) by pelicun itself
    for i in (0, 1):
        p = params[ids[i]]
        assert p["demand"] == "Peak Ground Acceleration" and p["incomplete"] == 0
        np.testing.assert_allclose(p["theta_0"], MEDIAN[:, i], rtol=1e-7)
        np.testing.assert_allclose(p["theta_1"], BETA[:, i], rtol=1e-5)
    # untrusted (clock-case) and missing (lamp) are Incomplete = 1, with the reason in the JSON metadata
    rows = {r["ID"]: r for r in csv.DictReader(open(paths["pelicun"]))}
    assert [rows[i]["Incomplete"] for i in ids] == ["0", "0", "1", "1"]
    assert all(rows[i]["Demand-Offset"] == "0" and rows[i]["Demand-Directional"] == "1" for i in ids)
    meta = json.loads(Path(paths["json"]).read_text())
    assert meta[ids[2]]["Case"] == "clock-case" and "untrusted" in meta[ids[2]]["Comments"]
    assert "never_exceeded" in meta[ids[3]]["Comments"]
    assert meta[ids[0]]["Values"] == {"m": 8.67, "eps": -6e5} and "bust-wood" in meta[ids[0]]["Description"]
    assert set(meta[ids[0]]["LimitStates"]) == {"LS1", "LS2"}


def test_openquake_reads_the_fragility_model_and_its_curves_are_the_fits(read_back):
    paths, got = read_back
    oq = got["openquake"]
    assert oq["limit_states"] == ["theta_0p1_slenderness", "theta_0p5_slenderness"]
    # only the complete, vouched objects are functions; the others are comments with their reason
    assert sorted(oq["functions"]) == ["screening_case=bust-wood", "screening_case=vase_stone"]
    text = Path(paths["nrml"]).read_text()
    assert "no fragility function for screening_case=clock-case: theta_0.1_slenderness: no fit (untrusted" in text
    assert "screening_case=vase_stone theta_0.1_slenderness: 2 point(s) left out of the fit" in text
    assert "no fragility function for screening_case=lamp: theta_0.5_slenderness: no fit (never_exceeded" in text
    assert "case 'bust-wood': m = 8.67 kg, eps = -600000 m-2" in text
    for i, fid in enumerate(["screening_case=bust-wood", "screening_case=vase_stone"]):
        f = oq["functions"][fid]
        assert f["imt"] == "PGA"
        assert f["minIML"] == pytest.approx(0.5 / G, rel=1e-5) and f["maxIML"] == pytest.approx(4.0 / G, rel=1e-5)
        grid = np.array(f["grid"])
        for s in range(2):      # OpenQuake's probabilities inside the vouched range are the fitted curve's
            expected = stats.norm.cdf(np.log(grid * G / MEDIAN[s, i]) / BETA[s, i])
            np.testing.assert_allclose(f["poes"][s], expected, rtol=1e-6, atol=1e-12)


def test_csv_carries_the_case_names_and_values():
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        rows = list(csv.DictReader(open(write_csv(fragility(), Path(tmp) / "f.csv"))))
    assert [r["case_name"] for r in rows[:4]] == NAMES and rows[0]["eps"] == "-600000"
    assert rows[0]["im_min"] == "0.5" and rows[0]["im_max"] == "4"
