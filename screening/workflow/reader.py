"""Reading a sweep result back: :func:`open_result` checks that a file is a readable screening result."""

from __future__ import annotations

from pathlib import Path

from screening.workflow.errors import SweepError, exception_line


class ResultError(SweepError):
    """A result file that cannot be read or is not a screening sweep result."""


#: Variables every result file has (checked by :func:`open_result`); the histories are optional
#: (``[output]`` of the study).
REQUIRED_VARIABLES = ("status", "peak_var_theta", "peak_p_uplift", "min_k_eq")


def open_result(path):
    """Open a result file lazily with xarray; :class:`ResultError` if unreadable or foreign."""
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise ResultError(f"{path}: no such result file")
    try:
        ds = xr.open_dataset(path, engine="netcdf4")
    except Exception as exc:                          # noqa: BLE001 - netCDF/HDF5 raise many types
        raise ResultError(f"{path}: cannot read the result file ({exception_line(exc)})") from None
    missing = [v for v in REQUIRED_VARIABLES if v not in ds.variables]
    if missing or "t" not in ds.dims:
        ds.close()
        raise ResultError(f"{path}: not a screening sweep result (missing {', '.join(missing) or 't'})")
    return ds


def damaged_data_error(path, exc):
    """The :class:`ResultError` for a result whose data cannot be read (netCDF/HDF5 report damaged
    chunks as ``RuntimeError``) although its header could."""
    return ResultError(f"{path}: cannot read the data of the result file, it is damaged ({exception_line(exc)})")


def result_key(path):
    """The ``study_sha256`` attribute of an existing result file, or ``None``."""
    import netCDF4

    try:
        with netCDF4.Dataset(path) as nc:
            return nc.getncattr("study_sha256") if "study_sha256" in nc.ncattrs() else None
    except (OSError, RuntimeError, ValueError):
        return None
