"""The CDO form of a result: selections, where strings go, blocks (the files: tests/integration/test_netcdf_cf.py)."""

import math

import numpy as np
import pytest
import xarray as xr

from screening.io import cdofile
from screening.io.cdofile import parse_selection, select, _string_attribute_target
from screening.io.errors import SweepError


def test_parse_selection_reads_numbers_and_cases():
    assert parse_selection(["k = 2.89e7", "case=white"], ("case", "k")) == {"k": 2.89e7, "case": "white"}
    assert parse_selection(["case=1"], ("case",)) == {"case": 1}
    assert parse_selection([], ("k",)) == {}


@pytest.mark.parametrize("item, said", [("k", "expected DIM=VALUE"), ("m=1", "swept dimensions (k, eps)"),
                                        ("k=inf", "finite number"), ("k=abc", "finite number")])
def test_parse_selection_names_the_bad_item(item, said):
    with pytest.raises(SweepError, match="--select") as err:
        parse_selection([item], ("k", "eps"))
    assert said in str(err.value)


def test_select_takes_the_nearest_value_and_cases_by_name_or_index():
    ds = xr.Dataset({"status": (("case", "k"), np.arange(4).reshape(2, 2))},
                    coords={"case": [0, 1], "case_name": ("case", ["white", "filtered"]), "k": [2e7, 3e7]})
    assert int(select(ds, {"case": "filtered", "k": 2.9e7})["status"]) == 3
    assert int(select(ds, {"case": 0, "k": 1.0})["status"]) == 0
    with pytest.raises(SweepError, match="no such case"):
        select(ds, {"case": "other"})
    with pytest.raises(SweepError, match="out of range 0..1"):
        select(ds, {"case": 2})


def test_a_case_index_is_plain_digits_and_a_string_coordinate_is_one_line():
    """Foreign content: ``case=²`` (a digit to ``str.isdigit``, not to ``int``) and a swept dimension whose
    values are strings were tracebacks."""
    assert parse_selection(["case=\u00b2"], ("case",)) == {"case": "\u00b2"}
    ds = xr.Dataset({"status": (("case", "k"), np.arange(4).reshape(2, 2))},
                    coords={"case": [0, 1], "case_name": ("case", ["white", "filtered"]), "k": ["soft", "stiff"]})
    with pytest.raises(SweepError, match="no such case"):
        select(ds, {"case": "\u00b2"})
    with pytest.raises(SweepError, match=r"--select k=2.0: the values of k are not numbers"):
        select(ds, parse_selection(["k=2"], ("case", "k")))


def test_attributes_netcdf_cannot_hold_become_json_and_ragged_flags_are_refused():
    from screening.io._zarr_store import netcdf_attributes

    out = netcdf_attributes({"meta": {"a": [1, 2]}, "gone": None, "mixed": [1, "x"], "nested": [[1], [2, 3]],
                             "values": [1, 2], "flag": True, "text": "t"})
    assert out["meta"] == '{"a": [1, 2]}' and "gone" not in out and out["mixed"] == '[1, "x"]'
    assert out["nested"] == "[[1], [2, 3]]" and out["values"].tolist() == [1, 2] and out["flag"] == 1
    assert netcdf_attributes({"flag_values": [0, 1]}, np.dtype("i1"))["flag_values"].dtype == np.int8
    with pytest.raises(SweepError, match="flag_values of status are not a flat list"):
        netcdf_attributes({"flag_values": [[0, 1], [2]]}, np.dtype("i1"), "status")


def test_strings_go_to_the_variable_they_name_or_their_dimension():
    variables = {"case", "spot_case"}
    assert _string_attribute_target("case_name", ("case",), variables) == "case"
    assert _string_attribute_target("spot_case_name", ("spot",), variables) == "spot_case"
    assert _string_attribute_target("excitation", ("case",), variables) == "case"
    assert _string_attribute_target("label", ("point",), variables) is None


@pytest.mark.parametrize("shape", [(7,), (3, 5), (2, 3, 4), (), (40, 1000)])
@pytest.mark.parametrize("row", [1, 4, 401])
def test_blocks_are_whole_chunks_of_bounded_size_covering_every_point_once(monkeypatch, shape, row):
    monkeypatch.setattr(cdofile, "BLOCK_VALUES", 4000)
    chunks, step = cdofile._grid_chunks(shape, row)
    per_chunk = math.prod(chunks)
    assert step % per_chunk == 0 and (step * row <= 4000 or step == per_chunk == 1)
    seen = np.zeros(shape, dtype=int)
    for slab in cdofile._grid_blocks(shape, step):
        block = seen[slab if slab else ...]
        assert max(block.size, 1) <= step
        if block.size >= per_chunk:                     # only the last block of the grid is short
            assert all(n % c == 0 or n == c for n, c in zip(block.shape, chunks)), (block.shape, chunks)
        seen[slab if slab else ...] += 1
    assert np.all(seen == 1) and seen.size == math.prod(shape)


def test_integers_decoded_to_float_get_their_fill_back():
    out = cdofile._encoded(xr.DataArray([1.0, np.nan]), np.dtype("i1"), -1)
    assert out.dtype == np.int8 and out.tolist() == [1, -1]


def test_variables_on_a_dimension_of_length_0_are_left_out_and_named(tmp_path):
    """No escalated point: ``escalation`` has length 0, which netCDF stores as unlimited; CDO refuses a variable
    on a second unlimited dimension ("Unsupported grid").  The CDO form leaves out those variables (they hold no
    value) and their dimension, names them in ``left_out``, and CDO reads the rest without a warning."""
    import shutil
    import subprocess

    import netCDF4

    from screening.io.reader import example_result

    result = example_result().assign(
        var_theta=(("eps", "t"), np.arange(6.0).reshape(2, 3) * 1e-6, {"units": "rad2"}),
        esc_grid_index=("escalation", np.zeros(0, dtype=np.int32), {"units": "1"}),
        esc_peak_abs_theta=(("escalation", "esc_sample"), np.zeros((0, 4)), {"units": "rad"}))
    source, dst = tmp_path / "result.nc", tmp_path / "cdo.nc"
    result.to_netcdf(source)
    with cdofile.open_source(source) as ds:
        cdofile.export_cdo(ds, dst, complevel=1, history="export")
    with netCDF4.Dataset(dst) as nc:
        assert [d for d, dim in nc.dimensions.items() if dim.isunlimited()] == ["t"]
        assert "escalation" not in nc.dimensions and not [v for v in nc.variables if v.startswith("esc_")]
        assert nc.left_out == "esc_grid_index, esc_peak_abs_theta: no values (a dimension of length 0)"
        np.testing.assert_array_equal(nc["var_theta"][:], result["var_theta"].values.T)
    if shutil.which("cdo"):
        proc = subprocess.run(["cdo", "-s", "sinfon", str(dst)], capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0 and "Warning" not in proc.stderr, proc.stderr
        assert "var_theta" in proc.stdout
