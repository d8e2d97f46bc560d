"""Parameter sweeps on dask.distributed, streamed into one CF-1.8 netCDF file.

:func:`run_sweep` runs a :class:`~screening.workflow.study.Study`:

1. The grid (``case`` x swept parameters) is flattened in C order and cut into batches of
   contiguous points (never across a case; by default about ``500`` points, a whole number
   of rows of the last dimension).  Each batch is **one** dask task calling
   :func:`screening.solvers.moments.solve_moments` on arrays (:func:`solve_batch`); there is no
   finer task graph.
2. A point that fails numerically is flagged by the solver (``status``).  A task that
   raises is retried by dask (``retries=2``); if it keeps failing its points get status
   ``task_failed`` (-1, histories NaN, ``n_steps = 0``) and the run carries on.
3. Results stream to disk batch by batch: each finished batch is saved as a part file in
   ``<out>.partial/`` (the resume record, keyed by :attr:`Study.key`: a hash of the study
   text, the package version and the layout version) and written into its region of a
   netCDF file being built in the same folder.  The client only ever holds one batch of
   histories.  When everything (including the Monte Carlo spot checks) is in, the file is
   renamed atomically to ``out`` and the partial folder removed.  An interrupted run
   re-started with the same command continues from the saved batches; a finished result
   with the same key is reused as is.
4. Spot checks (``[mcs]``): one task per point calling
   :func:`screening.solvers.montecarlo.monte_carlo`; ``"auto"`` picks the status-ok points with the
   highest ``peak_p_uplift``.

Storage: histories are ``float32`` (7 significant digits, half the disk and bandwidth of
``float64``; the solver tolerance is ``1e-7`` anyway), everything else ``float64`` or
integers; zlib level 1 with byte shuffle (``complevel``; compression is the client's main
cost, about 1.3 s per 10,000 points of 401 output times); chunks are ``(1, ..., n_last, nt)``
and each batch is flushed to disk as soon as it is written.  A 10,000-point sweep with
20 s records at 0.05 s is about 55 MB.

File layout (CF-1.8, checked with the IOOS compliance-checker in strict mode):

* dimensions: ``case`` (if the study has cases), one per swept parameter (file order), ``t``,
  and ``spot`` for the spot checks;
* coordinates: the swept values (units, long_name from :mod:`screening.schema`; no
  ``_FillValue``) -- except ``k``, whose values are the auxiliary coordinate ``k_value`` on
  dimension ``k`` (CF reads a coordinate variable in pressure units as a vertical axis);
  ``case`` (index) with ``case_name``; ``t`` [s] (no ``axis = "T"``: CF would then want a
  reference date in the units); fixed parameters as scalar coordinates with units, and
  parameters that differ between cases on ``case`` (NaN where they do not apply);
* data: the six histories on ``(grid..., t)``; per point ``status`` (flag variable),
  ``t_stop``, ``n_steps``, ``n_rejected``, ``peak_var_theta``, ``t_peak_var_theta``,
  ``peak_p_uplift``, ``min_k_eq``, ``theta_ul``; spot checks ``mcs_*`` on ``spot`` with the
  spot coordinates ``spot_<dim>``;
* global attributes: ``Conventions``, ``title``, ``history``, ``source``, the study file's
  path, text and hash, ``screening_version``, the intensity convention.

Workers must be able to import :mod:`screening` (same environment).  Only the client
touches the disk, so workers of a remote cluster need no shared file system.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import fcntl
import json
import logging
import math
import os
import sys
import time
import uuid
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from screening import __version__
from screening.condensation.api import uplift_threshold
from screening.solvers.moments import HISTORY_VARIABLES, solve_moments
from screening.status import PointStatus

STATUS_OK = int(PointStatus.ok)
STATUS_MEANINGS = {int(s): s.name for s in PointStatus if s >= 0}
from screening.schema import PARAMETERS, TIME, VARIABLES
from screening.model import Block
from screening.workflow.progress import Progress
from screening.workflow.study import build_models

#: Status of the points of a batch whose task failed even after the retries.
STATUS_TASK_FAILED = -1
STATUS_CODES = {STATUS_TASK_FAILED: "task_failed", **STATUS_MEANINGS}
#: Status of a Monte Carlo spot check.
SPOT_STATUS = {0: "ok", 1: "task_failed"}

HISTORY_DTYPE = np.float32
SUMMARY_FLOATS = ("t_stop", "peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq", "theta_ul")
SUMMARY_INTS = ("n_steps", "n_rejected")
SPOT_HISTORIES = ("var_theta", "var_theta_dot", "var_theta_se", "var_theta_dot_se")
#: State of a Monte Carlo sample at a spot point (``mcs_sample_state``).
SAMPLE_STATES = {0: "standing", 1: "overturned", 2: "diverged_or_failed"}

DEFAULT_BATCH = 500
SYNC_POINTS = 2000            # points written between flushes of the file (compression overlaps compute)
CONNECT_TIMEOUT = "15s"
TASK_RETRIES = 2
MAX_FAILURE_MESSAGES = 5
COMPLEVEL = 1
TITLE_FALLBACK = "Stochastic-linearization screening"
REFERENCE = ("Nonlinear dynamics of rocking rigid blocks under stochastic base excitation: "
             "a stochastic-linearization approach")
INTENSITY_CONVENTION = "E[xi(t) xi(s)] = 2 pi S0 delta(t - s), S0 two-sided PSD"


class SweepError(Exception):
    """A problem with the run set-up (output location, lock, cluster); one-line message."""


# ============================================================================ pure helpers
@dataclass(frozen=True)
class Batch:
    """Points ``lo <= i < hi`` (flat C-order indices of the grid), all in case ``case``."""

    index: int
    case: int
    lo: int
    hi: int

    @property
    def size(self):
        return self.hi - self.lo


def default_batch_size(study, n_workers, target=DEFAULT_BATCH):
    """Points per batch: about ``target``, at least 2 batches per worker, whole rows if possible."""
    per_case = study.points_per_case
    size = max(1, min(target, math.ceil(study.n_points / max(2 * n_workers, 1)), per_case))
    n_last = study.swept_shape[-1] if study.swept_shape else 1
    if n_last <= size:
        size = (size // n_last) * n_last
    return size


def plan_batches(study, batch_size):
    """Cut the grid into :class:`Batch` es of at most ``batch_size`` points, case by case."""
    if batch_size < 1:
        raise ValueError(f"parameter 'batch_size' must be an integer >= 1 (got {batch_size!r})")
    per_case = study.points_per_case
    batches = []
    for case in range(len(study.cases)):
        for lo in range(0, per_case, batch_size):
            hi = min(lo + batch_size, per_case)
            batches.append(Batch(len(batches), case, case * per_case + lo, case * per_case + hi))
    return batches


def hyperslabs(lo, hi, shape):
    """Split the flat C-order range ``[lo, hi)`` of an array of ``shape`` into hyperslabs.

    Returns a list of ``(slices, a, b)``: ``array[slices]`` holds the flat points
    ``a <= i < b`` in order; the pieces cover ``[lo, hi)`` exactly.
    """
    if not shape:
        return [((), lo, hi)] if hi > lo else []
    inner = int(np.prod(shape[1:], dtype=np.int64))
    i0, r0 = divmod(lo, inner)
    i1, r1 = divmod(hi, inner)
    out = []
    if i0 == i1:
        for sub, a, b in hyperslabs(r0, r1, shape[1:]):
            out.append(((slice(i0, i0 + 1),) + sub, i0 * inner + a, i0 * inner + b))
        return out
    if r0:
        for sub, a, b in hyperslabs(r0, inner, shape[1:]):
            out.append(((slice(i0, i0 + 1),) + sub, i0 * inner + a, i0 * inner + b))
        i0 += 1
    if i1 > i0:
        out.append(((slice(i0, i1),) + tuple(slice(0, n) for n in shape[1:]), i0 * inner, i1 * inner))
    if r1:
        for sub, a, b in hyperslabs(0, r1, shape[1:]):
            out.append(((slice(i1, i1 + 1),) + sub, i1 * inner + a, i1 * inner + b))
    return out


def batch_values(study, batch):
    """Swept parameter values of the points of ``batch`` (dict of 1-d arrays)."""
    per_case = study.points_per_case
    flat = np.arange(batch.lo - batch.case * per_case, batch.hi - batch.case * per_case)
    if not study.swept_dims:
        return {}
    idx = np.unravel_index(flat, study.swept_shape)
    return {name: study.sweeps[name][i] for name, i in zip(study.swept_dims, idx)}


def point_values(study, index):
    """``(case, values)`` at grid index tuple ``index`` (swept values as floats)."""
    case = index[0] if study.has_case_dim else 0
    swept = index[1:] if study.has_case_dim else index
    return case, {name: float(study.sweeps[name][i]) for name, i in zip(study.swept_dims, swept)}


def batch_models(study, batch):
    """``(block, foundation, excitation)`` with array fields for the points of ``batch``."""
    return build_models(study.cases[batch.case], batch_values(study, batch))


def solve_batch(block, foundation, excitation, t_out, rtol, max_steps, condensation="paper"):
    """The dask task: one vectorised :func:`solve_moments` call on a batch of points.

    Returns a dict of 1-d/2-d arrays over the batch: the histories as ``float32`` (points x
    time), the summaries (``float64``/``int32``), ``status`` (``int8``) and ``theta_ul`` [rad].
    """
    res = solve_moments(block, foundation, excitation, t_out, rtol=rtol, max_steps=max_steps,
                        condensation=condensation)
    n = res["status"].size
    out = {name: res[name].reshape(n, -1).astype(HISTORY_DTYPE) for name in HISTORY_VARIABLES}
    out["status"] = res["status"].reshape(n).astype(np.int8)
    for name in SUMMARY_FLOATS[:-1]:
        out[name] = res[name].reshape(n).astype(np.float64)
    for name in SUMMARY_INTS:
        out[name] = res[name].reshape(n).astype(np.int32)
    out["theta_ul"] = np.broadcast_to(uplift_threshold(block, foundation, condensation), res["status"].shape
                                      ).reshape(n).astype(np.float64)
    return out


def failed_result(n, nt):
    """Batch result for ``n`` points whose task failed: status ``task_failed``, NaN values."""
    out = {name: np.full((n, nt), np.nan, dtype=HISTORY_DTYPE) for name in HISTORY_VARIABLES}
    out["status"] = np.full(n, STATUS_TASK_FAILED, dtype=np.int8)
    for name in SUMMARY_FLOATS:
        out[name] = np.full(n, np.nan)
    for name in SUMMARY_INTS:
        out[name] = np.zeros(n, dtype=np.int32)
    return out


def select_spots(study, status, peak_p_uplift):
    """Grid index tuples of the Monte Carlo spot points.

    Explicit points are returned as given; ``"auto"`` takes the ``count`` points with
    ``status == ok`` and the highest ``peak_p_uplift`` (ties: lowest flat index first).
    ``status`` and ``peak_p_uplift`` are flat arrays over the grid.
    """
    spec = study.mcs
    if spec is None:
        return []
    if spec.points != "auto":
        return list(spec.points)
    ok = np.flatnonzero((status == STATUS_OK) & np.isfinite(peak_p_uplift))
    order = ok[np.argsort(-peak_p_uplift[ok], kind="stable")][:spec.count]
    return [tuple(int(i) for i in np.unravel_index(j, study.shape)) for j in order]


def spot_task(block, foundation, excitation, samples, model, t_end, dt, seed, condensation="paper"):
    """The dask task of one spot check: :func:`screening.solvers.montecarlo.monte_carlo` reduced to arrays.

    ``condensation`` applies to ``model="condensed"`` only (the coupled model has none).
    """
    from screening.solvers.montecarlo import monte_carlo

    ds = monte_carlo(block, foundation, excitation, n_samples=samples, model=model, t_end=t_end,
                     dt=dt, seed=seed, condensation=condensation if model == "condensed" else "paper")
    out = {name: np.asarray(ds[name].values, dtype=np.float64) for name in SPOT_HISTORIES}
    n_over, n_div = int(ds["n_overturned"]), int(ds["n_diverged"])
    out.update(n_overturned=np.int32(n_over), n_diverged=np.int32(n_div),
               n_used=np.int32(samples - n_over - n_div),
               peak_abs_theta=np.asarray(ds["peak_abs_theta"].values, dtype=np.float64),
               sample_state=sample_state(ds["overturned"].values, ds["diverged"].values))
    return out


def sample_state(overturned, diverged):
    """Per-sample state code (:data:`SAMPLE_STATES`) from the boolean flags of a Monte Carlo run."""
    state = np.zeros(np.shape(overturned), dtype=np.int8)
    state[np.asarray(overturned, dtype=bool)] = 1
    state[np.asarray(diverged, dtype=bool)] = 2
    return state


def failed_spot(nt, samples):
    out = {name: np.full(nt, np.nan) for name in SPOT_HISTORIES}
    out.update(n_overturned=np.int32(0), n_diverged=np.int32(0), n_used=np.int32(0),
               peak_abs_theta=np.full(samples, np.nan), sample_state=np.full(samples, 2, dtype=np.int8))
    return out


def relative_peak_error(linear, mcs):
    """``(max_t linear - max_t mcs) / max_t mcs`` over the common output grid; NaN if undefined."""
    linear, mcs = np.asarray(linear, dtype=float), np.asarray(mcs, dtype=float)
    if not (np.any(np.isfinite(linear)) and np.any(np.isfinite(mcs))):
        return math.nan
    ref = np.nanmax(mcs)
    return float((np.nanmax(linear) - ref) / ref) if ref > 0 else math.nan


def parameter_table(study):
    """Split the model parameters into constants and per-case values.

    Returns ``(constants, per_case, labels, case_labels)``: ``constants`` maps numeric
    parameter names to floats (same for every case, not swept), ``per_case`` maps the other
    non-swept numeric parameters to arrays over cases (NaN where one does not apply),
    ``labels``/``case_labels`` do the same for ``contact``, ``condensation``, ``excitation`` and
    ``envelope``.
    """
    names = [n for n in PARAMETERS if n not in study.sweeps]
    values = {}
    for name in names:
        col = []
        for case in study.cases:
            if name == "I_cm" and "I_cm" not in case.params:
                p = case.params
                col.append(float(Block(m=p["m"], b=p["b"], h=p["h"]).I_cm))
            else:
                col.append(float(case.params.get(name, math.nan)))
        if not all(math.isnan(v) for v in col):
            values[name] = np.array(col)
    constants = {n: float(v[0]) for n, v in values.items() if np.all(v == v[0])}
    per_case = {n: v for n, v in values.items() if n not in constants}
    labels, case_labels = {}, {}
    for name in ("contact", "condensation", "excitation", "envelope"):
        col = [getattr(c, name) for c in study.cases]
        if len(set(col)) == 1:
            labels[name] = col[0]
        else:
            case_labels[name] = col
    return constants, per_case, labels, case_labels


# ============================================================================ partial store
class PartialStore:
    """``<out>.partial/``: manifest, one ``.npz`` per finished batch / spot, the file being built.

    The manifest records the study key and the batch layout; a folder left by another study
    (or version) is cleared on open.  An exclusive ``flock`` keeps two runs apart.
    """

    MANIFEST = "manifest.json"
    LOCK = "lock"
    BUILDING = "result.nc.building"

    def __init__(self, out):
        self.out = Path(out)
        self.dir = self.out.with_name(self.out.name + ".partial")
        self._lock = None
        self.manifest = None

    # -- life cycle
    def open(self, key, layout, log):
        """Create/lock the folder; returns the manifest (with the batch layout to use)."""
        try:
            self.dir.mkdir(exist_ok=True)
            self._lock = open(self.dir / self.LOCK, "w")
        except OSError as exc:
            raise SweepError(f"cannot use the folder {self.dir} for partial results: "
                             f"{exc.strerror or exc}") from None
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            self._lock = None
            raise SweepError(f"another run is writing {self.out} (lock held on {self.dir})") from None
        old = self._read_manifest()
        if old is not None and old.get("key") == key:
            self.manifest = old
            return old
        if old is not None or self._owned_files():
            log(f"discarding partial results of a different study or version in {self.dir}")
            self._clear()
        self.manifest = {"key": key, "screening_version": __version__, **layout}
        tmp = self.dir / (self.MANIFEST + ".tmp")
        tmp.write_text(json.dumps(self.manifest, indent=1))
        os.replace(tmp, self.dir / self.MANIFEST)
        return self.manifest

    def close(self):
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    def remove(self):
        """Delete the folder (only the files this class writes), after a successful run."""
        self._clear()
        for name in (self.MANIFEST, self.LOCK):
            with contextlib.suppress(FileNotFoundError):
                (self.dir / name).unlink()
        self.close()
        with contextlib.suppress(OSError):
            self.dir.rmdir()

    @property
    def building(self):
        return self.dir / self.BUILDING

    # -- parts
    def batch_path(self, batch):
        return self.dir / f"batch-{batch.index:06d}.npz"

    def spot_path(self, i):
        return self.dir / f"spot-{i:04d}.npz"

    def save_batch(self, batch, result):
        self._save(self.batch_path(batch), result, lo=batch.lo, hi=batch.hi)

    def load_batch(self, batch):
        return self._load(self.batch_path(batch), lo=batch.lo, hi=batch.hi)

    def save_spot(self, i, index, result):
        self._save(self.spot_path(i), result, index=np.asarray(index, dtype=np.int64))

    def load_spot(self, i, index):
        return self._load(self.spot_path(i), index=np.asarray(index, dtype=np.int64))

    # -- internals
    def _save(self, path, result, **check):
        tmp = path.with_name(path.name + ".tmp")
        try:
            with open(tmp, "wb") as fh:
                np.savez(fh, __key__=np.asarray(self.manifest["key"]), **check, **result)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def _load(self, path, **check):
        """Arrays of a part file, or ``None`` if absent, unreadable or not this study's."""
        try:
            with np.load(path, allow_pickle=False) as data:
                if str(data["__key__"]) != self.manifest["key"]:
                    return None
                for name, value in check.items():
                    if not np.array_equal(data[name], value):
                        return None
                return {k: data[k] for k in data.files if k != "__key__" and k not in check}
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):   # BadZipFile: truncated/corrupt part
            return None

    def _read_manifest(self):
        try:
            return json.loads((self.dir / self.MANIFEST).read_text())
        except (OSError, ValueError):
            return None

    def _owned_files(self):
        pats = ("batch-*.npz*", "spot-*.npz*", self.BUILDING + "*", self.MANIFEST + "*")
        return [p for pat in pats for p in self.dir.glob(pat)]

    def _clear(self):
        for p in self._owned_files():
            with contextlib.suppress(FileNotFoundError):
                p.unlink()


