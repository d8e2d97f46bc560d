"""The result file: CF-1.8 (IOOS compliance-checker, strict), metadata and storage layout."""

import shutil
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from screening import Block, Foundation, __version__
from screening.core.condensation.api import uplift_threshold
from screening.solvers.moments import HISTORY_VARIABLES
from helpers import assert_cdo_form_of, in_process_client, quiet

from screening.cli import main
from screening.solvers.schema import DERIVED, LINEARIZATION, PARAMETERS

VARIABLES = {**LINEARIZATION, **DERIVED}
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

CHECKER = Path(sys.executable).parent / "compliance-checker"

#: GRID and CASES run under the default condensation.  The [accuracy] stage escalates points of GRID; CASES's
#: target (0.15) is below what the error model vouches for at its "white" case, so one point escalates to
#: Monte Carlo and its esc_* variables have a row (a study that escalates none has them on a dimension of
#: length 0, which the CDO form leaves out and names in ``left_out``).
GRID = """
title = "CF test grid"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = [2.0e7, 2.89e7]
lam = 8.95e8
eps = [-6e5, 6e7]
[excitation]
kind = "white"
S0 = {start = 1e-5, stop = 2.4e-3, num = 3, log = true}
[time]
t_end = 2.0
dt = 0.1
[mcs]
points = "auto"
count = 2
samples = 6
model = "condensed"
[accuracy]
target = 0.5
budget_s = 10
"""

CASES = """
title = "CF test cases – with a non-ASCII dash"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[excitation]
kind = "white"
[time]
t_end = 2.0
dt = 0.1
[[case]]
name = "white"
foundation.eps = 6e7
excitation.S0 = 2.4e-5
[[case]]
name = "filtered"
foundation.eps = -6e5
excitation = {kind = "kanai_tajimi", S0 = 2e-4, omega_g = 10.0, zeta_g = 0.4}
[mcs]
points = [{case = "filtered"}]
samples = 4
model = "condensed"
[accuracy]
target = 0.15
budget_s = 10
"""

SINGLE = """
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[excitation]
kind = "white"
S0 = 1e-4
envelope = "constant"
[time]
t_end = 1.0
dt = 0.1
"""


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cf")
    paths = {}
    with in_process_client(2) as client:
        for name, text in (("grid", GRID), ("cases", CASES), ("single", SINGLE)):
            paths[name] = folder / f"{name}.nc"
            run_sweep(parse_study(text, name=name, source=f"{name}.toml"), paths[name], client=client,
                      progress=False, log=quiet)
    return paths


@pytest.mark.skipif(not CHECKER.exists(), reason="IOOS compliance-checker is not installed in this environment "
                                                 "(pip install compliance-checker)")
@pytest.mark.parametrize("name", [pytest.param("grid", marks=pytest.mark.slow), "cases", "single"])   # grid: slow suite
def test_compliance_checker_cf18_strict_passes(results, name):
    assert_cf18_strict(results[name])


def assert_cf18_strict(path):
    """The IOOS compliance checker passes ``path`` against CF 1.8, strict, without exceptions."""
    proc = subprocess.run([str(CHECKER), "--test=cf:1.8", "--criteria=strict", str(path)],
                          capture_output=True, text=True, timeout=300)
    report = proc.stdout + proc.stderr
    assert proc.returncode == 0, report
    assert "All tests passed!" in proc.stdout, report
    assert "exceptions occurred" not in report, report


