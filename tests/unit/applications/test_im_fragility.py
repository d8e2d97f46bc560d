"""Fragility over intensity measures: refusals, flags, exports (CSV, OpenQuake NRML) and the CLI."""

import csv
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import xarray as xr
from scipy import stats

import screening
from screening.applications.im_fragility import fragility_over_im, nrml_parameters, write_csv, write_nrml
from screening.cli import main
from screening.core.model import Block, Foundation
from screening.core.excitations.white import WhiteNoise

BLOCK = Block(m=8.67, b=0.035, h=0.21)


@pytest.fixture(scope="module")
def result():
    s0 = np.geomspace(1e-5, 3e-3, 10)
    eps = xr.DataArray([0.0, 6e7], dims="eps", coords={"eps": [0.0, 6e7]})
    return screening.linearize(BLOCK, Foundation(k=2.89e7, lam=8.95e8, eps=eps),
                               WhiteNoise(xr.DataArray(s0, dims="S0", coords={"S0": s0}), band_limit_hz=None),
                               t_end=20.0, dt=0.05)   # the paper's white noise: the fitted numbers below


def test_pga_fit_is_the_s0_fit_transformed(result):
    """PGA is proportional to sqrt(S0): median_pga = pga(median_S0), beta_pga = beta_S0 / 2."""
    by_s0, _ = fragility_over_im(result, 0.1, "s0", relative_to="slenderness")
    by_pga, warnings = fragility_over_im(result, 0.1, "pga", relative_to="slenderness")
    assert not warnings
    ok = np.isfinite(by_s0["fit_median"].values)
    assert ok.any()
    np.testing.assert_allclose(by_pga["beta"].values[ok], by_s0["beta"].values[ok] / 2, rtol=1e-9)
    pga_per_sqrt_s0 = (by_pga["pga_median"] / np.sqrt(by_pga["S0"])).isel(S0=0)
    np.testing.assert_allclose(by_pga["fit_median"].values[ok],
                               (pga_per_sqrt_s0 * np.sqrt(by_s0["fit_median"])).values[ok], rtol=1e-9)


def test_refuses_non_intensity_and_non_monotone(result):
    with pytest.raises(ValueError, match="not an intensity dimension"):
        fragility_over_im(result, 0.1, "pga", dim="eps", relative_to="slenderness")
    reversed_ = result.isel(S0=slice(None, None, -1))
    with pytest.raises(ValueError, match="not strictly increasing"):
        fragility_over_im(reversed_, 0.1, "pga", relative_to="slenderness")
    with pytest.raises(ValueError, match="period"):
        fragility_over_im(result, 0.1, "sa", relative_to="slenderness")


def test_flags_negative_beta_and_threshold_beyond_slenderness(result):
    flipped = result.copy()
    flipped["var_theta"] = flipped["var_theta"].isel(S0=slice(None, None, -1)).assign_coords(S0=result.S0)
    flipped["var_theta_dot"] = flipped["var_theta_dot"].isel(S0=slice(None, None, -1)).assign_coords(S0=result.S0)
    flipped["cov_theta_theta_dot"] = flipped["cov_theta_theta_dot"].isel(S0=slice(None, None, -1)).assign_coords(
        S0=result.S0)
    frag, warnings = fragility_over_im(flipped, 0.1, "pga", relative_to="slenderness")
    assert (frag["fit_flag"] == 1).any() and any("beta <= 0" in w for w in warnings)
    _, warnings = fragility_over_im(result, 1.0, "pga", relative_to="slenderness")
    assert any("slenderness" in w for w in warnings)


