"""Parameter sweeps on dask.distributed, streamed into one CF-1.8 netCDF file: :func:`run_sweep`.

:func:`run_sweep` runs a :class:`~screening.sweep.study.Study`:

1. The grid is cut into batches (:mod:`screening.sweep.grid`); each batch is **one** dask task
   (:func:`screening.sweep.execution.solve_batch`).
2. A point that fails numerically is flagged by the solver (``status``).  A task that raises is
   retried by dask (``retries=2``); if it keeps failing its points get status
   :attr:`~screening.core.status.PointStatus.task_failed` (histories NaN, ``n_steps = 0``) and the run
   carries on.
3. Results stream to disk batch by batch: each finished batch is saved as a part file in
   ``<out>.partial/`` (the resume record, :class:`~screening.io.store.PartialStore`) and
   written into its region of the netCDF file being built in the same folder
   (:class:`~screening.io.writer.ResultFile`).  The client only ever holds one batch of
   histories.  When everything (including the Monte Carlo spot checks) is in, the file is
   renamed atomically to ``out`` and the partial folder removed.  An interrupted run re-started
   with the same command continues from the saved batches; a finished result with the same key
   is reused as is.
4. Spot checks (``[mcs]``): one task per point calling
   :func:`screening.solvers.montecarlo.monte_carlo`; ``"auto"`` picks the status-ok points with the
   highest ``peak_p_uplift``.

Only the client touches the disk, so workers of a remote cluster need no shared file system --
except for a zarr result (``out`` ending in ``.zarr``): the store is built in ``<out>.partial/`` by
the workers, each writing and compressing the chunks of its own batches in place
(:func:`screening.sweep._submit.solve_and_store_batch`) and marking them done; the client
creates the store's metadata, keeps a few bytes per point, writes the spot checks and moves the
finished store into place.  The store and its markers are the resume record of the batches.
Workers of a remote cluster then need the folder at the same path (a shared file system).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import math
import os
import shutil
import sys
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from screening._version import __version__
from screening.core.status import PointStatus, SpotStatus, Trust
from screening.sweep import _submit, execution
from screening.sweep.execution import SPOT_HISTORIES, SPOT_LINEAR
from screening.sweep.connect import run_on_workers
from screening.sweep.accuracy import Stage, escalate
from screening.io.errors import SweepError, exception_line, is_write_error, write_failure_reason
from screening.sweep.grid import default_batch_size, plan_batches, select_spots, warm_up_excitations
from screening.sweep.interrupt import interruptible, raise_if_interrupted, shielded
from screening.sweep.probabilities import finish_probabilities, probabilities_line
from screening.core.progress import Progress
from screening.io.reader import result_key, verify_result
from screening.io.store import PartialStore
from screening.io.writer import (COMPLEVEL, ResultFile, check_output_path, region_variables, result_attributes,
                                 Variable)
from screening.io._zarr_store import foreign_files, remove_store, write_completion_mark
from screening.io.zarrfile import is_zarr_path, zarr_batch_size

__all__ = ["MAX_FAILURE_MESSAGES", "IN_FLIGHT_PER_WORKER", "SweepReport", "run_sweep", "SampleCount"]

MAX_FAILURE_MESSAGES = 5
#: Outstanding batch tasks per worker (bounds the memory of client and scheduler).
IN_FLIGHT_PER_WORKER = 3


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
    #: points per trust flag of the linearization (:class:`screening.core.status.Trust`)
    trust_counts: dict = field(default_factory=dict)
    #: ``[accuracy]``: what the escalation did (:func:`screening.sweep.accuracy.escalate`)
    accuracy: dict = field(default_factory=dict)
    #: ``[accuracy]`` or ``[fragility]``: points per source of p_overturn / p_exceed
    #: (:func:`screening.sweep.probabilities.finish_probabilities`)
    probabilities: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    n_workers: int = 0


def _stderr(msg):
    print(msg, file=sys.stderr, flush=True)


def run_sweep(study, out, *, workers=2, scheduler=None, client=None, batch_size=None, force=False,
              progress=True, log=None, on_batch=None, complevel=COMPLEVEL):
    """Run ``study`` on dask and write the result file ``out``; returns a :class:`SweepReport`.

    The grid is cut into batches of points, one dask task each: the moment equations of the
    stochastic linearization are solved at every point of a batch and its per-point summaries (and
    histories, as ``[output]`` asks) written into ``out``, all or none.  Then come the optional stages:
    Monte Carlo spot checks (``[mcs]``), the escalation of untrusted points (``[accuracy]``) and the
    probabilities (``[fragility]``).  A result of the same study is reused; an interrupted run resumes
    from its finished batches (kept in ``<out>.partial/``).  Bad arguments raise before any work.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The validated study (:func:`~screening.sweep.study.load_study`).
    out : str or os.PathLike
        Path of the result, a netCDF file or (suffix ``.zarr``) a zarr store written by the workers;
        its folder must exist.
    workers : int or None, optional
        Worker processes of the local cluster (ignored with ``scheduler``/``client``); 0: in this
        process (one worker thread); None: the study's ``[cluster]`` (a dask-jobqueue cluster) if it has
        one, else 0 for a small study and 2 otherwise (:func:`~screening.sweep.execution.default_workers`).
    scheduler : str or os.PathLike, optional
        Address (``tcp://host:port``) or scheduler file of an existing dask cluster.
    client : distributed.Client, optional
        An existing client to use (not closed).
    batch_size : int, optional
        Points per task, in 1..2**31-1 (default :func:`~screening.sweep.grid.default_batch_size`;
        a resumed run keeps the layout it started with).
    force : bool, optional
        Recompute even if ``out`` holds the results of this study.
    progress : bool, optional
        Show a progress bar on stderr.
    log : callable, optional
        Receives one-line messages (default: stderr).
    on_batch : callable, optional
        ``on_batch(batch)`` after each batch is saved (e.g. for monitoring).
    complevel : int, optional
        Compression level, 1 (fastest, default) to 9 (zlib; zstd for zarr); 0 stores uncompressed.

    Returns
    -------
    SweepReport
        What the run did: the output path, whether it was reused, batches resumed and failed,
        points per status and trust flag, the stages' summaries and timings [s].

    Raises
    ------
    SweepError
        A bad argument, an output path that cannot be written, a cluster that cannot be reached or
        cannot run the solver, or a full or read-only disk (the finished batches are kept).

    Notes
    -----
    Each point's response covariance :math:`\\mathbf{C}(t)` of rotation and rotational velocity
    follows the Lyapunov moment equation of the equivalent linear system, eq. (45) in [1] (eq. (51)
    for filtered noise),

    .. math:: \\dot{\\mathbf{C}} = \\mathbf{P}\\mathbf{C} + \\mathbf{C}\\mathbf{P}^\\top
              + \\mathbb{E}[\\mathbf{v}\\mathbf{v}^\\top],

    with :math:`\\mathbf{P}` built from the equivalent stiffness and damping of eqs. (35)-(36) in [1]
    (corrected, ``docs/method.md``), updated from the moments at every step; the result's layout is
    described in [2].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] screening documentation, "What a result holds", ``docs/outputs.md``.

    Examples
    --------
    Arguments are checked before any cluster starts:

    >>> import os, tempfile
    >>> from screening.sweep.study import EXAMPLE_STUDY as text, parse_study
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     try:
    ...         run_sweep(parse_study(text), os.path.join(folder, "bed.nc"), batch_size=0)
    ...     except SweepError as exc:
    ...         print(exc)
    batch size must be an integer in 1..2147483647 (got 0)

    A run (in this process; numba compiles the solvers on the first run)::

        report = run_sweep(parse_study(text), "bed.nc", workers=0, progress=False)
        report.status_counts                      # points per status, e.g. {'ok': 2}
    """
    log = log or _stderr
    out = check_output_path(out, inputs=(study.source,))
    report = SweepReport(path=out, n_points=study.n_points)
    t_start = time.perf_counter()
    if not force and out.exists() and result_key(out) == study.key:
        problem = verify_result(out, study)
        if problem is None:
            log(f"{out} is up to date (same study and screening {__version__}): reusing it")
            report.reused = True
            return report
        log(f"{out} is the result of this study but {problem}: computing it again")
    if batch_size is not None and (isinstance(batch_size, bool) or int(batch_size) != batch_size
                                   or not 1 <= batch_size < 2**31):
        raise SweepError(f"batch size must be an integer in 1..{2**31 - 1} (got {batch_size!r})")
    cluster = None
    if study.cluster is not None and client is None and not scheduler and workers is None:
        cluster = study.cluster                    # the study's [cluster]: a dask-jobqueue cluster
    if cluster is None and client is None and not scheduler and workers is None:
        workers = execution.default_workers(study)
    if cluster is None and client is None and not scheduler and (isinstance(workers, bool)
                                                                 or not isinstance(workers, int) or workers < 0):
        raise SweepError(f"the number of workers must be an integer >= 0 (got {workers!r})")
    if isinstance(complevel, bool) or complevel not in range(10):
        raise SweepError(f"zlib level must be an integer in 0..9 (got {complevel!r})")
    zarr_store = is_zarr_path(out)
    if zarr_store:
        try:
            import zarr  # noqa: F401
        except ImportError:
            raise SweepError(f"{out}: a zarr result needs the zarr package (Python >= 3.11); "
                             "give a .nc path") from None

    timings = report.timings
    t0 = time.perf_counter()
    with shielded(), execution.dask_client(workers, scheduler, client, cluster, log) as c:
        if study.cluster is not None and cluster is None:
            log("the study's [cluster] table is not used: workers, a scheduler or a client are given")
        n_workers = len(c.nthreads()) or 1
        if cluster is not None:                    # the workers it keeps, not those started so far
            n_workers = max(n_workers, cluster.jobs * cluster.cores)
        elif client is None and not scheduler:
            c.wait_for_workers(max(workers, 1))
            n_workers = max(workers, 1)
        report.n_workers = n_workers
        timings["cluster_start"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        run_on_workers(c, execution.warm_up, warm_up_excitations(study))   # a worker that retires is left out
        timings["warm_up"] = time.perf_counter() - t0
        try:
            if batch_size is None and cluster is not None:
                batch_size = cluster.batch_size            # [cluster] batch_size, or None
            if batch_size is None:
                batch_size = default_batch_size(study, n_workers)
                if zarr_store:                   # whole chunks per batch
                    batch_size = zarr_batch_size(study.shape, int(study.has_case_dim), batch_size)
            _SweepRun(c, study, out, progress, log, on_batch, report, complevel, zarr_store).run(batch_size)
        except (OSError, RuntimeError) as exc:
            if not is_write_error(exc):
                raise
            raise SweepError(_write_error_message(out, exc)) from None
        t0 = time.perf_counter()
    timings["shutdown"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return report


def _write_error_message(out, exc):
    """One line: what could not be written, why, and that the finished batches are kept."""
    partial = PartialStore(out).dir
    where = getattr(exc, "filename", None) or f"the results of {out}"
    reason = write_failure_reason(exc)
    kept = len(list(partial.glob("batch-*.npz")) + list(partial.glob("done/batch-*.json"))) if partial.is_dir() else 0
    return (f"cannot write {where}: {reason}; the {kept} finished batch(es) are kept in {partial}: "
            "free some space or fix the permissions, then re-run the same command to resume")


class SampleCount:
    """Samples done per spot check, fed to a progress bar from the client's thread and from worker
    events (the client's event loop thread): each spot only counts up, under one lock."""

    def __init__(self, bar, n_spots):
        self.bar, self.done, self.lock = bar, [0] * n_spots, threading.Lock()

    def set(self, spot, done):
        with self.lock:
            step = max(int(done) - self.done[spot], 0)
            self.done[spot] += step
            if step:
                self.bar.update(step)


class _SweepRun:
    """One run of a study on a client: partial store, result file being built, task loop."""

    def __init__(self, client, study, out, progress, log, on_batch, report, complevel, zarr_store=False):
        self.client, self.study, self.out, self.zarr_store = client, study, Path(out), zarr_store
        self.progress, self.log, self.on_batch, self.report = progress, log, on_batch, report
        self.complevel = complevel
        self.token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"        # task keys unique per run
        self.store = PartialStore(out)
        self.write_time = 0.0
        self.target = None              # zarr: where the workers write (store.RegionTarget)
        self.escalated = None           # [accuracy]: (flat indices, models, runs) of the escalated points
        self.spot_runs = None           # [mcs]: (grid indices, results) of the spot checks
        self.values = None              # [accuracy], [fragility]: the per-point values the stages start from
        self.attrs = {}                 # global attributes set when the result is finished

    def run(self, batch_size):
        study, timings = self.study, self.report.timings
        layout = {"n_points": study.n_points, "shape": list(study.shape), "batch_size": int(batch_size),
                  "study_file": study.source}
        if self.zarr_store:
            layout["format"] = "zarr"
        manifest = self.store.open(study.key, layout, self.log)
        try:
            batches = plan_batches(study, manifest["batch_size"])
            self.report.n_batches = len(batches)
            created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
            attrs = result_attributes(study, created, manifest["batch_size"])
            if self.zarr_store:
                self.result = self._zarr_result(attrs, manifest["batch_size"])
            else:
                with contextlib.suppress(FileNotFoundError):
                    self.store.building.unlink()
                self.result = ResultFile(self.store.building, study, attrs, self.complevel)
            try:
                t0 = time.perf_counter()
                self._linearization(batches)
                timings["compute"] = time.perf_counter() - t0
                timings["write"] = self.write_time
                t0 = time.perf_counter()
                if study.probabilities:
                    self.values = stage_inputs(self.result, study)
                if study.accuracy is not None:
                    self.escalated, self.report.accuracy = escalate(
                        Stage(self.client, study, self.store, self.result, self.log, self.progress, self.values,
                              interim=self._interim if self.target is None else None))
                timings["accuracy"] = time.perf_counter() - t0
                t0 = time.perf_counter()
                if study.mcs is not None:
                    self.report.n_spots = self._spot_checks()
                timings["mcs"] = time.perf_counter() - t0
                if self.values is not None:
                    self.report.probabilities = finish_probabilities(study, self.result, self.values, self.escalated,
                                                                     self.spot_runs, log=self.log)
                    line = probabilities_line(self.report.probabilities)
                    self.attrs["probabilities_note"] = line
                    self.log(line)
                t0 = time.perf_counter()
                self._finalize()                    # closes the result
                timings["finalize"] = time.perf_counter() - t0
            except BaseException:
                self.result.close()
                raise
        except BaseException:
            self.store.close()
            raise
        self.store.remove()                         # closes it

    def _zarr_result(self, attrs, batch_size):
        """The zarr store of the run: the one of an interrupted run with the same manifest, or a new one."""
        study, path = self.study, self.store.zarr_building
        result = None
        if path.is_symlink() or (path.exists() and not path.is_dir()):    # planted in our folder: never followed
            path.unlink()
        if path.is_dir():
            try:
                result = ResultFile(path, study, attrs, self.complevel, zarr_batch_size=batch_size, reopen=True)
                for name in region_variables(study):  # every variable the workers write is there
                    result.format.dims(name)
            except Exception:                       # noqa: BLE001 - damaged metadata: start the store again
                self.log(f"discarding a damaged zarr store in {self.store.dir}")
                result = None
        if result is None:
            self.store.forget_markers()
            shutil.rmtree(path, ignore_errors=True)
            result = ResultFile(path, study, attrs, self.complevel, zarr_batch_size=batch_size)
        self.target = self.store.region_target(study.shape, study.output.stored, region_variables(study))
        blind = [w for w, ok in run_on_workers(self.client, _submit.sees_folder, self.target.store).items() if not ok]
        if blind:
            raise SweepError(f"{len(blind)} dask worker(s) (e.g. {blind[0]}) do not see {self.store.dir}: the workers "
                             "write a zarr result in place, so its folder must be at the same path on every worker "
                             "(a shared file system); give a .nc --out (only the client writes it)")
        return result

    # -- linearization batches
    def _submit(self, batch, suffix=""):
        key = f"solve_batch-{self.token}-{batch.index:06d}{suffix}"
        try:
            return _submit.submit_batch(self.client, self.study, batch, target=self.target, key=key)
        except ValueError as exc:      # its models cannot be built (e.g. S0 from a target PGA at extreme scales)
            return self.client.submit(_submit.refused_batch, str(exc), key=key, pure=False)

    def _is_saved(self, batch):
        if self.target is not None:
            return self.store.marker_path(batch).exists()
        return self.store.batch_path(batch).exists()

    def _load_saved(self, batch):
        """What was saved of ``batch`` (its arrays; for zarr its summary), or ``None`` if it must be redone."""
        if self.target is None:
            return self.store.load_batch(batch, execution.failed_result(
                batch.size, self.study.times.size, self.study.output.stored, self.study.fragility,
                probabilities=self.study.probabilities))
        if not self.store.marker_ok(batch):
            return None
        try:
            return self.result.read_summary(batch)
        except Exception:                           # noqa: BLE001 - a damaged chunk: compute it again
            return None

    def _write(self, batch, part, save):
        """Write (netCDF) or record (zarr: the worker wrote it) a finished batch; ``save``: keep its part."""
        start = time.perf_counter()
        if self.target is not None:
            self.result.record(batch, part)
        else:
            if save:
                self.store.save_batch(batch, part)
            write_batch(self.result, self.study, batch, part)
        self.write_time += time.perf_counter() - start

    def _write_failed(self, batch):
        """A batch whose task failed: NaN values and status ``task_failed`` in its region (not saved)."""
        start = time.perf_counter()
        if self.target is not None:
            self.store.forget_marker(batch)
        write_batch(self.result, self.study, batch, execution.failed_result(
            batch.size, self.study.times.size, self.study.output.stored, self.study.fragility))
        self.write_time += time.perf_counter() - start

    def _linearization(self, batches):
        from distributed import as_completed

        done = [b for b in batches if self._is_saved(b)]
        done_set = set(done)
        # submit what is missing first, so that workers compute while saved parts are merged; at most
        # IN_FLIGHT_PER_WORKER tasks per worker are outstanding, so neither the client nor the
        # scheduler holds the inputs or results of the whole grid
        todo = iter([b for b in batches if b not in done_set])
        window = IN_FLIGHT_PER_WORKER * max(self.report.n_workers, 1)
        pending = {}
        ready = as_completed(loop=self.client.loop)

        def top_up():
            while len(pending) < window:
                b = next(todo, None)
                if b is None:
                    return
                fut = self._submit(b)
                pending[fut] = b
                ready.add(fut)

        top_up()
        with Progress(self.study.n_points, label="points", enabled=self.progress) as bar:
            resumed = 0
            for b in done:
                part = self._load_saved(b)
                if part is None:                    # unreadable or stale part: compute it again
                    if self.target is not None:
                        self.store.forget_marker(b)
                    fut = self._submit(b, "-redo")
                    pending[fut] = b
                    ready.add(fut)
                    continue
                self._write(b, part, save=False)
                resumed += 1
                bar.update(b.size)
            if resumed:
                self.log(f"resuming: {resumed} of {len(batches)} batches were already done in {self.store.dir}")
            self.report.n_resumed_batches = resumed
            for fut in interruptible(ready):
                b = pending.pop(fut)
                try:
                    part = fut.result()
                except Exception as exc:            # noqa: BLE001 - any task failure is recorded
                    self._task_failed(b, exc)
                    part = None
                fut.release()
                top_up()                            # the next task runs while this batch is written
                if part is None:
                    self._write_failed(b)
                else:
                    self._write(b, part, save=True)
                del part
                bar.update(b.size)
                raise_if_interrupted()              # a Ctrl-C swallowed by a GC callback stops here
                if self.on_batch is not None:
                    self.on_batch(b)
        codes, counts = np.unique(self.result.status, return_counts=True)
        self.report.status_counts = {PointStatus(int(c)).name: int(n) for c, n in zip(codes, counts)}
        codes, counts = np.unique(self.result.sl_trust, return_counts=True)
        self.report.trust_counts = {Trust(int(c)).name: int(n) for c, n in zip(codes, counts)}

    def _task_failed(self, b, exc):
        self.report.n_failed_batches += 1
        if self.report.n_failed_batches <= MAX_FAILURE_MESSAGES:
            self.log(f"warning: batch {b.index} (points {b.lo}..{b.hi - 1}) failed after "
                     f"{execution.TASK_RETRIES} retries: {exception_line(exc)}; its points get status "
                     f"{PointStatus.task_failed.name}"
                     + ("; further failures are not shown"
                        if self.report.n_failed_batches == MAX_FAILURE_MESSAGES else ""))

    # -- Monte Carlo spot checks
    def _spot_checks(self):
        """Run (or reload) the Monte Carlo spot checks and write them; returns their number."""
        from distributed import as_completed

        study, store, log = self.study, self.store, self.log
        spec = study.mcs
        spots = select_spots(study, self.result.status, self.result.peak_p_uplift)
        if not spots:
            log("spot checks: no status-ok point to check")
            self.result.set_attrs(mcs_note="no spot checks: no status-ok point")
            return 0
        token = f"{study.key[:8]}-{uuid.uuid4().hex[:8]}"
        topic = f"screening-spot-samples-{token}"
        results, failed, pending = [None] * len(spots), [False] * len(spots), {}
        for i, index in enumerate(spots):
            results[i] = store.load_spot(i, index, _submit.failed_spot(study.times.size, spec.samples))
            if results[i] is None:
                pending[_submit.submit_spot(self.client, study, index, key=f"spot_check-{token}-{i:04d}",
                                              progress=(topic, i))] = i
        with Progress(len(spots) * spec.samples, label=f"spot checks ({len(spots)} x {spec.model}, samples)",
                      enabled=self.progress and bool(pending)) as bar:
            samples = SampleCount(bar, len(spots))
            for i in range(len(spots)):
                if results[i] is not None:
                    samples.set(i, spec.samples)
            self.client.subscribe_topic(topic, lambda event: samples.set(event[1]["spot"], event[1]["done"]))
            try:
                for fut in interruptible(as_completed(list(pending), loop=self.client.loop)):
                    i = pending.pop(fut)
                    try:
                        results[i] = fut.result()
                    except Exception as exc:              # noqa: BLE001 - recorded as a failed spot check
                        log(f"warning: spot check {i} failed: {exception_line(exc)}")
                        results[i] = _submit.failed_spot(study.times.size, spec.samples,
                                                           _submit.spot_linear_names(study))
                        failed[i] = True
                    else:
                        try:                              # the resume record only: the result is kept
                            store.save_spot(i, spots[i], results[i])
                        except OSError as exc:
                            log(f"warning: cannot save the resume record of spot check {i} "
                                f"({write_failure_reason(exc)}); its result is kept, an interrupted run "
                                "would compute it again")
                    fut.release()
                    samples.set(i, spec.samples)
                    raise_if_interrupted()
            finally:
                self.client.unsubscribe_topic(topic)
        write_spots(self.result, study, spots, results, failed, spec)
        self.spot_runs = (spots, results)
        return len(spots)

    # -- interim answers of the [accuracy] stage
    def _interim(self, write):
        """A complete result at ``out`` with the answers so far, while the ``[accuracy]`` stage runs (netCDF only):
        the file being built is copied, ``write(copy)`` adds the escalated points and best estimates (and returns
        them), the probabilities follow (without spot checks, which come later), and the copy replaces ``out``
        atomically.  Its ``interim_result`` attribute says what it is; a later run does not reuse it
        (:func:`~screening.io.reader.verify_result`) but resumes from the partial folder."""
        study = self.study
        self.result.commit()
        tmp = self.store.building.with_name(self.store.building.name + ".interim")   # cleared with the folder
        shutil.copyfile(self.store.building, tmp)
        res = ResultFile(tmp, study, None, self.complevel, reopen=True)
        try:
            for name, values in self.result.kept.items():
                res.kept[name][:] = values
            escalated = write(res)
            finish_probabilities(study, res, self.values, escalated)
            stamp = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
            res.set_attrs(interim_result=f"written at {stamp} while the [accuracy] stage ran, with the "
                                         f"{len(escalated[0])} escalated point(s) done by then (no spot checks); "
                                         "the run replaces it when it ends")
        finally:
            res.close()
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, self.out)

    # -- the end
    def _publish_store(self):
        """Mark the zarr store complete and move it to ``out``; a store already there is replaced only
        if it holds nothing but what screening wrote (else a one-line error, the new store kept)."""
        old = self.store.dir / "replaced.zarr"
        if os.path.lexists(old):
            remove_store(old)
        # every file checked again: the client writes some variables after the batches (spot checks,
        # escalation, probabilities), so a worker's check of a chunk may no longer hold (about 2.4 s per GB)
        write_completion_mark(self.store.zarr_building)
        if os.path.lexists(self.out):
            foreign = foreign_files(self.out) if self.out.is_dir() and not self.out.is_symlink() else [self.out.name]
            if foreign:
                raise SweepError(f"{self.out} holds files screening did not write (e.g. {foreign[0]}); "
                                 f"move them away and re-run the same command (the finished result is kept "
                                 f"in {self.store.dir})")
            os.replace(self.out, old)
        os.replace(self.store.zarr_building, self.out)
        if os.path.lexists(old) and not remove_store(old):
            kept = self.out.with_name(f"{self.out.name}.replaced-{uuid.uuid4().hex[:8]}")
            os.replace(old, kept)
            self.log(f"warning: files written into the replaced {self.out} after it was checked are kept in {kept}")

    def _finalize(self):
        """Close the file, flush it to disk and move it into place atomically (a zarr store: renamed,
        an older store at ``out`` removed after)."""
        raise_if_interrupted()
        self.result.close(**self.attrs,
                          n_failed_points=np.int32(np.sum(self.result.status == PointStatus.task_failed)))
        if self.target is not None:
            self._publish_store()
            return
        with open(self.store.building, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(self.store.building, self.out)


#: Per-point variables the stages after the linearization start from (:func:`stage_inputs`).
STAGE_INPUTS = ("peak_var_theta", "min_k_eq", "slenderness", "theta_ul", "sl_error_low", "sl_error_high",
                "p_overturn", "p_overturn_se")


def stage_inputs(result, study):
    """The per-point values the ``[accuracy]`` stage and the probabilities start from, read from ``result`` in one
    call once the linearization is written, then handed from stage to stage in memory: :data:`STAGE_INPUTS` (flat
    float64), ``p_exceed`` and ``p_exceed_se`` with ``[fragility]`` (points x thresholds), ``var_theta_end`` (the
    last stored ``var_theta``) and ``peak_var_theta_dot`` (the maximum of the stored ``var_theta_dot``), NaN where
    the result does not store the history.  The ``[accuracy]`` stage adds its best estimates (``best_*``)."""
    n, stored = study.n_points, study.output.stored
    values = result.read_points([*STAGE_INPUTS, *(("p_exceed", "p_exceed_se") if study.fragility is not None else ()),
                                 *((("var_theta", -1),) if "var_theta" in stored else ()),
                                 *((("var_theta_dot", None),) if "var_theta_dot" in stored else ())])
    for name in ("p_exceed", "p_exceed_se"):
        if name in values:
            values[name] = values[name].reshape(n, -1)
    values["var_theta_end"] = values.pop(("var_theta", -1), np.full(n, np.nan))
    values["peak_var_theta_dot"] = values.pop(("var_theta_dot", None), np.full(n, np.nan))
    return values


def write_batch(result, study, batch, part):
    """Write the arrays ``part`` of ``batch`` into its region of ``result`` (by the client) and keep its summary."""
    _submit.write_region(result.format, study.shape, study.output.stored, batch, part)
    result.record(batch, part, written=batch.size if study.output.stored else 0)


def write_spots(result, study, spots, results, failed, spec):
    """Write the spot checks into ``result`` on dimension ``spot`` (``spots``: grid index tuples; ``results``:
    the dicts of :func:`~screening.sweep.execution.spot_task`; ``failed``: flags)."""
    coords = []
    for axis, dim in enumerate(study.dims):
        idx = np.array([s[axis] for s in spots])
        if dim == "case":
            coords += [Variable("spot_case", "i4", ("spot",), idx.astype(np.int32), False, compress=False),
                       Variable("spot_case_name", str, ("spot",), np.array([study.cases[i].name for i in idx],
                                                                           dtype=object), None, compress=False)]
        else:
            coords.append(Variable(f"spot_{dim}", "f8", ("spot",), study.sweeps[dim][idx], False, compress=False))
    at = " ".join(c.name for c in coords)
    out = [Variable(f"mcs_{name}", "f8", ("spot", "t"), np.stack([r[name] for r in results]), coordinates=at)
           for name in SPOT_HISTORIES]
    out += [Variable(f"spot_{name}", "f8", ("spot", "t"), np.stack([r[f"sl_{name}"] for r in results]),
                     coordinates=at) for name in study.output.at_spots]          # [output] histories = "spots"
    out += [Variable(f"mcs_{name}", "i4", ("spot",), np.array([r[name] for r in results], dtype=np.int32), False, at)
            for name in ("n_overturned", "n_diverged", "n_used")]
    for name in SPOT_LINEAR:
        lin = [r[f"sl_{name}"] if f"sl_{name}" in r else result.history(name, s) for r, s in zip(results, spots)]
        mcs_peak = np.array([np.nanmax(r[name]) if np.any(np.isfinite(r[name])) else np.nan for r in results])
        out += [Variable(f"mcs_peak_{name}", "f8", ("spot",), mcs_peak, coordinates=at),
                Variable(f"mcs_rel_error_peak_{name}", "f8", ("spot",),
                         np.array([relative_peak_error(li, r[name]) for li, r in zip(lin, results)]), coordinates=at)]
    out += [Variable("sample", "i4", ("sample",), np.arange(spec.samples, dtype=np.int32), False, compress=False),
            Variable("mcs_peak_abs_theta", "f8", ("spot", "sample"), np.stack([r["peak_abs_theta"] for r in results]),
                     coordinates=at),
            Variable("mcs_sample_state", "i1", ("spot", "sample"), np.stack([r["sample_state"] for r in results]),
                     False, at)]
    if any("mcs_model" in r for r in results):        # a failed spot check: the flag value none (-1)
        out.append(Variable("mcs_model", "i1", ("spot",), np.array([r.get("mcs_model", -1) for r in results],
                                                                    dtype=np.int8), False, at))
    out.append(Variable("mcs_status", "i1", ("spot",), np.array(
        [SpotStatus.task_failed if f else SpotStatus.ok for f in failed], dtype=np.int8), False, at))
    selection = ("auto: the status-ok points with the highest peak_p_uplift (uplift occupancy, where "
                 "the Gaussian closure is least trustworthy)" if spec.points == "auto"
                 else "explicit points of the study file")
    result.add(coords + out, {"spot": len(spots), "sample": spec.samples}, {
        "mcs_model": spec.model, "mcs_samples": np.int32(spec.samples), "mcs_seed": np.int32(spec.seed),
        "mcs_selection": selection,
        "mcs_note": "Monte Carlo statistics over samples that neither overturned nor diverged"})


def relative_peak_error(linear, mcs):
    """``(max_t linear - max_t mcs) / max_t mcs`` over the common output grid; NaN if undefined.

    Parameters
    ----------
    linear : array_like
        The linearization's history (e.g. ``var_theta`` [rad2]) on the output times.
    mcs : array_like
        The Monte Carlo history of the same quantity on the same times.

    Returns
    -------
    float
        The relative error of the peak [1]; NaN when either history has no finite value or the
        Monte Carlo peak is not positive.

    Notes
    -----
    .. math:: e = \\frac{\\max_t \\sigma^2_{SL}(t) - \\max_t \\sigma^2_{MC}(t)}{\\max_t \\sigma^2_{MC}(t)}

    (NaN values ignored).

    """
    linear, mcs = np.asarray(linear, dtype=float), np.asarray(mcs, dtype=float)
    if not (np.any(np.isfinite(linear)) and np.any(np.isfinite(mcs))):
        return math.nan
    ref = np.nanmax(mcs)
    return float((np.nanmax(linear) - ref) / ref) if ref > 0 else math.nan
