"""Whether numba's on-disk cache of the solvers is current, and the one line saying so when it is not.

Numba compiles the solvers on first use (``cache=True``) and keeps them in ``__pycache__`` next to
each module (``<module>.<function>-<line>.py<XY>.nbi`` indexes).  A fresh clone has none, and the
first ``import screening`` plus the first run compile for one to two minutes: without a word that
looks like a hang.  :func:`announce_compilation` prints one line on stderr before that work starts.
Checked cheaply (a few ``stat`` calls, no numba import): the index of each key kernel must exist and
be newer than its source.  That cannot see a kernel compiled for a new type signature (another
condensation, another law): :class:`CompileAnnouncer`, installed by the commands, listens to numba's own
``numba:compile`` event (a compile after a cache miss) and says which kernel compiles, then every
:data:`COMPILE_INTERVAL` seconds while compiling goes on.

Numba checks a cached kernel against its own source file only: a kernel that calls a compiled
function of another module, or reads a constant of another module, keeps its old machine code when
only that other module changes (numba's documented caching limitation).  :func:`clear_stale_cache`,
run when the package is imported, removes the package's numba cache files whenever any source of the
package changed since they were written (a stamp of all sources), so an update never runs stale code.
"""

from __future__ import annotations

import hashlib
import os
import sys
import threading
import time
from pathlib import Path

__all__ = []

_PACKAGE = Path(__file__).resolve().parents[1]

#: ``(module path, function)`` of the kernels compiled on a first run: the moment solver and the
#: Monte Carlo sample integrator.
KEY_KERNELS = (("solvers/moments.py", "_batch_filtered"), ("kernels/mcs_kernels.py", "integrate_sample"))

#: What the first compilation costs (measured on a fresh clone, 2 cores: ~75 s before the first
#: point, ~20 s more for the Monte Carlo kernels).
FIRST_COMPILE = "about 10-60 s"


def _cache_folder(source):
    """Where numba keeps the cache of ``source``: ``__pycache__`` beside it, or under ``NUMBA_CACHE_DIR`` in
    ``<folder name>_<sha1 of the folder's absolute path>`` (numba's user-provided cache locator)."""
    custom = os.environ.get("NUMBA_CACHE_DIR")
    if custom:
        folder = os.path.dirname(os.path.abspath(source))
        return Path(custom).absolute() / f"{os.path.basename(folder)}_{hashlib.sha1(folder.encode()).hexdigest()}"
    return source.parent / "__pycache__"


def _index_is_current(module, function):
    source = _PACKAGE / module
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    try:
        indexes = list(_cache_folder(source).glob(f"{source.stem}.{function}-*.{tag}.nbi"))
        return bool(indexes) and max(p.stat().st_mtime for p in indexes) >= source.stat().st_mtime
    except OSError:
        return False


def cache_is_cold():
    """True if numba will compile the key kernels: an index is missing or older than its source.

    The cache looked at is numba's: beside the package, or under ``NUMBA_CACHE_DIR`` where it is set (a
    cluster node's own folder, the portable test run).  A package folder numba cannot write to, without
    ``NUMBA_CACHE_DIR`` (numba then caches elsewhere), is not judged: False.

    Returns
    -------
    bool
        Whether the first run will compile (about 10-60 s [s] per fresh cache).

    """
    if os.environ.get("NUMBA_DISABLE_JIT") == "1":
        return False
    if not os.environ.get("NUMBA_CACHE_DIR") and not os.access(_PACKAGE / "solvers", os.W_OK):
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


#: Longest silence while numba compiles [s]: a line at least this often.
COMPILE_INTERVAL = 10.0
#: Compiling shorter than this [s] is not worth a line (a small kernel); longer is said at once.
COMPILE_DELAY = 2.0


class CompileAnnouncer:
    """Lines on ``stream`` while numba compiles kernels its cache does not hold.

    :meth:`started` and :meth:`finished` are called for each compile (numba's ``numba:compile`` event,
    :func:`announcing_compiles`); :meth:`tick` (a background thread of :func:`announcing_compiles`, every
    second) writes the first line once compiling has gone on for ``delay`` seconds, then a "still
    compiling" line whenever nothing was said for ``interval`` seconds while compiling goes on.

    Parameters
    ----------
    stream : file-like, optional
        Where to write; default ``sys.stderr``.
    interval : float
        Longest silence while compiling [s].
    delay : float
        Compiling shorter than this is not announced [s].
    clock : callable
        Seconds [s] (a fake clock in tests).
    """

    def __init__(self, stream=None, interval=COMPILE_INTERVAL, delay=COMPILE_DELAY, clock=time.monotonic):
        self.stream, self.interval, self.delay, self.clock = stream, interval, delay, clock
        self.active, self.count, self.name = 0, 0, ""
        self._first = self._last = self._idle_since = None
        self._lock = threading.Lock()

    def _write(self, text):
        try:
            stream = self.stream if self.stream is not None else sys.stderr
            stream.write(text + "\n")
            stream.flush()
        except (OSError, ValueError):       # a closed or broken stderr: say nothing
            pass

    def started(self, name):
        """A compile of ``name`` began; the lines name the outermost compile going on (the kernel called, not the
        helpers and numba's own implementations it compiles on the way)."""
        with self._lock:
            self.active += 1
            self.count += 1
            if self.active == 1 or not self.name:
                self.name = name
            if self._first is None:
                self._first = self.clock()

    def finished(self):
        with self._lock:
            self.active = max(self.active - 1, 0)
            if not self.active:
                self._idle_since = self.clock()

    def tick(self):
        with self._lock:
            now = self.clock()
            busy = self.active or (self._idle_since is not None and now - self._idle_since < 1.0)
            if not busy or self._first is None:
                return
            if self._last is None:
                if now - self._first >= self.delay:
                    self._last = now
                    self._write(f"screening: compiling {self.name} with numba (not in its cache yet; first run "
                                f"only, {FIRST_COMPILE})...")
            elif now - self._last >= self.interval:
                self._last = now
                self._write(f"screening: still compiling ({self.count} kernel(s) so far, now {self.name}, "
                            f"{now - self._first:.0f} s)")


