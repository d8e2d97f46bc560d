"""Checks of a ``--scheduler`` before dask is given it (screening.sweep.connect), against local servers.

A thread listening on a free local port plays the scheduler: one that sends dask's handshake (a frame count, the
frame lengths, a msgpack map) passes; one that sends HTTP, closes at once, stays silent or declares a huge first
message is refused in one line.  Scheduler files and malformed addresses are refused before any connection.
"""

import json
import socket
import struct
import threading

import msgpack
import pytest

from screening.sweep import connect
from screening.io.errors import SweepError


def _handshake():
    head = msgpack.packb({"op": "handshake", "pickle-protocol": 5})
    message = struct.pack("<QQ", 1, len(head)) + head
    return struct.pack("<Q", len(message)) + message


def _server(reply):
    """``tcp://127.0.0.1:<port>`` of a one-connection server sending ``reply`` (None: silent until closed)."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    done = threading.Event()

    def serve():
        conn, _ = listener.accept()
        with conn:
            if reply is not None:
                conn.sendall(reply)
            if reply != b"":                        # b"": closed at once
                done.wait(5.0)
        listener.close()

    threading.Thread(target=serve, daemon=True).start()
    return f"tcp://127.0.0.1:{listener.getsockname()[1]}", done


def test_a_server_sending_dasks_handshake_is_a_scheduler():
    address, done = _server(_handshake())
    try:
        assert connect.check_scheduler(address, timeout=5.0) == address
    finally:
        done.set()


@pytest.mark.parametrize("reply, message", [
    (b"HTTP/1.1 400 Bad Request\r\n\r\n", "is not a dask scheduler"),
    (b"", "closed the connection"),
    (None, "did not answer like a dask scheduler within 0.3 s"),
    (struct.pack("<Q", connect.MAX_HANDSHAKE + 1), "declares"),
])
def test_anything_else_is_refused_in_one_line(reply, message):
    address, done = _server(reply)
    try:
        with pytest.raises(SweepError, match=message) as err:
            connect.check_scheduler(address, timeout=0.3 if reply is None else 5.0)
        assert "\n" not in str(err.value)
    finally:
        done.set()


@pytest.mark.parametrize("address, message", [("tcp://host", "not host:port"), ("tcp://host:0", "port in 1..65535"),
                                              ("ucx://host:8786", "protocol 'ucx'"),
                                              ("tcp://" + "h" * 300 + ":1", "not a host name")])
def test_malformed_addresses_are_refused_before_connecting(address, message):
    with pytest.raises(SweepError, match=message):
        connect.check_scheduler(address, timeout=0.1)


def test_a_scheduler_file_gives_its_address_and_a_bad_one_is_named(tmp_path):
    good, bad, empty = tmp_path / "s.json", tmp_path / "bad.json", tmp_path / "none.json"
    good.write_text(json.dumps({"address": "tcp://10.0.0.5:8786", "workers": {}}))
    bad.write_text("{not json")
    empty.write_text(json.dumps({"workers": {}}))
    assert connect.scheduler_address(good) == "tcp://10.0.0.5:8786"
    with pytest.raises(SweepError, match="is not valid JSON"):
        connect.scheduler_address(bad)
    with pytest.raises(SweepError, match='has no "address" string'):
        connect.scheduler_address(empty)
    assert connect.scheduler_address(tmp_path / "absent.json") == str(tmp_path / "absent.json")


def test_the_handshake_test_reads_dasks_frames():
    message = _handshake()[8:]
    assert connect.is_handshake(message)
    assert not connect.is_handshake(message[:-1])                        # a frame cut short
    assert not connect.is_handshake(struct.pack("<QQ", 1, 3) + b"abc")   # a first frame that is not a map
    assert not connect.is_handshake(struct.pack("<QQ", 0, 0))            # no frame
