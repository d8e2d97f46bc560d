"""Input checks shared by the model objects and the file readers: one clear ``ValueError`` per bad
parameter or input file."""

from __future__ import annotations

import errno
import numbers
import os
import stat

import numpy as np
import xarray as xr

__all__ = []


#: numpy dtype kinds that are not real numbers although ``float()`` accepts some of them: booleans,
#: dates, durations, strings, bytes, complex and structured values.
NOT_NUMBERS = "bMmUSVc"


def _shown(value):
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def as_checked_array(name, value, *, lower=None, lower_inclusive=False, upper=None,
                     upper_inclusive=False, range_text=None):
    """``value`` as a float array (0-d for a scalar, unit unchanged) after checking it is finite and in range.

    Parameters
    ----------
    name : str
        The parameter's name as the user wrote it; it opens the message.
    value : float or array_like
        The value [its SI unit]; booleans, strings, bytes, dates, durations and complex values are refused.
    lower, upper : float, optional
        The bounds [unit of ``value``]; None: unbounded.
    lower_inclusive, upper_inclusive : bool, default False
        Whether a bound itself is allowed.
    range_text : str, optional
        The allowed range in words (default from the bounds, e.g. ``"a finite number > 0"``).

    Returns
    -------
    numpy.ndarray
        ``value``; ``ValueError`` ``"parameter '<name>' must be <range> (got <value>)"`` for the first bad
        element or an empty array.
    """
    if range_text is None:
        parts = []
        if lower is not None:
            parts.append(f"{'>=' if lower_inclusive else '>'} {lower:g}")
        if upper is not None:
            parts.append(f"{'<=' if upper_inclusive else '<'} {upper:g}")
        range_text = "a finite number" + (" " + " and ".join(parts) if parts else "")
    if isinstance(value, (str, bytes, bool, np.bool_)) or np.asarray(value).dtype.kind in NOT_NUMBERS:
        raise ValueError(f"parameter '{name}' must be {range_text} (got {_shown(value)})")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"parameter '{name}' must be {range_text} (got {_shown(value)})") from None
    if arr.size == 0:
        raise ValueError(f"parameter '{name}' must be {range_text} (got an empty array)")
    bad = ~np.isfinite(arr)
    if lower is not None:
        bad |= (arr < lower) if lower_inclusive else (arr <= lower)
    if upper is not None:
        bad |= (arr > upper) if upper_inclusive else (arr >= upper)
    if np.any(bad):
        shown = float(arr[bad].flat[0]) if arr.ndim else float(arr)
        raise ValueError(f"parameter '{name}' must be {range_text} (got {shown!r})")
    return arr


def check_scalar(name, value, **bounds):
    """A finite scalar in the range of ``bounds`` (of :func:`as_checked_array`) as a float; arrays, booleans, dates and strings are refused with one line naming ``name``."""
    arr = as_checked_array(name, value, **bounds)
    if arr.ndim != 0:
        raise ValueError(f"parameter '{name}' must be a single number (got an array of shape {arr.shape})")
    return float(arr)


def check_integer(name, value, lower, upper=None):
    """An integer (no float, no boolean) ``>= lower`` (and ``<= upper``) as an ``int``, or one ``ValueError`` line naming ``name``."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))
    if not ok or value < lower or (upper is not None and value > upper):
        rng = f">= {lower}" if upper is None else f"in {lower}..{upper}"
        raise ValueError(f"parameter '{name}' must be an integer {rng} (got {_shown(value)})")
    return int(value)


def check_size(name, size, limit, what):
    """``ValueError`` naming the parameter ``name`` that sets ``size`` (elements about to be allocated, ``what`` in words) where it exceeds ``limit`` or is NaN."""
    if not size <= limit:
        raise ValueError(f"parameter '{name}' asks for {size:.3g} {what}; at most {limit:.3g} (a bound on the "
                         f"memory of one call)")


def checked(name, value, **kwargs):
    """Like :func:`as_checked_array`, but a float for a scalar and a float64 DataArray (dims, coordinates kept) for a DataArray."""
    if isinstance(value, xr.DataArray):
        as_checked_array(name, value.values, **kwargs)
        return value if value.dtype == np.float64 else value.astype(np.float64)
    arr = as_checked_array(name, value, **kwargs)
    if arr.ndim == 0 and (isinstance(value, numbers.Number) or np.ndim(value) == 0):
        return float(arr)
    return arr


# ----------------------------------------------------------------------------- input files
class InputFileError(ValueError):
    """An input file that cannot be read: ``"<what> <path> <problem>"``; ``problem`` alone as attribute."""

    def __init__(self, what, path, problem):
        super().__init__(f"{what} {path} {problem}")
        self.path, self.problem = path, problem


def file_problem(path):
    """Why ``path`` cannot be read as an input file (``"does not exist"``, ``"is a folder, not a file"``, ...), or None for a regular file.

    Notes
    -----
    Tells a missing file from a folder, a FIFO, a device, a socket, a broken link and a link loop.
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "is a broken symbolic link" if os.path.islink(path) else "does not exist"
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop"
        return _cannot(exc)
    return _mode_problem(mode)


def _cannot(exc):
    return f"cannot be read ({exc.strerror or exc.__class__.__name__})"


def _mode_problem(mode):
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "is a folder, not a file"
    if stat.S_ISFIFO(mode):
        return "is a FIFO (named pipe), not a file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "is a device, not a file"
    if stat.S_ISSOCK(mode):
        return "is a socket, not a file"
    return "is not a regular file"


def input_path(path, what="file"):
    """``path`` as ``str`` (bytes decoded by the file-system encoding); ``ValueError`` naming ``what`` for a non-path or a NUL character."""
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"{what}: must be a path (got {type(path).__name__})")
    path = os.fspath(path)
    if "\0" in path:
        raise ValueError(f"{what}: a path cannot contain a NUL character")
    return path


def read_input_bytes(path, what, max_bytes):
    """The bytes of the regular file ``path``, at most ``max_bytes``, checked before anything is read.

    Notes
    -----
    :class:`InputFileError` (a ``ValueError``) ``"<what> <path> <problem>"`` for a missing file, a folder, a
    FIFO, a device, a link loop or a larger file.  Opened without blocking and read with a bound, so a file
    that grows while it is read is refused too.
    """
    path = input_path(path, what)
    problem = file_problem(path)
    if problem is None:
        try:
            fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        except OSError as exc:
            problem = _cannot(exc)
    if problem is not None:
        raise InputFileError(what, path, problem)
    with os.fdopen(fd, "rb") as fh:
        info = os.fstat(fh.fileno())
        problem = _mode_problem(info.st_mode)        # replaced between the check and the open
        if problem is None and info.st_size > max_bytes:
            problem = f"has {info.st_size} bytes; at most {max_bytes} are read"
        if problem is None:
            data = fh.read(max_bytes + 1)
            if len(data) > max_bytes:
                problem = f"has more than {max_bytes} bytes; at most {max_bytes} are read"
    if problem is not None:
        raise InputFileError(what, path, problem)
    return data


def read_input_text(path, what, max_bytes):
    """:func:`read_input_bytes` decoded as UTF-8 (a byte-order mark dropped); ``"is not UTF-8 text (byte <n>)"`` otherwise."""
    data = read_input_bytes(path, what, max_bytes)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputFileError(what, input_path(path), f"is not UTF-8 text (byte {exc.start})") from None
