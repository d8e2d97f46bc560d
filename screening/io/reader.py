"""Reading a sweep result back: :func:`open_result` checks that a file (or zarr store) is a readable
screening result."""

from __future__ import annotations

from pathlib import Path

from screening.core import limits
from screening.io._zarr_store import read_attrs
from screening.io.errors import exception_line, SweepError
from screening.io.zarrfile import check_store, is_zarr_store, open_zarr_result, store_problem
from screening.solvers.moments import HISTORY_VARIABLES

__all__ = ["ResultError", "REQUIRED_VARIABLES", "open_result", "layout_problem", "damaged_data_error",
           "result_key", "VERIFY_BLOCK_BYTES", "verify_result", "example_result"]


class ResultError(SweepError):
    """A result file that cannot be read or is not a screening sweep result."""


#: Variables every result file has (checked by :func:`open_result`); the histories are optional
#: (``[output]`` of the study).
REQUIRED_VARIABLES = ("status", "peak_var_theta", "peak_p_uplift", "min_k_eq")


def open_result(path):
    """Open a result file lazily with xarray; :class:`ResultError` if unreadable or foreign.

    A netCDF file or a zarr store (checked for completeness first) is opened without reading its
    data; it must hold :data:`REQUIRED_VARIABLES` and a ``t`` dimension, in a layout
    :func:`layout_problem` accepts.

    Parameters
    ----------
    path : str or os.PathLike
        The result: a netCDF file or a ``.zarr`` store.

    Returns
    -------
    xarray.Dataset
        The result, lazily loaded (close it when done).

    Raises
    ------
    ResultError
        No such file, an incomplete store, an unreadable file or one that is not a screening result.

    References
    ----------
    .. [1] screening documentation, "What a result holds", ``docs/outputs.md``.
    .. [2] NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8, section 3.5 "Flags",
       https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "result.nc")
    ...     result.to_netcdf(path)
    ...     with open_result(path) as ds:
    ...         print(dict(ds.sizes), ds["status"].attrs["flag_meanings"])
    ...     xr.Dataset({"x": ("t", [1.0])}).to_netcdf(os.path.join(folder, "other.nc"))
    ...     try:
    ...         open_result(os.path.join(folder, "other.nc"))
    ...     except ResultError as exc:
    ...         print(str(exc)[len(folder) + 1:])
    {'eps': 2, 't': 3} ok failed
    other.nc: not a screening sweep result (missing status, peak_var_theta, peak_p_uplift, min_k_eq)
    """
    import xarray as xr

    path = Path(path)
    zarr = is_zarr_store(path)
    if not path.is_file() and not zarr:
        raise ResultError(f"{path}: no such result file")
    problem = store_problem(path, deep=False) if zarr else None
    if problem:
        raise ResultError(f"{path}: not a usable result: {problem}")
    try:
        ds = open_zarr_result(path) if zarr else xr.open_dataset(path, engine="netcdf4")
    except Exception as exc:                          # noqa: BLE001 - netCDF/HDF5 raise many types
        raise ResultError(f"{path}: cannot read the result file ({exception_line(exc)})") from None
    missing = [v for v in REQUIRED_VARIABLES if v not in ds.variables]
    if missing or "t" not in ds.dims:
        ds.close()
        raise ResultError(f"{path}: not a screening sweep result (missing {', '.join(missing) or 't'})")
    problem = layout_problem(ds)
    if problem:
        ds.close()
        raise ResultError(f"{path}: not a screening sweep result ({problem})")
    return ds


