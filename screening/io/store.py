"""The resume record of a sweep: ``<out>.partial/``, one ``.npz`` part per finished batch or spot check.

The manifest records the study key (:attr:`Study.key`: a hash of the study text, the package version
and the layout version) and the batch layout; an interrupted run re-started with the same command
continues from the saved parts.  Only the client process touches this folder -- except for a zarr
result (``--out result.zarr``): the store is built in this folder by the workers, each of which
marks a batch done (:class:`RegionTarget`) once its region is written, and the store with its
markers is the resume record of the batches.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shutil
import stat
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from screening._version import __version__
from screening.core.atomicfile import create_new as _create, open_nofollow as _open_nofollow
from screening.io._zarr_store import file_check
from screening.io.errors import SweepError

__all__ = []


class PartialStore:
    """``<out>.partial/``: manifest, one ``.npz`` per finished batch / spot, the file being built.

    The manifest records the study key and the batch layout; a folder left by another study
    (or version) is cleared on open.  An exclusive ``flock`` keeps two runs apart.
    """

    MANIFEST = "manifest.json"
    LOCK = "lock"
    BUILDING = "result.nc.building"
    ZARR_BUILDING = "result.zarr.building"
    DONE = "done"                 # markers of the batches written into the zarr store

    def __init__(self, out):
        self.out = Path(out)
        self.dir = self.out.with_name(self.out.name + ".partial")
        #: The netCDF file and the zarr store being built, in the folder.
        self.building, self.zarr_building = self.dir / self.BUILDING, self.dir / self.ZARR_BUILDING
        self._lock = None
        self.manifest = None

    # -- life cycle
    def open(self, key, layout, log):
        """Create/lock the folder; returns the manifest (with the batch layout to use)."""
        try:
            self._make_dir()
            self._lock = os.fdopen(_open_nofollow(self.dir / self.LOCK, os.O_RDWR | os.O_CREAT), "w")
        except OSError as exc:
            raise SweepError(f"cannot use the folder {self.dir} for partial results: "
                             f"{_reason(exc)}") from None
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            self._lock = None
            raise SweepError(f"another run is writing {self.out} (lock held on {self.dir})") from None
        old = self._read_manifest()
        if old is not None and old.get("key") == key:
            if _layout_ok(old, layout):
                self.manifest = old
                return old
            log(f"discarding damaged partial results (manifest) in {self.dir}")
        elif old is not None or self._owned_files():
            log(f"discarding partial results of a different study or version in {self.dir}")
        self._clear()
        self.manifest = {"key": key, "screening_version": __version__, **layout}
        tmp = self.dir / (self.MANIFEST + ".tmp")
        with _create(tmp) as fh:
            fh.write(json.dumps(self.manifest, indent=1).encode())
        os.replace(tmp, self.dir / self.MANIFEST)
        return self.manifest

    def _make_dir(self):
        """Create ``self.dir`` (mode 0700) or accept an existing one only if it is a real directory
        (not a symbolic link) owned by this user: files are created in it."""
        try:
            self.dir.mkdir(mode=0o700)
        except FileExistsError:
            pass
        st = os.lstat(self.dir)
        if stat.S_ISLNK(st.st_mode):
            raise OSError(0, "it is a symbolic link (remove it, or give another --out)")
        if not stat.S_ISDIR(st.st_mode):
            raise OSError(0, "it exists and is not a folder (remove it, or give another --out)")
        if hasattr(os, "geteuid") and st.st_uid != os.geteuid():
            raise OSError(0, f"it is owned by another user (uid {st.st_uid}); remove it, or give another --out")

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

    # -- zarr: the store and its batch markers
    def region_target(self, shape, histories, variables):
        """The :class:`RegionTarget` of the zarr store being built (its marker folder created)."""
        done = self.dir / self.DONE
        _own_folder(done)
        return RegionTarget(str(self.zarr_building.resolve()), str(done.resolve()), self.manifest["key"],
                            tuple(shape), tuple(histories), tuple(variables))

    def marker_path(self, batch):
        return self.dir / self.DONE / f"batch-{batch.index:06d}.json"

    def marker_ok(self, batch):
        """Whether ``batch`` is marked done by a marker of this study whose chunk files are all there
        with the sizes they had when the batch was written."""
        try:
            with os.fdopen(_open_nofollow(self.marker_path(batch), os.O_RDONLY), "rb") as fh:
                marker = json.loads(fh.read(1 << 22))
            if [marker.get(k) for k in ("key", "index", "lo", "hi")] != [self.manifest["key"], batch.index,
                                                                         batch.lo, batch.hi]:
                return False
            files = marker["files"]
            return bool(files) and all(check[0] >= 0 and file_check(self.zarr_building / name) == list(check)
                                       for name, check in files.items())
        except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError, IndexError):
            return False

    def forget_marker(self, batch):
        """Remove the marker of ``batch`` (its region is being written again)."""
        with contextlib.suppress(FileNotFoundError):
            self.marker_path(batch).unlink()

    def forget_markers(self):
        done = self.dir / self.DONE
        if done.is_symlink():
            done.unlink()
        shutil.rmtree(done, ignore_errors=True)

    # -- parts
    def batch_path(self, batch):
        return self.dir / f"batch-{batch.index:06d}.npz"

    def spot_path(self, i):
        return self.dir / f"spot-{i:04d}.npz"

    def save_batch(self, batch, result):
        self._save(self.batch_path(batch), result, lo=batch.lo, hi=batch.hi)

    def load_batch(self, batch, template=None):
        """Arrays of the saved part of ``batch``; ``None`` if absent, unreadable, not this study's or
        (given ``template``, a result of the same batch) not of the same variables, shapes and kinds."""
        return _like(self._load(self.batch_path(batch), lo=batch.lo, hi=batch.hi), template)

    def save_spot(self, i, index, result):
        self._save(self.spot_path(i), result, index=np.asarray(index, dtype=np.int64))

    def load_spot(self, i, index, template=None):
        return _like(self._load(self.spot_path(i), index=np.asarray(index, dtype=np.int64)), template)

    # -- internals
    def _save(self, path, result, **check):
        tmp = path.with_name(path.name + ".tmp")
        try:
            with _create(tmp) as fh:
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
            with os.fdopen(_open_nofollow(self.dir / self.MANIFEST, os.O_RDONLY), "rb") as fh:
                manifest = json.loads(fh.read(1 << 20))
        except (OSError, ValueError, RecursionError):
            return None
        return manifest if isinstance(manifest, dict) else None

    def _owned_files(self):
        pats = ("batch-*.npz*", "spot-*.npz*", self.BUILDING + "*", self.MANIFEST + "*", self.ZARR_BUILDING + "*",
                self.DONE, "replaced.zarr")
        return [p for pat in pats for p in self.dir.glob(pat)]

    def _clear(self):
        for p in self._owned_files():
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
                continue
            with contextlib.suppress(FileNotFoundError):
                p.unlink()


# ----------------------------------------------------------------------------- safe files
def _reason(exc):
    if isinstance(exc, OSError) and exc.errno == 40:            # ELOOP: O_NOFOLLOW met a link
        return "a symbolic link is in the way (remove it)"
    return exc.strerror or str(exc)


def _own_folder(path):
    """Make ``path`` a folder of this run: an existing real folder is kept; a link or anything else
    planted there is removed (never followed) and a new folder (mode 0700) created."""
    with contextlib.suppress(FileNotFoundError):
        st = os.lstat(path)
        if stat.S_ISDIR(st.st_mode):
            return
        os.unlink(path)
    os.mkdir(path, 0o700)


def _layout_ok(manifest, layout):
    """A manifest whose key matches is used only if its layout is sane and the study's."""
    size = manifest.get("batch_size")
    if isinstance(size, bool) or not isinstance(size, int) or not 1 <= size < 2**31:
        return False
    return all(manifest.get(k) == layout[k] for k in ("n_points", "shape", "format") if k in layout)


