"""Where a cold start's compiling goes: a study run in this process (``--workers 0``) on an empty numba cache,
numba's compile events timed per kernel.

Prints the run's wall time, then each compiled function with its compile seconds (a caller's time includes the
compiling of what it calls on first use) and how many signatures it compiled::

    nice -n 5 env PYTHONPATH=. python benchmarks/compile_profile.py run examples/collection.toml --workers 0 \\
        --out /tmp/compile_profile.nc --quiet --no-plots

The arguments are ``screening``'s (any command).
"""

from __future__ import annotations

import collections
import os
import sys
import tempfile
import time

if __name__ == "__main__":   # as a script only: a cache of its own, one thread
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="numba_cold_")
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from numba.core import event  # noqa: E402


class CompileTimes(event.Listener):
    """Seconds of numba's ``numba:compile`` events per function (``module.qualname``)."""

    def __init__(self):
        self.started, self.seconds, self.count = {}, collections.Counter(), collections.Counter()

    def on_start(self, ev):
        self.started[id(ev.data["dispatcher"]), str(ev.data["args"])] = time.perf_counter()

    def on_end(self, ev):
        dispatcher = ev.data["dispatcher"]
        began = self.started.pop((id(dispatcher), str(ev.data["args"])), None)
        if began is not None:
            name = f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"
            self.seconds[name] += time.perf_counter() - began
            self.count[name] += 1


def main(argv):
    times = CompileTimes()
    event.register("numba:compile", times)
    start = time.perf_counter()
    from screening.cli import main as screening

    status = screening(argv)
    print(f"screening {' '.join(argv)}: exit {status}, {time.perf_counter() - start:.1f} s wall, numba cache "
          f"{os.environ.get('NUMBA_CACHE_DIR')}")
    print("compile [s]  signatures  function")
    for name, seconds in times.seconds.most_common(25):
        print(f"{seconds:11.2f}  {times.count[name]:10d}  {name}")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
