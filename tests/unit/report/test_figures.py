"""Figures (screening.report.figures) on synthetic result datasets of every grid shape."""

import numpy as np
import pytest
import xarray as xr
from matplotlib.image import imread

from screening.solvers.moments import HISTORY_VARIABLES
from screening.schema import LINEARIZATION as VARIABLES
from screening.report.figures import (plot_histories, plot_peaks, plot_result, plot_spots, point_label, spot_file_label,
                             representative_points)
from screening.schema import attributes

PNG = b"\x89PNG\r\n\x1a\n"


def synthetic(dims, sizes, spots=0, seed=0):
    """A dataset with the layout of a sweep result (values are arbitrary but positive)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0, 21)
    shape = tuple(sizes)
    coords = {"t": ("t", t, {"units": "s"})}
    for dim, n in zip(dims, sizes):
        if dim == "case":
            coords["case"] = ("case", np.arange(n))
            coords["case_name"] = ("case", [f"c{i}" for i in range(n)])
        elif dim == "k":
            coords["k_value"] = ("k", np.linspace(1e7, 3e7, n), {"units": "N m-2"})
        else:
            coords[dim] = (dim, np.geomspace(1e-5, 1e-3, n), {"units": "m2 s-3"})
    peak = rng.uniform(1e-8, 1e-4, shape)
    data = {name: (dims + ("t",), rng.uniform(0.1, 1.0, shape + (21,)).astype(np.float32),
                   VARIABLES[name]) for name in HISTORY_VARIABLES}
    data["status"] = (dims, np.zeros(shape, dtype=np.int8), attributes("status"))
    data["peak_var_theta"] = (dims, peak, VARIABLES["peak_var_theta"])
    data["peak_p_uplift"] = (dims, rng.uniform(0, 1, shape), VARIABLES["peak_p_uplift"])
    data["min_k_eq"] = (dims, rng.uniform(10, 1000, shape), VARIABLES["min_k_eq"])
    ds = xr.Dataset(data, coords=coords, attrs={"title": "synthetic"})
    if spots:
        for dim, n in zip(dims, sizes):
            if dim == "case":
                ds["spot_case"] = ("spot", np.arange(spots) % n)
            else:
                values = ds["k_value" if dim == "k" else dim].values
                ds[f"spot_{dim}"] = ("spot", values[np.arange(spots) % n])
        for name in ("var_theta", "var_theta_dot"):
            ds[f"mcs_{name}"] = (("spot", "t"), rng.uniform(0.1, 1.0, (spots, 21)))
            ds[f"mcs_{name}_se"] = (("spot", "t"), np.full((spots, 21), 0.01))
            ds[f"mcs_rel_error_peak_{name}"] = ("spot", rng.uniform(-0.2, 0.2, spots))
        ds["mcs_n_overturned"] = ("spot", np.arange(spots))
        ds.attrs.update(mcs_model="coupled", mcs_samples=10)
    return ds


def assert_png(path, min_width=500):
    assert path.read_bytes()[:8] == PNG
    image = imread(path)
    assert image.shape[1] >= min_width
    assert image[..., :3].std() > 0.05          # not a blank canvas


@pytest.mark.parametrize("dims, sizes", [(("eps", "S0"), (4, 6)), (("S0",), (7,)), (("case",), (3,)),
                                          (("k", "eps", "S0"), (2, 3, 4)), (("case", "S0"), (2, 5))],
                         ids=["2d", "1d", "cases", "3d-with-k", "case-x-S0"])
def test_all_figures_for_every_grid_shape(tmp_path, dims, sizes):
    ds = synthetic(dims, sizes, spots=2)
    paths = plot_result(ds, "r", tmp_path)
    labels = [spot_file_label(ds, i) for i in range(2)]
    assert [p.name for p in paths] == ["r_histories.png", "r_peaks.png", "r_spots.png",
                                       f"r_spot0_{labels[0]}.png", f"r_spot1_{labels[1]}.png"]
    assert labels[0] != labels[1] and all(c not in "".join(labels) for c in " ,=/")
    for p in paths:
        assert_png(p)


def test_single_point_has_histories_but_no_maps(tmp_path):
    ds = synthetic((), ())
    assert representative_points(ds) == [{}]
    assert plot_peaks(ds, tmp_path / "p.png") is None and not (tmp_path / "p.png").exists()
    assert plot_spots(ds, tmp_path / "s.png") is None
    assert_png(plot_histories(ds, tmp_path / "h.png"))
    assert point_label(ds, {}) == "single point"


def test_representative_points_are_min_median_max_and_top_uplift():
    ds = synthetic(("eps", "S0"), (3, 4))
    peak = np.arange(12, dtype=float).reshape(3, 4) + 1.0
    upl = np.zeros((3, 4))
    upl[1, 2] = 0.9
    status = np.zeros((3, 4), dtype=np.int8)
    status[2, 3] = 1                                   # the largest peak is not ok: ignored
    ds["peak_var_theta"].values[:] = peak
    ds["peak_p_uplift"].values[:] = upl
    ds["status"].values[:] = status
    points = representative_points(ds)
    assert points == [{"eps": 0, "S0": 0}, {"eps": 1, "S0": 1}, {"eps": 2, "S0": 2}, {"eps": 1, "S0": 2}]
    assert point_label(ds, points[0]) == "eps=1e-05, S0=1e-05"


def test_labels_use_case_names_and_k_values():
    ds = synthetic(("case", "k"), (2, 3))
    assert point_label(ds, {"case": 1, "k": 2}) == "c1, k=3e+07"