def layout_problem(ds):
    """What is wrong with the layout of an opened result (a short phrase), or ``""``.

    Checked from the header only (no data is read): the grid is the dimensions of ``status`` and
    has at most :data:`~screening.core.limits.MAX_POINTS_CEILING` points, ``t`` has at least
    one instant and at most :data:`~screening.core.limits.MAX_TIMES`, every history is
    ``grid x t`` and every summary ``grid``, and ``status`` carries integer ``flag_values`` with one
    word of ``flag_meanings`` each (CF flags, [2]).

    Parameters
    ----------
    ds : xarray.Dataset
        An opened result.

    Returns
    -------
    str
        The first problem found, or ``""`` for a sound layout.

    References
    ----------
    .. [1] screening documentation, "What a result holds", ``docs/outputs.md``.
    .. [2] NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8, section 3.5 "Flags",
       https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> layout_problem(result)
    ''
    >>> layout_problem(result.assign(status=result["status"].astype(float)))
    'status is not an integer variable (float64)'
    """
    import numpy as np

    grid = tuple(ds["status"].dims)
    if "t" in grid:
        return "status varies over t"
    n_points = int(np.prod([ds.sizes[d] for d in grid], dtype=np.float64))
    if n_points > limits.MAX_POINTS_CEILING:
        return f"its grid declares {n_points:.3g} points, more than the {limits.MAX_POINTS_CEILING} read"
    nt = ds.sizes["t"]
    if not 1 <= nt <= limits.MAX_TIMES:
        return f"t has {nt} instants (1..{limits.MAX_TIMES} expected)"
    for name in HISTORY_VARIABLES:                     # stored histories ([output] may leave them out)
        if name in ds.variables and tuple(ds[name].dims) != grid + ("t",):
            return f"{name} has dimensions ({', '.join(ds[name].dims)}), not ({', '.join(grid + ('t',))})"
    for name in REQUIRED_VARIABLES:
        if tuple(ds[name].dims) != grid:
            return f"{name} has dimensions ({', '.join(ds[name].dims)}), not ({', '.join(grid)})"
        if ds[name].dtype.kind not in "fiu":
            return f"{name} is not numeric ({ds[name].dtype})"
    if ds["status"].dtype.kind not in "iu":
        return f"status is not an integer variable ({ds['status'].dtype})"
    attrs = ds["status"].attrs
    values, meanings = attrs.get("flag_values"), attrs.get("flag_meanings")
    if values is None or meanings is None:
        return "status has no flag_values / flag_meanings"
    values = np.atleast_1d(np.asarray(values))
    if values.ndim != 1 or values.dtype.kind not in "iu" or not isinstance(meanings, str) \
            or len(meanings.split()) != values.size or values.size > 64:
        return "the flag_values and flag_meanings of status do not match"
    return ""


def damaged_data_error(path, exc):
    """The :class:`ResultError` for a result whose data cannot be read (netCDF/HDF5 report damaged
    chunks as ``RuntimeError``) although its header could.

    Parameters
    ----------
    path : str or os.PathLike
        The result file.
    exc : BaseException
        The error reading its data raised.

    Returns
    -------
    ResultError
        The error to raise, its message on one line.

    References
    ----------
    .. [1] screening documentation, "How results are stored, and what the tool guarantees about them",
       ``docs/outputs_storage.md``.

    Examples
    --------
    >>> print(damaged_data_error("result.nc", RuntimeError("NetCDF: HDF error")))
    result.nc: cannot read the data of the result file, it is damaged (RuntimeError: NetCDF: HDF error)
    """
    return ResultError(f"{path}: cannot read the data of the result file, it is damaged ({exception_line(exc)})")


def result_key(path):
    """The ``study_sha256`` attribute of an existing result file (or zarr store), or ``None``.

    The key is the hash of the study text, the package version and the result layout
    (:attr:`Study.key <screening.sweep.study.Study.key>`): a result with the study's key is
    reused rather than computed again.

    Parameters
    ----------
    path : str or os.PathLike
        A netCDF file or a zarr store.

    Returns
    -------
    str or None
        The key, or None when the file is missing, unreadable or has no key.

    References
    ----------
    .. [1] screening documentation, "How results are stored, and what the tool guarantees about them",
       ``docs/outputs_storage.md``.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "result.nc")
    ...     result.to_netcdf(path)
    ...     result_key(path), result_key(os.path.join(folder, "missing.nc"))
    ('ab12', None)
    """
    import netCDF4

    if is_zarr_store(path):
        try:
            key = read_attrs(path).get("study_sha256")
        except Exception:                             # noqa: BLE001 - zarr raises many types on damage
            return None
        return key if isinstance(key, str) else None
    try:
        with netCDF4.Dataset(path) as nc:
            return nc.getncattr("study_sha256") if "study_sha256" in nc.ncattrs() else None
    except (OSError, RuntimeError, ValueError):
        return None


#: Bytes read at a time when a whole result file is checked (:func:`verify_result`).
VERIFY_BLOCK_BYTES = 32 * 2**20


