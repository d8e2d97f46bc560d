"""Ctrl-C handling for long runs: an interrupt is never lost and never printed as a traceback.

Python raises ``KeyboardInterrupt`` wherever the main thread happens to be. When that is a garbage
collector callback or a ``__del__`` (dask's ``GCDiagnosis`` registers one), the exception is
"ignored": a traceback goes to stderr and the run carries on as if nothing was pressed; inside
dask's own waits (``Client.sync``) it makes dask log a traceback. :func:`interrupt_guard` records
every Ctrl-C and silences the ignored copies; inside :func:`shielded` (a block that talks to dask)
a Ctrl-C is only recorded and raised where it is safe: while :func:`interruptible` waits for the
next result, between batches (:func:`raise_if_interrupted`) or when the block ends.
"""
import atexit
import contextlib
import os
import signal
import sys
import threading

__all__ = []

_pressed = threading.Event()
_depth = {"shielded": 0, "open": 0}


def interrupted():
    """True once Ctrl-C was pressed inside :func:`interrupt_guard`.

    Read by the loops of a run between batches and by the writers before they commit a file, so a
    Ctrl-C that Python swallowed (in a garbage-collector callback) still stops the run.

    Returns
    -------
    bool
        Whether a Ctrl-C was recorded in the current :func:`interrupt_guard` block.

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    """
    return _pressed.is_set()


def raise_if_interrupted():
    """Raise ``KeyboardInterrupt`` if a Ctrl-C was pressed (e.g. one swallowed by a GC callback).

    Returns
    -------
    None
        Returns only when no Ctrl-C was recorded (:func:`interrupted` is False).

    Raises
    ------
    KeyboardInterrupt
        When :func:`interrupted` is True.

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    """
    if _pressed.is_set():
        raise KeyboardInterrupt


@contextlib.contextmanager
def interrupt_guard():
    """Record Ctrl-C while the block runs; still raise ``KeyboardInterrupt`` at once as usual.

    Only acts in the main thread (signal handlers cannot be installed elsewhere).  Installs a SIGINT
    handler that records the press (:func:`interrupted`) and raises unless inside :func:`shielded`,
    and an unraisable hook (``sys.unraisablehook``) that records a ``KeyboardInterrupt`` Python
    would otherwise print and ignore; both are restored, and the record cleared, when the block ends.

    Returns
    -------
    contextlib.AbstractContextManager
        The guarded block (yields None).

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    .. [2] Python documentation, "sys.unraisablehook",
       https://docs.python.org/3/library/sys.html#sys.unraisablehook
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _pressed.clear()

    def on_sigint(signum, frame):
        _pressed.set()
        if not _depth["shielded"] or _depth["open"]:
            raise KeyboardInterrupt

    def on_unraisable(unraisable, default=sys.unraisablehook):
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            _pressed.set()                  # swallowed where it was raised: remembered here instead
            return
        default(unraisable)

    old_handler, old_hook = signal.signal(signal.SIGINT, on_sigint), sys.unraisablehook
    sys.unraisablehook = on_unraisable
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_handler)
        sys.unraisablehook = old_hook
        _pressed.clear()


@contextlib.contextmanager
def shielded():
    """Inside this block a Ctrl-C is recorded, not raised where it lands (see the module docstring).

    Used around the code that talks to dask: a ``KeyboardInterrupt`` inside dask's own waits would
    make it log a traceback.  The recorded Ctrl-C is raised by :func:`interruptible` while waiting
    for the next result, by :func:`raise_if_interrupted`, or when the block ends.  Nested blocks
    count.

    Returns
    -------
    contextlib.AbstractContextManager
        The shielded block (yields None); leaving it raises ``KeyboardInterrupt`` if a Ctrl-C was
        recorded.

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    """
    _depth["shielded"] += 1
    try:
        yield
    finally:
        _depth["shielded"] -= 1
    raise_if_interrupted()


def interruptible(iterable):
    """Iterate, letting a Ctrl-C raise at once while waiting for the next item (also in :func:`shielded`).

    Wraps an iterator of results (dask's ``as_completed``): before each item a recorded Ctrl-C is
    raised, and while ``next`` waits a new one raises at once, even inside :func:`shielded`.

    Parameters
    ----------
    iterable : iterable
        The items to yield (typically finished futures as they complete).

    Yields
    ------
    object
        The items of ``iterable``, in its order.

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    """
    iterator = iter(iterable)
    while True:
        raise_if_interrupted()
        _depth["open"] += 1
        try:
            item = next(iterator)
        except StopIteration:
            return
        finally:
            _depth["open"] -= 1
        yield item


@contextlib.contextmanager
def deferred_interrupt():
    """A Ctrl-C in this block is held back and raised as ``KeyboardInterrupt`` by the caller (the
    yielded list is non-empty then), e.g. after a cluster has finished starting.

    Only acts in the main thread; the previous SIGINT handler is restored when the block ends.

    Returns
    -------
    contextlib.AbstractContextManager
        The block; it yields a list that gets one ``True`` per Ctrl-C pressed inside it.

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    """
    pressed = []
    if threading.current_thread() is not threading.main_thread():
        yield pressed
        return

    old = signal.signal(signal.SIGINT, lambda *_: pressed.append(True))
    try:
        yield pressed
    finally:
        signal.signal(signal.SIGINT, old)


def dask_setup(worker):
    """Set up a worker process of the local cluster of ``screening run`` when it starts: ignore SIGINT.

    dask calls this hook (its "preload" of this module, named by
    :func:`screening.sweep.execution.dask_client` for the processes it starts, never for a
    cluster it is given) in the worker's main thread, before any task.  The terminal's Ctrl-C
    reaches the whole process group, and the client stops the run with one line and closes its
    workers itself, so a worker ignores SIGINT instead of printing a traceback while it computes.
    A spawned worker, when it exits (its work directory removed, its streams flushed by
    multiprocessing), then skips tearing down its modules: scipy, numba and xarray take ~0.5 s,
    which the client would wait for at the end of every run (a forked one exits through
    ``os._exit`` already).

    Parameters
    ----------
    worker : distributed.Worker
        The worker being started (dask passes it; unused).

    Returns
    -------
    None

    References
    ----------
    .. [1] Python documentation, "signal: Set handlers for asynchronous events",
       https://docs.python.org/3/library/signal.html
    .. [2] Dask.distributed documentation, "Preloading",
       https://distributed.dask.org/en/stable/preloading.html
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    atexit.register(os._exit, 0)
