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

__all__ = []


def temporary_beside(path, suffix=""):
    """A new empty file next to ``path``, to write ``path`` into.

    Its name is hidden and random (``.<name>.<random>.tmp<suffix>``), made by
    :func:`tempfile.mkstemp` with ``O_EXCL`` in ``path``'s folder, so no one can have planted a link
    at it; ``suffix`` serves writers that read the format from the name (``".nc"``, ``".png"``).
    The file is created and closed; :func:`publish` renames it over ``path``.

    Parameters
    ----------
    path : str or path-like
        The file to be written [-]; its folder must exist.
    suffix : str, default ""
        Appended after ``.tmp`` [-].

    Returns
    -------
    pathlib.Path
        The new empty file, in ``path``'s folder.

    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suffix}", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def publish(tmp, path):
    """Give the written ``tmp`` the permissions of a new file (umask) and rename it to ``path``.

    :func:`tempfile.mkstemp` makes files readable by their owner only; a published file gets the
    mode ``0o666 & ~umask`` an ordinary ``open`` would give it.  The rename (``os.replace``) is
    atomic on one file system: a reader sees the old file or the new one, never a part, and a link
    at ``path`` is replaced, not followed.

    Parameters
    ----------
    tmp : str or path-like
        The written file [-], in ``path``'s folder (:func:`temporary_beside`).
    path : str or path-like
        Its final name [-].

    Returns
    -------
    None

    """
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o666 & ~mask)
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path`` to write; renamed to ``path`` if the block succeeds,
    removed if it raises.

    For writers that open the file themselves (netCDF, PNG): the block writes the yielded path,
    and ``path`` then holds the whole new content, or (on any exception, Ctrl-C included) what it
    held before.

    Parameters
    ----------
    path : str or path-like
        The file to write [-]; its folder must exist.

    Yields
    ------
    pathlib.Path
        The temporary file to write (:func:`temporary_beside`), published by :func:`publish`.

    """
    tmp = temporary_beside(path)
    try:
        yield tmp
        publish(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def atomic_open(path, mode="w", **kwargs):
    """``open(path, mode, **kwargs)`` for writing, atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path-like
        The file to write [-].
    mode : str, default "w"
        A writing mode of :func:`open` (``"w"``, ``"wb"``) [-].
    **kwargs
        Passed to :func:`open` (``encoding``, ``newline``).

    Yields
    ------
    file object
        The open temporary file; ``path`` gets its content when the block ends without an exception.

    """
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def open_nofollow(path, flags, mode=0o600):
    """``os.open`` that never follows a symbolic link at ``path`` and only accepts a regular file
    (a FIFO or device planted there is refused, without blocking).

    Parameters
    ----------
    path : str or path-like
        The file to open [-].
    flags : int
        ``os.O_*`` flags [-]; ``O_NOFOLLOW``, ``O_CLOEXEC`` and ``O_NONBLOCK`` are added (the
        descriptor is set blocking again once the file is known to be regular).
    mode : int, default 0o600
        The permissions of a file it creates [-] (before the umask).

    Returns
    -------
    int
        An open file descriptor (the caller closes it).

    Raises
    ------
    OSError
        ``path`` is a symbolic link (``ELOOP``), missing, or not a regular file.

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
    """A new file at ``path`` for writing (whatever was there, link or file, is removed first, the
    new one created with ``O_EXCL``): a planted link cannot redirect the write.

    Parameters
    ----------
    path : str or path-like
        The file to create [-]; created with mode ``0o600`` (before the umask).

    Returns
    -------
    io.BufferedWriter
        The new file, open for writing bytes.

    """
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    return os.fdopen(open_nofollow(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL), "wb")
