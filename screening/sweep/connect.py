"""Checks of a ``--scheduler`` before dask is given it.

``distributed.Client(address, timeout=...)`` bounds the TCP connect but not the handshake: a
server that accepts and stays silent hung the run forever, and a peer that is not a dask scheduler
made dask allocate whatever frame size its first bytes declared (exabytes).  A malformed scheduler
JSON file gave AssertionError/TypeError tracebacks.  :func:`check_scheduler` reads the scheduler
file with bounds, checks the address (``tcp://`` or ``host:port``; ``tls://`` only with dask's TLS
settings; a port in 1..65535, a host name of at most :data:`MAX_HOST` characters), then opens one
TCP connection and reads the whole handshake message a dask scheduler sends on accept (its
little-endian length, the frame count and lengths, a msgpack map), all within
:data:`HANDSHAKE_TIMEOUT` in total; silence, a closed connection, an implausible length or bytes
that are not such a message are a one-line :class:`SweepError`.

Once connected, :func:`check_workers` refuses workers that would compute silently with other code: each
worker's :func:`software_versions` (screening and a digest of its sources, Python, numpy, numba) must equal
the client's, and a ``NUMBA_CACHE_DIR`` it was given must be writable; a worker that joins later is closed
by :class:`VersionGuard`.  :func:`jobqueue_cluster` builds the dask-jobqueue cluster of a study's
``[cluster]`` table (:class:`~screening.sweep.config.ClusterSpec`).
"""

from __future__ import annotations

import json
import operator
import os
import platform
import shutil
import socket
import struct
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
from distributed.core import Status
from distributed.diagnostics.plugin import WorkerPlugin

from screening._version import __version__
from screening.io.errors import SweepError, exception_line
from screening.kernels.cache import source_stamp

__all__ = []

#: Seconds to wait for the connection and for the scheduler's first bytes.
HANDSHAKE_TIMEOUT = 10.0
#: Largest handshake message accepted [bytes] (a real one is under 1 kB).
MAX_HANDSHAKE = 1 << 20
#: Longest host name accepted (a DNS name has at most 253 characters).
MAX_HOST = 253
#: Largest scheduler JSON file read [bytes] (a scheduler with thousands of workers writes a few MB).
MAX_SCHEDULER_FILE = 64 << 20
#: dask's settings of a TLS client; ``tls://`` without them cannot connect.
TLS_SETTINGS = ("distributed.comm.tls.client.cert", "distributed.comm.tls.ca-file")


def scheduler_address(scheduler):
    """The address in ``scheduler`` (an address, or a scheduler JSON file with an ``address``).

    A path ending in ``.json`` that names a file is read as dask's scheduler file (at most
    :data:`MAX_SCHEDULER_FILE` bytes) and its ``"address"`` returned; anything else is returned as
    given, as text.

    Parameters
    ----------
    scheduler : str or os.PathLike
        A scheduler address (``tcp://host:port``) or the path of a scheduler JSON file.

    Returns
    -------
    str
        The scheduler's address.

    Raises
    ------
    SweepError
        A scheduler file that is too large, unreadable, not JSON, or without an ``"address"`` string.

    References
    ----------
    .. [1] Dask.distributed documentation, "Connect to a scheduler" and "Launch Dask from a scheduler
       file", https://distributed.dask.org/en/stable/client.html and
       https://docs.dask.org/en/stable/deploying-cli.html
    """
    text = str(scheduler)
    if text.endswith(".json") and Path(text).is_file():
        try:
            size = Path(text).stat().st_size
            if size > MAX_SCHEDULER_FILE:
                raise SweepError(f"the scheduler file {text} has {size} bytes; at most {MAX_SCHEDULER_FILE} "
                                 "(a dask scheduler file lists the scheduler and its workers)")
            with open(text, "rb") as fh:
                info = json.loads(fh.read(MAX_SCHEDULER_FILE + 1))
        except ValueError as exc:
            raise SweepError(f"the scheduler file {text} is not valid JSON ({' '.join(str(exc).split())[:120]})") \
                from None
        except (OSError, RecursionError) as exc:
            raise SweepError(f"cannot read the scheduler file {text}: {exc.__class__.__name__}") from None
        address = info.get("address") if isinstance(info, dict) else None
        if not isinstance(address, str) or not address:
            raise SweepError(f"the scheduler file {text} has no \"address\" string")
        return address
    return text


