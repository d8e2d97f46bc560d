"""One-line errors for bad model parameters and input files (screening.core.validation)."""

import numpy as np
import pytest
import xarray as xr

from screening.core.validation import (InputFileError, as_checked_array, check_integer, check_scalar, check_size,
                                       checked, file_problem, input_path, read_input_text)


@pytest.mark.parametrize("value, shown", [(-1.0, "-1.0"), (float("inf"), "inf"), ("3", "'3'"), (True, "True"),
                                          ([1.0, 0.0], "0.0")])
def test_a_value_out_of_range_is_refused_naming_the_parameter_the_range_and_the_value(value, shown):
    with pytest.raises(ValueError) as err:
        as_checked_array("k", value, lower=0.0)
    assert str(err.value) == f"parameter 'k' must be a finite number > 0 (got {shown})"


def test_bounds_may_be_inclusive():
    assert as_checked_array("x", [0.0, 1.0], lower=0.0, lower_inclusive=True, upper=1.0,
                            upper_inclusive=True).tolist() == [0.0, 1.0]
    with pytest.raises(ValueError, match=r"must be a finite number >= 0 and < 1 \(got 1.0\)"):
        as_checked_array("x", 1.0, lower=0.0, lower_inclusive=True, upper=1.0)


def test_checked_gives_floats_for_scalars_arrays_for_arrays_and_keeps_labels():
    assert type(checked("m", 2)) is float
    assert isinstance(checked("m", [1, 2]), np.ndarray)
    da = xr.DataArray([1, 2], dims="case")
    out = checked("m", da, lower=0.0)
    assert out.dims == ("case",) and out.dtype == np.float64


def test_scalar_integer_and_size_checks():
    assert check_scalar("b", 0.5, lower=0.0) == 0.5
    with pytest.raises(ValueError, match="^parameter 'b' must be a single number"):
        check_scalar("b", [0.5, 0.6], lower=0.0)
    assert check_integer("n", 3, 1) == 3
    for bad in (0, 2.0, True):
        with pytest.raises(ValueError, match=r"^parameter 'n' must be an integer >= 1"):
            check_integer("n", bad, 1)
    check_size("n", 10, 10, "values")
    with pytest.raises(ValueError, match="^parameter 'n' asks for 11 values; at most 10"):
        check_size("n", 11, 10, "values")


def test_input_files_are_checked_before_reading(tmp_path):
    assert file_problem(tmp_path / "missing.toml") == "does not exist"
    assert file_problem(tmp_path) == "is a folder, not a file"
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    assert file_problem(tmp_path / "loop") == "is a symbolic link loop"
    assert input_path(b"a.toml") == "a.toml"
    with pytest.raises(ValueError, match="NUL"):
        input_path("a\0b")
    f = tmp_path / "a.txt"
    f.write_text("hello")
    assert file_problem(f) is None and read_input_text(f, "record", 100) == "hello"
    with pytest.raises(InputFileError) as err:
        read_input_text(tmp_path, "record", 100)
    assert str(err.value) == f"record {tmp_path} is a folder, not a file"
    with pytest.raises(ValueError):
        read_input_text(f, "record", 3)                     # larger than allowed
