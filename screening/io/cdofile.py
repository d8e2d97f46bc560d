"""The CDO form of a sweep result (``screening export RESULT OUT --layout cdo``), streamed block by block.

CDO (2.1) reads a variable as ``(time, z, y, x)``; the result file (:mod:`screening.io.writer`)
is laid out for xarray and CF, and CDO cannot use it as it is (measured with CDO 2.1.1):

* time must be the first dimension ("Time must be the first dimension! ... skipped variable") and
  be recognised as time: an unlimited dimension, or units with a reference date;
* with ``t`` in plain ``s``, CDO writes the times of its outputs truncated to whole seconds
  (0.1 ... 0.9 s all become 0); with ``seconds since <date>`` they are kept, but xarray then decodes
  ``t`` to datetimes;
* every CF scalar or auxiliary coordinate named in a ``coordinates`` attribute (the fixed
  parameters, ``k_value``, ``spot_*``, ``esc_*``) gives "Coordinates variable ... can't be assigned",
  and string variables "Unsupported data type (char/string), skipped variable";
* at most three dimensions besides time ("4 dimensional variables without time dimension are not
  supported");
* a dimension of length 0 (``escalation`` when the ``[accuracy]`` stage escalated no point) is an
  unlimited dimension in netCDF (a length of 0 means unlimited there), and a variable on a second
  unlimited dimension besides time is "Unsupported grid, skipped variable".

So the CDO file has ``t`` first and unlimited with :data:`screening.solvers.schema.CDO_TIME` (the same
seconds, from a placeholder reference date), no ``coordinates`` attributes (the parameters stay
variables with their units), string variables as attributes of their dimension's variable
(:func:`_string_attribute_target`), ``p_exceed`` as one variable per threshold, at most
:data:`MAX_GRID_DIMS` grid dimensions (``select`` fixes the others), and neither the dimensions of
length 0 nor the variables on them (they hold no value; the global attribute ``left_out`` names
them).  The swept parameters are CDO's z (levels: ``sellevel`` by value), y and x (``selindexbox``).
"""

from __future__ import annotations

import json
import math

import numpy as np

from screening.io._zarr_store import netcdf_attributes
from screening.io.errors import read_values, SweepError
from screening.io.layout import hyperslabs
from screening.io.reader import open_result
from screening.io.writer import POINT_CHUNK, point_chunks
from screening.solvers.schema import CDO_LAYOUT, cdo_threshold_attributes, CDO_TIME

__all__ = ["MAX_GRID_DIMS", "BLOCK_VALUES", "SOURCE_CACHE_BYTES", "open_source", "parse_selection", "select",
           "export_cdo"]

#: Grid dimensions CDO can hold besides time (z, y, x).
MAX_GRID_DIMS = 3
#: Values read and written per block (memory of the export independent of the grid size).
BLOCK_VALUES = 2**22
#: netCDF chunk cache [bytes] of each variable of the result read (the default, 64 MiB, would keep up to that
#: much of every history read in memory; the export reads each chunk about once).
SOURCE_CACHE_BYTES = 4 * 2**20


def open_source(path):
    """The result at ``path`` opened for an export: its netCDF variables with a chunk cache of
    :data:`SOURCE_CACHE_BYTES`, so that the memory of an export does not grow with the grid.

    Parameters
    ----------
    path : str or os.PathLike
        A result: a netCDF file or a ``.zarr`` store (:func:`~screening.io.reader.open_result`).

    Returns
    -------
    xarray.Dataset
        The result, lazily loaded (close it when done); netCDF4's default chunk cache is restored.

    References
    ----------
    .. [1] NetCDF-C documentation, "Chunk cache", https://docs.unidata.ucar.edu/netcdf-c/current/
    .. [2] screening documentation, "The command line", ``docs/cli.md`` (``screening export --layout cdo``).

    Examples
    --------
    >>> import os, tempfile
    >>> import netCDF4
    >>> from screening.io.reader import example_result
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = os.path.join(folder.name, "result.nc")
    >>> example_result().to_netcdf(path)
    >>> before = netCDF4.get_chunk_cache()
    >>> ds = open_source(path)
    >>> dict(ds.sizes), netCDF4.get_chunk_cache() == before
    ({'eps': 2, 't': 3}, True)
    >>> ds.close(); folder.cleanup()
    """
    import netCDF4

    saved = netCDF4.get_chunk_cache()
    netCDF4.set_chunk_cache(SOURCE_CACHE_BYTES)
    try:
        return open_result(path)
    finally:
        netCDF4.set_chunk_cache(*saved)


