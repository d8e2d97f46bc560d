"""``screening.linearize`` as an xarray-native function: scalars, 1-d arrays and DataArrays broadcast by name."""

import numpy as np
import pytest
import xarray as xr

from screening import Block, Envelope, Foundation, KanaiTajimi, WhiteNoise, linearize
from screening.core.condensation import cubic
from screening.solvers.schema import DERIVED, LINEARIZATION, PARAMETERS
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.solvers.timegrid import output_times

SUMMARIES = ("peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq", "status", "t_stop", "n_steps")
BED = dict(k=2.89e7, lam=8.95e8)


def assert_point_equals(grid_point, one, rtol=1e-12):
    """A point of a grid result equals the scalar result, every history, summary and derived value."""
    for name in HISTORY_VARIABLES + SUMMARIES + ("theta_ul", "slenderness"):
        np.testing.assert_allclose(grid_point[name].values, one[name].values, rtol=rtol, atol=0.0, err_msg=name)


def test_scalar_input_gives_0d_summaries_and_parameters_as_scalar_coordinates(paper_block):
    bed, exc = Foundation(eps=6e7, **BED), WhiteNoise(2.4e-5, Envelope(4.0, 2.0))
    ds = linearize(paper_block, bed, exc, t_end=6.0, condensation="paper")     # eq. (19)'s theta_ul below
    direct = solve_moments(paper_block, bed, exc, output_times(6.0, 0.05), condensation="paper")
    assert dict(ds.sizes) == {"t": 121}
    for name in HISTORY_VARIABLES:
        assert ds[name].dims == ("t",)
        np.testing.assert_array_equal(ds[name].values, direct[name])
    for name in SUMMARIES:
        assert ds[name].dims == ()
        np.testing.assert_array_equal(ds[name].values, direct[name])
    for name in ("m", "b", "h", "I_cm", "g", "k", "lam", "eps", "S0", "T1", "T2"):
        assert name in ds.coords and ds[name].ndim == 0 and ds[name].attrs == PARAMETERS[name]
    assert float(ds["I_cm"]) == paper_block.I_cm and float(ds["S0"]) == 2.4e-5
    assert float(ds["theta_ul"]) == paper_block.m * paper_block.g / (2 * paper_block.b**2 * 2.89e7)
    assert float(ds["slenderness"]) == paper_block.slenderness
    assert ds["slenderness"].attrs == DERIVED["slenderness"] and ds["peak_var_theta"].attrs == LINEARIZATION[
        "peak_var_theta"]
    assert {k: ds.attrs[k] for k in ("contact", "excitation", "envelope", "condensation")} == {
        "contact": "hunt_crossley", "excitation": "white", "envelope": "exponential", "condensation": "paper"}
    assert not any(name in ds.attrs for name in PARAMETERS)          # one home: the coordinates


def test_labels_follow_the_model_kind():
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, c=2e4), KanaiTajimi(1e-4, 10.0, 0.4),
                   t_end=2.0)
    assert "c" in ds.coords and "lam" not in ds.coords
    assert float(ds["omega_g"]) == 10.0 and float(ds["zeta_g"]) == 0.4
    assert ds.attrs["contact"] == "winkler" and ds.attrs["excitation"] == "kanai_tajimi"


def test_a_1d_array_is_a_dimension_named_after_its_parameter(paper_block):
    S0 = np.array([1e-5, 2e-4, 5e-4])
    ds = linearize(paper_block, Foundation(**BED), WhiteNoise(S0), t_end=4.0)
    assert ds["var_theta"].dims == ("S0", "t") and ds["status"].dims == ("S0",)
    np.testing.assert_array_equal(ds["S0"].values, S0)
    assert ds["S0"].attrs == PARAMETERS["S0"]
    assert ds["theta_ul"].dims == () and ds["slenderness"].dims == ()        # S0 is not their parameter
    for i, s in enumerate(S0):
        assert_point_equals(ds.isel(S0=i), linearize(paper_block, Foundation(**BED), WhiteNoise(s), t_end=4.0))


def test_two_parameters_broadcast_as_an_outer_product_equal_to_point_by_point_calls(paper_block):
    eps = np.array([-6e5, 0.0, 6e7])
    S0 = xr.DataArray([1e-5, 5e-4], dims="S0", coords={"S0": [1e-5, 5e-4]})
    ds = linearize(paper_block, Foundation(eps=eps, **BED), WhiteNoise(S0, Envelope(4.0, 2.0)), t_end=6.0)
    assert ds["var_theta"].dims == ("eps", "S0", "t") and ds["peak_var_theta"].shape == (3, 2)
    assert ds["theta_ul"].dims == ("eps",)
    for i, e in enumerate(eps):
        for j in range(2):
            one = linearize(paper_block, Foundation(eps=e, **BED), WhiteNoise(float(S0[j]), Envelope(4.0, 2.0)),
                            t_end=6.0)
            assert_point_equals(ds.isel(eps=i, S0=j), one)


