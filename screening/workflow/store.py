"""The resume record of a sweep: ``<out>.partial/``, one ``.npz`` part per finished batch or spot check.

The manifest records the study key (:attr:`Study.key`: a hash of the study text, the package version
and the layout version) and the batch layout; an interrupted run re-started with the same command
continues from the saved parts.  Only the client process touches this folder.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from screening import __version__
from screening.workflow.errors import SweepError


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
