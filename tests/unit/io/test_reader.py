"""Checked reading of a result back (screening.io.reader), on the smallest result written to disk here:
a netCDF file and a zarr store open with their data intact; a foreign file, a missing variable, a broken layout
and an unfinished store are refused in one line naming what is wrong; the study key of a result is read back."""

import warnings

import numpy as np
import pytest

from screening.io import reader
from screening.io._zarr_store import write_completion_mark
from screening.io.reader import ResultError


def _netcdf(tmp_path, ds=None, name="r.nc"):
    path = tmp_path / name
    (reader.example_result() if ds is None else ds).to_netcdf(path)
    return path


def _zarr(tmp_path, finished=True):
    path = tmp_path / "r.zarr"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reader.example_result().to_zarr(path, zarr_format=3)
    if finished:
        write_completion_mark(path)
    return path


@pytest.mark.parametrize("form", ["netcdf", "zarr"])
def test_a_result_opens_with_its_values(tmp_path, form):
    path = _netcdf(tmp_path) if form == "netcdf" else _zarr(tmp_path)
    expected = reader.example_result()
    with reader.open_result(path) as ds:
        assert set(reader.REQUIRED_VARIABLES) <= set(ds.variables)
        for name in reader.REQUIRED_VARIABLES:
            np.testing.assert_array_equal(ds[name].values, expected[name].values)


def test_an_unfinished_store_is_refused_with_why(tmp_path):
    with pytest.raises(ResultError, match="completion mark") as err:
        reader.open_result(_zarr(tmp_path, finished=False))
    assert "\n" not in str(err.value)


def test_a_foreign_file_and_a_missing_variable_are_refused_in_one_line(tmp_path):
    (tmp_path / "notes.nc").write_text("not a netCDF file")
    with pytest.raises(ResultError) as err:
        reader.open_result(tmp_path / "notes.nc")
    assert "notes.nc" in str(err.value) and "\n" not in str(err.value)
    missing = reader.REQUIRED_VARIABLES[-1]
    with pytest.raises(ResultError, match=missing):
        reader.open_result(_netcdf(tmp_path, reader.example_result().drop_vars(missing), "m.nc"))


def test_the_layout_is_checked_from_the_header():
    ds = reader.example_result()
    assert reader.layout_problem(ds) == ""
    broken = ds.copy()
    broken["status"].attrs["flag_meanings"] = "ok"              # one word for several values
    assert reader.layout_problem(broken) != ""


def test_the_study_key_of_a_result_is_read_back_and_none_without_one(tmp_path):
    ds = reader.example_result()
    ds.attrs["study_sha256"] = "ab" * 32
    assert reader.result_key(_netcdf(tmp_path, ds)) == "ab" * 32
    plain = reader.example_result()
    plain.attrs.pop("study_sha256", None)
    assert reader.result_key(_netcdf(tmp_path, plain, "plain.nc")) is None
    assert reader.result_key(tmp_path / "absent.nc") is None
