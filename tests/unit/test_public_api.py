"""The public face of the package: importing it does nothing but import, and every source module has
a test module of its own name."""

import os
import subprocess
import sys
from pathlib import Path

import import_graph as ig

ROOT = Path(__file__).resolve().parents[2]

#: Imports every module of the package in a fresh interpreter that looks like a worker process of a
#: local cluster (the process name and environment an import-time worker setup would react to), and
#: prints what changed: signal handlers, exit handlers, threads.
PROBE = """
import atexit, importlib, multiprocessing, pkgutil, signal, sys, threading

multiprocessing.current_process().name = "Dask Worker process (from Nanny)"
by_screening = []            # (what, module) of every exit handler, signal handler or thread the package sets up


def watch(owner, name):
    original = getattr(owner, name)

    def wrapper(*args, **kwargs):
        caller = sys._getframe(1).f_globals.get("__name__", "")
        if caller.split(".")[0] == "screening":
            by_screening.append((name, caller))
        return original(*args, **kwargs)
    setattr(owner, name, wrapper)


watch(atexit, "register")
watch(signal, "signal")
watch(threading.Thread, "start")


def handlers():
    return {s: signal.getsignal(s) for s in signal.valid_signals() if signal.getsignal(s) is not None}


before = (handlers(), sorted(t.name for t in threading.enumerate()))
import screening
modules = [m.name for m in pkgutil.walk_packages(screening.__path__, "screening.")]
for name in modules:
    importlib.import_module(name)
after = (handlers(), sorted(t.name for t in threading.enumerate()))
changed = {s: (before[0].get(s), h) for s, h in after[0].items() if before[0].get(s) != h}
print(len(modules), repr(changed), repr(by_screening), [t for t in after[1] if t not in before[1]])
"""


def test_importing_the_package_changes_no_signal_handler_exit_handler_or_thread():
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SCREENING_LOCAL_WORKER": "1"}
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    count, rest = out.stdout.split(" ", 1)
    assert int(count) >= 90, out.stdout                 # every module was imported
    assert rest.strip() == "{} [] []", out.stdout       # no handler changed, none set up by screening, no thread


def test_the_worker_setup_runs_as_a_dask_preload_only():
    """A worker of a local cluster ignores SIGINT through dask's preload hook, not through an import."""
    from screening.sweep import execution, interrupt

    assert execution.WORKER_SETUP == interrupt.__name__ and callable(interrupt.dask_setup)


#: Source modules without a test module of their own name, each with its reason.
UNTESTED = {
    "report.fragility_figures": "tested in tests/unit/report/test_figures.py",
    "report.spot_figures": "tested in tests/unit/report/test_figures.py",
    "report.record_figures": "tested through the commands in test_cli_records.py and test_cloud.py",
    "report.tradeoff_figures": "tested through run_tradeoff in test_tradeoff.py",
    "sweep.run": "run_sweep, tested in tests/integration/test_sweep.py",
    "cli.commands": "the commands, tested in tests/integration/test_cli.py",
    "cli.__main__": "python -m screening.cli, run in tests/integration/test_edges.py",
    "_version": "one constant, read as screening.__version__ in tests/unit/io/test_writer.py",
}


def test_every_source_module_has_a_test_module_of_its_own_name():
    """``a.b`` is tested by ``test_b.py`` or ``test_a_b.py``; a package-internal ``a._b`` by ``test_b.py``
    (:func:`import_graph.has_test_module`)."""
    tests = ig.test_modules()
    graph = ig.read_graph()
    modules = [m for m, p in graph.modules.items() if m and p.name != "__init__.py"]
    missing = sorted(m for m in modules if not ig.has_test_module(m, tests) and m not in UNTESTED)
    assert not missing, missing
    stale = sorted(m for m in UNTESTED if m not in modules or ig.has_test_module(m, tests))
    assert not stale, stale