# ============================================================================ netCDF writer
#: Swept parameters whose values are stored in an auxiliary coordinate ``<name>_value`` on
#: dimension ``<name>`` instead of a coordinate variable ``<name>``: CF (section 4.3) takes a
#: coordinate variable with pressure units (``k`` is in N m-2) for a vertical coordinate and
#: then wants the dimensions in T, Z, Y, X order (strict cf:1.8 check 2.4).
AUX_GRID_COORDINATES = {"k": "k_value"}


def grid_coordinate(dim):
    """Name of the variable holding the values of grid dimension ``dim``."""
    return AUX_GRID_COORDINATES.get(dim, dim)


def _chunks(shape, nt):
    if not shape:
        return (nt,)
    last = min(shape[-1], max(1, 2**18 // nt))
    return (1,) * (len(shape) - 1) + (last, nt)


def _slab_key(slab):
    return slab if slab else Ellipsis


class ResultFile:
    """Build the CF-1.8 result file of ``study`` at ``path`` (netCDF4/HDF5), batch by batch.

    Keeps the flat ``status`` and ``peak_p_uplift`` of the grid in memory (for the spot
    selection); histories go straight to disk.
    """

    def __init__(self, path, study, attrs, complevel=COMPLEVEL):
        self.path = Path(path)
        self.zlib = {"zlib": complevel > 0, "complevel": max(complevel, 1)}
        self.study = study
        self.shape = study.shape
        self.nt = study.times.size
        self.status = np.full(study.n_points, STATUS_TASK_FAILED, dtype=np.int8)
        self.peak_p_uplift = np.full(study.n_points, np.nan)
        import netCDF4                  # here, not at module level: workers never need it

        self._unsynced = 0
        self.nc = netCDF4.Dataset(self.path, "w", format="NETCDF4")
        self.nc.set_auto_mask(False)
        try:
            self._define(attrs)
        except BaseException:
            self.nc.close()
            raise

    # -- definition
    def _define(self, attrs):
        nc, study = self.nc, self.study
        dims = study.dims
        for dim, n in zip(dims, self.shape):
            nc.createDimension(dim, n)
        nc.createDimension("t", self.nt)
        if study.has_case_dim:
            v = nc.createVariable("case", "i4", ("case",), fill_value=False)
            v.setncatts({"long_name": "case index (names in case_name)", "units": "1"})
            v[:] = np.arange(len(study.cases), dtype=np.int32)
            v = nc.createVariable("case_name", str, ("case",))
            v.long_name = "case name (the [[case]] tables of the study file)"
            v[:] = np.array([c.name for c in study.cases], dtype=object)
        aux = []
        for name, values in study.sweeps.items():
            v = nc.createVariable(grid_coordinate(name), "f8", (name,), fill_value=False)
            v.setncatts(PARAMETERS[name])
            v[:] = values
            if grid_coordinate(name) != name:
                aux.append(grid_coordinate(name))
        v = nc.createVariable("t", "f8", ("t",), fill_value=False)
        # no axis = "T": CF checkers then demand "units since epoch" (metadata.TIME has it)
        v.setncatts({k: val for k, val in TIME.items() if k != "axis"})
        v[:] = study.times

        constants, per_case, labels, case_labels = parameter_table(study)
        coords = (["case_name"] if study.has_case_dim else []) + aux
        for name, value in constants.items():
            v = nc.createVariable(name, "f8", (), fill_value=False)
            v.setncatts(PARAMETERS[name])
            v[...] = value
            coords.append(name)
        for name, values in per_case.items():
            v = nc.createVariable(name, "f8", ("case",), fill_value=np.nan)
            v.setncatts(PARAMETERS[name])
            v[:] = values
            coords.append(name)
        for name, values in case_labels.items():
            v = nc.createVariable(name, str, ("case",))
            v.long_name = f"{name} model of the case"
            v[:] = np.array(values, dtype=object)
            coords.append(name)
        self.coordinates = " ".join(coords)

        grid = dims
        for name in HISTORY_VARIABLES:
            v = nc.createVariable(name, "f4", grid + ("t",), **self.zlib, shuffle=self.zlib["zlib"],
                                  chunksizes=_chunks(self.shape, self.nt), fill_value=HISTORY_DTYPE(np.nan))
            self._attrs(v, VARIABLES[name])
        v = nc.createVariable("status", "i1", grid, **self.zlib, fill_value=False)
        codes = sorted(STATUS_CODES)
        self._attrs(v, {"long_name": "solver status of the point",
                        "flag_values": np.array(codes, dtype=np.int8),
                        "flag_meanings": " ".join(STATUS_CODES[c] for c in codes)})
        for name in SUMMARY_FLOATS:
            v = nc.createVariable(name, "f8", grid, **self.zlib, fill_value=np.nan)
            self._attrs(v, VARIABLES[name])
        for name in SUMMARY_INTS:
            v = nc.createVariable(name, "i4", grid, **self.zlib, fill_value=False)
            self._attrs(v, VARIABLES[name])
        nc.setncatts({**attrs, **labels})

    def _attrs(self, var, attrs):
        var.setncatts(attrs)
        if self.coordinates:
            var.coordinates = self.coordinates

    # -- data
    def write_batch(self, batch, result):
        """Write the arrays of ``batch`` (as returned by :func:`solve_batch`) into their regions."""
        nc = self.nc
        for slab, a, b in hyperslabs(batch.lo, batch.hi, self.shape):
            rows = slice(a - batch.lo, b - batch.lo)
            region = tuple(s.stop - s.start for s in slab)
            for name in HISTORY_VARIABLES:
                nc[name][slab + (slice(None),)] = result[name][rows].reshape(region + (self.nt,))
            for name in ("status",) + SUMMARY_FLOATS + SUMMARY_INTS:
                nc[name][_slab_key(slab)] = result[name][rows].reshape(region)
        self._unsynced += batch.size
        if self._unsynced >= SYNC_POINTS:
            nc.sync()           # compress and write the cached chunks now, while workers compute
            self._unsynced = 0
        self.status[batch.lo:batch.hi] = result["status"]
        self.peak_p_uplift[batch.lo:batch.hi] = result["peak_p_uplift"]

    def history(self, name, index):
        """Stored history of ``name`` at grid index tuple ``index`` (float64)."""
        return np.asarray(self.nc[name][tuple(index) + (slice(None),)], dtype=np.float64)

    def write_spots(self, spots, results, failed, spec):
        """Spot-check variables on dimension ``spot`` (``spots``: grid index tuples)."""
        nc, study = self.nc, self.study
        nc.createDimension("spot", len(spots))
        coords = []
        for axis, dim in enumerate(study.dims):
            idx = np.array([s[axis] for s in spots])
            if dim == "case":
                v = nc.createVariable("spot_case", "i4", ("spot",), fill_value=False)
                v.setncatts({"long_name": "case index of the spot point", "units": "1"})
                v[:] = idx.astype(np.int32)
                v = nc.createVariable("spot_case_name", str, ("spot",))
                v.long_name = "case name of the spot point"
                v[:] = np.array([study.cases[i].name for i in idx], dtype=object)
                coords += ["spot_case", "spot_case_name"]
            else:
                v = nc.createVariable(f"spot_{dim}", "f8", ("spot",), fill_value=False)
                v.setncatts({**PARAMETERS[dim], "long_name": f"{PARAMETERS[dim]['long_name']} at the spot point"})
                v[:] = study.sweeps[dim][idx]
                coords.append(f"spot_{dim}")
        coord_attr = " ".join(coords)

        def var(name, dtype, dims, attrs, values, fill=np.nan):
            v = nc.createVariable(name, dtype, dims, **self.zlib, fill_value=fill)
            v.setncatts(attrs)
            if coord_attr:
                v.coordinates = coord_attr
            v[...] = values

        meta = {
            "var_theta": ("rad2", "Monte Carlo ensemble variance of the rocking rotation"),
            "var_theta_dot": ("rad2 s-2", "Monte Carlo ensemble variance of the rocking angular velocity"),
            "var_theta_se": ("rad2", "standard error of the Monte Carlo rotation variance"),
            "var_theta_dot_se": ("rad2 s-2", "standard error of the Monte Carlo angular-velocity variance"),
        }
        for name, (units, long_name) in meta.items():
            var(f"mcs_{name}", "f8", ("spot", "t"), {"units": units, "long_name": long_name},
                np.stack([r[name] for r in results]))
        for name, long_name in (("n_overturned", "number of overturned Monte Carlo samples"),
                                ("n_diverged", "number of diverged Monte Carlo samples"),
                                ("n_used", "number of Monte Carlo samples in the statistics")):
            var(f"mcs_{name}", "i4", ("spot",), {"units": "1", "long_name": long_name},
                np.array([r[name] for r in results], dtype=np.int32), fill=False)
        for name in ("var_theta", "var_theta_dot"):
            lin = [self.history(name, s) for s in spots]
            mcs_peak = np.array([np.nanmax(r[name]) if np.any(np.isfinite(r[name])) else np.nan
                                 for r in results])
            units = meta[name][0]
            var(f"mcs_peak_{name}", "f8", ("spot",),
                {"units": units, "long_name": f"peak over the output times of mcs_{name}"}, mcs_peak)
            rel = np.array([relative_peak_error(li, r[name]) for li, r in zip(lin, results)])
            var(f"mcs_rel_error_peak_{name}", "f8", ("spot",),
                {"units": "1", "long_name": f"relative error of the linearization's peak {name} against "
                                            "Monte Carlo, (max_t lin - max_t mcs) / max_t mcs on the output times"},
                rel)
        nc.createDimension("sample", spec.samples)
        v = nc.createVariable("sample", "i4", ("sample",), fill_value=False)
        v.setncatts({"long_name": "Monte Carlo sample index (input seeded with default_rng([seed, sample]))",
                     "units": "1"})
        v[:] = np.arange(spec.samples, dtype=np.int32)
        var("mcs_peak_abs_theta", "f8", ("spot", "sample"),
            {"units": "rad", "long_name": "peak |theta| of each Monte Carlo sample over the record (for fragility)"},
            np.stack([r["peak_abs_theta"] for r in results]))
        codes = sorted(SAMPLE_STATES)
        var("mcs_sample_state", "i1", ("spot", "sample"),
            {"long_name": "state of each Monte Carlo sample at the end of the record",
             "flag_values": np.array(codes, dtype=np.int8),
             "flag_meanings": " ".join(SAMPLE_STATES[c] for c in codes)},
            np.stack([r["sample_state"] for r in results]), fill=False)
        codes = sorted(SPOT_STATUS)
        var("mcs_status", "i1", ("spot",),
            {"long_name": "status of the Monte Carlo spot check", "flag_values": np.array(codes, dtype=np.int8),
             "flag_meanings": " ".join(SPOT_STATUS[c] for c in codes)},
            np.array([1 if f else 0 for f in failed], dtype=np.int8), fill=False)
        selection = ("auto: the status-ok points with the highest peak_p_uplift (uplift occupancy, where "
                     "the Gaussian closure is least trustworthy)" if spec.points == "auto"
                     else "explicit points of the study file")
        nc.setncatts({"mcs_model": spec.model, "mcs_samples": np.int32(spec.samples),
                      "mcs_seed": np.int32(spec.seed), "mcs_selection": selection,
                      "mcs_note": "Monte Carlo statistics over samples that neither overturned nor diverged"})

    def set_attrs(self, **attrs):
        self.nc.setncatts(attrs)

    def close(self):
        if self.nc.isopen():
            self.nc.close()


# ============================================================================ run
@dataclass
class SweepReport:
    """What :func:`run_sweep` did: output path, reuse/resume counts, status counts, timings [s]."""

    path: Path
    reused: bool = False
    n_points: int = 0
    n_batches: int = 0
    n_resumed_batches: int = 0
    n_failed_batches: int = 0
    n_spots: int = 0
    status_counts: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    n_workers: int = 0


class ResultError(SweepError):
    """A result file that cannot be read or is not a screening sweep result."""


#: Variables every result file has (checked by :func:`open_result`).
REQUIRED_VARIABLES = HISTORY_VARIABLES + ("status", "peak_var_theta", "peak_p_uplift", "min_k_eq")


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


def result_key(path):
    """The ``study_sha256`` attribute of an existing result file, or ``None``."""
    import netCDF4

    try:
        with netCDF4.Dataset(path) as nc:
            return nc.getncattr("study_sha256") if "study_sha256" in nc.ncattrs() else None
    except (OSError, RuntimeError, ValueError):
        return None


def check_output_path(out):
    """Raise :class:`SweepError` unless ``out`` can be written (its folder must exist)."""
    out = Path(out)
    if out.is_dir():
        raise SweepError(f"output path {out} is a directory")
    if not out.parent.is_dir():
        raise SweepError(f"output folder {out.parent} does not exist")
    if not os.access(out.parent, os.W_OK):
        raise SweepError(f"output folder {out.parent} is not writable")
    return out


def _stderr(msg):
    print(msg, file=sys.stderr, flush=True)


def _warm_up():
    """Import the solver and load its compiled code on a worker; returns the time taken [s]."""
    start = time.perf_counter()
    from screening.model.excitation import WhiteNoise
    from screening.solvers.moments import solve_moments as solve
    from screening.model import Block, Foundation

    solve(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8), WhiteNoise(1e-5), np.array([0.0, 0.1]))
    return time.perf_counter() - start


@contextlib.contextmanager
def dask_client(workers=2, scheduler=None, client=None):
    """A ``distributed.Client``: the given one, one connected to ``scheduler`` (an address
    or a scheduler JSON file), or a new ``LocalCluster`` of ``workers`` single-threaded
    processes (closed on exit)."""
    if client is not None:
        yield client
        return
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            if str(scheduler).endswith(".json") and Path(scheduler).is_file():
                c = Client(scheduler_file=str(scheduler), timeout=CONNECT_TIMEOUT)
            else:
                c = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SweepError(f"cannot connect to the dask scheduler {scheduler}: {exc}") from None
        try:
            try:
                c.wait_for_workers(1, timeout=30)
            except TimeoutError:
                raise SweepError(f"the dask scheduler {scheduler} has no workers") from None
            yield c
        finally:
            c.close()
        return
    try:
        # the scheduler's HTTP server binds 8787 even without a dashboard, and warns on stderr when
        # that port is taken (another run, another cluster): give it a free port on localhost instead
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    except Exception as exc:                          # noqa: BLE001 - dask raises RuntimeError & co
        raise SweepError(f"cannot start a local dask cluster of {workers} worker(s): "
                         f"{type(exc).__name__}: {exc}") from None
    try:
        with Client(cluster) as c:
            yield c
    finally:
        cluster.close()


def run_sweep(study, out, *, workers=2, scheduler=None, client=None, batch_size=None, force=False,
              progress=True, log=None, on_batch=None, complevel=COMPLEVEL):
    """Run ``study`` on dask and write the result file ``out``; returns a :class:`SweepReport`.

    Parameters
    ----------
    study : :class:`screening.workflow.study.Study`.
    out : path of the netCDF result; its folder must exist.
    workers : worker processes of the local cluster (ignored with ``scheduler``/``client``).
    scheduler : address (``tcp://host:port``) or scheduler file of an existing dask cluster.
    client : an existing ``distributed.Client`` to use (not closed).
    batch_size : points per task (default :func:`default_batch_size`; a resumed run keeps the
        layout it started with).
    force : recompute even if ``out`` holds the results of this study.
    progress : show a progress bar on stderr.
    log : callable receiving one-line messages (default: stderr).
    on_batch : callable ``on_batch(batch)`` after each batch is saved (e.g. for monitoring).
    complevel : zlib level of the file, 1 (fastest, default) to 9; 0 stores uncompressed.
    """
    log = log or _stderr
    out = check_output_path(out)
    report = SweepReport(path=out, n_points=study.n_points)
    t_start = time.perf_counter()
    if not force and out.exists() and result_key(out) == study.key:
        log(f"{out} is up to date (same study and screening {__version__}): reusing it")
        report.reused = True
        return report
    if batch_size is not None and (isinstance(batch_size, bool) or int(batch_size) != batch_size
                                   or batch_size < 1):
        raise SweepError(f"batch size must be an integer >= 1 (got {batch_size!r})")
    if client is None and not scheduler and (isinstance(workers, bool) or not isinstance(workers, int)
                                             or workers < 1):
        raise SweepError(f"the number of workers must be an integer >= 1 (got {workers!r})")
    if isinstance(complevel, bool) or complevel not in range(10):
        raise SweepError(f"zlib level must be an integer in 0..9 (got {complevel!r})")

    timings = report.timings
    t0 = time.perf_counter()
    with dask_client(workers, scheduler, client) as c:
        n_workers = len(c.nthreads()) or 1
        if client is None and not scheduler:
            c.wait_for_workers(workers)
            n_workers = workers
        report.n_workers = n_workers
        timings["cluster_start"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        try:
            c.run(_warm_up)
        except Exception as exc:                      # noqa: BLE001 - e.g. screening missing on a worker
            raise SweepError(f"the dask workers cannot run the solver: {exception_line(exc)}") from None
        timings["warm_up"] = time.perf_counter() - t0
        try:
            _SweepRun(c, study, out, progress, log, on_batch, report, complevel).run(
                batch_size or default_batch_size(study, n_workers))
        except (OSError, RuntimeError) as exc:
            if not _is_write_error(exc):
                raise
            raise SweepError(_write_error_message(out, exc)) from None
        t0 = time.perf_counter()
    timings["shutdown"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return report


def exception_line(exc):
    """``Type: message`` of an exception on one line (at most 200 characters of message)."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"


def write_failure_reason(exc):
    """Why a write failed, on one line: the operating system's words when it gave any."""
    return exc.strerror if isinstance(exc, OSError) and exc.strerror else " ".join(str(exc).split())[:200]


#: errno values of a failing file system (full, quota, too large, read-only, permissions, I/O, gone).
_DISK_ERRNOS = frozenset(getattr(errno, name) for name in (
    "ENOSPC", "EDQUOT", "EFBIG", "EACCES", "EPERM", "EROFS", "EIO", "ENOENT", "ENOTDIR", "EISDIR",
    "ENAMETOOLONG", "ESTALE", "EXDEV") if hasattr(errno, name))


def _is_write_error(exc):
    """A failure of the disk (full, read-only, permission): an OS error on a file or with a file-system
    errno (not a network error of dask), or an error of the netCDF/HDF5 library (which reports a failed
    write as ``RuntimeError: NetCDF: ...``)."""
    if isinstance(exc, OSError):
        return exc.filename is not None or exc.errno in _DISK_ERRNOS
    return str(exc).startswith("NetCDF:")


def _write_error_message(out, exc):
    """One line: what could not be written, why, and that the finished batches are kept."""
    partial = PartialStore(out).dir
    where = getattr(exc, "filename", None) or f"the results of {out}"
    reason = write_failure_reason(exc)
    kept = len(list(partial.glob("batch-*.npz"))) if partial.is_dir() else 0
    return (f"cannot write {where}: {reason}; the {kept} finished batch(es) are kept in {partial}: "
            "free some space or fix the permissions, then re-run the same command to resume")


class _SweepRun:
    """One run of a study on a client: partial store, result file being built, task loop."""

    def __init__(self, client, study, out, progress, log, on_batch, report, complevel):
        self.client, self.study, self.out = client, study, Path(out)
        self.progress, self.log, self.on_batch, self.report = progress, log, on_batch, report
        self.complevel = complevel
        self.token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"        # task keys unique per run
        self.store = PartialStore(out)
        self.write_time = 0.0

    def run(self, batch_size):
        study, timings = self.study, self.report.timings
        layout = {"n_points": study.n_points, "shape": list(study.shape), "batch_size": int(batch_size),
                  "study_file": study.source}
        manifest = self.store.open(study.key, layout, self.log)
        try:
            batches = plan_batches(study, manifest["batch_size"])
            self.report.n_batches = len(batches)
            created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
            with contextlib.suppress(FileNotFoundError):
                self.store.building.unlink()
            self.result = ResultFile(self.store.building, study,
                                     _global_attrs(study, created, manifest["batch_size"]), self.complevel)
            try:
                t0 = time.perf_counter()
                self._linearization(batches)
                timings["compute"] = time.perf_counter() - t0
                timings["write"] = self.write_time
                t0 = time.perf_counter()
                if study.mcs is not None:
                    self.report.n_spots = _spot_checks(self.client, study, self.store, self.result,
                                                       self.progress, self.log)
                timings["mcs"] = time.perf_counter() - t0
                t0 = time.perf_counter()
                self._finalize()
                timings["finalize"] = time.perf_counter() - t0
            finally:
                self.result.close()
        finally:
            self.store.close()
        self.store.remove()

    # -- linearization batches
    def _submit(self, batch, suffix=""):
        return self.client.submit(solve_batch, *batch_models(self.study, batch), self.study.times,
                                  self.study.rtol, self.study.max_steps,
                                  self.study.cases[batch.case].condensation, retries=TASK_RETRIES, pure=False,
                                  key=f"solve_batch-{self.token}-{batch.index:06d}{suffix}")

    def _write(self, batch, part, save):
        start = time.perf_counter()
        if save:
            self.store.save_batch(batch, part)
        self.result.write_batch(batch, part)
        self.write_time += time.perf_counter() - start

    def _linearization(self, batches):
        from distributed import as_completed

        done = [b for b in batches if self.store.batch_path(b).exists()]
        done_set = set(done)
        # submit what is missing first, so that workers compute while saved parts are merged
        pending = {self._submit(b): b for b in batches if b not in done_set}
        with Progress(self.study.n_points, label="points", enabled=self.progress) as bar:
            resumed = 0
            for b in done:
                part = self.store.load_batch(b)
                if part is None:                    # unreadable or stale part: compute it again
                    pending[self._submit(b, "-redo")] = b
                    continue
                self._write(b, part, save=False)
                resumed += 1
                bar.update(b.size)
            if resumed:
                self.log(f"resuming: {resumed} of {len(batches)} batches were already done in {self.store.dir}")
            self.report.n_resumed_batches = resumed
            for fut in as_completed(list(pending)):
                b = pending.pop(fut)
                try:
                    part, ok = fut.result(), True
                except Exception as exc:            # noqa: BLE001 - any task failure is recorded
                    self.report.n_failed_batches += 1
                    if self.report.n_failed_batches <= MAX_FAILURE_MESSAGES:
                        self.log(f"warning: batch {b.index} (points {b.lo}..{b.hi - 1}) failed after "
                                 f"{TASK_RETRIES} retries: {exception_line(exc)}; its points get status task_failed"
                                 + ("; further failures are not shown"
                                    if self.report.n_failed_batches == MAX_FAILURE_MESSAGES else ""))
                    part, ok = failed_result(b.size, self.study.times.size), False
                fut.release()
                self._write(b, part, save=ok)
                del part
                bar.update(b.size)
                if self.on_batch is not None:
                    self.on_batch(b)
        codes, counts = np.unique(self.result.status, return_counts=True)
        self.report.status_counts = {STATUS_CODES[int(c)]: int(n) for c, n in zip(codes, counts)}

    # -- the end
    def _finalize(self):
        """Close the file, flush it to disk and move it into place atomically."""
        self.result.set_attrs(n_failed_points=np.int32(np.sum(self.result.status == STATUS_TASK_FAILED)))
        self.result.close()
        with open(self.store.building, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(self.store.building, self.out)


def _spot_checks(client, study, store, result, progress, log):
    """Run (or reload) the Monte Carlo spot checks and write them; returns their number."""
    from distributed import as_completed

    spec = study.mcs
    spots = select_spots(study, result.status, result.peak_p_uplift)
    if not spots:
        log("spot checks: no status-ok point to check")
        result.set_attrs(mcs_note="no spot checks: no status-ok point")
        return 0
    token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"
    results, failed, pending = [None] * len(spots), [False] * len(spots), {}
    for i, index in enumerate(spots):
        results[i] = store.load_spot(i, index)
        if results[i] is None:
            case, values = point_values(study, index)
            fut = client.submit(spot_task, *build_models(study.cases[case], values), spec.samples, spec.model,
                                study.t_end, study.dt, spec.seed, study.cases[case].condensation, key=f"spot_check-{token}-{i:04d}",
                                retries=TASK_RETRIES, pure=False)
            pending[fut] = i
    with Progress(len(spots), label=f"spot checks ({spec.model}, {spec.samples} samples)",
                  enabled=progress and bool(pending)) as bar:
        bar.update(len(spots) - len(pending))
        for fut in as_completed(list(pending)):
            i = pending.pop(fut)
            try:
                results[i] = fut.result()
            except Exception as exc:                  # noqa: BLE001 - recorded as a failed spot check
                log(f"warning: spot check {i} failed: {exception_line(exc)}")
                results[i] = failed_spot(study.times.size, spec.samples)
                failed[i] = True
            else:
                try:                                  # the resume record only: the result is kept
                    store.save_spot(i, spots[i], results[i])
                except OSError as exc:
                    log(f"warning: cannot save the resume record of spot check {i} "
                        f"({write_failure_reason(exc)}); its result is kept, an interrupted run "
                        "would compute it again")
            fut.release()
            bar.update(1)
    result.write_spots(spots, results, failed, spec)
    return len(spots)


def _global_attrs(study, created, batch_size):
    cmd = f"screening run {study.source}"
    return {
        "Conventions": "CF-1.8",
        "title": study.title or TITLE_FALLBACK,
        "summary": study.description or ("Time-varying second-order rocking statistics of a rigid block on a "
                                         "flexible nonlinear foundation by stochastic linearization and "
                                         "Lyapunov moment equations, over a parameter grid"),
        "history": f"{created}: {cmd} (screening {__version__})",
        "source": f"screening {__version__}: stochastic linearization + Lyapunov moment equations "
                  "(screening.solvers.moments.solve_moments)",
        "references": REFERENCE,
        "comment": ("histories (var_theta, var_theta_dot, cov_theta_theta_dot, c_eq, k_eq, p_uplift) are "
                    "stored as float32, everything else as float64/integers; values after a point stopped "
                    "(status != ok) are NaN"),
        "date_created": created,
        "screening_version": __version__,
        "intensity_convention": INTENSITY_CONVENTION,
        "study_name": study.name,
        "study_file": study.source,
        "study_sha256": study.key,
        "study_text": study.text,
        "grid_dims": " ".join(study.dims),
        "rtol": study.rtol,
        "max_steps": np.int32(study.max_steps),
        "t_end": study.t_end,
        "dt": study.dt,
        "batch_size": np.int32(batch_size),
    }
