"""Writing a file all or nothing, never through a planted link: the one helper every writer uses.

The content goes to a new file made by :func:`tempfile.mkstemp` (``O_EXCL``) in the target's folder,
which gets the umask's permissions and is renamed over the target: a link at the target is replaced
(not followed), and a failing write leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path

__all__ = []


def temporary_beside(path, suffix=""):
    """A new empty file ``.<name>.<random>.tmp<suffix>`` in ``path``'s folder, to write ``path`` into.

    Notes
    -----
    Made by :func:`tempfile.mkstemp` with ``O_EXCL``, so no one can have planted a link at it; ``suffix``
    serves writers that read the format from the name (``".nc"``); :func:`publish` renames it over ``path``.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suffix}", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def publish(tmp, path):
    """Give the written ``tmp`` the mode ``0o666 & ~umask`` and rename it (``os.replace``, atomic) to ``path``.

    Notes
    -----
    A reader sees the old file or the new one, never a part, and a link at ``path`` is replaced, not followed.
    """
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o666 & ~mask)
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``: renamed to ``path`` if the block succeeds, removed if it raises (Ctrl-C included)."""
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
    """``os.open`` (``O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK`` added) that accepts only a regular file; returns the descriptor.

    Notes
    -----
    Raises ``OSError`` where ``path`` is a symbolic link (``ELOOP``), missing, or not a regular file (a FIFO
    is refused without blocking); the descriptor is set blocking again once the file is known to be regular.
    """
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
    """A new file at ``path`` open for writing bytes (mode ``0o600`` before the umask), whatever was there removed first."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    return os.fdopen(open_nofollow(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL), "wb")