def test_dimensions_coordinates_and_units(results):
    with xr.open_dataset(results["grid"]) as ds:
        assert ds["var_theta"].dims == ("k", "eps", "S0", "t")
        assert ds.sizes["spot"] == 2
        for name, var in (("k", "k_value"), ("eps", "eps"), ("S0", "S0")):
            assert ds[var].dims == (name,)
            assert ds[var].attrs["units"] == PARAMETERS[name]["units"]
            assert ds[var].attrs["long_name"] == PARAMETERS[name]["long_name"]
        # k (in pressure units): a coordinate variable without units, its values with units in k_value
        np.testing.assert_array_equal(ds["k"].values, [2.0e7, 2.89e7])
        np.testing.assert_array_equal(ds["k_value"].values, [2.0e7, 2.89e7])
        assert "units" not in ds["k"].attrs and "N m-2" in ds["k"].attrs["comment"]
        assert "k_value" in ds["var_theta"].coords
        assert ds["t"].attrs["units"] == "s" and "axis" not in ds["t"].attrs
        np.testing.assert_allclose(ds["t"].values, np.arange(21) * 0.1)
        for name in HISTORY_VARIABLES + ("peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq",
                                         "t_stop", "n_steps", "theta_ul"):
            assert ds[name].attrs["units"] == VARIABLES[name]["units"], name
            assert ds[name].attrs["long_name"] == VARIABLES[name]["long_name"], name
        for name in ("m", "b", "h", "I_cm", "g", "lam", "T1", "T2"):     # fixed parameters: scalar coords
            assert name in ds["var_theta"].coords and ds[name].ndim == 0
            assert ds[name].attrs["units"] == PARAMETERS[name]["units"]
        assert float(ds["m"]) == 8.67 and float(ds["T1"]) == 4.0
        assert ds["status"].attrs["flag_meanings"].split()[:2] == ["task_failed", "ok"]
        np.testing.assert_array_equal(ds["status"].attrs["flag_values"], [-1, 0, 1, 2, 3, 4, 5])
        first = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.0e7, lam=8.95e8, eps=-6e5)
        assert ds["theta_ul"].values[0, 0, 0] == pytest.approx(float(uplift_threshold(*first)), rel=1e-12)
        assert ds["spot_S0"].attrs["units"] == "m2 s-3"
        assert ds["mcs_rel_error_peak_var_theta"].attrs["units"] == "1"


def test_every_swept_parameter_is_an_index_to_select_and_reduce_on(results):
    """Issue 13: xarray selects by value and reduces over every swept parameter, k included."""
    with xr.open_dataset(results["grid"]) as ds:
        for dim in ("k", "eps", "S0"):
            assert dim in ds.indexes
            values = ds[dim].values
            picked = ds["peak_var_theta"].sel({dim: values[1]})
            np.testing.assert_array_equal(picked.values, ds["peak_var_theta"].isel({dim: 1}).values)
            near = ds["peak_var_theta"].sel({dim: values[0] * (1 + 1e-9)}, method="nearest")
            np.testing.assert_array_equal(near.values, ds["peak_var_theta"].isel({dim: 0}).values)
            peak = ds["var_theta"].max(dim)
            assert dim not in peak.dims and peak.sizes["t"] == ds.sizes["t"]
        assert ds.sel(k=2.89e7, eps=6e7)["status"].dims == ("S0",)


