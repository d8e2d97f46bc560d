"""The zarr form of a sweep result (``--out result.zarr``): written in place by the workers.

:class:`ZarrFormat` is the zarr (format 3) :class:`~screening.io.formats.ResultFormat`
(:class:`~screening.io.writer.NetcdfFormat` is the netCDF one), so that one piece of code
(:class:`~screening.io.writer.ResultFile`) lays out the variables of both forms.
Variables defined are created at the next :meth:`ZarrFormat.commit` (xarray writes their metadata and
any values written; the grid variables are left unwritten for the workers).  A grid variable is cut
into chunks that each lie in one batch (:func:`point_chunks`),
so that every worker compresses and writes whole chunks of its own, with no lock.

:func:`export_netcdf` converts a finished store to the netCDF file a direct run writes.  netCDF4 /
HDF5 files cannot be written from several processes, hence this second form for large runs.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np

from screening.io._zarr_store import (COMPLETION_MARK, file_check, netcdf_attributes, read_completion_mark,
                                      warnings_ignored)
from screening.io.errors import read_values
from screening.io.layout import history_chunks
from screening.solvers.outputs import GRID_OUTPUTS
from screening.io._zarr_store import write_completion_mark  # noqa: F401 (the examples' finished runs)

__all__ = ["ZARR_SUFFIX", "ZARR_FORMAT", "BLOCK_BYTES", "COMPLETION_MARK", "ZARR_FILL", "is_zarr_path",
           "is_zarr_store", "point_chunks", "zarr_batch_size", "ZarrFormat", "store_problem", "check_store",
           "open_zarr_result", "export_netcdf"]

ZARR_SUFFIX = ".zarr"
ZARR_FORMAT = 3
#: Bytes read at a time when a variable is copied (:func:`export_netcdf`) or checked.
BLOCK_BYTES = 32 * 2**20
#: What a chunk that was never written reads as (zarr's fill value): for a flag, the value of a failed
#: point (:mod:`screening.solvers.outputs`), never ``ok``.
ZARR_FILL = {o.name: int(o.failed) for o in GRID_OUTPUTS if o.is_flag}


def is_zarr_path(path):
    """Whether ``path`` names a zarr result (by its suffix).

    Parameters
    ----------
    path : str or os.PathLike
        An output path.

    Returns
    -------
    bool
        True if the suffix is :data:`ZARR_SUFFIX` (``.zarr``).

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> is_zarr_path("outputs/run.zarr"), is_zarr_path("outputs/run.nc")
    (True, False)
    """
    return Path(path).suffix == ZARR_SUFFIX


def is_zarr_store(path):
    """Whether ``path`` is a folder holding a zarr store (format 2 or 3).

    Parameters
    ----------
    path : str or os.PathLike
        A path.

    Returns
    -------
    bool
        True for a folder (not a link) with a ``zarr.json`` (format 3) or ``.zgroup`` (format 2).

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     empty = is_zarr_store(folder)
    ...     with open(os.path.join(folder, "zarr.json"), "w") as fh:
    ...         _ = fh.write('{"zarr_format": 3, "node_type": "group"}')
    ...     empty, is_zarr_store(folder)
    (False, True)
    """
    path = Path(path)
    return path.is_dir() and not path.is_symlink() and any((path / m).is_file() for m in ("zarr.json", ".zgroup"))


# ----------------------------------------------------------------------------- chunks
def point_chunks(shape, n_lead, batch_size):
    """Chunk shape over the grid ``shape`` such that every chunk lies in one batch of ``batch_size``.

    Batches are runs of ``batch_size`` points in C order that restart at each of the ``n_lead``
    leading dimensions (``case``: 1, else 0; :func:`screening.sweep.grid.plan_batches`).  A chunk
    is ``c`` indices of one swept dimension ``j`` times everything after it, ``c * inner(j)``
    points, with ``c`` dividing that dimension's size (any ``c`` for the first swept dimension,
    whose last chunk may be short) and the chunk's size dividing ``batch_size``.  The largest such
    chunk is returned.

    Parameters
    ----------
    shape : tuple of int
        The grid's shape.
    n_lead : int
        Leading dimensions batches never cross (1 with ``case``, else 0).
    batch_size : int
        Points per batch.

    Returns
    -------
    tuple of int
        The chunk shape.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> point_chunks((2, 10, 6), n_lead=1, batch_size=30)         # 5 rows of 6: 30 points a chunk
    (1, 5, 6)
    """
    shape = tuple(int(n) for n in shape)
    lead, swept = (1,) * n_lead, shape[n_lead:]
    per_case = math.prod(swept)
    if batch_size >= per_case:
        return lead + swept
    best, chunk = 1, lead + (1,) * len(swept)
    for j, n in enumerate(swept):
        inner = math.prod(swept[j + 1:])
        fits = range(1, n + 1) if j == 0 else [d for d in range(1, n + 1) if n % d == 0]
        c = max((d for d in fits if batch_size % (d * inner) == 0), default=0)
        if c >= 1 and c * inner > best:
            best, chunk = c * inner, lead + (1,) * j + (c,) + swept[j + 1:]
    return chunk


def zarr_batch_size(shape, n_lead, target):
    """A batch size of at most ``target`` points that is a whole number of large chunks
    (:func:`point_chunks`): the grid of a zarr result is then cut into few, large chunks.

    Parameters
    ----------
    shape : tuple of int
        The grid's shape.
    n_lead : int
        Leading dimensions batches never cross (1 with ``case``, else 0).
    target : int
        The batch size aimed at (at least 1).

    Returns
    -------
    int
        Points per batch.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> zarr_batch_size((10, 6), n_lead=0, target=40)             # 6 whole rows of 6
    36
    """
    swept = tuple(shape)[n_lead:]
    per_case = math.prod(swept)
    if target >= per_case:
        return target
    best = 1
    for j, n in enumerate(swept):
        inner = math.prod(swept[j + 1:])
        if j == 0:
            c = min(n, target // inner)
        else:
            c = max((d for d in range(1, n + 1) if n % d == 0 and d * inner <= target), default=0)
        best = max(best, c * inner)
    return best * (target // best)


# ----------------------------------------------------------------------------- the result format
def _codecs(dtype, zlib, complevel, shuffle):
    """Compression of a numeric variable where netCDF would use zlib: blosc/zstd at ``complevel`` (with
    byte shuffle if asked); none where netCDF uses none; strings keep zarr's default."""
    from zarr.codecs import BloscCodec

    if np.dtype(dtype).kind not in "fiu":
        return {}
    if not zlib:
        return {"compressors": None}
    return {"compressors": (BloscCodec(cname="zstd", clevel=int(complevel), shuffle="shuffle" if shuffle
                                       else "noshuffle", typesize=np.dtype(dtype).itemsize),)}