def _like(part, template):
    """``part`` if it holds exactly the variables of ``template`` with the same shapes and dtype
    kinds, else ``None`` (a damaged or foreign part is computed again)."""
    if part is None or template is None:
        return part
    if set(part) != set(template):
        return None
    for name, ref in template.items():
        value, ref = np.asarray(part[name]), np.asarray(ref)
        if value.shape != ref.shape or value.dtype.kind != ref.dtype.kind:
            return None
    return part


@dataclass(frozen=True)
class RegionTarget:
    """Where a worker writes a batch of a zarr result: the store, the marker folder, the study key,
    the grid ``shape``, the stored ``histories`` and all ``variables`` of a region (sent with each task)."""

    store: str
    done: str
    key: str
    shape: tuple
    histories: tuple
    variables: tuple

    def mark_done(self, batch, files):
        """Mark ``batch`` done once its region is written: a marker holding ``files`` (``{chunk file: [size,
        checksum]}``, :meth:`~screening.io.zarrfile.ZarrFormat.chunk_files`), created atomically (a batch cut
        short has none)."""
        marker = {"key": self.key, "index": batch.index, "lo": batch.lo, "hi": batch.hi, "files": files}
        path = Path(self.done) / f"batch-{batch.index:06d}.json"
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        try:
            with _create(tmp) as fh:
                fh.write(json.dumps(marker).encode())
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
