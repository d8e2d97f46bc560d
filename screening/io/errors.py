"""The errors of a sweep and their one-line messages (shared by the workflow and the command line)."""

from __future__ import annotations

import errno
import os

__all__ = []


class SweepError(Exception):
    """A problem with the run set-up (output location, lock, cluster); one-line message."""


def exception_line(exc):
    """``Type: message`` of an exception on one line (at most 200 characters of message).

    Runs of white space (new lines of a traceback-like message) become one space, so that a failed
    point or batch is reported on one line of the log and in a result's string attributes.

    Parameters
    ----------
    exc : BaseException
        The exception to describe.

    Returns
    -------
    str
        ``"<type name>: <message>"``, the message cut to 200 characters.

    """
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"


class ReadFailure(Exception):
    """A value of a result could not be read while converting it (a damaged chunk, an I/O error):
    the message is the reason; the command names the result, not the file it was writing."""


def read_values(read):
    """``read()`` (a value of a result being converted); its failure as :class:`ReadFailure`.

    Converting a result (``screening export``) reads it chunk by chunk; an I/O error, a netCDF
    ``RuntimeError`` or a codec's ``ValueError`` on a damaged chunk becomes a :class:`ReadFailure`
    whose message is the reason, so that the command names the result it was reading.

    Parameters
    ----------
    read : callable
        Called with no argument; returns the value read.

    Returns
    -------
    object
        What ``read()`` returned.

    Raises
    ------
    ReadFailure
        When ``read()`` raised ``OSError``, ``RuntimeError`` or ``ValueError``.

    """
    try:
        return read()
    except (OSError, RuntimeError, ValueError) as exc:      # netCDF: RuntimeError; codecs: ValueError & co
        raise ReadFailure(write_failure_reason(exc)) from exc


#: Free space [bytes] below which a netCDF/HDF5 write failure is reported as a full disk.
LOW_SPACE_BYTES = 64 * 2**20


def write_failure_reason(exc, path=None):
    """Why a write failed, on one line: the operating system's words when it gave any.

    The netCDF/HDF5 library reports a full disk as ``NetCDF: HDF error``; with the ``path`` written,
    the free space of its file system is looked up and named (a full disk said as such: less than
    :data:`LOW_SPACE_BYTES` free).

    Parameters
    ----------
    exc : BaseException
        The exception the write raised.
    path : str or os.PathLike, optional
        The file being written; its file system's free space [bytes] explains a ``NetCDF:`` error.

    Returns
    -------
    str
        The reason: the ``strerror`` of an ``OSError``, else the message (at most 200 characters),
        completed with the free space for a netCDF error when ``path`` is given.

    """
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    text = " ".join(str(exc).split())[:200]
    if path is not None and text.startswith("NetCDF:"):
        import shutil

        try:
            free = shutil.disk_usage(os.path.dirname(os.path.abspath(os.fspath(path))) or ".").free
        except OSError:
            return text
        if free < LOW_SPACE_BYTES:
            return f"no space left on the device ({free / 2**20:.1f} MiB free; the netCDF library said: {text})"
        return f"{text} (the netCDF library gives no reason; {free / 2**30:.1f} GiB free on the device)"
    return text


#: errno values of a failing file system (full, quota, too large, read-only, permissions, I/O, gone).
_DISK_ERRNOS = frozenset(getattr(errno, name) for name in (
    "ENOSPC", "EDQUOT", "EFBIG", "EACCES", "EPERM", "EROFS", "EIO", "ENOENT", "ENOTDIR", "EISDIR",
    "ENAMETOOLONG", "ESTALE", "EXDEV") if hasattr(errno, name))


def is_write_error(exc):
    """A failure of the disk (full, read-only, permission): an OS error on a file or with a file-system
    errno (not a network error of dask), or an error of the netCDF/HDF5 library (which reports a failed
    write as ``RuntimeError: NetCDF: ...``).

    Parameters
    ----------
    exc : BaseException
        The exception a write raised.

    Returns
    -------
    bool
        True for a failure of the disk (the sweep stops with the reason), False otherwise (a failed
        task, retried or reported per batch).

    """
    if isinstance(exc, OSError):
        return exc.filename is not None or exc.errno in _DISK_ERRNOS
    return str(exc).startswith("NetCDF:")