def check_scheduler(scheduler, timeout=None):
    """Raise :class:`SweepError` unless a dask scheduler answers at ``scheduler`` (TCP addresses;
    other protocols are left to dask).

    The address (see :func:`scheduler_address`) must be ``host:port``, ``tcp://host:port`` or
    ``tls://host:port`` with a port in 1..65535; a ``tls://`` address needs dask's TLS settings
    (:data:`TLS_SETTINGS`) and is then left to dask.  A TCP address is connected to, and the whole
    handshake message a dask scheduler sends on accept must arrive within ``timeout`` and be one
    (:func:`is_handshake`).

    Parameters
    ----------
    scheduler : str or os.PathLike
        A scheduler address or the path of a scheduler JSON file.
    timeout : float, optional
        The time allowed for the connection and the whole handshake [s]; default
        :data:`HANDSHAKE_TIMEOUT`.

    Returns
    -------
    str
        The address checked (the one in the scheduler file for a file).

    Raises
    ------
    SweepError
        A malformed address, missing TLS settings, no connection, silence, or a peer that is not
        a dask scheduler; one line.

    References
    ----------
    .. [1] Dask.distributed documentation, "Connect to a scheduler" and "Launch Dask from a scheduler
       file", https://distributed.dask.org/en/stable/client.html and
       https://docs.dask.org/en/stable/deploying-cli.html
    """
    timeout = HANDSHAKE_TIMEOUT if timeout is None else timeout
    address = scheduler_address(scheduler)
    shown = address if len(address) <= 80 else address[:80] + "..."
    protocol, sep, rest = address.partition("://")
    if not sep:
        protocol, rest = "tcp", address
    if protocol not in ("tcp", "tls"):
        raise SweepError(f"the dask scheduler address {shown!r}: protocol {protocol[:20]!r}:// is not supported "
                         "(tcp:// or tls://)")
    host, sep, port = rest.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not (port.isascii() and port.isdigit()) or len(port) > 5 \
            or not 1 <= int(port) <= 65535:
        raise SweepError(f"the dask scheduler address {shown!r} is not host:port or {protocol}://host:port "
                         "with a port in 1..65535")
    if len(host) > MAX_HOST or any(c.isspace() for c in host):
        raise SweepError(f"the dask scheduler address {shown!r}: the host name is not a host name "
                         f"(at most {MAX_HOST} characters, no spaces)")
    if protocol == "tls":
        import dask

        if not all(dask.config.get(key, None) for key in TLS_SETTINGS):
            raise SweepError(f"the dask scheduler address {shown!r} needs TLS settings: set "
                             f"{' and '.join(TLS_SETTINGS)} in dask's configuration")
        return address                              # the TLS handshake is dask's (bounded by its timeout)
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, int(port)), timeout=timeout) as sock:
            (length,) = struct.unpack("<Q", _receive(sock, 8, deadline, shown))
            if not 8 < length <= MAX_HANDSHAKE:
                raise SweepError(f"the server at {shown} is not a dask scheduler (its first message declares "
                                 f"{length} bytes)")
            message = _receive(sock, length, deadline, shown)
    except (socket.timeout, TimeoutError):
        raise SweepError(f"the server at {shown} did not answer like a dask scheduler within "
                         f"{timeout:g} s") from None
    except (OSError, UnicodeError, OverflowError, ValueError) as exc:
        raise SweepError(f"cannot connect to the dask scheduler {shown}: "
                         f"{getattr(exc, 'strerror', None) or exc}") from None
    if not is_handshake(message):
        raise SweepError(f"the server at {shown} is not a dask scheduler (its first message is not dask's "
                         "handshake)")
    return address


def _receive(sock, n, deadline, shown):
    """``n`` bytes from ``sock`` before ``deadline`` (``time.monotonic``); a closed connection is a
    :class:`SweepError`, the deadline ``socket.timeout``."""
    data = bytearray()
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise socket.timeout
        sock.settimeout(left)
        chunk = sock.recv(min(n - len(data), 1 << 16))
        if not chunk:
            raise SweepError(f"the server at {shown} closed the connection: not a dask scheduler")
        data += chunk
    return bytes(data)


