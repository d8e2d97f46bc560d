"""The CF-1.8 netCDF result file of a sweep, written batch by batch (:class:`ResultFile`).

Every grid variable is laid out from its declaration (:mod:`screening.solvers.outputs`), every other
``units``, ``long_name`` and flag attribute comes from :mod:`screening.solvers.schema`.  :class:`ResultFile` lays
out the result on a :class:`~screening.io.formats.ResultFormat`: :class:`NetcdfFormat` (this file, written
by the client) or :class:`~screening.io.zarrfile.ZarrFormat` (``--out result.zarr``, whose grid variables the
workers write).  It knows no stage: the stages (:mod:`screening.sweep`) write their variables by name and region.

Storage: histories are ``float32`` (7 significant digits, half the disk and bandwidth of
``float64``; the solver tolerance is ``1e-7`` anyway), everything else ``float64`` or
integers; zlib level 1 with byte shuffle (``complevel``; compression is the client's main
cost, about 1.3 s per 10,000 points of 401 output times); chunks are ``(1, ..., n_last, nt)``
for histories and C-order runs of about :data:`POINT_CHUNK` points for everything else, each
variable with a chunk cache of :data:`CACHED_CHUNKS` chunks (the netCDF default, 64 MiB per
variable, would keep the written chunks of the whole grid in memory: client memory independent of
the number of points), and a file with histories is synced every :data:`SYNC_POINTS` points (the
per-point chunks alone are written when they leave the cache: syncing them would compress each
partly filled chunk again and again).  A 10,000-point sweep with 20 s
records at 0.05 s is about 55 MB.

File layout (checked with the IOOS compliance-checker in strict mode):

* dimensions: ``case`` (if the study has cases), one per swept parameter (file order), ``t``,
  and ``spot`` / ``sample`` for the spot checks;
* coordinates: the swept values (no ``_FillValue``); a parameter in units of pressure (``k``) has
  no ``units`` on its coordinate variable and its values with units in the auxiliary coordinate
  ``k_value`` (CF reads a coordinate variable in pressure units as a vertical axis;
  :func:`screening.solvers.schema.grid_coordinate_attributes`); ``case`` (index) with ``case_name``; ``t`` [s]
  (no ``axis = "T"``: CF would then want a reference date in the units); fixed parameters as scalar
  coordinates, and parameters that differ between cases on ``case`` (NaN where they do not apply);
* data: the six histories on ``(grid..., t)``; per point ``status`` (flag variable), ``t_stop``,
  ``n_steps``, ``n_rejected``, ``peak_var_theta``, ``t_peak_var_theta``, ``peak_p_uplift``,
  ``min_k_eq``, ``theta_ul``, ``slenderness``; spot checks ``mcs_*`` on ``spot`` with the spot
  coordinates ``spot_<dim>``;
* global attributes: :func:`screening.solvers.schema.global_attributes`, ``title``, ``history``,
  ``source``, the study file's path, text and hash, the solver settings.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path
from typing import NamedTuple

import numpy as np

from screening._version import __version__
from screening.io._zarr_store import foreign_files
from screening.io.errors import SweepError
from screening.io.layout import history_chunks, hyperslabs, parameter_table
from screening.io.zarrfile import is_zarr_path, is_zarr_store, point_chunks as zarr_point_chunks, ZarrFormat
from screening.solvers.outputs import client_variables, GRID_OUTPUTS, selected
from screening.solvers.schema import (attributes, global_attributes, grid_coordinate_attributes, PRESSURE_PARAMETERS,
                                      SWEEP, TIME)

__all__ = []

SYNC_POINTS = 2000            # points of histories between flushes of the file (compression overlaps compute)
COMPLEVEL = 1
#: Points per chunk of a per-point variable (about; whole trailing dimensions first).
POINT_CHUNK = 2**14
#: Chunks each variable keeps in its cache: those the batches in flight are filling.
CACHED_CHUNKS = 4
TITLE_FALLBACK = "Stochastic-linearization screening"


def check_output_path(out, inputs=()):
    """Raise :class:`SweepError` unless ``out`` can be written (its folder must exist).

    ``out`` may not be one of the ``inputs`` (the study or result file a command reads, under any
    spelling or link), nor an existing file that is not a regular file (a FIFO or a device would
    block or be clobbered).  An existing ``.zarr`` store is replaced only if it is a finished result
    screening wrote.

    Parameters
    ----------
    out : str or os.PathLike
        The output path (a netCDF file, or a ``.zarr`` store).
    inputs : iterable of str or os.PathLike, optional
        The files or folders the command reads.

    Returns
    -------
    pathlib.Path
        ``out``, checked.

    Raises
    ------
    SweepError
        One line: the output is an input, lies inside one, is a directory or a special file, or its
        folder is missing or not writable.

    """
    out = Path(out)
    for path in inputs:
        if _same_file(out, path):
            raise SweepError(f"output path {out} is the input file {path}; give another --out")
        if _inside(out, path):
            raise SweepError(f"output path {out} is inside the input {path}; give another --out")
    zarr = is_zarr_path(out)
    if zarr and out.exists() and not is_zarr_store(out):
        raise SweepError(f"output path {out} exists and is not a zarr store; give another --out")
    if zarr and is_zarr_store(out):
        foreign = foreign_files(out)
        if foreign:
            raise SweepError(f"output path {out} holds files screening did not write as a finished result "
                             f"(e.g. {foreign[0]}); only such a store is replaced: give another --out")
    if out.is_dir() and not zarr:
        raise SweepError(f"output path {out} is a directory")
    try:
        mode = out.lstat().st_mode if zarr else out.stat().st_mode
    except OSError:
        mode = None
    if mode is not None and not stat.S_ISREG(mode) and not (zarr and stat.S_ISDIR(mode)):
        raise SweepError(f"output path {out} exists and is not a regular file (a FIFO, socket or device); "
                         "give another --out")
    if not out.parent.is_dir():
        raise SweepError(f"output folder {out.parent} does not exist")
    if not os.access(out.parent, os.W_OK):
        raise SweepError(f"output folder {out.parent} is not writable")
    return out


def _inside(out, folder):
    """Whether ``out`` lies inside the folder ``folder`` (links resolved)."""
    if not os.path.isdir(folder):
        return False
    return Path(os.path.realpath(out.parent)).is_relative_to(os.path.realpath(folder))


def _same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(os.path.abspath(a)) == Path(os.path.abspath(b))


def result_attributes(study, created, batch_size):
    """Global attributes of the result file of ``study`` (``created``: ISO time stamp).

    The CF attributes (``Conventions``, title, history, source, comment), a summary and the study's
    provenance: its name, file, text and key (``study_sha256``), grid dimensions, solver settings,
    output times [s] and the batch size.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    created : str
        ISO 8601 time stamp of the run.
    batch_size : int
        Points per batch of the run.

    Returns
    -------
    dict
        ``{attribute: value}``.

    """
    cmd = f"screening run {study.source}"
    return global_attributes(
        __version__,
        title=study.title or TITLE_FALLBACK,
        summary=study.description or ("Time-varying second-order rocking statistics of a rigid block on a "
                                      "flexible nonlinear foundation by stochastic linearization and "
                                      "Lyapunov moment equations, over a parameter grid"),
        history=f"{created}: {cmd} (screening {__version__})",
        source=f"screening {__version__}: stochastic linearization + Lyapunov moment equations "
               "(screening.solvers.moments.solve_moments)",
        comment=("histories (var_theta, var_theta_dot, cov_theta_theta_dot, c_eq, k_eq, p_uplift) are "
                 "stored as float32, everything else as float64/integers; values after a point stopped "
                 "(status != ok) are NaN"),
        date_created=created,
        study_name=study.name,
        study_file=study.source,
        study_sha256=study.key,
        study_text=study.text,
        grid_dims=" ".join(study.dims),
        rtol=study.rtol,
        max_steps=np.int32(study.max_steps),
        t_end=study.t_end,
        dt=study.dt,
        batch_size=np.int32(batch_size),
        output_histories=study.output.histories,
        output_history_variables=" ".join(study.output.stored),
    )


def point_chunks(shape, target=POINT_CHUNK):
    """Chunks of a per-point variable on ``shape``: C-order runs of about ``target`` points, so that
    consecutive batches fill one chunk after the other.

    Parameters
    ----------
    shape : tuple of int
        The grid's shape.
    target : int, optional
        Points per chunk at most (default :data:`POINT_CHUNK`).

    Returns
    -------
    tuple of int
        The chunk shape: whole trailing dimensions while they fit, then a part of the next one.

    """
    chunks = []
    size = 1
    for n in reversed(shape):
        c = max(1, min(n, target // size))
        chunks.insert(0, c)
        size *= c
    return tuple(chunks)


def _slab_key(slab):
    return slab if slab else Ellipsis


def region_variables(study):
    """Names of the grid variables a batch of ``study`` writes.

    The stored histories (``[output]``), then every per-point variable a result of the study holds.
    """
    return tuple(o.name for o in _outputs(study))


def _outputs(study):
    """The declared grid variables the result of ``study`` holds, in file order."""
    return selected(study.output.stored, study.derived_inputs, study.probabilities, study.fragility is not None)


class NetcdfFormat:
    """The netCDF4/HDF5 :class:`~screening.io.formats.ResultFormat`, written by the client alone.

    ``complevel``: zlib level of the compressed variables.  ``mode``: ``"w"`` creates the file, ``"a"`` opens
    an existing one.
    """

    def __init__(self, path, complevel=COMPLEVEL, mode="w"):
        import netCDF4              # here, not at module level: workers never need it

        self.dataset = netCDF4.Dataset(path, mode, format="NETCDF4")
        self.dataset.set_auto_mask(False)
        self.complevel = complevel

    # -- definition
    def dimension(self, name, size):
        self.dataset.createDimension(name, size)

    def dimension_size(self, name):
        return len(self.dataset.dimensions[name])

    def define(self, name, dtype, dims, attrs, fill=False, values=None, compress=False, shuffle=None, chunks=None):
        """Create variable ``name`` with its attributes (and ``values``): zlib-compressed where
        ``compress`` (``shuffle``: byte shuffle; None, netCDF's default), in ``chunks`` with a chunk cache
        of :data:`CACHED_CHUNKS` of them."""
        storage = {"zlib": self.complevel > 0, "complevel": max(self.complevel, 1)} if compress else {}
        if shuffle is not None:
            storage["shuffle"] = shuffle
        if chunks:
            storage.update(chunksizes=chunks,
                           chunk_cache=CACHED_CHUNKS * np.dtype(dtype).itemsize * math.prod(chunks))
        v = self.dataset.createVariable(name, dtype, dims, fill_value=fill, **storage)
        v.setncatts(attrs)
        if values is not None:
            v[slice(None) if dtype is str else Ellipsis] = values

    def has(self, name):
        return name in self.dataset.variables

    # -- data
    def write(self, name, region, values):
        self.dataset[name][region] = values

    def read(self, name, region=Ellipsis):
        return self.dataset[name][region]

    def dims(self, name):
        return self.dataset[name].dimensions

    def attrs(self, name):
        v = self.dataset[name]
        return {key: v.getncattr(key) for key in v.ncattrs()}

    def set_attrs(self, attrs):
        self.dataset.setncatts(attrs)

    def commit(self):
        self.dataset.sync()

    def is_open(self):
        return self.dataset.isopen()

    def finish(self):
        if self.dataset.isopen():
            self.dataset.close()


class Variable(NamedTuple):
    """A variable a stage adds to a result (:meth:`ResultFile.add`): its attributes are its schema's (``table``)."""

    name: str
    dtype: object
    dims: tuple
    values: object
    fill: object = np.nan
    coordinates: str = ""
    table: dict = SWEEP
    compress: bool = True


class ResultFile:
    """Build the CF-1.8 result of ``study`` at ``path``, batch by batch: a netCDF4/HDF5 file
    (:class:`NetcdfFormat`), or with ``zarr_batch_size`` (the batch size of the run) a zarr store whose
    grid variables the workers write (:class:`~screening.io.zarrfile.ZarrFormat`, chunks of
    :func:`~screening.io.zarrfile.point_chunks`), through :class:`~screening.io.formats.ResultFormat` alone.

    ``attrs``: the global attributes (:func:`result_attributes`); ``reopen``: open the zarr store of an
    interrupted run (or a netCDF file: a copy of the one being built, for an interim result) instead of
    creating one.  Keeps what the client keeps of every point
    (:func:`screening.solvers.outputs.client_variables`: spot selection, run summary) in memory;
    histories go straight to disk.
    """

    def __init__(self, path, study, attrs, complevel=COMPLEVEL, zarr_batch_size=None, reopen=False):
        self.path = Path(path)
        self.study = study
        self.dims, self.shape, self.n_points = study.dims, study.shape, study.n_points
        self.nt = study.times.size
        #: What the client keeps of every point (:func:`screening.solvers.outputs.client_variables`), flat.
        self.kept = {o.name: o.failed_array(self.n_points) for o in GRID_OUTPUTS if o.client}
        #: The kept status, trust flag and peak uplift probability of every point (arrays of :attr:`kept`).
        self.status, self.sl_trust, self.peak_p_uplift = (self.kept[n] for n in ("status", "sl_trust",
                                                                                  "peak_p_uplift"))
        self._unsynced = 0
        if zarr_batch_size is not None:
            chunks = zarr_point_chunks(self.shape, int(study.has_case_dim), zarr_batch_size)
            self.format = ZarrFormat(self.path, "r+" if reopen else "w", self.dims, chunks, complevel)
        else:
            self.format = NetcdfFormat(self.path, complevel, "a" if reopen else "w")
        if not reopen:
            try:
                self._define(attrs)
                self.format.commit()
            except BaseException:
                self.format.finish()
                raise
        #: The ``coordinates`` attribute of the grid variables.
        self.coordinates = self.grid_coordinates()

    @property
    def nc(self):
        """The format's own dataset (a ``netCDF4.Dataset`` or a zarr group), for inspection."""
        return self.format.dataset

    # -- definition
    def define(self, name, dtype, dims, fill, coordinates="", table=SWEEP, values=None, **storage):
        """Define variable ``name`` with its schema attributes (and ``coordinates``)."""
        attrs = attributes(name, table)
        if coordinates:
            attrs["coordinates"] = coordinates
        self.format.define(name, dtype, dims, attrs, fill, values, **storage)

    def add(self, variables, dimensions=None, attrs=None):
        """Create the ``dimensions`` (``{name: size}``), define each of ``variables`` (:class:`Variable`) with its
        values, and set the global ``attrs``."""
        for name, size in (dimensions or {}).items():
            self.format.dimension(name, size)
        for v in variables:
            self.define(v.name, v.dtype, v.dims, v.fill, v.coordinates, v.table, v.values,
                        **({"compress": True} if v.compress else {}))
        if attrs:
            self.format.set_attrs(attrs)

    def _define(self, attrs):
        fmt, study, dims = self.format, self.study, self.dims
        for dim, n in zip(dims, self.shape):
            fmt.dimension(dim, n)
        fmt.dimension("t", self.nt)
        if study.has_case_dim:
            self.define("case", "i4", ("case",), False, values=np.arange(len(study.cases), dtype=np.int32))
            self.define("case_name", str, ("case",), None, values=np.array([c.name for c in study.cases],
                                                                              dtype=object))
        aux = []
        for name, values in study.sweeps.items():
            fmt.define(name, "f8", (name,), grid_coordinate_attributes(name), values=values)
            if name in PRESSURE_PARAMETERS:          # the values with units (schema.PRESSURE_PARAMETERS)
                fmt.define(f"{name}_value", "f8", (name,), attributes(f"{name}_value"), values=values)
                aux.append(f"{name}_value")
        fmt.define("t", "f8", ("t",), TIME, values=study.times)

        constants, per_case, labels, case_labels = parameter_table(study)
        coords = (["case_name"] if study.has_case_dim else []) + aux
        for name, value in constants.items():
            self.define(name, "f8", (), False, values=value)
            coords.append(name)
        for name, values in per_case.items():
            self.define(name, "f8", ("case",), np.nan, values=values)
            coords.append(name)
        for name, values in case_labels.items():
            self.define(name, str, ("case",), None, values=np.array(values, dtype=object))
            coords.append(name)
        coordinates = " ".join(coords)

        frag = study.fragility
        for output in _outputs(study):
            if output.shape == "threshold" and not fmt.has("threshold"):
                fmt.dimension("threshold", len(frag.thresholds))
                fmt.define("threshold", "f8", ("threshold",), {
                    "units": "rad" if frag.relative_to is None else "1",
                    "long_name": "rotation threshold of p_exceed" + (
                        "" if frag.relative_to is None else f", as a fraction of {frag.relative_to}")},
                    values=np.asarray(frag.thresholds, dtype=float))
            extra = ({"method": frag.method, "relative_to": str(frag.relative_to)} if output.shape == "threshold"
                     else {})
            self._declare(output, coordinates, extra)
        fmt.set_attrs({**attrs, **labels})

    def _declare(self, output, coordinates, extra):
        """Define the grid variable of the declaration ``output`` (:mod:`screening.solvers.outputs`): its
        dimensions, type, fill value, attributes (with ``coordinates`` and ``extra``), compression and
        chunks."""
        dims = self.dims
        if output.shape == "history":
            dims += ("t",)
            storage = {"shuffle": self.format.complevel > 0, "chunks": history_chunks(self.shape, self.nt)}
        elif output.shape == "threshold":
            n = self.format.dimension_size("threshold")
            dims += ("threshold",)
            storage = {"chunks": point_chunks(self.shape, POINT_CHUNK // n) + (n,)}
        else:
            storage = {"chunks": point_chunks(self.shape)}
        attrs = dict(output.attrs)
        if coordinates:
            attrs["coordinates"] = coordinates
        self.format.define(output.name, output.dtype, dims, {**attrs, **extra}, output.fill, compress=True, **storage)

    def grid_coordinates(self):
        """The ``coordinates`` attribute of the grid variables."""
        return self.format.attrs("status").get("coordinates", "")

    # -- data
    def write(self, name, region, values):
        self.format.write(name, region, values)

    def record(self, batch, summary, written=0):
        """Keep what the client keeps of ``batch`` (a worker wrote the rest); ``written``: points with histories
        the client wrote, committed every :data:`SYNC_POINTS` of them (compression overlaps the workers' compute)."""
        for name, values in self.kept.items():
            values[batch.lo:batch.hi] = summary[name]
        self._unsynced += written
        if self._unsynced >= SYNC_POINTS:
            self.format.commit()
            self._unsynced = 0

    def read_summary(self, batch):
        """What the client keeps of ``batch``, as stored (flat arrays)."""
        out = {}
        for name in client_variables():
            parts = [np.asarray(self.format.read(name, _slab_key(slab))).reshape(-1)
                     for slab, _, _ in hyperslabs(batch.lo, batch.hi, self.shape)]
            out[name] = np.concatenate(parts)
        return out

    def history(self, name, index):
        """Stored history of ``name`` at grid index tuple ``index`` (float64)."""
        return np.asarray(self.format.read(name, tuple(index) + (slice(None),)), dtype=np.float64)

    def has(self, name):
        """Whether the result defines variable ``name``."""
        return self.format.has(name)

    def commit(self):
        """Create what was defined since (a zarr store creates its variables here)."""
        self.format.commit()

    def read(self, name, t_index=None):
        """Flat float64 values of per-point variable ``name`` over the grid (a history: at output index
        ``t_index``, or its maximum over time with ``None``)."""
        if "t" not in self.format.dims(name):
            return np.asarray(self.format.read(name), dtype=np.float64).reshape(-1)
        if t_index is not None:
            return np.asarray(self.format.read(name, (Ellipsis, t_index % self.nt)), dtype=np.float64).reshape(-1)
        out = np.full(self.n_points, np.nan)
        step = max(SYNC_POINTS, 1)
        for lo in range(0, self.n_points, step):          # a slab of histories at a time
            for slab, a, b in hyperslabs(lo, min(lo + step, self.n_points), self.shape):
                rows = np.asarray(self.format.read(name, slab + (slice(None),)), dtype=np.float64).reshape(
                    b - a, self.nt)
                finite = np.isfinite(rows).any(axis=1)
                out[a:b][finite] = np.nanmax(rows[finite], axis=1)
        return out

    def read_points(self, names):
        """Several variables at once, as :meth:`read` reads each: ``names`` holds variable names and
        ``(history, t_index)`` pairs; returns ``{name or pair: flat float64 values}``."""
        return {name: self.read(*name) if isinstance(name, tuple) else self.read(name) for name in names}

    def read_all(self, name):
        """The stored values of variable ``name`` (float64, its own shape)."""
        return np.asarray(self.format.read(name), dtype=float)

    def set_attrs(self, **attrs):
        self.format.set_attrs(attrs)

    def close(self, **attrs):
        """Set the global ``attrs`` (if any) and close the result."""
        if attrs:
            self.format.set_attrs(attrs)
        self.format.finish()