class announcing_compiles:
    """Context: a :class:`CompileAnnouncer` on numba's ``numba:compile`` event, with its ticker thread; removed
    on exit.  Without numba's event API (or with ``quiet``) it does nothing.

    Parameters
    ----------
    quiet : bool, default False
        Say nothing.
    stream : file-like, optional
        Where to write; default ``sys.stderr``.
    """

    def __init__(self, quiet=False, stream=None):
        self.quiet, self.stream = quiet, stream
        self.announcer, self._listener, self._stop, self._thread = None, None, threading.Event(), None

    def __enter__(self):
        if self.quiet:
            return self
        try:
            from numba.core import event
        except ImportError:                 # an old numba: the cache check alone
            return self
        announcer = self.announcer = CompileAnnouncer(self.stream)

        class _Listener(event.Listener):
            def on_start(self, ev):
                dispatcher = (ev.data or {}).get("dispatcher")
                func = getattr(dispatcher, "py_func", None)
                announcer.started(getattr(func, "__qualname__", "a kernel"))

            def on_end(self, ev):
                announcer.finished()

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        self._thread = threading.Thread(target=self._run, name="compile-announcer", daemon=True)
        self._thread.start()
        return self

    def _run(self):
        while not self._stop.wait(1.0):
            self.announcer.tick()

    def __exit__(self, *exc):
        if self._listener is not None:
            from numba.core import event

            event.unregister("numba:compile", self._listener)
            self._stop.set()
            self._thread.join()
        return False


_STAMP_NAME = "numba-sources.sha256"
#: The folders whose sources compiled code can depend on: compiled code lives in ``core/``, ``kernels/`` and
#: ``solvers/``, and a folder imports only folders below it (``tests/unit/test_layers.py``).
COMPILED_LAYERS = ("data", "core", "kernels", "solvers")


def source_stamp(package=None):
    """A digest of the Python sources compiled code can depend on (the top level of ``package`` and its
    :data:`COMPILED_LAYERS`), of Python's and of numba's version.

    Parameters
    ----------
    package : path-like, optional
        The package folder; default the installed ``screening`` package.

    Returns
    -------
    str
        Hexadecimal SHA-256 digest [-]; it changes when any of those ``.py`` files changes (an edit of
        ``sweep/`` or ``cli/`` keeps the compiled kernels).

    """
    package = Path(package) if package is not None else _PACKAGE
    digest = hashlib.sha256(sys.version.encode())
    try:
        from importlib.metadata import version

        digest.update(version("numba").encode())
    except Exception:                       # numba's metadata unreadable: the sources alone
        pass
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package).parts
        if len(parts) > 1 and parts[0] not in COMPILED_LAYERS:
            continue
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def clear_stale_cache(package=None):
    """Remove the numba cache files of ``package`` if its sources changed since they were written.

    The stamp of :func:`source_stamp` is kept in ``package/__pycache__``; when it differs from the
    sources' (or is missing while cache files exist), every ``*.nbi`` / ``*.nbc`` file under the
    package's ``__pycache__`` folders is removed and the stamp rewritten.  Nothing is done with
    ``NUMBA_CACHE_DIR`` set (numba then caches elsewhere) or where the package folder is not writable.

    Parameters
    ----------
    package : path-like, optional
        As in :func:`source_stamp`.

    Returns
    -------
    int
        The number of cache files removed [-].

    Notes
    -----
    Numba keys a cached kernel on its own file's time stamp; a callee or a constant from another file
    is frozen into the kernel's machine code.  A stamp over every source compiled code can reach (the
    layers up to ``solvers/``, :func:`source_stamp`) is conservative there: such a change recompiles the
    kernels once (about a minute), never runs stale code.

    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return 0
    package = Path(package) if package is not None else _PACKAGE
    stamp_file = package / "__pycache__" / _STAMP_NAME
    try:
        stamp = source_stamp(package)
        if stamp_file.is_file() and stamp_file.read_text().strip() == stamp:
            return 0
        if not os.access(package, os.W_OK):
            return 0
        removed = 0
        for pattern in ("*.nbi", "*.nbc"):
            for path in package.rglob(f"__pycache__/{pattern}"):
                try:
                    path.unlink()
                    removed += 1
                except FileNotFoundError:   # another process removed it first
                    pass
        stamp_file.parent.mkdir(exist_ok=True)
        temporary = stamp_file.with_name(f"{_STAMP_NAME}.{os.getpid()}")
        temporary.write_text(stamp + "\n")
        os.replace(temporary, stamp_file)   # atomic: a concurrent import reads the old or the new stamp
        return removed
    except OSError:                         # a read-only or vanishing folder: numba's own checks remain
        return 0
