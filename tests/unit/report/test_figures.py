"""Figures (screening.report: figures, spot_figures, fragility_figures) on synthetic result datasets of every grid shape."""

import numpy as np
import pytest
import xarray as xr
from matplotlib.image import imread

from screening.solvers.moments import HISTORY_VARIABLES
from screening.solvers.schema import LINEARIZATION as VARIABLES
from screening.report.figure_base import point_label
from screening.report.figures import plot_histories, plot_peaks, plot_result, representative_points
from screening.report.spot_figures import plot_spots, spot_file_label
from screening.solvers.schema import attributes

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


# ----------------------------------------------------------------------------- flagged and untrusted points
from screening.report import figures, fragility_figures, spot_figures  # noqa: E402
from screening.core.status import PointStatus, Trust  # noqa: E402


def _flagged(dims, sizes, spots=0):
    """A synthetic result with one flagged point (status 1, a finite peak up to its stop), one
    untrusted point and the slenderness angle."""
    ds = synthetic(dims, sizes, spots=spots)
    flat = ds["status"].values.reshape(-1)
    flat[1] = PointStatus.k_eq_negative
    trust = np.full(flat.shape, Trust.check, dtype=np.int8)
    trust[1], trust[2], trust[0] = Trust.untrusted, Trust.untrusted, Trust.trusted
    ds["sl_trust"] = (dims, trust.reshape(ds["status"].shape), attributes("sl_trust"))
    ds["slenderness"] = ((), 0.1648, {"units": "rad"})
    return ds


@pytest.fixture
def drawn(monkeypatch):
    """The figures passed to ``save_figure`` (in order)."""
    figs = []
    for module in (figures, spot_figures, fragility_figures):
        monkeypatch.setattr(module, "save_figure", lambda fig, path: figs.append(fig))
    return figs


def _texts(fig):
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    return [t.get_text() for legend in legends for t in legend.get_texts()]


def test_curves_mask_flagged_points_and_mark_untrusted_ones(drawn):
    ds = _flagged(("S0",), (7,))
    figures.plot_peaks(ds, "unused.png")
    fig = drawn[0]
    peak_line = fig.axes[0].get_lines()[0]
    y = np.asarray(peak_line.get_ydata(), dtype=float)
    assert np.isnan(y[1]) and np.isfinite(y[[0, 2, 3]]).all()          # flagged: not an ordinary value
    hollow = fig.axes[0].get_lines()[1]                                 # untrusted ring (status ok only)
    np.testing.assert_array_equal(hollow.get_xdata(), ds["S0"].values[[2]])
    crosses = fig.axes[0].get_lines()[2]
    np.testing.assert_array_equal(crosses.get_xdata(), ds["S0"].values[[1]])
    texts = _texts(fig)
    assert "flagged (status != ok, not a value): 1" in texts and "linearization untrusted: 1" in texts
    assert "k_eq_negative 1" in fig.get_suptitle() and "untrusted 2" in fig.get_suptitle()


def test_maps_mask_flagged_cells_and_name_the_status_colours(drawn):
    ds = _flagged(("eps", "S0"), (3, 4))
    figures.plot_peaks(ds, "unused.png")
    fig = drawn[0]
    mesh = fig.axes[0].collections[0]
    z = np.ma.getmaskarray(mesh.get_array()).reshape(3, 4)
    assert z[0, 1] and not z[0, 0]                                      # flagged cell masked
    assert len(fig.axes[0].collections) == 3                            # + flagged and untrusted hatches
    status_bar = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"][-1]
    labels = [t.get_text() for t in status_bar.get_yticklabels()]
    assert labels == str(ds["status"].attrs["flag_meanings"]).split()
    assert "linearization untrusted: 1" in _texts(fig)


@pytest.mark.parametrize("response", ["sigma", "fraction"])
def test_response_as_sigma_or_a_fraction_of_the_slenderness(drawn, response):
    ds = _flagged(("S0",), (7,))
    figures.plot_peaks(ds, "unused.png", response=response)
    y = np.asarray(drawn[0].axes[0].get_lines()[0].get_ydata(), dtype=float)
    expected = np.sqrt(ds["peak_var_theta"].values) / (0.1648 if response == "fraction" else 1.0)
    np.testing.assert_allclose(y[[0, 2]], expected[[0, 2]], rtol=1e-12)
    assert ("atan(b/h)" in drawn[0].axes[0].get_ylabel()) == (response == "fraction")