@pytest.mark.skipif(shutil.which("ncks") is None, reason="NCO (ncks) is not installed")
def test_nco_selects_by_value_on_k(results, tmp_path):
    out = tmp_path / "k.nc"
    proc = subprocess.run(["ncks", "-O", "-d", "k,2.5e7,3.0e7", str(results["grid"]), str(out)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    with xr.open_dataset(out) as ds:
        np.testing.assert_array_equal(ds["k"].values, [2.89e7])


@pytest.fixture(scope="module")
def cdo_files(results, tmp_path_factory):
    """``screening export --layout cdo`` of each result."""
    folder = tmp_path_factory.mktemp("cdo")
    paths = {}
    for name, path in results.items():
        paths[name] = folder / f"{name}_cdo.nc"
        assert main(["export", str(path), str(paths[name]), "--layout", "cdo"]) == 0
    return paths


def _cdo(*args):
    proc = subprocess.run(["cdo", "-s", *map(str, args)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and "Warning" not in proc.stderr, proc.stderr
    return proc.stdout


def test_the_result_itself_is_not_for_cdo(results):
    """Measured reasons for the CDO form (issue 13): CDO takes (time, z, y, x) and finds no time axis
    in t [s]; the result is laid out for xarray and CF (t last, CF coordinates)."""
    with netCDF4.Dataset(results["grid"]) as nc:
        assert nc["var_theta"].dimensions[-1] == "t" and not nc.dimensions["t"].isunlimited()
        assert nc["t"].units == "s" and "k_value" in nc["var_theta"].coordinates


@pytest.mark.parametrize("name", ["grid", "cases", "single"])
def test_the_cdo_form_holds_every_value(results, cdo_files, name):
    assert_cdo_form_of(results[name], cdo_files[name])
    with xr.open_dataset(cdo_files[name]) as ds:        # a user's xarray: t decoded from the placeholder date
        assert ds["t"].dtype.kind == "M"
        assert "coordinates" not in ds["var_theta"].encoding


@pytest.mark.skipif(shutil.which("cdo") is None, reason="CDO is not installed")
@pytest.mark.parametrize("name", ["grid", "cases", "single"])
def test_cdo_lists_every_history_of_the_cdo_form_without_warnings(results, cdo_files, name):
    _cdo("sinfon", cdo_files[name])
    names = _cdo("showname", cdo_files[name]).split()
    assert set(HISTORY_VARIABLES) <= set(names), names
    assert ("status" in names) == (name != "single")      # CDO takes no scalar variables as fields
    with xr.open_dataset(results[name]) as ds:
        assert int(_cdo("ntime", cdo_files[name])) == ds.sizes["t"]


@pytest.mark.skipif(shutil.which("cdo") is None, reason="CDO is not installed")
def test_cdo_reduces_over_time_as_xarray_does(results, cdo_files, tmp_path):
    out = tmp_path / "timmax.nc"
    _cdo("timmax", "-selname,var_theta,k_eq", cdo_files["grid"], out)
    mean = tmp_path / "timmean.nc"
    _cdo("timmean", "-selname,var_theta", cdo_files["grid"], mean)
    with xr.open_dataset(results["grid"]) as ds, xr.open_dataset(out, decode_times=False) as peak, \
            xr.open_dataset(mean, decode_times=False) as avg:
        for name in ("var_theta", "k_eq"):
            assert peak[name].sizes["t"] == 1
            np.testing.assert_array_equal(peak[name].isel(t=0).transpose(*ds["status"].dims).values,
                                          ds[name].max("t").values)
        np.testing.assert_allclose(avg["var_theta"].isel(t=0).values, ds["var_theta"].mean("t").values, rtol=1e-6)


@pytest.mark.skipif(shutil.which("cdo") is None, reason="CDO is not installed")
def test_cdo_selects_along_every_swept_parameter(results, cdo_files, tmp_path):
    """k (the first swept parameter) is CDO's z axis: sellevel by value; eps and S0 its y and x:
    selindexbox (1-based indices)."""
    level, box = tmp_path / "level.nc", tmp_path / "box.nc"
    _cdo("sellevel,2.89e7", cdo_files["grid"], level)
    _cdo("selindexbox,2,3,1,1", "-selname,var_theta,status", cdo_files["grid"], box)
    with xr.open_dataset(results["grid"]) as ds, xr.open_dataset(level, decode_times=False) as a, \
            xr.open_dataset(box, decode_times=False) as b:
        np.testing.assert_array_equal(a["k"].values, [2.89e7])
        np.testing.assert_array_equal(a["var_theta"].isel(k=0).transpose("eps", "S0", "t").values,
                                      ds["var_theta"].sel(k=2.89e7).values)
        np.testing.assert_allclose(a["t"].values, ds["t"].values)      # sub-second times kept
        picked = ds.isel(eps=[0], S0=[1, 2])
        np.testing.assert_array_equal(b["S0"].values, picked["S0"].values)
        np.testing.assert_array_equal(b["var_theta"].transpose("k", "eps", "S0", "t").values,
                                      picked["var_theta"].values)
        np.testing.assert_array_equal(b["status"].isel(t=0).values if "t" in b["status"].dims else b["status"].values,
                                      picked["status"].values)


@pytest.mark.skipif(not CHECKER.exists(), reason="IOOS compliance-checker is not installed in this environment "
                                                 "(pip install compliance-checker)")
@pytest.mark.parametrize("name", ["grid", "cases", "single"])
def test_the_cdo_form_passes_the_cf18_strict_check(cdo_files, name):
    assert_cf18_strict(cdo_files[name])


def test_storage_layout_and_global_attributes(results):
    with netCDF4.Dataset(results["grid"]) as nc:
        for name in ("k", "k_value", "eps", "S0", "t"):
            assert "_FillValue" not in nc[name].ncattrs(), name
        for name in HISTORY_VARIABLES:
            assert nc[name].dtype == np.float32
            assert nc[name].filters()["zlib"] and nc[name].filters()["shuffle"]
            assert nc[name].chunking()[-1] == nc.dimensions["t"].size
        for name in ("peak_var_theta", "min_k_eq", "t_stop"):
            assert nc[name].dtype == np.float64 and nc[name].filters()["zlib"]
        assert nc["status"].dtype == np.int8 and nc["n_steps"].dtype == np.int32
        attrs = nc.__dict__
        assert attrs["Conventions"] == "CF-1.8"
        assert attrs["title"] == "CF test grid"
        assert attrs["screening_version"] == __version__
        assert attrs["study_text"] == GRID
        assert attrs["study_file"] == "grid.toml" and len(attrs["study_sha256"]) == 64
        assert "screening run grid.toml" in attrs["history"]
        assert "2 pi S0" in attrs["intensity_convention"]
        assert attrs["contact"] == "hunt_crossley" and attrs["excitation"] == "white"


def test_case_dimension_layout(results):
    with xr.open_dataset(results["cases"]) as ds:
        assert ds["var_theta"].dims == ("case", "t")
        assert ds["case"].values.tolist() == [0, 1]
        assert ds["case_name"].values.tolist() == ["white", "filtered"]
        assert ds["S0"].dims == ("case",) and ds["S0"].values.tolist() == [2.4e-5, 2e-4]
        assert np.isnan(ds["zeta_g"].values[0]) and ds["zeta_g"].values[1] == 0.4
        assert ds["excitation"].values.tolist() == ["white", "kanai_tajimi"]
        assert ds["spot_case_name"].values.tolist() == ["filtered"]
        assert "–" in ds.attrs["title"]
        assert ds.swap_dims(case="case_name")["peak_var_theta"].sel(case_name="filtered").size == 1


def test_single_point_result_is_dimensionless_but_time(results):
    with xr.open_dataset(results["single"]) as ds:
        assert ds["var_theta"].dims == ("t",)
        assert ds["status"].dims == () and int(ds["status"]) == 0
        assert ds.attrs["envelope"] == "constant" and "T1" not in ds.variables


@pytest.mark.skipif(shutil.which("ncdump") is None, reason="ncdump (netcdf-bin) is not installed")
def test_ncdump_header_reads(results):
    proc = subprocess.run(["ncdump", "-h", str(results["grid"])], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and 'var_theta:units = "rad2"' in proc.stdout


def test_slenderness_is_stored_per_point_from_the_model(results):
    from screening.solvers.schema import attributes

    with xr.open_dataset(results["grid"]) as ds:
        assert ds["slenderness"].dims == ds["theta_ul"].dims == ("k", "eps", "S0")
        np.testing.assert_array_equal(ds["slenderness"].values, np.arctan2(0.035, 0.21))
        assert {k: ds["slenderness"].attrs[k] for k in ("units", "long_name")} == attributes("slenderness")


FOUR_SWEPT = SINGLE.replace("k = 2.89e7\nlam = 8.95e8", "k = [2.0e7, 2.89e7]\nlam = [8.95e8, 1e9]\neps = [0.0, 6e7]").replace(
    "S0 = 1e-4", "S0 = [1e-4, 2e-4]")


def test_the_cdo_form_of_four_swept_parameters_needs_a_selection(tmp_path, capsys):
    """CDO holds 3 dimensions besides time: with 4 swept parameters the export names them and asks for
    --select; with one fixed, CDO reads the rest and its values are those of ds.sel."""
    from helpers import one_line_error

    result = tmp_path / "four.nc"
    with in_process_client(1) as client:
        run_sweep(parse_study(FOUR_SWEPT, name="four", source="four.toml"), result, client=client, progress=False,
                  log=quiet)
    out = tmp_path / "four_cdo.nc"
    assert main(["export", str(result), str(out), "--layout", "cdo"]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert "at most 3 dimensions besides time" in line and "(k, lam, eps, S0)" in line and "--select k=2e+07" in line
    assert not out.exists()
    for bad, said in ((["--select", "m=1"], "one of the swept dimensions (k, lam, eps, S0)"),
                      (["--select", "k=nan"], "finite number"), (["--select", "k"], "expected DIM=VALUE")):
        assert main(["export", str(result), str(out), "--layout", "cdo", *bad]) == 2
        assert said in one_line_error(capsys.readouterr().err)
    assert main(["export", str(result), str(out), "--select", "lam=1e9"]) == 2
    assert "--layout cdo only" in one_line_error(capsys.readouterr().err)
    assert main(["export", str(result), str(out), "--layout", "cdo", "--select", "lam=0.99e9"]) == 0
    with xr.open_dataset(result) as ds, xr.open_dataset(out, decode_times=False) as cdo:
        picked = ds.sel(lam=1e9)
        assert cdo["var_theta"].dims == ("t", "k", "eps", "S0") and float(cdo["lam"]) == 1e9
        np.testing.assert_array_equal(cdo["var_theta"].transpose("k", "eps", "S0", "t").values,
                                      picked["var_theta"].values)
        np.testing.assert_array_equal(cdo["status"].values, picked["status"].values)
        assert "--select lam=0.99e9" in cdo.attrs["history"].splitlines()[-1]
    if shutil.which("cdo"):
        assert set(HISTORY_VARIABLES) <= set(_cdo("showname", out).split())
