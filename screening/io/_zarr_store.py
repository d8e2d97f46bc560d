"""The files of a zarr result (package-internal; used by :mod:`screening.io.zarrfile`, the sweep, the resume
record, the writer, the reader and the CDO export): each file's size and checksum, the completion mark a finished
store carries, what in a folder screening did not write, the removal of a finished store, the store's global
attributes, and attributes as netCDF can store them.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat
from pathlib import Path

import numpy as np

from screening.core.atomicfile import create_new
from screening.io.errors import SweepError

#: The completion mark of a finished store (:func:`write_completion_mark`), in its top folder.
COMPLETION_MARK = "screening-complete.json"


# ----------------------------------------------------------------------------- integrity
def file_check(path):
    """``[size [bytes], checksum]`` of the regular file ``path`` (read without following a link), or
    ``[-1, ""]`` if it is missing, a link or not a regular file."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except OSError:
        return [-1, ""]
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return [-1, ""]
        digest, size = hashlib.blake2b(digest_size=16), 0
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
            size += len(block)
    return [size, digest.hexdigest()]


def _store_entries(root):
    """``(files, foreign)`` of the folder ``root``: the relative paths (``/``-separated) of its regular
    files other than the completion mark, and those of its entries that are neither a regular file
    nor a folder (links, FIFOs...)."""
    files, foreign = [], []
    root = Path(root)
    for folder, dirs, names in os.walk(root):
        rel = Path(folder).relative_to(root)
        for name in list(dirs):
            if os.path.islink(os.path.join(folder, name)):
                foreign.append((rel / name).as_posix())
                dirs.remove(name)
        for name in names:
            st = os.lstat(os.path.join(folder, name))
            path = (rel / name).as_posix()
            if not stat.S_ISREG(st.st_mode):
                foreign.append(path)
            elif path != COMPLETION_MARK:
                files.append(path)
    return sorted(files), foreign


def write_completion_mark(root):
    """Write the completion mark of the finished store ``root``: ``{"files": {path: [size, checksum]}}``
    of every file of the store.  Written last, atomically: a store without it was never finished."""
    files, foreign = _store_entries(root)
    if foreign:
        raise OSError(0, f"the zarr store {root} holds {foreign[0]}, which is not a regular file")
    checks = {path: file_check(Path(root) / path) for path in files}
    mark = Path(root) / COMPLETION_MARK
    tmp = mark.with_name(mark.name + ".tmp")
    with create_new(tmp) as fh:
        fh.write(json.dumps({"format": 1, "files": checks}).encode())
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, mark)


def read_completion_mark(root):
    """The files ``{path: [size, checksum]}`` of the completion mark of ``root``, or ``None`` if it has
    none (or an unreadable one)."""
    try:
        fd = os.open(Path(root) / COMPLETION_MARK, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
        with os.fdopen(fd, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                return None
            mark = json.loads(fh.read(1 << 28))
        files = mark["files"]
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        return None
    ok = isinstance(files, dict) and all(isinstance(v, list) and len(v) == 2 for v in files.values())
    return files if ok else None


def foreign_files(root):
    """Entries of the folder ``root`` that screening did not write as a finished store (all of them
    if it has no completion mark); ``[]`` when it may be replaced."""
    files, foreign = _store_entries(root)
    mark = read_completion_mark(root)
    if mark is None:
        return foreign + files or [COMPLETION_MARK + " (missing)"]
    return foreign + [f for f in files if f not in mark]


def remove_store(root):
    """Delete the files of the finished store ``root`` its completion mark lists, the mark, and the
    folders left empty; anything else stays.  Returns whether ``root`` is gone."""
    for path in read_completion_mark(root) or {}:
        with contextlib.suppress(OSError, ValueError):
            os.unlink(Path(root) / path)
    with contextlib.suppress(OSError):
        os.unlink(Path(root) / COMPLETION_MARK)
    for folder, _, _ in sorted(os.walk(root), key=lambda entry: -len(entry[0])):
        with contextlib.suppress(OSError):
            os.rmdir(folder)
    return not os.path.lexists(root)


@contextlib.contextmanager
def warnings_ignored():
    """zarr warns that consolidated metadata is not in the format 3 specification (yet): it is read by
    xarray and zarr-python, and optional for other readers."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def read_attrs(path):
    """The global attributes of the store at ``path`` (a dict; empty if it has none)."""
    import zarr

    with warnings_ignored():
        return dict(zarr.open_group(path, mode="r").attrs)


def netcdf_attributes(attrs, dtype=None, where="the result"):
    """``attrs`` as netCDF can store them: lists as arrays, ``None`` dropped, JSON objects and lists
    netCDF cannot type (nested, mixed) as JSON text; ``flag_values`` in ``dtype`` (a
    :class:`~screening.io.errors.SweepError` naming ``where`` if they are not a flat list of
    numbers)."""
    out = {}
    for name, value in attrs.items():
        if value is None:
            continue
        if isinstance(value, (bool, np.bool_)):
            value = int(value)
        if name == "flag_values" and dtype is not None:
            try:
                flags = np.asarray(value, dtype=dtype)
                if flags.ndim > 1:
                    raise ValueError
            except (TypeError, ValueError, OverflowError):
                raise SweepError(f"the flag_values of {where} are not a flat list of numbers of its type "
                                 f"({dtype}); cannot export it") from None
            out[name] = flags
        elif isinstance(value, (dict, list, tuple)):
            array = None
            with contextlib.suppress(TypeError, ValueError, OverflowError):
                array = np.asarray(value)
            ok = array is not None and array.ndim == 1 and array.size and (
                array.dtype.kind in "iuf" or array.dtype.kind == "U" and all(isinstance(v, str) for v in value))
            out[name] = array if ok else json.dumps(value, ensure_ascii=False, default=str)
        else:
            out[name] = value
    return out
