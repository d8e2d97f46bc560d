"""The errors of a sweep and their one-line messages (shared by the workflow and the command line)."""

from __future__ import annotations

import errno


class SweepError(Exception):
    """A problem with the run set-up (output location, lock, cluster); one-line message."""


def exception_line(exc):
    """``Type: message`` of an exception on one line (at most 200 characters of message)."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"


class ReadFailure(Exception):
    """A value of a result could not be read while converting it (a damaged chunk, an I/O error):
    the message is the reason; the command names the result, not the file it was writing."""


def read_values(read):
    """``read()`` (a value of a result being converted); its failure as :class:`ReadFailure`."""
    try:
        return read()
    except (OSError, RuntimeError, ValueError) as exc:      # netCDF: RuntimeError; codecs: ValueError & co
        raise ReadFailure(write_failure_reason(exc)) from exc


def write_failure_reason(exc):
    """Why a write failed, on one line: the operating system's words when it gave any."""
    return exc.strerror if isinstance(exc, OSError) and exc.strerror else " ".join(str(exc).split())[:200]


#: errno values of a failing file system (full, quota, too large, read-only, permissions, I/O, gone).
_DISK_ERRNOS = frozenset(getattr(errno, name) for name in (
    "ENOSPC", "EDQUOT", "EFBIG", "EACCES", "EPERM", "EROFS", "EIO", "ENOENT", "ENOTDIR", "EISDIR",
    "ENAMETOOLONG", "ESTALE", "EXDEV") if hasattr(errno, name))


def is_write_error(exc):
    """A failure of the disk (full, read-only, permission): an OS error on a file or with a file-system
    errno (not a network error of dask), or an error of the netCDF/HDF5 library (which reports a failed
    write as ``RuntimeError: NetCDF: ...``)."""
    if isinstance(exc, OSError):
        return exc.filename is not None or exc.errno in _DISK_ERRNOS
    return str(exc).startswith("NetCDF:")