def parse_selection(items, grid):
    """``{dim: value}`` from ``DIM=VALUE`` strings; ``dim`` a grid dimension, ``value`` a number (a
    case name or index for ``case``).  :class:`SweepError` naming the item otherwise.

    Parameters
    ----------
    items : iterable of str
        The ``--select`` options, ``"DIM=VALUE"`` each (the value in the dimension's SI unit).
    grid : sequence of str
        The result's grid dimensions.

    Returns
    -------
    dict
        ``{dim: value}``: a float for a swept parameter, an int (index) or str (name) for ``case``.

    Raises
    ------
    SweepError
        An item that is not ``DIM=VALUE``, an unknown dimension or a value that is not a finite number.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Other tools: xarray, NCO, CDO",
       ``docs/outputs.md``.
    .. [2] U. Schulzweida, "CDO User Guide", Max Planck Institute for Meteorology,
       https://code.mpimet.mpg.de/projects/cdo/wiki/Cdo#Documentation

    Examples
    --------
    >>> parse_selection(["eps=6e7", "case=roof"], grid=("case", "eps", "S0"))
    {'eps': 60000000.0, 'case': 'roof'}
    """
    out = {}
    for item in items:
        dim, sep, value = item.partition("=")
        dim, value = dim.strip(), value.strip()
        if not sep or dim not in grid:
            raise SweepError(f"--select {item!r}: expected DIM=VALUE with DIM one of the swept dimensions "
                             f"({', '.join(grid) or 'none'})")
        if dim == "case":
            out[dim] = int(value) if value.isascii() and value.isdigit() else value
            continue
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not math.isfinite(number):
            raise SweepError(f"--select {item!r}: the value of {dim} must be a finite number")
        out[dim] = number
    return out


def select(ds, selection):
    """``ds`` at the nearest swept value of each ``{dim: value}`` (a case by name or index).

    Parameters
    ----------
    ds : xarray.Dataset
        An opened result.
    selection : dict
        ``{dim: value}`` (:func:`parse_selection`); values in the dimension's SI unit.

    Returns
    -------
    xarray.Dataset
        The result with each selected dimension fixed (dropped).

    Raises
    ------
    SweepError
        An unknown case name, a case index out of range or a dimension without numeric values.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Other tools: xarray, NCO, CDO",
       ``docs/outputs.md``.
    .. [2] U. Schulzweida, "CDO User Guide", Max Planck Institute for Meteorology,
       https://code.mpimet.mpg.de/projects/cdo/wiki/Cdo#Documentation

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> float(select(result, {"eps": 5e7})["peak_var_theta"])       # the nearest eps: 6e7 m-2
    4e-06
    """
    for dim, value in selection.items():
        if dim == "case" and isinstance(value, str):
            names = [str(n) for n in ds["case_name"].values]
            if value not in names:
                raise SweepError(f"--select case={value}: no such case (cases: {', '.join(names)})")
            ds = ds.isel(case=names.index(value))
        elif dim == "case":
            if not 0 <= value < ds.sizes["case"]:
                raise SweepError(f"--select case={value}: case index out of range 0..{ds.sizes['case'] - 1}")
            ds = ds.isel(case=value)
        elif ds[dim].dtype.kind not in "iuf":
            raise SweepError(f"--select {dim}={value}: the values of {dim} are not numbers ({ds[dim].dtype}); "
                             "nothing to select the nearest from")
        else:
            ds = ds.sel({dim: value}, method="nearest")
    return ds


def _string_attribute_target(name, dims, variables):
    """The variable that carries string variable ``name`` (on ``dims``) as an attribute in the CDO file:
    ``<x>`` for ``<x>_name``, else the coordinate variable of its dimension (``None``: a global attribute)."""
    if name.endswith("_name") and name[:-5] in variables:
        return name[:-5]
    if len(dims) == 1 and dims[0] in variables:
        return dims[0]
    return None


