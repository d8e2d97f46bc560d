"""The result formats (screening.io.formats.ResultFormat): netCDF and zarr implement the one interface and write a
region alike."""

import numpy as np
import pytest

from screening.io.formats import ResultFormat
from screening.io.writer import NetcdfFormat

zarr = pytest.importorskip("zarr")

from screening.io.zarrfile import ZarrFormat  # noqa: E402


def _formats(tmp_path):
    return [NetcdfFormat(tmp_path / "r.nc"), ZarrFormat(tmp_path / "r.zarr", "w", grid=("x", "y"), chunks=(2, 3))]


def test_both_formats_are_result_formats(tmp_path):
    formats = _formats(tmp_path)
    try:
        assert all(isinstance(fmt, ResultFormat) for fmt in formats)
    finally:
        for fmt in formats:
            fmt.finish()
    assert not isinstance(object(), ResultFormat)


def test_a_region_written_through_either_format_reads_back_the_same(tmp_path):
    values = np.arange(6, dtype=float).reshape(2, 3) + 0.5
    got = []
    for fmt in _formats(tmp_path):
        fmt.dimension("x", 4)
        fmt.dimension("y", 3)
        fmt.define("v", "f8", ("x", "y"), {"units": "m"}, np.nan, compress=True, chunks=(2, 3))
        fmt.set_attrs({"title": "t"})
        fmt.commit()
        fmt.write("v", (slice(2, 4), slice(0, 3)), values)
        fmt.commit()
        got.append((np.asarray(fmt.read("v")), fmt.dims("v"), fmt.attrs("v")["units"], fmt.has("v"), fmt.has("w")))
        fmt.finish()
    (a, dims_a, units_a, *has_a), (b, dims_b, units_b, *has_b) = got
    np.testing.assert_array_equal(a[2:], values)
    np.testing.assert_array_equal(a, b)
    assert np.all(np.isnan(a[:2]))
    assert tuple(dims_a) == tuple(dims_b) == ("x", "y") and units_a == units_b == "m" and has_a == has_b == [True, False]
