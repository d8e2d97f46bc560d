"""The write path of ``screening run``, traced: the modules of ``screening/io`` and ``screening/sweep`` the
client passes through, from the command until ``run_sweep`` returns (the result file closed and in place).

Run: ``python benchmarks/write_path.py [--list] [--study FILE]``.  A ``sys.setprofile`` hook on the client's
thread notes, at every call and return, the innermost frame of those folders; a *stop* is a change of that
module, a *return* a stop at a module already left before.  Three counts: every call (``all calls``), and each
call site's first trip only (``first trips``: a call from the same line to the same function of those folders
again, in a loop or for the next batch, is skipped with everything under it: the path a reader follows), and those
first trips with the property reads (``study.dims``) left out as attribute reads, not visits.  Also counted: the
calls against the layers, from ``io/`` up into ``sweep/`` or from another io module into the writer.  The default study is
the package's example (two points) with spot checks, ``[accuracy]`` and ``[fragility]``: every stage that
writes.  The run is in this process (``--workers 0``), netCDF, no figures; numba compiles on a first run.
"""

import argparse
import collections
import os
import sys
import tempfile
from pathlib import Path

FOLDERS = ("screening/io/", "screening/sweep/")

STUDY = """\
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = [0.0, 6e7]
[excitation]
kind = "white"
S0 = 1e-4
[time]
t_end = 2.0
dt = 0.05
[mcs]
points = "auto"
count = 1
samples = 20
[fragility]
thresholds = [0.01]
[accuracy]
target = 0.3
budget_s = 30
"""


def _module(filename):
    """``io/writer.py`` for a file of the two folders, else None."""
    for folder in FOLDERS:
        at = filename.find(folder)
        if at >= 0:
            return filename[at + len("screening/"):]
    return None


def _property_codes():
    """The code of every property getter of the classes in the two folders (an attribute read, not a visit)."""
    import functools
    import inspect

    codes = set()
    for name, module in list(sys.modules.items()):
        if not name.startswith(("screening.io", "screening.sweep")):
            continue
        for cls in [c for _, c in inspect.getmembers(module, inspect.isclass) if c.__module__ == name]:
            for attr in vars(cls).values():
                if isinstance(attr, property) and attr.fget is not None:
                    codes.add(attr.fget.__code__)
                elif isinstance(attr, functools.cached_property):
                    codes.add(attr.func.__code__)
    return codes


def trace(argv):
    """Run the CLI with ``argv`` under the hook; returns the stops of every call, of first trips, and of first
    trips without the property reads."""
    from screening.cli import commands
    from screening.sweep import run, study  # noqa: F401 (their classes' properties)
    from screening.io import writer  # noqa: F401

    every, first, lean, against = [], [], [], []
    seen_sites, skipping, reading, done = set(), [], [], []
    properties = _property_codes()

    def innermost(frame):
        while frame is not None:
            name = _module(frame.f_code.co_filename)
            if name is not None:
                return name
            frame = frame.f_back
        return None

    def stop(stops, here):
        if here is not None and (not stops or stops[-1] != here):
            stops.append(here)

    def hook(frame, event, arg):
        if done or event not in ("call", "return"):
            return
        here = innermost(frame if event == "call" else frame.f_back)
        if event == "return" and frame.f_code is run.run_sweep.__code__:
            done.append(True)
        stop(every, here)
        if event == "call" and _module(frame.f_code.co_filename) is not None:
            caller = frame.f_back
            site = (caller.f_code, caller.f_lineno, frame.f_code) if caller is not None else frame.f_code
            if not skipping and site in seen_sites:
                skipping.append(frame)
            seen_sites.add(site)
        if event == "call" and not skipping:
            caller, callee = innermost(frame.f_back), _module(frame.f_code.co_filename)
            if caller and callee and caller.startswith("io/") and callee != caller and (
                    callee.startswith("sweep/") or callee == "io/writer.py"):
                against.append((f"{caller}:{frame.f_back.f_code.co_name} -> {callee}:{frame.f_code.co_name}",
                                frame.f_code in properties))
        if not skipping:
            stop(first, here)
            if event == "call" and not reading and frame.f_code in properties:
                reading.append(frame)
            if not reading:
                stop(lean, here)
            if event == "return" and reading and reading[-1] is frame:
                reading.pop()
        if event == "return" and skipping and skipping[-1] is frame:
            skipping.pop()

    sys.setprofile(hook)
    try:
        commands.main(argv)
    except SystemExit as exc:
        if exc.code:
            raise
    finally:
        sys.setprofile(None)
    return every, first, lean, against


def _count(stops):
    """``(stops, modules, returns)``."""
    seen, returns = set(), 0
    for name in stops:
        returns += name in seen
        seen.add(name)
    return len(stops), len(seen), returns


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", help="a study file (default: the example with [mcs], [accuracy], [fragility])")
    parser.add_argument("--list", action="store_true", help="print the stops in order")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        study = Path(args.study) if args.study else Path(folder) / "write_path.toml"
        if not args.study:
            study.write_text(STUDY)
        out = Path(folder) / "r.nc"
        every, first, lean, against = trace(["run", str(study), "--out", str(out), "--workers", "0", "--no-plots", "--quiet"])
        assert out.exists(), "the run wrote no result"
    calls = sum(not read for _, read in against)
    print(f"against the layers (first trips): {calls} calls from io/ up into sweep/ or from another io module into "
          f"the writer, and {len(against) - calls} property reads of a sweep object by io/"
          + "".join(f"\n  {c}{' (property)' if read else ''}" for c, read in sorted(set(against)) if args.list))
    for label, path in (("all calls", every), ("first trips", first), ("first trips, property reads left out", lean)):
        n, modules, returns = _count(path)
        if args.list:
            print(f"{label}: " + " -> ".join(path))
        tail = _count(path[path.index("sweep/run.py"):])[2] if "sweep/run.py" in path else 0
        print(f"write path, {label}: {n} stops in {modules} modules, {returns} returns to a module already left "
              f"({tail} from run_sweep on, after the study is loaded)")
        print("  visits: " + ", ".join(f"{name} {k}" for name, k in collections.Counter(path).most_common()))


if __name__ == "__main__":
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    main()
