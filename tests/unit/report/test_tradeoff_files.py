"""The trade study's file layout (screening.report.tradeoff_files): string-labelled dimensions stored as
``<dim>_name`` coordinates and back, through a real netCDF file; the encoding; the file names."""

import numpy as np
import xarray as xr

from screening.report import tradeoff_files as tf


def _dataset():
    labels = {d: [f"{d}-{i}" for i in range(2)] for d in tf.LABEL_DIMS}
    dims = tuple(tf.LABEL_DIMS)
    values = np.arange(2.0 ** len(dims)).reshape((2,) * len(dims))
    return xr.Dataset({"err": (dims, values, {"units": "1"})},
                      coords={**{d: (d, labels[d], {"long_name": f"the {d}"}) for d in dims},
                              "point": ("point", np.arange(3, dtype=np.int64))})


def test_the_file_layout_survives_a_netcdf_round_trip_unchanged(tmp_path):
    ds = _dataset()
    written = tf.to_file_layout(ds)
    assert not any(d in written.coords for d in tf.LABEL_DIMS)
    assert all(written[f"{d}_name"].attrs == {"long_name": f"the {d}"} for d in tf.LABEL_DIMS)
    assert written["point"].dtype == np.int32
    encoding = {name: enc for name, enc in tf.file_encoding(written).items() if name in written.variables}
    written.to_netcdf(tmp_path / "t.nc", encoding=encoding)
    with xr.open_dataset(tmp_path / "t.nc") as back:
        restored = tf.from_file_layout(back.load())
    for d in tf.LABEL_DIMS:
        assert restored[d].values.tolist() == ds[d].values.tolist()
    xr.testing.assert_equal(restored["err"].drop_vars("point", errors="ignore"), ds["err"])
    assert float(restored["err"].sel({d: f"{d}-1" for d in tf.LABEL_DIMS})) == 2.0 ** len(tf.LABEL_DIMS) - 1


def test_float_coordinates_get_no_fill_value_and_the_histories_are_compressed():
    enc = tf.file_encoding(xr.Dataset(coords={"S0": [1e-4], "point": [0]}))
    assert enc["S0"] == {"_FillValue": None} and "point" not in enc
    assert all(enc[n] == {"zlib": True, "complevel": 4} for n in ("var_theta", "var_theta_se", "p_uplift"))


def test_the_five_files_share_the_stem_in_the_folder(tmp_path):
    paths = tf.output_paths(tmp_path, "trade")
    assert set(paths) == {"nc", "md", "csv", "error_vs_cost", "validity"}
    assert all(p.parent == tmp_path and p.name.startswith("trade") for p in paths.values())
    assert len({p.name for p in paths.values()}) == 5