def test_csv_and_nrml_exports(result, tmp_path):
    # without the trust rule's verdicts (trust=False) no point is known to be untrusted: every fit is exported
    # (fits through untrusted points are left out of the NRML: the next test)
    frag, _ = fragility_over_im(result.drop_vars(["sl_trust", "sl_error_low", "sl_error_high"]), 0.1, "pga",
                                relative_to="slenderness")
    rows = list(csv.DictReader(open(write_csv(frag, tmp_path / "f.csv"))))
    ok = np.isfinite(frag["fit_median"].values)
    assert len(rows) == ok.size and rows[0]["intensity_measure"] == "pga_median" and rows[0]["units"] == "m s-2"
    fitted = [r for r in rows if r["fit_flag"] == "ok"]
    assert len(fitted) == ok.sum()
    assert float(fitted[0]["median"]) == pytest.approx(float(frag["fit_median"].values[ok][0]), rel=1e-7)
    root = ET.parse(write_nrml(frag, tmp_path / "f.xml")).getroot()
    ns = {"n": "http://openquake.org/xmlns/nrml/0.5"}
    fun = root.find("n:fragilityModel/n:fragilityFunction", ns)
    assert fun.get("shape") == "logncdf" and fun.find("n:imls", ns).get("imt") == "PGA"
    par = fun.find("n:params", ns)
    mean, std = float(par.get("mean")), float(par.get("stddev"))
    # OpenQuake's reading of (mean, stddev) reproduces the fitted curve, IM in g
    sigma = math.sqrt(math.log(1 + (std / mean) ** 2))
    mu = mean**2 / math.sqrt(std**2 + mean**2)
    median_g = float(frag["fit_median"].values[ok][0]) / 9.80665
    # mean and stddev are written with 8 significant digits: the curve is reproduced to about 1e-7 of them
    assert stats.lognorm.cdf(median_g, sigma, scale=mu) == pytest.approx(0.5, abs=1e-6)
    assert sigma == pytest.approx(float(frag["beta"].values[ok][0]), rel=1e-7)
    assert nrml_parameters(1.0, 0.0) == (1.0, 0.0)


def test_cli_fragility_im(result, tmp_path, capsys):
    path = tmp_path / "res.nc"
    result.to_netcdf(path)
    assert main(["fragility", str(path), "--threshold", "0.1", "--relative-to", "slenderness", "--im", "pga"]) == 0
    for suffix in (".nc", ".png", ".csv", ".xml"):
        assert (tmp_path / f"res_fragility_pga{suffix}").exists()
    assert "lognormal fit over pga_median" in capsys.readouterr().err
    assert main(["fragility", str(path), "--threshold", "0.1", "--im", "pga", "--dim", "eps"]) == 2
    assert "not an intensity dimension" in capsys.readouterr().err


def test_linearize_results_carry_trust_and_fits_count_the_untrusted_points(result, tmp_path):
    """screening.linearize returns sl_trust and its band by default; a fit leaves out the untrusted and the
    stopped points of its curve (no [accuracy] here: none has a best estimate), counts them, and the CSV and
    NRML say so."""
    assert {"sl_trust", "sl_error_low", "sl_error_high"} <= set(result.data_vars)
    frag, _ = fragility_over_im(result, 0.1, "pga", relative_to="slenderness")
    stopped = result["status"].isin([1, 2])
    untrusted = (((result["sl_trust"] == 2) & (result["status"] == 0)) | stopped).sum("S0")
    np.testing.assert_array_equal(frag["fit_n_unvouched"].values, untrusted.transpose(*frag["fit_n_unvouched"].dims))
    rows = list(csv.DictReader(open(write_csv(frag, tmp_path / "f.csv"))))
    assert [int(r["n_unvouched"]) for r in rows] == list(untrusted.values)
    text = open(write_nrml(frag, tmp_path / "f.xml")).read()
    fitted = frag["fit_flag"].values == 0
    shaky = int(np.sum(fitted & (frag["fit_n_unvouched"].values > 0)))
    assert shaky > 0 and text.count("point(s) left out of the fit (nothing vouches for them)") == shaky
    # such a fit stands on its vouched points: a function of the NRML, over the range they vouch for
    assert text.count("<fragilityFunction") == int(np.sum(fitted))


def test_a_separated_fit_is_incomplete_and_not_a_function(tmp_path):
    """Stripes that separate exceeding from not exceeding perfectly (beta not identified) carry
    ``fit_degenerate``: the pelicun row is Incomplete with the reason in the JSON, the NRML has no function."""
    import json

    from screening.applications.im_fragility import write_pelicun_csv, write_pelicun_json

    frag = xr.Dataset({"fit_median": ((), 2.0, {"units": "m s-2", "intensity": "stripe_pga"}), "beta": 0.013,
                       "fit_flag": np.int8(0), "threshold_rad": 0.01, "stripe_pga": ("level", [1.0, 2.0, 4.0])},
                      attrs={"fit_degenerate": "the stripes separate exceeding from not exceeding perfectly"})
    rows = list(csv.DictReader(open(write_pelicun_csv(frag, tmp_path / "p.csv"))))
    assert rows[0]["Incomplete"] == "1" and rows[0]["LS1-Theta_0"] == ""
    meta = json.loads(write_pelicun_json(frag, tmp_path / "p.json").read_text())
    assert "degenerate: the stripes separate" in meta["screening"]["Comments"]
    text = open(write_nrml(frag, tmp_path / "f.xml")).read()
    assert "<fragilityFunction" not in text and "no fragility function for screening: theta_exceeds_threshold: " \
        "degenerate" in text