def _grid_chunks(shape, row_values):
    """Chunks over the grid ``shape`` of a variable with ``row_values`` values per point (C-order runs of
    points, :data:`BLOCK_VALUES` values at most when the shape allows), and the points per block: whole
    chunks of about :data:`BLOCK_VALUES` values, so that every chunk is written once, in full."""
    chunks = point_chunks(shape, max(1, min(POINT_CHUNK, BLOCK_VALUES // max(row_values, 1))))
    points = math.prod(chunks)
    return chunks, points * max(1, BLOCK_VALUES // (max(row_values, 1) * points))


def _grid_blocks(shape, step):
    """Hyperslabs of the grid ``shape`` of ``step`` points each (C order)."""
    n = math.prod(shape)
    for lo in range(0, n, step):
        yield from (slab for slab, _, _ in hyperslabs(lo, min(lo + step, n), shape))


def export_cdo(ds, dst, complevel, history, selection=None):
    """Write the opened result ``ds`` (:func:`~screening.io.reader.open_result`) at ``dst`` (a new
    netCDF4 file) in the CDO layout (module docstring), after ``selection`` (``{dim: value}``,
    :func:`select`).  ``history``: the line appended to the ``history`` attribute.  Raises
    :class:`SweepError` if more than :data:`MAX_GRID_DIMS` grid dimensions remain.

    The data is streamed in blocks of at most about :data:`BLOCK_VALUES` values, each chunk of the
    new file written once, so memory does not grow with the grid.

    Parameters
    ----------
    ds : xarray.Dataset
        The opened result.
    dst : str or os.PathLike
        The netCDF4 file to write (created or overwritten; the caller makes it appear all or none).
    complevel : int
        zlib compression level, 0 (none) to 9.
    history : str
        The line appended to the file's ``history`` attribute (the command that wrote it).
    selection : dict, optional
        ``{dim: value}`` fixed first (:func:`select`).

    Returns
    -------
    None

    Raises
    ------
    SweepError
        More than :data:`MAX_GRID_DIMS` grid dimensions left after the selection.
    ReadFailure
        A value of the result that cannot be read.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Other tools: xarray, NCO, CDO",
       ``docs/outputs.md``.
    .. [2] U. Schulzweida, "CDO User Guide", Max Planck Institute for Meteorology,
       https://code.mpimet.mpg.de/projects/cdo/wiki/Cdo#Documentation

    Examples
    --------
    >>> import os, tempfile, netCDF4
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     dst = os.path.join(folder, "cdo.nc")
    ...     export_cdo(result, dst, complevel=1, history="screening export --layout cdo")
    ...     with netCDF4.Dataset(dst) as nc:
    ...         print(nc["t"].units, nc.dimensions["t"].isunlimited(), nc["status"].dimensions)
    seconds since 1970-01-01 00:00:00 True ('eps',)
    """
    import netCDF4

    ds = select(ds, selection or {})
    grid = tuple(ds["status"].dims)
    if len(grid) > MAX_GRID_DIMS:
        raise SweepError(f"CDO reads at most {MAX_GRID_DIMS} dimensions besides time and this result has "
                         f"{len(grid)} ({', '.join(grid)}): fix {len(grid) - MAX_GRID_DIMS} of them with "
                         f"--select DIM=VALUE (e.g. --select {grid[0]}={_example(ds, grid[0])})")
    shape = tuple(ds.sizes[d] for d in grid)
    nt = ds.sizes["t"]
    empty = [name for name, v in ds.variables.items() if 0 in v.shape]       # on a dimension of length 0
    ds = ds.drop_vars(empty)                                                   # and the dimensions go with them
    strings = {name: v for name, v in ds.variables.items() if v.dtype.kind in "OSU"}
    zlib = {"zlib": True, "complevel": complevel} if complevel > 0 else {}
    with netCDF4.Dataset(dst, "w", format="NETCDF4") as nc:
        nc.set_auto_mask(False)
        nc.createDimension("t", None)
        for dim, size in ds.sizes.items():
            if dim != "t":
                nc.createDimension(dim, size)
        t = nc.createVariable("t", "f8", ("t",), fill_value=False)
        t.setncatts(netcdf_attributes({**{k: v for k, v in ds["t"].attrs.items() if k != "units"}, **CDO_TIME}))
        t[:nt] = np.asarray(ds["t"].values, dtype=np.float64)
        for name, v in ds.variables.items():
            if name == "t" or name in strings:
                continue
            dtype = np.dtype(v.encoding.get("dtype", v.dtype)).newbyteorder("=")
            fill = v.encoding.get("_FillValue")
            fill = False if fill is None or (isinstance(fill, float) and dtype.kind != "f") else fill
            attrs = netcdf_attributes({k: val for k, val in v.attrs.items() if k != "coordinates"}, dtype, name)
            extra = _after_grid(name, v.dims, grid, ds.dims)
            on_grid = extra is not None
            storage = zlib if v.dims and v.dims != (name,) else {}
            if on_grid and extra == ("threshold",):
                _write_per_threshold(nc, name, v, ds["threshold"], dtype, fill, attrs, grid, shape, storage)
                continue
            dims = ("t",) + tuple(d for d in v.dims if d != "t") if "t" in v.dims else v.dims
            chunks = {}
            if on_grid:
                row = math.prod(ds.sizes[d] for d in extra)
                grid_chunk, step = _grid_chunks(shape, row)
                sizes = (1,) + grid_chunk if extra == ("t",) else grid_chunk + tuple(ds.sizes[d] for d in extra)
                chunks = {"chunksizes": sizes, "chunk_cache": 2 * dtype.itemsize * math.prod(sizes)}
            out = nc.createVariable(name, dtype, dims, fill_value=fill, **storage, **chunks)
            out.setncatts(attrs)
            if on_grid:
                for slab in _grid_blocks(shape, step):
                    values = _encoded(v[slab], dtype, fill)
                    if extra == ("t",):
                        out[(slice(0, nt),) + slab] = np.moveaxis(values, -1, 0)
                    else:
                        out[slab if slab else ...] = values
            else:
                values = _encoded(v, dtype, fill)
                if "t" in v.dims:
                    values = np.moveaxis(values, v.dims.index("t"), 0)
                    out[(slice(0, nt),) + (slice(None),) * (values.ndim - 1)] = values
                else:
                    out[...] = values
        labels = {}
        for name, v in strings.items():
            target = _string_attribute_target(name, v.dims, nc.variables)
            text = json.dumps([str(s) for s in np.atleast_1d(v.values)], ensure_ascii=False)
            if target is None:
                labels[name] = text
            else:
                nc[target].setncattr(name, text)
        attrs = dict(ds.attrs)
        attrs["history"] = f"{attrs['history']}\n{history}" if attrs.get("history") else history
        if empty:
            labels["left_out"] = f"{', '.join(empty)}: no values (a dimension of length 0)"
        nc.setncatts(netcdf_attributes({**attrs, **labels, "layout": CDO_LAYOUT}))


def _write_per_threshold(nc, name, v, thresholds, dtype, fill, attrs, grid, shape, storage):
    """``name`` on ``grid + (threshold,)`` as the variables ``<name>_<i>``, one per threshold."""
    grid_chunk, step = _grid_chunks(shape, thresholds.size)
    chunks = {"chunksizes": grid_chunk, "chunk_cache": 2 * dtype.itemsize * math.prod(grid_chunk)} if shape else {}
    outs = []
    for i, value in enumerate(np.asarray(thresholds.values, dtype=float)):
        out = nc.createVariable(f"{name}_{i}", dtype, grid, fill_value=fill, **storage, **chunks)
        out.setncatts({**attrs, **cdo_threshold_attributes(value, thresholds.attrs)})
        outs.append(out)
    for slab in _grid_blocks(shape, step):
        values = _encoded(v[slab], dtype, fill)
        for i, out in enumerate(outs):
            out[slab if slab else ...] = values[..., i]


def _after_grid(name, dims, grid, all_dims):
    """The dimensions of variable ``name`` after the grid ones, or ``None`` if it is not a grid variable
    (a dimension's own coordinate, or a variable on other dimensions)."""
    if name in all_dims or dims[:len(grid)] != grid:
        return None
    if not grid and dims not in (("t",), ("threshold",)):
        return None
    return dims[len(grid):]


def _encoded(var, dtype, fill):
    """The values of ``var`` (read from the source: a failure is a
    :class:`~screening.io.errors.ReadFailure`) in the stored
    ``dtype`` (an integer variable decoded to float with NaN: its ``fill``)."""
    values = np.asarray(read_values(lambda: var.values))
    if values.dtype.kind == "f" and dtype.kind in "iu" and fill is not False:
        values = np.where(np.isnan(values), fill, values)
    return values.astype(dtype, copy=False)


def _example(ds, dim):
    if dim == "case":
        return str(ds["case_name"].values[0])
    return f"{float(ds[dim].values[0]):.6g}"