def test_fraction_without_the_slenderness_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="slenderness"):
        figures.plot_result(synthetic(("S0",), (4,)), "r", tmp_path, response="fraction")


def test_histories_and_spots_say_which_points_are_flagged_or_untrusted(drawn):
    ds = _flagged(("S0",), (7,), spots=3)
    figures.plot_histories(ds, "unused.png", points=[{"S0": 0}, {"S0": 1}, {"S0": 2}])
    labels = [line.get_label() for line in drawn[0].axes[0].get_lines()]
    assert labels[1].endswith("[flagged: k_eq_negative]") and labels[2].endswith("[linearization untrusted]")
    assert drawn[0].axes[0].get_lines()[2].get_linestyle() == "--"
    assert "untrusted 2" in drawn[0].get_suptitle()
    spot_figures.plot_spots(ds, "unused.png")
    titles = [ax.get_title() for ax in drawn[1].axes]
    assert "[linearization trusted]" in titles[0] and "[flagged: k_eq_negative]" in titles[2]


def test_fragility_monte_carlo_points_take_the_colour_of_their_curve(drawn):
    from matplotlib.colors import to_rgba

    ds = _flagged(("eps", "S0"), (2, 5))
    p = xr.DataArray(np.linspace(0, 1, 10).reshape(2, 5), dims=("eps", "S0"), coords={"eps": ds["eps"], "S0": ds["S0"]})
    frag = xr.Dataset({"p_exceed": p, "mcs_p_exceed": ("spot", [0.2, 0.7]), "mcs_p_exceed_se": ("spot", [0.05, 0.05])},
                      coords={"spot_eps": ("spot", ds["eps"].values[[0, 1]]), "spot_S0": ("spot", ds["S0"].values[[2, 3]])},
                      attrs={"threshold": 0.02, "relative_to": "slenderness", "method": "vanmarcke"})
    frag["S0"].attrs["units"] = "m2 s-3"
    fragility_figures.plot_fragility(frag, "S0", "unused.png", flags=ds[["status", "sl_trust"]])
    ax = drawn[0].axes[0]
    curves = {line.get_label(): line.get_color() for line in ax.get_lines() if line.get_label().startswith("eps=")}
    markers = [c for c in ax.containers]                                   # one errorbar per curve
    assert len(markers) == 2
    for container, eps in zip(markers, ds["eps"].values):
        assert to_rgba(container.lines[0].get_color()) == to_rgba(curves[f"eps={eps:.3g}"])
    assert any(t.startswith("flagged (status != ok): 1 of 10") for t in _texts(drawn[0]))


def test_fragility_draws_the_best_estimate_band_and_says_which_method_gave_each_point(drawn):
    from screening.report.fragility_figures import BEST_MARKERS
    from screening.core.status import BestMethod

    ds = _flagged(("S0",), (6,))
    s0 = ds["S0"]
    p = xr.DataArray(np.linspace(0.05, 0.9, 6), dims="S0", coords={"S0": s0})
    method = np.array([BestMethod.linearization, BestMethod.corrected_linearization, BestMethod.coupled_monte_carlo,
                       BestMethod.condensed_monte_carlo, BestMethod.stiff_bed_monte_carlo, BestMethod.unreliable],
                      dtype=np.int8)
    low = (p - 0.05).where(method != BestMethod.unreliable)
    frag = xr.Dataset({"p_exceed": p, "best_p_exceed": p + 0.01, "best_p_exceed_low": low,
                       "best_p_exceed_high": low + 0.1, "best_method": ("S0", method)},
                      attrs={"threshold": 0.02, "relative_to": "slenderness", "method": "vanmarcke"})
    frag["S0"].attrs["units"] = "m2 s-3"
    fragility_figures.plot_fragility(frag, "S0", "unused.png", flags=ds[["status", "sl_trust"]])
    ax = drawn[0].axes[0]
    texts = _texts(drawn[0])
    for m in BestMethod:
        marker, label = BEST_MARKERS[m]
        assert label in texts
        line = next(line for line in ax.get_lines() if line.get_label() == label)
        np.testing.assert_array_equal(line.get_xdata(), s0.values[method == m])
    assert "best estimate band (+-2 se)" in texts
    assert any(t.startswith("best estimates (all points): linearization 1") and "unreliable 1" in t for t in texts)
    band = next(c for c in ax.collections if c.get_label() == "best estimate band (+-2 se)")
    assert band.get_paths()                                 # the shaded band exists (NaN where unreliable)
    assert any(t.startswith("flagged (status != ok): 1") for t in texts)     # flag marks kept
