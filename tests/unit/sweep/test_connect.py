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


# ----------------------------------------------------------------------------- the workers' software
def test_a_version_mismatch_names_both_versions_in_one_line():
    mine = connect.software_versions()
    assert connect.version_mismatch("tcp://w:1", dict(mine), mine) is None
    line = connect.version_mismatch("tcp://w:1", {**mine, "numba": "0.50.0"}, mine)
    assert line == (f"the dask worker tcp://w:1 runs numba 0.50.0; this client runs numba {mine['numba']}: "
                    "install the same versions on the workers")
    line = connect.version_mismatch("tcp://w:1", {"numpy": mine["numpy"]}, mine)     # an old worker lacks keys
    assert "runs screening missing, python missing, numba missing;" in line and "\n" not in line


def test_a_worker_is_refused_with_another_version_or_an_unwritable_numba_cache(tmp_path, monkeypatch):
    mine = connect.software_versions()
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert connect.worker_problem(mine) is None
    fake = {**mine, "screening": "0.0.1 (sources 000000000000)"}
    assert connect.worker_problem(fake).endswith(f"runs screening {mine['screening']}; this client runs screening "
                                                 "0.0.1 (sources 000000000000): install the same versions on the workers")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))            # created, writable
    assert connect.worker_problem(mine) is None and (tmp_path / "cache").is_dir()
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "file" / "cache"))   # under a file: not a folder
    assert "cannot write numba's cache folder NUMBA_CACHE_DIR=" in connect.worker_problem(mine)


def test_a_joining_worker_with_another_version_is_closed_before_it_computes():
    from distributed.core import Status

    class Worker:
        address, status, events, scheduled = "tcp://w:2", Status.running, [], []

        def log_event(self, topic, msg):
            self.events.append((topic, msg))

        def close(self, **kwargs):
            pass

    worker = Worker()
    worker.loop = type("Loop", (), {"add_callback": lambda self, *a, **k: worker.scheduled.append((a, k))})()
    connect.VersionGuard(connect.software_versions()).setup(worker)         # the same: nothing happens
    assert worker.status == Status.running and not worker.events and not worker.scheduled
    with pytest.raises(RuntimeError, match="runs numba .*; this client runs numba 0.0.0"):
        connect.VersionGuard({**connect.software_versions(), "numba": "0.0.0"}).setup(worker)
    assert worker.status == Status.closing_gracefully                         # no task starts on it
    assert worker.events[0][0] == connect.REFUSED_TOPIC and "numba 0.0.0" in worker.events[0][1]["problem"]
    assert worker.scheduled == [((worker.close,), {"reason": "screening-refused", "nanny": True})]


def test_check_workers_refuses_a_cluster_of_another_version(monkeypatch):
    """The client's versions faked (the in-process worker runs on its own thread and sees the real ones)."""
    import threading

    from helpers import in_process_client

    real = connect.software_versions

    def faked():
        versions = real()
        if threading.current_thread() is threading.main_thread():
            versions["numpy"] = "1.0.0"
        return versions

    with in_process_client(1) as client:
        done = connect.check_workers(client)                                  # the same versions: accepted
        assert connect.VersionGuard.name in client.run(lambda dask_worker: list(dask_worker.plugins)).popitem()[1]
        done()
        assert connect.VersionGuard.name not in client.run(lambda dask_worker: list(dask_worker.plugins)).popitem()[1]
        monkeypatch.setattr(connect, "software_versions", faked)
        with pytest.raises(SweepError) as err:
            connect.check_workers(client)
        assert str(err.value).startswith("the dask worker inproc://") and "\n" not in str(err.value)
        assert f"runs numpy {real()['numpy']}; this client runs numpy 1.0.0" in str(err.value)


def test_run_on_workers_leaves_out_a_worker_that_left_and_names_one_that_fails():
    class Client:
        def __init__(self, answers):
            self.answers = answers

        def run(self, function, *args, on_error):
            assert on_error == "return"
            return self.answers

    from distributed.comm.core import CommClosedError

    assert connect.run_on_workers(Client({"a": 1, "b": CommClosedError("gone")}), len) == {"a": 1}
    with pytest.raises(SweepError, match="no dask worker answered: the workers left"):
        connect.run_on_workers(Client({"b": CommClosedError("gone")}), len)
    with pytest.raises(SweepError, match="the dask workers cannot run the solver: ModuleNotFoundError: No module"):
        connect.run_on_workers(Client({"a": 1, "b": ModuleNotFoundError("No module named 'screening'")}), len)


def test_the_job_scripts_of_slurm_and_pbs_retire_workers_and_keep_numba_on_the_node(monkeypatch, tmp_path):
    pytest.importorskip("dask_jobqueue")
    from screening.sweep.config import cluster_table

    for kind, command, directive in (("slurm", "sbatch", "#SBATCH -t 02:00:00"), ("pbs", "qsub", "walltime=02:00:00")):
        spec = cluster_table({"cluster": {"kind": kind, "memory": "8GB", "cores": 4, "walltime": "02:00:00",
                                          "queue": "short", "job_script_prologue": ["module load python"]}})
        monkeypatch.setenv("PATH", "/nonexistent")
        with pytest.raises(SweepError, match=f"submits jobs with {command}, which is not on this machine's PATH"):
            connect.jobqueue_cluster(spec)
        (tmp_path / command).write_text("#!/bin/sh\nexit 1\n")
        (tmp_path / command).chmod(0o755)
        monkeypatch.setenv("PATH", str(tmp_path))
        with connect.jobqueue_cluster(spec) as cluster:                       # nothing submitted
            script = cluster.job_script()
        assert directive in script and "short" in script
        lines = script.splitlines()
        worker = next(i for i, line in enumerate(lines) if "distributed.cli.dask_worker" in line)
        cache = lines.index('export NUMBA_CACHE_DIR="${TMPDIR:-/tmp}/screening-numba-$(id -u)"')
        assert cache < lines.index("module load python") < worker                       # before the workers start
        assert "--nthreads 1 " in lines[worker] and "--nworkers 4 " in lines[worker]       # one thread per worker
        assert "--lifetime 6600s --lifetime-stagger 300s" in lines[worker]