def _no_fill(fill):
    """A ``fill`` of ``False`` (none) or ``None`` (unused for what we store)."""
    return fill is None or fill is False


class _Pending:
    """A variable defined but not yet created in the store: its attributes and any values written."""

    def __init__(self, fmt, name, dtype, dims, fill, attrs, storage):
        self.format, self.name, self.dims, self.fill, self.storage = fmt, name, tuple(dims), fill, storage
        self.dtype = np.dtype(object) if dtype is str else np.dtype(dtype)
        self.attrs, self.values = dict(attrs), None

    @property
    def shape(self):
        return tuple(self.format.dimension_size(d) for d in self.dims)

    def write(self, key, values):
        if self.values is None:
            fill = ("" if self.dtype.kind == "O" else 0) if _no_fill(self.fill) else self.fill
            self.values = np.full(self.shape, fill, dtype=self.dtype)
        self.values[key] = values


class ZarrFormat:
    """The zarr (format 3) :class:`~screening.io.formats.ResultFormat`.

    ``mode``: ``"w"`` (a new store; the folder must not exist) or ``"r+"``.  ``chunks``: the chunk shape
    over the grid dimensions ``grid`` (:func:`point_chunks`); other variables are one chunk.
    ``complevel``: blosc/zstd level of the compressed variables.  Variables defined are created at the
    next :meth:`commit` (xarray writes their metadata and any values written; the grid variables are
    left unwritten for the workers).
    """

    def __init__(self, path, mode="r+", grid=(), chunks=(), complevel=1):
        self.path = Path(path)
        self.grid, self.chunks, self.complevel = tuple(grid), tuple(chunks), complevel
        self.dimensions, self._pending, self._attrs, self._arrays = {}, {}, {}, {}
        self._created, self._open, self._group = mode == "r+", True, None

    @property
    def group(self):
        if self._group is None:
            import zarr

            with zarr.config.set({"array.write_empty_chunks": True}):   # every chunk of a batch is a file
                self._group = zarr.open_group(self.path, mode="r+", zarr_format=ZARR_FORMAT)
        return self._group

    dataset = group

    # -- definition
    def dimension(self, name, size):
        self.dimensions[name] = int(size)

    def dimension_size(self, name):
        """Size of dimension ``name`` (of an existing store: read from its arrays, once)."""
        if name not in self.dimensions and self._created:
            for _, arr in self.group.arrays():
                for dim, size in zip(arr.metadata.dimension_names or (), arr.shape):
                    self.dimensions.setdefault(dim, size)
        return self.dimensions[name]

    def define(self, name, dtype, dims, attrs, fill=False, values=None, compress=False, shuffle=None, chunks=None):
        """Define variable ``name`` (created at the next :meth:`commit`): compressed where ``compress``
        (byte shuffle if ``shuffle``); ``chunks`` (netCDF's) are not used: a grid variable is chunked by
        batch."""
        zlib = compress and self.complevel > 0
        var = _Pending(self, name, dtype, dims, fill, attrs, (zlib, max(self.complevel, 1) if compress else 1,
                                                               bool(shuffle)))
        self._pending[name] = var
        if values is not None:
            var.write(Ellipsis, values)

    def has(self, name):
        return name in self._pending or self._created and name in {n for n, _ in self.group.arrays()}

    def _array(self, name):
        """Array ``name`` of the store, writing every chunk as a file (an empty one too): asked of the array
        itself where zarr can (zarr's global configuration is shared by the worker threads of a process:
        one thread's ``config.set`` ending while another opens an array left that one without it)."""
        if name not in self._arrays:
            import zarr

            with zarr.config.set({"array.write_empty_chunks": True}):
                arr = self.group[name]
            with_config = getattr(arr, "with_config", None)
            self._arrays[name] = arr if with_config is None else with_config({"write_empty_chunks": True})
        return self._arrays[name]

    # -- data
    def write(self, name, region, values):
        if name in self._pending:
            self._pending[name].write(region, values)
        else:
            self._array(name)[region] = values

    def read(self, name, region=Ellipsis):
        if name in self._pending:
            return self._pending[name].values[region]
        return self._array(name)[region]

    def dims(self, name):
        if name in self._pending:
            return self._pending[name].dims
        return tuple(self._array(name).metadata.dimension_names or ())

    def attrs(self, name):
        if name in self._pending:
            return dict(self._pending[name].attrs)
        return dict(self._array(name).attrs)

    def set_attrs(self, attrs):
        if self._created:
            self.group.attrs.update({k: _json(v) for k, v in attrs.items()})
        else:
            self._attrs.update(attrs)

    def commit(self):
        """Create the pending variables (metadata, and the values that were written)."""
        if self._created and not self._pending:
            return
        import dask.array as da
        import xarray as xr

        variables, encoding = {}, {}
        for name, v in self._pending.items():
            chunks = self._chunks(v)
            if v.values is None:                    # a grid variable: the workers write it
                data = da.zeros(v.shape, dtype=v.dtype, chunks=chunks or -1)
            else:
                data = v.values
            variables[name] = xr.Variable(v.dims, data, v.attrs)
            enc = {"_FillValue": None if _no_fill(v.fill) else v.fill, **_codecs(v.dtype, *v.storage)}
            if name in ZARR_FILL:
                enc["fill_value"] = ZARR_FILL[name]
            if chunks:
                enc["chunks"] = chunks
            encoding[name] = enc
        # xarray replaces the global attributes on every write: give it those of the store
        ds = xr.Dataset(variables, attrs=dict(self.group.attrs) if self._created else self._attrs)
        ds.to_zarr(self.path, mode="a" if self._created else "w-", compute=False, encoding=encoding,
                   consolidated=False, zarr_format=ZARR_FORMAT, write_empty_chunks=True)
        self._pending.clear()
        self._created, self._group = True, None
        self._arrays.clear()

    def _chunks(self, var):
        shape = var.shape
        if not shape:
            return None
        if self.grid and var.dims[:len(self.grid)] == self.grid:
            return self.chunks + shape[len(self.grid):]
        return shape

    def is_open(self):
        return self._open

    def finish(self):
        """Create what is pending and write the consolidated metadata (one read to open the store)."""
        if self._open:
            self._open = False
            self.commit()
            import zarr

            with warnings_ignored():
                zarr.consolidate_metadata(self.path, zarr_format=ZARR_FORMAT)

    # -- batches
    def chunk_files(self, names, slabs):
        """``{relative path: [size [bytes], checksum]}`` of the chunk files of variables ``names`` over
        the grid ``slabs`` (tuples of slices; a file that is missing has size -1, checksum ``""``)."""
        files = {}
        for name in names:
            arr = self._array(name)
            for slab in slabs:
                ranges = [range(s.start // c, (s.stop - 1) // c + 1) for s, c in zip(slab, arr.chunks)]
                for index in np.ndindex(*[len(r) for r in ranges]):
                    coords = tuple(r[i] for r, i in zip(ranges, index)) + (0,) * (arr.ndim - len(slab))
                    key = f"{name}/{arr.metadata.encode_chunk_key(coords)}"
                    files[key] = file_check(self.path / key)
        return files


# ----------------------------------------------------------------------------- integrity
def store_problem(root, deep=True):
    """Why the zarr store ``root`` is not a finished, intact result (a short phrase), or ``None``.

    It must have its completion mark, and every file the mark lists must be there with its size
    (and, ``deep``, its checksum: every chunk is read).  A missing chunk would otherwise read as the
    fill value, a zeroed one as whatever it decodes to.

    Parameters
    ----------
    root : str or os.PathLike
        The store's folder.
    deep : bool, optional
        Also compare every file's checksum (reads the whole store).

    Returns
    -------
    str or None
        The first problem found, or None for a finished, intact store.

    References
    ----------
    .. [1] screening documentation, "How results are stored, and what the tool guarantees about them",
       ``docs/outputs_storage.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> folder = tempfile.TemporaryDirectory()
    >>> store = os.path.join(folder.name, "result.zarr")
    >>> import warnings
    >>> with warnings.catch_warnings():                 # zarr: consolidated metadata is not in format 3 (yet)
    ...     warnings.simplefilter("ignore")
    ...     _ = result.to_zarr(store, zarr_format=3)
    >>> write_completion_mark(store)                  # what a finished run does last
    >>> store_problem(store) is None
    True
    >>> os.remove(os.path.join(store, "peak_var_theta", "c", "0"))          # a chunk lost
    >>> store_problem(store)
    'its file peak_var_theta/c/0 is missing'
    >>> folder.cleanup()
    """
    files = read_completion_mark(root)
    if files is None:
        return ("it has no completion mark: the store of an interrupted run (re-run the same command to "
                "finish it) or one screening did not write")
    for path, (size, digest) in files.items():
        full = Path(root) / path
        try:
            st = os.lstat(full)
        except (OSError, ValueError):
            return f"its file {path} is missing"
        if not stat.S_ISREG(st.st_mode) or st.st_size != size:
            return f"its file {path} has changed (size {st.st_size}, {size} bytes written)"
        if deep and file_check(full) != [size, digest]:
            return f"its file {path} has changed since it was written (checksum)"
    return None


def _json(value):
    """An attribute value as JSON (numpy scalars and arrays to Python)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


# ----------------------------------------------------------------------------- reading and export
def open_zarr_result(path):
    """The result store at ``path`` opened lazily with xarray, as a netCDF result opens: arrays read on
    access, not dask arrays (the readers' computations are numpy's).

    Parameters
    ----------
    path : str or os.PathLike
        The store's folder.

    Returns
    -------
    xarray.Dataset
        The result (use :func:`~screening.io.reader.open_result` to have it checked first).

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> folder = tempfile.TemporaryDirectory()
    >>> store = os.path.join(folder.name, "result.zarr")
    >>> import warnings
    >>> with warnings.catch_warnings():                 # zarr: consolidated metadata is not in format 3 (yet)
    ...     warnings.simplefilter("ignore")
    ...     _ = result.to_zarr(store, zarr_format=3)
    >>> write_completion_mark(store)                  # what a finished run does last
    >>> with open_zarr_result(store) as ds:
    ...     print(dict(ds.sizes), ds["peak_var_theta"].values)
    {'eps': 2, 't': 3} [1.e-06 4.e-06]
    >>> folder.cleanup()
    """
    import xarray as xr

    with warnings_ignored():
        return xr.open_zarr(path, zarr_format=ZARR_FORMAT, consolidated=None, chunks=None)


def check_store(path, expected_dims, required):
    """Why the finished store at ``path`` cannot be reused for a study (a short reason), or ``None``.

    Every file is checked against the completion mark (:func:`store_problem`), the dimensions and the
    variables against the study's, and every chunk is read (a damaged one raises).

    Parameters
    ----------
    path : str or os.PathLike
        The store's folder.
    expected_dims : dict of str to int
        The study's dimensions and their sizes.
    required : sequence of str
        The variables the study's result must hold.

    Returns
    -------
    str or None
        The first reason found, or None for a store the study can reuse.

    References
    ----------
    .. [1] screening documentation, "How results are stored, and what the tool guarantees about them",
       ``docs/outputs_storage.md``.

    Examples
    --------
    >>> import os, tempfile, warnings
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> folder = tempfile.TemporaryDirectory()
    >>> store = os.path.join(folder.name, "result.zarr")
    >>> with warnings.catch_warnings():                 # zarr: consolidated metadata is not in format 3 (yet)
    ...     warnings.simplefilter("ignore")
    ...     _ = result.to_zarr(store, zarr_format=3)
    >>> write_completion_mark(store)                  # what a finished run does last
    >>> check_store(store, dict(result.sizes), ["status"]) is None
    True
    >>> check_store(store, {**result.sizes, "time": 7}, ["status"])
    "its dimension 'time' does not have the study's size 7"
    >>> check_store(store, dict(result.sizes), ["status", "p_overturn"])
    'it lacks p_overturn'
    >>> folder.cleanup()
    """
    import zarr

    problem = store_problem(path)
    if problem:
        return problem

    with warnings_ignored():
        group = zarr.open_group(path, mode="r")
        arrays = dict(group.arrays())
    dims = {}
    for arr in arrays.values():
        dims.update(zip(arr.metadata.dimension_names or (), arr.shape))
    for dim, size in expected_dims.items():
        if dims.get(dim) != size:
            return f"its dimension {dim!r} does not have the study's size {size}"
    missing = [v for v in required if v not in arrays]
    if missing:
        return f"it lacks {', '.join(missing)}"
    for arr in arrays.values():
        for block in _blocks(arr):
            arr[block]
    return None


def _blocks(arr):
    """Index tuples covering ``arr`` in blocks of about :data:`BLOCK_BYTES` along its first dimension."""
    if not arr.shape:
        yield ()
        return
    row = math.prod(arr.shape[1:]) * max(getattr(arr.dtype, "itemsize", 8), 8)
    step = max(1, BLOCK_BYTES // max(row, 1))
    for lo in range(0, arr.shape[0], step):
        yield (slice(lo, lo + step),)


def _export_fill(value, dtype):
    """The netCDF ``_FillValue`` of an exported variable: the store's own (NaN for floats, an integer flag's
    padding such as ``esc_sample_state``'s -1 kept in its type), ``False`` (none) where it has none."""
    if value is None or dtype.kind not in "fiu":
        return False
    if dtype.kind == "f":
        return np.nan if isinstance(value, str) or not np.isfinite(float(value)) else dtype.type(value)
    return dtype.newbyteorder("=").type(int(value))


def export_netcdf(src, dst, complevel, history):
    """Write the zarr result ``src`` as the CF netCDF file ``dst`` (a new file), block by block.

    Every variable keeps its dimensions, type, values and attributes (``flag_values`` in the type of
    its variable, as CF wants); floats keep their NaN fill value.  Storage as in a direct run: zlib
    at ``complevel``, byte shuffle and ``(1, ..., n, nt)`` chunks for the histories.  ``history``:
    the line appended to the ``history`` attribute.

    Parameters
    ----------
    src : str or os.PathLike
        The zarr result.
    dst : str or os.PathLike
        The netCDF4 file to write (created or overwritten; the caller makes it appear all or none).
    complevel : int
        zlib compression level, 0 (none) to 9.
    history : str
        The line appended to the ``history`` attribute (the command that wrote it).

    Returns
    -------
    None

    Raises
    ------
    SweepError
        ``flag_values`` that are not a flat list of numbers of their variable's type.
    ReadFailure
        A chunk of the store that cannot be read.

    References
    ----------
    .. [1] screening documentation, "What a result holds", section "Zarr results", ``docs/outputs.md``.
    .. [2] Zarr core specification, version 3, https://zarr-specs.readthedocs.io/en/latest/v3/core/index.html
    .. [3] NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8, section 3.5 "Flags",
       https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html

    Examples
    --------
    >>> import netCDF4
    >>> import os, tempfile
    >>> import numpy as np, xarray as xr
    >>> from screening.io.reader import example_result
    >>> result = example_result()
    >>> folder = tempfile.TemporaryDirectory()
    >>> store = os.path.join(folder.name, "result.zarr")
    >>> import warnings
    >>> with warnings.catch_warnings():                 # zarr: consolidated metadata is not in format 3 (yet)
    ...     warnings.simplefilter("ignore")
    ...     _ = result.to_zarr(store, zarr_format=3)
    >>> write_completion_mark(store)                  # what a finished run does last
    >>> export_netcdf(store, os.path.join(folder.name, "result.nc"), complevel=1, history="screening export")
    >>> with netCDF4.Dataset(os.path.join(folder.name, "result.nc")) as nc:
    ...     print(nc["status"].dtype, nc["status"].flag_values, nc["peak_var_theta"][:], nc.study_sha256)
    int8 [0 1] [1.e-06 4.e-06] ab12
    >>> folder.cleanup()
    """
    import netCDF4
    import zarr

    with warnings_ignored():
        group = zarr.open_group(src, mode="r")
        arrays = dict(group.arrays())
        attrs = dict(group.attrs)
    grid = tuple(arrays["status"].metadata.dimension_names or ())
    with netCDF4.Dataset(dst, "w", format="NETCDF4") as nc:
        nc.set_auto_mask(False)
        for arr in arrays.values():
            for dim, size in zip(arr.metadata.dimension_names or (), arr.shape):
                if dim not in nc.dimensions:
                    nc.createDimension(dim, size)
        for name, arr in arrays.items():
            dims = tuple(arr.metadata.dimension_names or ())
            var_attrs = dict(arr.attrs)
            fill = _export_fill(var_attrs.pop("_FillValue", None), arr.dtype)
            kind = arr.dtype.kind
            dtype = str if kind in "OTU" else arr.dtype.newbyteorder("=")
            storage = {}
            if dims and dims != (name,) and kind in "fiu" and complevel > 0:
                storage = {"zlib": True, "complevel": complevel}
                if dims[:len(grid)] == grid and dims[len(grid):] == ("t",):
                    storage.update(shuffle=True, chunksizes=history_chunks(arr.shape[:len(grid)], arr.shape[-1]))
            var = nc.createVariable(name, dtype, dims, fill_value=None if dtype is str else fill, **storage)
            var.setncatts(netcdf_attributes(var_attrs, None if dtype is str else dtype, name))
            for block in _blocks(arr):
                values = read_values(lambda: arr[block])
                var[block if block else ...] = np.asarray(values, dtype=object) if dtype is str else values
        if attrs.get("history"):
            attrs["history"] = f"{attrs['history']}\n{history}"
        nc.setncatts(netcdf_attributes(attrs))
