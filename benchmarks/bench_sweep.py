"""Benchmark: a 10,000-point white-noise sweep (100 eps x 100 S0, 20 s records) end to end.

Runs the sweep exactly as ``screening run`` does (:func:`screening.sweep.run.run_sweep`, timed in
a fresh process: local dask cluster, batches, streaming netCDF write, atomic rename) with 1 and then 2 worker
processes, and prints points per second end to end, the 1 -> 2 worker scaling, and where
the time goes: cluster start-up, worker warm-up (imports + loading the numba cache),
the compute phase (batches solved and streamed to disk; the client's write time inside it
is shown separately), finalisation, shutdown; plus the PNG figures once.

    .venv/bin/python benchmarks/bench_sweep.py            # sweep function, 1 and 2 workers
    .venv/bin/python benchmarks/bench_sweep.py --cli      # through the `screening run` console script
    .venv/bin/python benchmarks/bench_sweep.py --n 50 --repeat 2 --complevel 0
    .venv/bin/python benchmarks/bench_sweep.py --n 316 --histories none --workers 2   # 100,000 points, 2 workers
    .venv/bin/python benchmarks/bench_sweep.py --rss 100,316,1000 --histories none   # peak RSS vs points

``--histories none`` adds ``[output] histories = "none"`` (summaries only).  The end-to-end rate is
also given as a ratio to the single-core solver rate measured in the same run (the same solver
work in one process, no dask, no I/O).  ``--rss`` runs 2 workers at each grid side given and
prints the peak resident memory of the client and of the largest worker process (psutil,
sampled every 0.1 s), the client's growth in bytes per added point (the summary arrays it keeps
are ~10 bytes per point) and writes ``outputs/cost_curve.png``.

Targets: >= 1,000 points/s end to end with 2 workers; >= 1.5x from 1 to 2 workers.
The machine should be otherwise idle (2 cores): numbers on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STUDY = """
title = "benchmark: {n} eps x {n} S0, modulated white noise, 20 s"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = {{start = -6e5, stop = 6e7, num = {n}}}
[excitation]
kind = "white"
band_limit_hz = "none"      # the paper's idealized input (the prototype's); the band's cost: band_order_cost.py
S0 = {{start = 1e-5, stop = 2.4e-3, num = {n}, log = true}}
[time]
t_end = 20.0
dt = 0.05
{output}"""

#: Points of the grid the single-core solver rate is measured on (evenly spread over the flattened grid).
CHECK_POINTS = 5000

PHASES = ("cluster_start", "warm_up", "compute", "write", "finalize", "shutdown")


def jit_in_this_process():
    """Import the solver and run it once (compiles only if the on-disk numba cache is stale) [s]."""
    start = time.perf_counter()
    from screening.sweep.execution import warm_up

    warm_up()
    return time.perf_counter() - start


def _solve_share(n, side, queue, histories=True, condensation=None):
    """Solve ``n`` points evenly spread over the flattened ``side`` x ``side`` benchmark grid (the same mix of
    cheap and costly points as the sweep) in this process, with ``condensation`` (default: the package's);
    put the time taken [s]."""
    import numpy as np

    from screening.core.excitations.white import WhiteNoise
    from screening.core.condensation import DEFAULT_CONDENSATION
    from screening.solvers.moments import solve_moments
    from screening.core.model import Block, Foundation
    from screening.solvers.timegrid import output_times

    t = output_times(20.0, 0.05)
    flat = np.unique(np.linspace(0, side * side - 1, min(n, side * side)).round().astype(int))
    i, j = np.unravel_index(flat, (side, side))
    models = (Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, np.linspace(-6e5, 6e7, side)[i]),
              WhiteNoise(np.geomspace(1e-5, 2.4e-3, side)[j], band_limit_hz=None))
    condensation = condensation or DEFAULT_CONDENSATION
    solve_moments(models[0], Foundation(2.89e7, 8.95e8), WhiteNoise(1e-5, band_limit_hz=None), t[:3], condensation=condensation)  # JIT cache
    start = time.perf_counter()
    solve_moments(*models, t, histories=histories, condensation=condensation)
    queue.put(time.perf_counter() - start)


def single_core(n=CHECK_POINTS, side=100, histories=True, condensation=None):
    """Seconds to solve ``n`` points of the ``side`` x ``side`` grid in one fresh process (no dask, no I/O)
    with ``condensation`` (default: the package's; ``"paper"``: the single-core prototype of the paper's method)."""
    import multiprocessing as mp

    queue = mp.get_context("spawn").Queue()
    proc = mp.get_context("spawn").Process(target=_solve_share, args=(n, side, queue, histories, condensation))
    proc.start()
    seconds = queue.get()
    proc.join()
    return seconds


def machine_scaling(n=CHECK_POINTS, side=100, histories=True):
    """The same solver work in 1 process, then in 2 concurrent processes (no dask, no I/O).

    Returns ``(t1, t2, ratio)``: seconds for ``n`` points of the ``side`` x ``side`` grid alone, the slower of two concurrent
    ``n``-point runs, and ``2 t1 / t2`` -- the best speed-up this machine can give 2 workers now.
    """
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    times = []
    for n_proc in (1, 2):
        queue = ctx.Queue()
        procs = [ctx.Process(target=_solve_share, args=(n, side, queue, histories)) for _ in range(n_proc)]
        for p in procs:
            p.start()
        times.append(max(queue.get() for _ in procs))
        for p in procs:
            p.join()
    return times[0], times[1], 2 * times[0] / times[1]


class RssSampler:
    """Peak RSS [bytes] of this process and of its child processes (the local cluster), sampled."""

    def __init__(self, period=0.1):
        import threading

        import psutil

        self.me = psutil.Process()
        self.client = 0
        self.worker = 0
        self.period = period
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        import psutil

        while not self._stop.is_set():
            try:
                self.client = max(self.client, self.me.memory_info().rss)
                for child in self.me.children(recursive=True):
                    try:
                        self.worker = max(self.worker, child.memory_info().rss)
                    except psutil.Error:
                        pass
            except psutil.Error:
                pass
            self._stop.wait(self.period)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def rss_curve(sides, histories, complevel, tmp):
    """Peak RSS of client and workers and points/s for 2 workers at each grid side; table + PNG."""
    from screening.sweep.study import parse_study

    rows = []
    for side in sides:
        study = parse_study(STUDY.format(n=side, output=OUTPUT[histories]), name="bench")
        out = tmp / f"rss-{side}.nc"
        with RssSampler() as rss:
            wall, _ = sweep_here(study, out, 2, complevel)
        rows.append((study.n_points, wall, rss.client, rss.worker, out.stat().st_size))
        out.unlink()
        print(f"{study.n_points:>9} points: {study.n_points / wall:7.0f} points/s, peak RSS client "
              f"{rss.client / 2**20:7.1f} MiB, largest worker {rss.worker / 2**20:7.1f} MiB, file "
              f"{rows[-1][4] / 2**20:.1f} MiB", flush=True)
    base = rows[0]
    for n, _, client, worker, _ in rows[1:]:
        print(f"  {n} vs {base[0]} points: client RSS x{client / base[2]:.2f} "
              f"({(client - base[2]) / (n - base[0]):.0f} bytes per added point), worker RSS x{worker / base[3]:.2f}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        n = [r[0] for r in rows]
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.5))
        a1.plot(n, [r[2] / 2**20 for r in rows], "o-", label="client")
        a1.plot(n, [r[3] / 2**20 for r in rows], "s-", label="largest worker")
        a1.set(xscale="log", xlabel="points", ylabel="peak RSS [MiB]", title=f"histories = {histories}")
        a1.legend()
        a2.plot(n, [r[0] / r[1] for r in rows], "o-")
        a2.set(xscale="log", xlabel="points", ylabel="points/s (2 workers, end to end)")
        fig.tight_layout()
        png = Path(__file__).resolve().parents[1] / "outputs" / "cost_curve.png"
        png.parent.mkdir(exist_ok=True)
        fig.savefig(png, dpi=100)
        print(f"cost curve: {png}")
    except ImportError:
        pass


OUTPUT = {"all": "", "none": '[output]\nhistories = "none"\n'}


def sweep_here(study, out, workers, complevel):
    """``run_sweep`` in this process: ``(wall [s], timings)``."""
    from screening.sweep.run import run_sweep

    start = time.perf_counter()
    report = run_sweep(study, out, workers=workers, force=True, progress=False, log=lambda *_: None,
                       complevel=complevel)
    wall = time.perf_counter() - start
    assert report.status_counts.get("ok", 0) > 0 and report.n_failed_batches == 0
    return wall, {**report.timings, "batches": report.n_batches}


def _run_sweep_child(study_path, out, workers, complevel, queue):
    """Time ``run_sweep`` in this fresh process: its imports done, its solvers not yet loaded -- the
    state of the ``screening run`` client when it starts the cluster (its workers are forked from it)."""
    from screening.sweep.study import parse_study

    study = parse_study(Path(study_path).read_text(), name="bench", source=str(study_path))
    queue.put(sweep_here(study, out, workers, complevel))


def run_function(study_path, out, workers, complevel):
    """``run_sweep`` timed in a fresh process (see :func:`_run_sweep_child`): ``(wall [s], timings)``."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_run_sweep_child, args=(str(study_path), str(out), workers, complevel, queue))
    proc.start()
    result = queue.get()
    proc.join()
    return result


def run_cli(study_path, out, workers, complevel):
    exe = Path(sys.executable).parent / "screening"
    start = time.perf_counter()
    subprocess.run([str(exe), "run", str(study_path), "--out", str(out), "--workers", str(workers), "--force",
                    "--no-plots", "--quiet", "--complevel", str(complevel)], check=True, capture_output=True)
    return time.perf_counter() - start, {}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100, help="values per swept parameter (default 100)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per worker count; the fastest is kept")
    parser.add_argument("--cli", action="store_true", help="time the `screening run` console script instead")
    parser.add_argument("--complevel", type=int, default=1, help="zlib level of the file (default 1; 0 = none)")
    parser.add_argument("--histories", choices=("all", "none"), default="all", help="[output] histories")
    parser.add_argument("--rss", help="comma-separated grid sides: peak RSS and points/s per size, 2 workers")
    parser.add_argument("--workers", default="1,2", help="comma-separated worker counts to run (default 1,2)")
    args = parser.parse_args(argv)

    from screening.sweep.study import parse_study

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if args.rss:
            jit_in_this_process()
            rss_curve([int(v) for v in args.rss.split(",")], args.histories, args.complevel, tmp)
            return
        study_path = tmp / "bench.toml"
        study_path.write_text(STUDY.format(n=args.n, output=OUTPUT[args.histories]))
        study = parse_study(study_path.read_text(), name="bench", source=str(study_path))
        out = tmp / "bench.nc"
        n_points = study.n_points
        print(f"{n_points} points x {study.times.size} output times; "
              f"{'console script' if args.cli else 'run_sweep()'}; zlib level {args.complevel}; "
              f"best of {args.repeat}")
        print(f"numba: import + first call in this process (compiles only if the cache is stale): "
              f"{jit_in_this_process():.2f} s")
        t1, t2, ratio = machine_scaling(side=args.n, histories=args.histories == "all")
        single_core = CHECK_POINTS / t1
        print(f"machine check, solver only (no dask, no I/O): {CHECK_POINTS} points of the grid in {t1:.2f} s alone "
              f"({single_core:.0f} points/s on one core), {t2:.2f} s with 2 processes side by side -> at most "
              f"{ratio:.2f}x from 2 workers on this machine now")
        rows = {}
        for workers in sorted({int(v) for v in args.workers.split(",")}):
            best = None
            for _ in range(args.repeat):
                wall, timings = (run_cli(study_path, out, workers, args.complevel) if args.cli
                                 else run_function(study_path, out, workers, args.complevel))
                if best is None or wall < best[0]:
                    best = (wall, timings)
            rows[workers] = best
            size = out.stat().st_size / 1e6
        print(f"result file: {size:.1f} MB")
        header = f"{'workers':>7} {'total':>7} {'pts/s':>7} " + " ".join(f"{p:>13}" for p in PHASES) \
            + f" {'compute pts/s':>13} {'batches':>7}"
        print(header)
        for workers, (wall, t) in rows.items():
            phases = " ".join(f"{t[p]:>12.2f}s" if p in t else f"{'-':>13}" for p in PHASES)
            compute_rate = f"{n_points / t['compute']:>13.0f}" if t else f"{'-':>13}"
            print(f"{workers:>7} {wall:>6.2f}s {n_points / wall:>7.0f} {phases} {compute_rate} "
                  f"{t.get('batches', '-'):>7}")
        if 2 in rows:
            w2, t2 = rows[2]
            rate = n_points / w2
            print(f"end to end, 2 workers: {rate:.0f} points/s  (target >= 1000: {'PASS' if rate >= 1000 else 'FAIL'})")
            print(f"end to end, 2 workers / single-core solver rate: {rate / single_core:.2f}  "
                  f"(target >= 1.6: {'PASS' if rate / single_core >= 1.6 else 'FAIL'})")
            if t2:
                fixed = t2["cluster_start"] + t2["warm_up"] + t2["finalize"] + t2["shutdown"]
                print(f"2 workers: fixed costs (start-up, warm-up, finalize, shutdown) {fixed:.2f} s = "
                      f"{100 * fixed / w2:.0f} % of the total; client write time {t2['write']:.2f} s "
                      f"(overlaps the compute phase)")
        if 1 in rows and 2 in rows:
            (w1, t1), (w2, t2) = rows[1], rows[2]
            scaling = w1 / w2
            print(f"scaling 1 -> 2 workers, end to end: {scaling:.2f}x  "
                  f"(target >= 1.5: {'PASS' if scaling >= 1.5 else 'FAIL'})")
            if t1 and t2:
                print(f"scaling 1 -> 2 workers, compute phase: {t1['compute'] / t2['compute']:.2f}x")
        if not args.cli:
            from screening.report.figures import plot_result
            from screening.io.reader import open_result

            start = time.perf_counter()
            with open_result(out) as ds:
                plot_result(ds, "bench", tmp)
            print(f"PNG figures (not in the totals above): {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
