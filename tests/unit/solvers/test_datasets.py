"""The result datasets (``screening.solvers.datasets``): one contract for linearize and monte_carlo."""

import math

import numpy as np
import pytest
import xarray as xr

import screening
from screening import Block, ConstantEnvelope, Envelope, Foundation, KanaiTajimi, WhiteNoise, linearize, monte_carlo
from screening.solvers import schema
from screening.core.condensation import cubic, get
from screening.solvers.datasets import finish, linearization_dataset, model_fields
from screening.solvers.moments import solve_moments

BLOCK = Block(8.67, 0.035, 0.21)
HC = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)


def small_mc(foundation=HC, excitation=WhiteNoise(2.4e-5), **kwargs):
    args = dict(n_samples=3, model="condensed", t_end=0.5, dt=0.05, progress=False)
    args.update(kwargs)
    return monte_carlo(BLOCK, foundation, excitation, **args)


def assert_contract(ds, table=None):
    """Parameters are coordinates with the schema's metadata; derived quantities are variables; no
    parameter or derived quantity is an attribute; every variable carries its declared metadata."""
    for name in schema.PARAMETERS:
        assert name not in ds.attrs, name
        if name in ds.variables:
            assert name in ds.coords and ds[name].attrs == schema.PARAMETERS[name], name
    for name in ("theta_ul", "slenderness"):
        assert name in ds.data_vars and name not in ds.attrs and ds[name].attrs["units"] == "rad"
    for name in ds.variables:
        declared = schema.attributes(name, table)
        assert {k: ds[name].attrs[k] for k in ("units", "long_name") if k in declared} == {
            k: declared[k] for k in ("units", "long_name") if k in declared}, name
    assert ds.attrs["Conventions"] == schema.CONVENTIONS and "2 pi S0" in ds.attrs["intensity_convention"]


def test_monte_carlo_is_exported_at_top_level():
    assert screening.monte_carlo is monte_carlo and "monte_carlo" in screening.__all__


def test_linearize_and_monte_carlo_follow_the_same_contract():
    exc = WhiteNoise(2.4e-5, Envelope(4.0, 2.0))
    lin = linearize(BLOCK, HC, exc, t_end=0.5)
    mc = small_mc(excitation=exc)
    assert_contract(lin)
    assert_contract(mc, schema.MONTE_CARLO)
    for name in model_fields(BLOCK, HC, exc):
        assert float(lin[name]) == float(mc[name]), name
    assert float(lin["slenderness"]) == float(mc["slenderness"]) == BLOCK.slenderness
    assert float(lin["theta_ul"]) == float(mc["theta_ul"])                 # both of the paper's condensation
    assert mc["var_theta"].attrs == schema.MONTE_CARLO["var_theta"]
    assert mc["t"].attrs == schema.TIME and mc["sample"].attrs == schema.COORDINATES["sample"]


@pytest.mark.parametrize("foundation, excitation, present, absent", [
    (Foundation(k=2.89e7, c=2e4, eps=-6e5), KanaiTajimi(2e-4, 10.0, 0.4), ("c", "omega_g", "zeta_g", "T1", "T2"),
     ("lam",)),
    (HC, WhiteNoise(1e-5, ConstantEnvelope()), ("lam",), ("c", "omega_g", "zeta_g", "T1", "T2")),
], ids=["winkler_kt", "hc_constant"])
def test_monte_carlo_parameters_follow_the_model_kind(foundation, excitation, present, absent):
    ds = small_mc(foundation=foundation, excitation=excitation, model="coupled")
    assert all(name in ds.coords for name in present) and not any(name in ds.variables for name in absent)
    assert ds.attrs["contact"] == foundation.law and ds.attrs["excitation"] == excitation.kind
    assert ds.attrs["envelope"] == excitation.envelope.kind
    assert float(ds["k"]) == 2.89e7 and float(ds["I_cm"]) == BLOCK.I_cm


def test_monte_carlo_theta_ul_is_that_of_the_condensation_or_the_exact_angle():
    paper = small_mc(condensation="paper")
    cub = small_mc(condensation="cubic")
    coupled = small_mc(model="coupled")
    assert float(paper["theta_ul"]) == get("paper").uplift_threshold(BLOCK, HC)
    assert float(cub["theta_ul"]) == cubic.uplift_threshold(BLOCK, HC) != float(paper["theta_ul"])
    assert float(coupled["theta_ul"]) == float(cub["theta_ul"]) and coupled.attrs["theta_ul_condensation"] == "cubic"
    assert "condensation" not in coupled.attrs and "theta_ul_note" not in coupled.attrs
    assert cub.attrs["theta_capacity"] == math.inf and "theta_capacity" not in paper.attrs
    assert paper.attrs["m_sdof"] == BLOCK.m_sdof


def test_coupled_softening_bed_beyond_the_cubic_limit_falls_back_to_the_paper_threshold():
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=-6e7)          # carries the block, but not under "cubic"
    with pytest.raises(ValueError):
        cubic.uplift_threshold(BLOCK, bed)
    ds = small_mc(foundation=bed, model="coupled")
    assert float(ds["theta_ul"]) == get("paper").uplift_threshold(BLOCK, bed)
    assert ds.attrs["theta_ul_condensation"] == "paper" and "cubic" in ds.attrs["theta_ul_note"]


def test_monte_carlo_dataset_writes_to_netcdf(tmp_path):
    ds = small_mc()
    ds.to_netcdf(tmp_path / "mc.nc")
    with xr.open_dataset(tmp_path / "mc.nc") as back:
        assert float(back["S0"]) == 2.4e-5 and back["theta_ul"].attrs["units"] == "rad"


def test_linearization_dataset_keeps_foreign_coordinates_and_rejects_undeclared_variables():
    t = np.linspace(0.0, 1.0, 5)
    res = solve_moments(BLOCK, HC, WhiteNoise(np.array([1e-5, 1e-4])), t)
    S0 = xr.DataArray([1e-5, 1e-4], dims="x", coords={"x": ["low", "high"]})
    S0.x.attrs["long_name"] = "my label"
    params = {"m": 8.67, "S0": S0}
    derived = {"theta_ul": ((), 1e-3), "slenderness": ((), 0.16)}
    ds = linearization_dataset(res, t, ("x",), params, derived, {"contact": "hunt_crossley"})
    assert ds["x"].attrs == {"long_name": "my label"} and ds["S0"].attrs == schema.PARAMETERS["S0"]
    assert ds["var_theta"].dims == ("x", "t") and float(ds["m"]) == 8.67
    with pytest.raises(KeyError, match="'not_declared'"):
        finish(ds.assign(not_declared=((), 1.0)))
