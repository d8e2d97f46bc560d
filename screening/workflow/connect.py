"""Checks of a ``--scheduler`` before dask is given it.

``distributed.Client(address, timeout=...)`` bounds the TCP connect but not the handshake: a
server that accepts and stays silent hung the run forever, and a peer that is not a dask scheduler
made dask allocate whatever frame size its first bytes declared (exabytes).  A malformed scheduler
JSON file gave AssertionError/TypeError tracebacks.  :func:`check_scheduler` reads the scheduler
file with bounds, then opens one TCP connection and reads the first 8 bytes a dask scheduler sends
on accept (the little-endian length of its handshake message) within :data:`HANDSHAKE_TIMEOUT`;
silence, a closed connection or an implausible length is a one-line :class:`SweepError`.
"""

from __future__ import annotations

import json
import socket
import struct
from pathlib import Path

from screening.workflow.errors import SweepError

#: Seconds to wait for the connection and for the scheduler's first bytes.
HANDSHAKE_TIMEOUT = 10.0
#: Largest handshake message accepted [bytes] (a real one is under 1 kB).
MAX_HANDSHAKE = 1 << 20


def scheduler_address(scheduler):
    """The address in ``scheduler`` (an address, or a scheduler JSON file with an ``address``)."""
    text = str(scheduler)
    if text.endswith(".json") and Path(text).is_file():
        try:
            with open(text, "rb") as fh:
                info = json.loads(fh.read(1 << 20))
        except (OSError, ValueError, RecursionError) as exc:
            raise SweepError(f"cannot read the scheduler file {text}: {exc.__class__.__name__}") from None
        address = info.get("address") if isinstance(info, dict) else None
        if not isinstance(address, str) or not address:
            raise SweepError(f"the scheduler file {text} has no \"address\" string")
        return address
    return text


def check_scheduler(scheduler, timeout=None):
    """Raise :class:`SweepError` unless a dask scheduler answers at ``scheduler`` (TCP addresses;
    other protocols are left to dask)."""
    timeout = HANDSHAKE_TIMEOUT if timeout is None else timeout
    address = scheduler_address(scheduler)
    rest = address[len("tcp://"):] if address.startswith("tcp://") else address
    if "://" in rest:
        return address
    host, sep, port = rest.rpartition(":")
    host = host.strip("[]")
    if not sep or not port.isdigit() or not host:
        raise SweepError(f"the dask scheduler address {address!r} is not host:port or tcp://host:port")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout) as sock:
            sock.settimeout(timeout)
            head = b""
            while len(head) < 8:
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    raise SweepError(f"the server at {address} closed the connection: not a dask scheduler")
                head += chunk
    except socket.timeout:
        raise SweepError(f"the server at {address} did not answer like a dask scheduler within "
                         f"{timeout:g} s") from None
    except OSError as exc:
        raise SweepError(f"cannot connect to the dask scheduler {address}: {exc.strerror or exc}") from None
    (length,) = struct.unpack("<Q", head)
    if not 0 < length <= MAX_HANDSHAKE:
        raise SweepError(f"the server at {address} is not a dask scheduler (its first message declares "
                         f"{length} bytes)")
    return address