def verify_result(path, study):
    """Why the result file ``path`` of ``study`` cannot be reused (a short reason), or ``None``.

    A finished file with the study's key is still read through before it is reused: the
    grid and time dimensions must have the study's sizes, every required variable must
    be there, and every data chunk must decompress (damaged chunks raise in netCDF/HDF5).  The
    data is read in blocks of about :data:`VERIFY_BLOCK_BYTES` along the first dimension.

    Parameters
    ----------
    path : str or os.PathLike
        A netCDF file or a zarr store.
    study : screening.sweep.study.Study
        The study the result should hold.

    Returns
    -------
    str or None
        The reason, or None when the result can be reused.

    References
    ----------
    .. [1] screening documentation, "How results are stored, and what the tool guarantees about them",
       ``docs/outputs_storage.md``.

    Examples
    --------
    >>> import os, tempfile
    >>> from screening.sweep.study import EXAMPLE_STUDY as text, parse_study
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "result.nc")
    ...     result.to_netcdf(path)
    ...     verify_result(path, parse_study(text))            # 20 s at 0.05 s: 401 instants
    "its dimension 't' does not have the study's size 401"
    """
    import netCDF4
    import numpy as np

    expected = dict(zip(study.dims, study.shape), t=int(study.times.size))
    if is_zarr_store(path):
        try:
            return check_store(path, expected, REQUIRED_VARIABLES)
        except Exception as exc:                      # noqa: BLE001 - zarr/codecs raise many types on damage
            return f"its data cannot be read ({exception_line(exc)})"
    try:
        with netCDF4.Dataset(path) as nc:
            nc.set_auto_mask(False)
            if "interim_result" in nc.ncattrs():
                return "it is an interim result (its [accuracy] stage had not ended)"
            for dim, size in expected.items():
                if dim not in nc.dimensions or len(nc.dimensions[dim]) != size:
                    return f"its dimension {dim!r} does not have the study's size {size}"
            missing = [v for v in REQUIRED_VARIABLES if v not in nc.variables]
            if missing:
                return f"it lacks {', '.join(missing)}"
            for var in nc.variables.values():
                shape = var.shape
                if not shape:
                    var[...]
                    continue
                row = int(np.prod(shape[1:], dtype=np.int64)) * getattr(var.dtype, "itemsize", 8)
                step = max(1, VERIFY_BLOCK_BYTES // max(row, 1))
                for lo in range(0, shape[0], step):
                    var[lo:lo + step]
    except (OSError, RuntimeError, ValueError, IndexError, TypeError, KeyError) as exc:
        return f"its data cannot be read ({exception_line(exc)})"
    return None


def example_result():
    """A two-point result in memory: the smallest layout :func:`open_result` accepts, for examples.

    The grid is the two beds of :data:`~screening.sweep.study.EXAMPLE_STUDY` (``eps`` = 0 and 6e7
    [m-2]) with three output instants and the required variables only (:data:`REQUIRED_VARIABLES`);
    the values are made up, not computed.

    Returns
    -------
    xarray.Dataset
        ``status`` (CF flags ``ok`` / ``failed``), ``peak_var_theta`` [rad2], ``peak_p_uplift`` [1] and
        ``min_k_eq`` [N m rad-1] on ``eps`` [m-2]; ``t`` [s]; the global attribute ``study_sha256``.

    References
    ----------
    .. [1] screening documentation, "What a result holds", ``docs/outputs.md``.
    .. [2] NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8, section 3.5 "Flags",
       https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html

    Examples
    --------
    >>> result = example_result()
    >>> dict(result.sizes), layout_problem(result), result["peak_var_theta"].attrs["units"]
    ({'eps': 2, 't': 3}, '', 'rad2')
    """
    import numpy as np
    import xarray as xr

    flags = {"flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "ok failed"}
    return xr.Dataset(
        {"status": ("eps", np.zeros(2, dtype=np.int8), flags),
         "peak_var_theta": ("eps", [1e-6, 4e-6], {"units": "rad2"}),
         "peak_p_uplift": ("eps", [0.1, 0.3], {"units": "1"}),
         "min_k_eq": ("eps", [900.0, 700.0], {"units": "N m rad-1"})},
        coords={"eps": ("eps", [0.0, 6e7], {"units": "m-2"}), "t": ("t", [0.0, 0.05, 0.1], {"units": "s"})},
        attrs={"study_sha256": "ab12"})
