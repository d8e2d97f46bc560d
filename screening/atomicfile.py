"""Writing a file all or nothing, never through a planted link: the one helper every writer uses.

The content goes to a new file made by :func:`tempfile.mkstemp` in the target's folder (a name no
one can have planted a link at; created with ``O_EXCL``), which gets the usual permissions (the
umask) and is renamed over the target: the target is replaced whole, a link at the target is
replaced (not followed), and a failing write leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path

__all__ = ["temporary_beside", "publish", "atomic_path", "atomic_open", "open_nofollow", "create_new"]


def temporary_beside(path, suffix=""):
    """A new empty file next to ``path`` (its name hidden and random, ending in ``.tmp`` and ``suffix``:
    for writers that read the format from the name) to write ``path`` into."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suffix}", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def publish(tmp, path):
    """Give the written ``tmp`` the permissions of a new file (umask) and rename it to ``path``."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o666 & ~mask)
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path`` to write; renamed to ``path`` if the block succeeds,
    removed if it raises."""
    tmp = temporary_beside(path)
    try:
        yield tmp
        publish(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def atomic_open(path, mode="w", **kwargs):
    """``open(path, mode, **kwargs)`` for writing, atomically (:func:`atomic_path`)."""
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def open_nofollow(path, flags, mode=0o600):
    """``os.open`` that never follows a symbolic link at ``path`` and only accepts a regular file
    (a FIFO or device planted there is refused, without blocking)."""
    fd = os.open(path, flags | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK, mode)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(0, f"{path} is not a regular file")
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd


def create_new(path):
    """A new file at ``path`` for writing (whatever was there, link or file, is removed first, the
    new one created with ``O_EXCL``): a planted link cannot redirect the write."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    return os.fdopen(open_nofollow(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL), "wb")