def test_a_dataarray_keeps_its_own_dimension_and_coordinates():
    names = ["slim", "squat", "tall"]
    b = xr.DataArray([0.035, 0.06, 0.03], dims="shape", coords={"shape": names})
    h = xr.DataArray([0.21, 0.15, 0.30], dims="shape", coords={"shape": names})
    kind = xr.DataArray(["a", "b", "c"], dims="shape", coords={"shape": names})
    b = b.assign_coords(kind=kind)
    S0 = np.array([1e-5, 5e-4])
    ds = linearize(Block(8.67, b, h), Foundation(**BED), WhiteNoise(S0), t_end=4.0)
    assert ds["var_theta"].dims == ("shape", "S0", "t")
    assert list(ds["shape"].values) == names and list(ds["kind"].values) == ["a", "b", "c"]   # kept as given
    assert ds["b"].dims == ("shape",) and ds["b"].attrs == PARAMETERS["b"]
    # the default I_cm follows b and h along their dimension
    np.testing.assert_allclose(ds["I_cm"].values, 8.67 * (b.values**2 + h.values**2) / 3, rtol=1e-15)
    np.testing.assert_array_equal(ds["slenderness"].values, np.arctan2(b.values, h.values))
    for i in range(3):
        for j in range(2):
            one = linearize(Block(8.67, float(b[i]), float(h[i])), Foundation(**BED), WhiteNoise(S0[j]), t_end=4.0)
            assert_point_equals(ds.isel(shape=i, S0=j), one)


def test_default_inertia_is_derived_again_on_the_grid():
    m, b = np.array([8.67, 12.0]), np.array([0.035, 0.05])
    ds = linearize(Block(m, b, 0.21), Foundation(**BED), WhiteNoise(1e-4), t_end=2.0)
    assert ds["var_theta"].dims == ("m", "b", "t") and ds["I_cm"].dims == ("m", "b")
    for i in range(2):
        for j in range(2):
            one = linearize(Block(m[i], b[j], 0.21), Foundation(**BED), WhiteNoise(1e-4), t_end=2.0)
            assert float(ds["I_cm"][i, j]) == pytest.approx(float(one["I_cm"]), rel=1e-15)
            assert_point_equals(ds.isel(m=i, b=j), one)
    given = linearize(Block(m, 0.035, 0.21, I_cm=0.2), Foundation(**BED), WhiteNoise(1e-4), t_end=2.0)
    assert given["I_cm"].ndim == 0 and float(given["I_cm"]) == 0.2


def test_cubic_grid_has_capacity_variables(paper_block):
    eps = np.array([-2e7, 6e7])
    ds = linearize(paper_block, Foundation(eps=eps, **BED), WhiteNoise(5e-4, Envelope(4.0, 2.0)),
                   condensation="cubic")
    assert ds["theta_capacity"].dims == ("eps",) and ds["peak_p_beyond_capacity"].dims == ("eps",)
    assert "theta_capacity" not in ds.attrs
    for i, e in enumerate(eps):
        one = linearize(paper_block, Foundation(eps=e, **BED), WhiteNoise(5e-4, Envelope(4.0, 2.0)),
                        condensation="cubic")
        assert float(ds["theta_capacity"][i]) == one.attrs["theta_capacity"]
        assert float(ds["peak_p_beyond_capacity"][i]) == pytest.approx(one.attrs["peak_p_beyond_capacity"],
                                                                       rel=1e-12, abs=0.0)
        assert float(ds["theta_ul"][i]) == cubic.uplift_threshold(paper_block, Foundation(eps=e, **BED))
    assert np.isinf(ds["theta_capacity"][1]) and float(ds["peak_p_beyond_capacity"][1]) == 0.0


def test_inputs_that_cannot_be_labelled_raise_clearly(paper_block):
    with pytest.raises(ValueError, match="'S0'.*1-d array.*shape"):
        linearize(paper_block, Foundation(**BED), WhiteNoise(np.full((2, 2), 1e-4)))
    a = xr.DataArray([1e-5, 1e-4], dims="x", coords={"x": [0, 1]})
    b = xr.DataArray([6e7, 0.0], dims="x", coords={"x": [0, 2]})
    with pytest.raises(ValueError, match="same coordinate values"):
        linearize(paper_block, Foundation(eps=b, **BED), WhiteNoise(a))
    with pytest.raises(ValueError, match="'t' is reserved"):
        linearize(paper_block, Foundation(**BED), WhiteNoise(xr.DataArray([1e-5, 1e-4], dims="t")))
    with pytest.raises(ValueError, match="named 'eps'"):
        linearize(paper_block, Foundation(eps=0.0, **BED), WhiteNoise(xr.DataArray([1e-5, 1e-4], dims="eps")))
    with pytest.raises(ValueError, match="'S0'"):
        WhiteNoise(xr.DataArray([1e-5, -1.0], dims="x"))             # values are validated


def test_model_objects_keep_dataarrays():
    S0 = xr.DataArray([1e-5, 1e-4], dims="x", coords={"x": [3, 4]})
    exc = WhiteNoise(S0)
    assert isinstance(exc.S0, xr.DataArray) and exc.S0.dims == ("x",) and exc.S0.dtype == np.float64
    blk = Block(xr.DataArray([8, 9], dims="x"), 0.035, 0.21)          # integers: stored as floats
    assert blk.m.dtype == np.float64 and isinstance(blk.I_cm, xr.DataArray)