def is_handshake(message):
    """Whether ``message`` (the bytes after the length) is a dask handshake: a frame count, the frame
    lengths adding up to the rest, and a first frame that is a msgpack map.

    Dask's wire format: a little-endian 8-byte frame count ``n``, ``n`` 8-byte frame lengths, then
    the frames; the first frame of the scheduler's greeting is a msgpack-encoded map.

    Parameters
    ----------
    message : bytes
        The message, without its leading 8-byte total length.

    Returns
    -------
    bool
        True if the bytes are such a message, False for anything else (never raises).

    References
    ----------
    .. [1] Dask.distributed documentation, "Connect to a scheduler" and "Launch Dask from a scheduler
       file", https://distributed.dask.org/en/stable/client.html and
       https://docs.dask.org/en/stable/deploying-cli.html
    .. [2] msgpack specification, https://github.com/msgpack/msgpack/blob/master/spec.md
    """
    import msgpack

    if len(message) < 16:
        return False
    (n,) = struct.unpack_from("<Q", message)
    if not 1 <= n <= (len(message) - 8) // 8:
        return False
    lengths = struct.unpack_from(f"<{n}Q", message, 8)
    start = 8 + 8 * n
    if sum(lengths) != len(message) - start:
        return False
    try:
        head = msgpack.unpackb(message[start:start + lengths[0]], raw=False, strict_map_key=False)
    except Exception:                                   # noqa: BLE001 - msgpack raises many types on junk
        return False
    return isinstance(head, dict)


# ----------------------------------------------------------------------------- the workers' software
#: The topic of the worker events of a refused worker (:class:`VersionGuard`).
REFUSED_TOPIC = "screening-refused-worker"
#: The dask-jobqueue cluster class of each ``[cluster] kind``.
JOBQUEUE_CLASSES = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "local": "local.LocalCluster"}


def software_versions():
    """What a result depends on besides the study: screening's version and a digest of its sources
    (:func:`~screening.kernels.cache.source_stamp`, first 12 hex digits), Python's, numpy's and numba's.

    Returns
    -------
    dict
        ``{"screening": "0.1.0 (sources 1a2b3c4d5e6f)", "python": "3.12.3", "numpy": ..., "numba": ...}``.
    """
    return {"screening": f"{__version__} (sources {source_stamp()[:12]})", "python": platform.python_version(),
            "numpy": np.__version__, "numba": numba.__version__}


def version_mismatch(worker, theirs, mine):
    """One line naming what differs between a worker's :func:`software_versions` ``theirs`` and the
    client's ``mine``, or None when nothing does.

    Parameters
    ----------
    worker : str
        The worker's address.
    theirs, mine : dict
        The worker's and the client's versions.

    Returns
    -------
    str or None
        The line, or None.
    """
    names = [name for name in mine if theirs.get(name) != mine[name]]
    if not names:
        return None
    worker_side = ", ".join(f"{n} {theirs.get(n, 'missing')}" for n in names)
    client_side = ", ".join(f"{n} {mine[n]}" for n in names)
    return (f"the dask worker {worker} runs {worker_side}; this client runs {client_side}: install the same "
            "versions on the workers")


def worker_problem(expected, dask_worker=None):
    """On a worker: why it cannot compute for a client with :func:`software_versions` ``expected`` (the
    versions differ, or numba's cache folder ``NUMBA_CACHE_DIR`` is not writable), or None.

    Parameters
    ----------
    expected : dict
        The client's :func:`software_versions`.
    dask_worker : distributed.Worker, optional
        The worker (``client.run`` passes it), named in the line.

    Returns
    -------
    str or None
        One line, or None when the worker may compute.

    References
    ----------
    .. [1] Numba documentation, "Environment variables" (``NUMBA_CACHE_DIR``),
       https://numba.readthedocs.io/en/stable/reference/envvars.html
    """
    where = dask_worker.address if dask_worker is not None else f"on {platform.node()}"
    problem = version_mismatch(where, software_versions(), expected)
    if problem is None:
        problem = _cache_problem(where)
    return problem


