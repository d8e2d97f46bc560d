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
"""

from __future__ import annotations

import json
import socket
import struct
import time
from pathlib import Path

from screening.io.errors import SweepError

__all__ = ["HANDSHAKE_TIMEOUT", "MAX_HANDSHAKE", "MAX_HOST", "MAX_SCHEDULER_FILE", "TLS_SETTINGS",
           "scheduler_address", "check_scheduler", "is_handshake"]

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

    Examples
    --------
    >>> import json, os, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "scheduler.json")
    ...     with open(path, "w") as fh:
    ...         json.dump({"address": "tcp://10.0.0.5:8786", "workers": {}}, fh)
    ...     scheduler_address(path)
    'tcp://10.0.0.5:8786'
    >>> scheduler_address("tcp://127.0.0.1:8786")
    'tcp://127.0.0.1:8786'
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

    Examples
    --------
    >>> try:
    ...     check_scheduler("tcp://localhost:99999")
    ... except SweepError as exc:
    ...     print(exc)
    the dask scheduler address 'tcp://localhost:99999' is not host:port or tcp://host:port with a port in 1..65535
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

    Examples
    --------
    >>> import struct, msgpack
    >>> head = msgpack.packb({"op": "handshake"})
    >>> is_handshake(struct.pack("<QQ", 1, len(head)) + head)
    True
    >>> is_handshake(b"HTTP/1.1 400 Bad Request\\r\\n")
    False
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
