"""One-line reasons for failed runs and writes (screening.io.errors)."""

import errno

import pytest

from screening.io.errors import ReadFailure, exception_line, is_write_error, read_values, write_failure_reason


def test_an_exception_is_one_line_of_type_and_message_at_most_200_characters():
    assert exception_line(ValueError("a\n  b")) == "ValueError: a b"
    assert len(exception_line(RuntimeError("x" * 500))) == len("RuntimeError: ") + 200


def test_a_failed_read_becomes_a_read_failure_with_the_reason():
    assert read_values(lambda: 3) == 3

    def damaged():
        raise OSError(errno.EIO, "Input/output error")

    with pytest.raises(ReadFailure, match="^Input/output error$"):
        read_values(damaged)


def test_write_failures_are_said_in_the_operating_systems_words_and_netcdf_ones_with_the_free_space(tmp_path):
    assert write_failure_reason(OSError(errno.ENOSPC, "No space left on device")) == "No space left on device"
    said = write_failure_reason(RuntimeError("NetCDF: HDF error"), tmp_path / "out.nc")
    assert said.startswith("NetCDF: HDF error (the netCDF library gives no reason; ") or said.startswith("no space")


def test_disk_errors_are_told_from_other_errors():
    assert is_write_error(OSError(errno.ENOSPC, "full"))
    assert is_write_error(RuntimeError("NetCDF: HDF error"))
    assert not is_write_error(OSError(errno.ECONNRESET, "reset"))
    assert not is_write_error(ValueError("bad"))
