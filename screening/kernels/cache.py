"""Whether numba's on-disk cache of the solvers is current, and the one line saying so when it is not.

Numba compiles the solvers on first use (``cache=True``) and keeps them in ``__pycache__`` next to
each module (``<module>.<function>-<line>.py<XY>.nbi`` indexes).  A fresh clone has none, and the
first ``import screening`` plus the first run compile for one to two minutes: without a word that
looks like a hang.  :func:`announce_compilation` prints one line on stderr before that work starts.
Checked cheaply (a few ``stat`` calls, no numba import): the index of each key kernel must exist and
be newer than its source.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["KEY_KERNELS", "FIRST_COMPILE", "cache_is_cold", "announce_compilation"]

_PACKAGE = Path(__file__).resolve().parents[1]

#: ``(module path, function)`` of the kernels compiled on a first run: the moment solver and the
#: Monte Carlo sample integrator.
KEY_KERNELS = (("solvers/moments.py", "_solve_batch"), ("solvers/mcs_kernels.py", "integrate_sample"))

#: What the first compilation costs (measured on a fresh clone, 2 cores: ~75 s before the first
#: point, ~20 s more for the Monte Carlo kernels).
FIRST_COMPILE = "about 10-60 s"


def _index_is_current(module, function):
    source = _PACKAGE / module
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    folder = source.parent / "__pycache__"
    try:
        indexes = list(folder.glob(f"{source.stem}.{function}-*.{tag}.nbi"))
        return bool(indexes) and max(p.stat().st_mtime for p in indexes) >= source.stat().st_mtime
    except OSError:
        return False


def cache_is_cold():
    """True if numba will compile the key kernels: an index is missing or older than its source.

    Only the cache next to the package is looked at: with ``NUMBA_CACHE_DIR`` set, or a package
    folder numba cannot write to (it then caches elsewhere), the answer is False (nothing said).

    Returns
    -------
    bool
        Whether the first run will compile (about 10-60 s [s] per fresh cache).

    References
    ----------
    .. [1] Numba documentation, "Notes on caching",
       https://numba.readthedocs.io/en/stable/developer/caching.html

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, {"NUMBA_CACHE_DIR": "/elsewhere"}):   # numba caches elsewhere
    ...     cache_is_cold()
    False
    """
    if os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("NUMBA_DISABLE_JIT") == "1":
        return False
    if not os.access(_PACKAGE / "solvers", os.W_OK):
        return False
    return not all(_index_is_current(module, function) for module, function in KEY_KERNELS)


def announce_compilation(stream=None):
    """Print one line on ``stream`` if :func:`cache_is_cold`; returns whether it did.

    Parameters
    ----------
    stream : file-like, optional
        Where to write [-]; default ``sys.stderr``.  A closed or broken stream is ignored.

    Returns
    -------
    bool
        True if the line was due (the cache is cold), False otherwise.

    References
    ----------
    .. [1] Numba documentation, "Notes on caching",
       https://numba.readthedocs.io/en/stable/developer/caching.html

    Examples
    --------
    >>> import io, os
    >>> from unittest import mock
    >>> out = io.StringIO()
    >>> with mock.patch.dict(os.environ, {"NUMBA_CACHE_DIR": "/elsewhere"}):   # nothing to announce
    ...     announce_compilation(out), out.getvalue()
    (False, '')
    """
    if not cache_is_cold():
        return False
    stream = stream if stream is not None else sys.stderr
    try:
        stream.write(f"screening: compiling the solvers with numba (first run only, {FIRST_COMPILE})...\n")
        stream.flush()
    except (OSError, ValueError):           # a closed or broken stderr: say nothing
        pass
    return True