def _cache_problem(where):
    """Why numba cannot keep its compiled code in ``NUMBA_CACHE_DIR`` (set, but not a writable folder), or None."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    if not folder:
        return None
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder):
            pass
    except OSError as exc:
        return (f"the dask worker {where} cannot write numba's cache folder NUMBA_CACHE_DIR={folder} "
                f"({exc.strerror or exc}): give each node a writable folder of its own")
    return None


class VersionGuard(WorkerPlugin):
    """A worker plugin: a worker joining with other :func:`software_versions` than ``expected`` (or an
    unwritable numba cache) is closed before it computes, and says why once on :data:`REFUSED_TOPIC`."""

    name = "screening-version-guard"

    def __init__(self, expected):
        self.expected = expected

    def setup(self, worker):
        problem = worker_problem(self.expected, worker)
        if problem is not None:
            worker.log_event(REFUSED_TOPIC, {"worker": worker.address, "problem": problem})
            worker.status = Status.closing_gracefully               # no task starts on it
            worker.loop.add_callback(worker.close, reason="screening-refused", nanny=True)
            raise RuntimeError(problem)


#: Calls of :func:`run_on_workers` when every worker left meanwhile, and how long [s] each retry waits for a
#: worker to join (batch jobs replacing retired ones).
RUN_ATTEMPTS = 3
REJOIN_TIMEOUT = 30.0


def run_on_workers(client, function, *args):
    """``client.run(function, *args)`` on the workers that stay: ``{address: result}``; a worker that
    leaves meanwhile (retired at its lifetime, its job ended) is left out.

    Parameters
    ----------
    client : distributed.Client
        The connected client.
    function : callable
        What to run on each worker.
    *args
        Its arguments.

    Returns
    -------
    dict
        The result of each worker that answered.

    Raises
    ------
    SweepError
        A worker that cannot run it (e.g. screening is not installed there), or none left (one line).

    References
    ----------
    .. [1] Dask.distributed documentation, "Client.run",
       https://distributed.dask.org/en/stable/api.html#distributed.Client.run
    """
    for attempt in range(RUN_ATTEMPTS):
        if attempt:                                 # every worker left at once: wait for the next to join
            try:
                client.wait_for_workers(1, timeout=REJOIN_TIMEOUT)
            except Exception:                       # noqa: BLE001 - dask's TimeoutError, a closed client
                break
        try:
            answers = client.run(function, *args, on_error="return")
        except OSError:                             # the workers left while the call was sent
            answers = {}
        except Exception as exc:                    # noqa: BLE001 - e.g. a function the workers cannot load
            raise SweepError(f"the dask workers cannot run the solver: {exception_line(exc)}") from None
        for answer in answers.values():
            if isinstance(answer, Exception) and not isinstance(answer, OSError):
                raise SweepError(f"the dask workers cannot run the solver: {exception_line(answer)}")
        kept = {worker: answer for worker, answer in answers.items() if not isinstance(answer, OSError)}
        if kept:
            return kept
    raise SweepError("no dask worker answered: the workers left (their lifetime or their jobs ended) and no new "
                     f"one joined within {RUN_ATTEMPTS - 1} x {REJOIN_TIMEOUT:.0f} s")


def check_workers(client, log=None):
    """Refuse a cluster whose workers run other code than this client: one line naming both versions.

    Every connected worker's :func:`worker_problem` must be None (else :class:`SweepError`, the workers left
    as they are); then a :class:`VersionGuard` is registered so that workers joining later (new batch jobs)
    are checked too, and closed if they differ (``log`` gets one line each).  Returns a function that
    removes the guard (call it when the run ends).

    Parameters
    ----------
    client : distributed.Client
        The connected client.
    log : callable, optional
        Receives the line of each worker refused later.

    Returns
    -------
    callable
        ``done()``: unregisters the guard and the log subscription.

    Raises
    ------
    SweepError
        A worker with other versions or an unwritable ``NUMBA_CACHE_DIR``; a worker that cannot run the check.

    References
    ----------
    .. [1] Dask.distributed documentation, "Plugins", https://distributed.dask.org/en/stable/plugins.html
    """
    expected = software_versions()
    for problem in run_on_workers(client, worker_problem, expected).values():
        if problem is not None:
            raise SweepError(problem)
    if log is not None:
        client.subscribe_topic(REFUSED_TOPIC, lambda event: log(f"warning: refused a joining worker: "
                                                               f"{event[1]['problem']}"))
    try:
        client.register_plugin(VersionGuard(expected))
    except Exception as exc:                        # noqa: BLE001 - a worker that joined since, and differs
        raise SweepError(exception_line(exc)) from None

    def done():
        for step in (lambda: client.unregister_worker_plugin(VersionGuard.name),
                     lambda: client.unsubscribe_topic(REFUSED_TOPIC)):
            try:
                step()
            except Exception:                       # noqa: BLE001 - a cluster already gone
                pass
    return done


def jobqueue_cluster(spec):
    """The dask-jobqueue cluster of a ``[cluster]`` table, no job submitted yet (the caller keeps ``spec.jobs``
    jobs with ``cluster.adapt(minimum_jobs=spec.jobs, maximum_jobs=spec.jobs)``, so that a retired job is
    replaced, and closes it).

    Each job runs ``spec.cores`` single-threaded worker processes (the solver holds the GIL) that retire after
    ``spec.lifetime_s`` +- ``spec.lifetime_stagger_s`` (dask's ``--lifetime``/``--lifetime-stagger``), and
    its script exports ``NUMBA_CACHE_DIR = spec.numba_cache_dir`` (a folder of the node) before the workers
    start.  The scheduler runs in this process, its dashboard on a free port.

    Parameters
    ----------
    spec : screening.sweep.config.ClusterSpec
        The ``[cluster]`` table.

    Returns
    -------
    dask_jobqueue.JobQueueCluster
        The cluster (its scheduler running in this process).

    Raises
    ------
    SweepError
        dask-jobqueue is not installed, the queue's submit command (``sbatch``, ``qsub``) is not on the
        ``PATH``, or the cluster cannot start (one line).

    References
    ----------
    .. [1] dask-jobqueue documentation, https://jobqueue.dask.org/en/latest/
    .. [2] screening documentation, "Distributed runs", ``docs/distributed.md``.
    """
    try:
        import dask_jobqueue
        import dask_jobqueue.local
    except ImportError:
        raise SweepError(f"the [cluster] table (kind = {spec.kind!r}) needs dask-jobqueue: "
                         "pip install 'screening[cluster]'") from None
    options = {key: value for key in ("queue", "account", "interface", "local_directory")
               if (value := getattr(spec, key)) is not None and spec.kind != "local"}
    if spec.kind != "local":
        options["walltime"] = spec.walltime
        options["job_script_prologue"] = [f'export NUMBA_CACHE_DIR="{spec.numba_cache_dir}"',
                                          *spec.job_script_prologue]
    elif spec.local_directory is not None:
        options["local_directory"] = spec.local_directory
    args = ["--lifetime", f"{spec.lifetime_s:g}s", "--lifetime-stagger", f"{spec.lifetime_stagger_s:g}s"]
    make = operator.attrgetter(JOBQUEUE_CLASSES[spec.kind])(dask_jobqueue)
    command = getattr(make.job_cls, "submit_command", None)
    if command and shutil.which(command.split()[0]) is None:
        raise SweepError(f"[cluster] kind = {spec.kind!r} submits jobs with {command}, which is not on this machine's "
                         "PATH: run screening where the batch queue's commands are (a login node)")
    try:
        cluster = make(
            cores=spec.cores, processes=spec.cores, memory=spec.memory, worker_extra_args=args,
            job_extra_directives=list(spec.job_extra_directives), scheduler_options={"dashboard_address": ":0"},
            **options)
    except Exception as exc:                        # noqa: BLE001 - dask-jobqueue raises many types
        raise SweepError(f"cannot start the dask-jobqueue {JOBQUEUE_CLASSES[spec.kind]}: {exception_line(exc)}") \
            from None
    return cluster
