"""Benchmark: the cost per point of the three condensations side by side, and the 100,000-point sweep
against a single-core prototype of the paper's method (issue 38).

    .venv/bin/python benchmarks/bench_condensations.py                 # both parts
    .venv/bin/python benchmarks/bench_condensations.py --part costs --points 2000 --repeat 5
    .venv/bin/python benchmarks/bench_condensations.py --part sweep --n 316 --repeat 3
    .venv/bin/python benchmarks/bench_condensations.py --part cpu --n 316 --repeat 2       # CPU seconds, loaded machines

Per point (``--part costs``): ``linearize`` (the solver with every history, as a user calls it, trust
columns included) and ``solve_moments(histories=False)`` (what a history-free sweep runs), on
``--points`` white-noise points (S0 from 1e-6 to 2.4e-3, 20 s records, the paper's block) on a
hardening (eps = 6e7) and a softening (eps = -6e5) bed, in CPU seconds of this process per point.
Each timed call starts without cached coefficient tables (a fresh process builds one per bed; that
cost is in the figures).  The condensations are timed in turn, the order rotated every repeat, and
the ratios to ``paper`` are taken within each repeat: the table gives the median ratio and the range
over the repeats.

End to end (``--part sweep``): the sweep of :mod:`bench_sweep` (``--n`` x ``--n`` points, histories
none, 2 workers, the default condensation, timed in a fresh process as ``screening run`` runs it)
against the prototype: the paper's method (``condensation = "paper"``) solved on one core in one
process, no dask, no I/O, on 5,000 points spread over the same grid.  The two are interleaved
``--repeat`` times and each sweep's rate is divided by the prototype rate measured just before it.

CPU model (``--part cpu``): the same comparison in CPU seconds, which a loaded machine distorts less
than the wall clock: each half of the sweep's batches solved by ``solve_batch`` in a fresh process, as
one of the 2 workers would (its first batch included), against the prototype's CPU time per point; the
rate of 2 workers is the points over the slower half's CPU time (no dask, no I/O, no tail).

The machine is shared (2 cores): the load average is printed with the figures.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

CONDENSATIONS = ("paper", "cubic", "virtual_work")
BEDS = (("hardening", 6e7), ("softening", -6e5))


def _load():
    return "load average " + " ".join(f"{v:.1f}" for v in os.getloadavg())


def point_costs(n_points, repeat):
    """``{(bed, measure, condensation): [seconds per point, one per repeat]}``."""
    from screening.core.condensation import quadrature
    from screening.core.model import Block, Foundation
    from screening.core.excitations.white import WhiteNoise
    from screening.analysis.linearization import linearize
    from screening.solvers.moments import solve_moments
    from screening.solvers.timegrid import output_times

    block = Block(8.67, 0.035, 0.21)
    S0 = np.logspace(-6, np.log10(2.4e-3), n_points)
    t = output_times(20.0, 0.05)
    measures = {
        "linearize": lambda fnd, name: linearize(block, fnd, WhiteNoise(S0, band_limit_hz=None), condensation=name),
        "solve (no histories)": lambda fnd, name: solve_moments(block, fnd, WhiteNoise(S0, band_limit_hz=None), t, condensation=name,
                                                                histories=False),
    }
    for name in CONDENSATIONS:                          # load (or compile) every solver first
        linearize(block, Foundation(2.89e7, 8.95e8, 6e7), WhiteNoise(S0[:2], band_limit_hz=None), condensation=name)
    out = {}
    for r in range(repeat):
        order = CONDENSATIONS[r % 3:] + CONDENSATIONS[:r % 3]
        for bed, eps in BEDS:
            fnd = Foundation(2.89e7, 8.95e8, eps)
            for measure, run in measures.items():
                for name in order:
                    quadrature._TABLES.clear()          # as in a fresh process: the bed's table is built
                    start = time.process_time()
                    run(fnd, name)
                    out.setdefault((bed, measure, name), []).append((time.process_time() - start) / n_points)
    return out


def print_costs(costs, n_points, repeat):
    print(f"cost per point, {n_points} white-noise points per call, CPU time, {repeat} repeats "
          f"(median [min - max]); ratio to paper within each repeat; {_load()}")
    print(f"{'bed':>10} {'measure':>22} " + " ".join(f"{name:>22}" for name in CONDENSATIONS)
          + " " + " ".join(f"{name + ' / paper':>24}" for name in CONDENSATIONS[1:]))
    worst = 0.0
    for bed, _ in BEDS:
        for measure in ("linearize", "solve (no histories)"):
            cells = []
            for name in CONDENSATIONS:
                v = np.array(costs[(bed, measure, name)]) * 1e3
                cells.append(f"{np.median(v):.3f} [{v.min():.3f}-{v.max():.3f}] ms")
            ratios = []
            paper = np.array(costs[(bed, measure, "paper")])
            for name in CONDENSATIONS[1:]:
                q = np.array(costs[(bed, measure, name)]) / paper
                worst = max(worst, float(np.median(q)))
                ratios.append(f"{np.median(q):.3f} [{q.min():.3f}-{q.max():.3f}]")
            print(f"{bed:>10} {measure:>22} " + " ".join(f"{c:>22}" for c in cells) + " "
                  + " ".join(f"{c:>24}" for c in ratios))
    print(f"largest median ratio to paper: {worst:.3f}  (target <= 1.15: {'PASS' if worst <= 1.15 else 'FAIL'})")


def sweep_against_prototype(side, repeat):
    """``[(sweep points/s, prototype points/s, timings)]``, interleaved."""
    import bench_sweep
    from screening.sweep.study import parse_study

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        study_path = Path(tmp) / "bench.toml"
        study_path.write_text(bench_sweep.STUDY.format(n=side, output=bench_sweep.OUTPUT["none"]))
        n_points = parse_study(study_path.read_text(), name="bench").n_points
        for _ in range(repeat):
            seconds = bench_sweep.single_core(side=side, histories=False, condensation="paper")
            prototype = bench_sweep.CHECK_POINTS / seconds
            wall, timings = bench_sweep.run_function(study_path, Path(tmp) / "bench.nc", 2, 1)
            rows.append((n_points / wall, prototype, timings))
            print(f"  sweep {n_points} points, 2 workers: {n_points / wall:7.0f} points/s end to end "
                  f"(compute phase {n_points / timings['compute']:.0f}); prototype (paper, one core): "
                  f"{prototype:6.0f} points/s; ratio {n_points / wall / prototype:.2f}; {_load()}", flush=True)
    return n_points, rows


def _cpu_half(side, part, queue):
    """CPU seconds of ``solve_batch`` over every other batch (from ``part``) of the sweep, in this fresh process."""
    import bench_sweep
    from screening.sweep._submit import trust_models
    from screening.sweep.execution import solve_batch, warm_up
    from screening.sweep.grid import batch_point_models, default_batch_size, plan_batches
    from screening.sweep.study import parse_study

    study = parse_study(bench_sweep.STUDY.format(n=side, output=bench_sweep.OUTPUT["none"]), name="bench")
    warm_up()
    start, n = time.process_time(), 0
    for batch in plan_batches(study, default_batch_size(study, 2))[part::2]:
        case = study.cases[batch.case]
        block, foundation, excitation, _ = batch_point_models(study, batch)
        solve_batch(block, foundation, excitation, case.condensation_model, study.times, study.rtol, study.max_steps,
                    study.output.stored, study.fragility, trust_models(case.condensation_model.name),
                    study.derived_inputs, None, case.cutoff, study.probabilities)
        n += batch.hi - batch.lo
    queue.put((n, time.process_time() - start))


def _cpu_prototype(side, queue):
    """CPU seconds of the prototype (``bench_sweep.single_core``'s work) in this fresh process."""
    import bench_sweep
    from screening.core.excitations.white import WhiteNoise
    from screening.core.model import Block, Foundation
    from screening.solvers.moments import solve_moments
    from screening.solvers.timegrid import output_times

    t = output_times(20.0, 0.05)
    flat = np.unique(np.linspace(0, side * side - 1, min(bench_sweep.CHECK_POINTS, side * side)).round().astype(int))
    i, j = np.unravel_index(flat, (side, side))
    models = (Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, np.linspace(-6e5, 6e7, side)[i]),
              WhiteNoise(np.geomspace(1e-5, 2.4e-3, side)[j], band_limit_hz=None))
    solve_moments(models[0], Foundation(2.89e7, 8.95e8), WhiteNoise(1e-5, band_limit_hz=None), t[:3], condensation="paper")
    start = time.process_time()
    solve_moments(*models, t, histories=False, condensation="paper")
    queue.put((flat.size, time.process_time() - start))


def cpu_model(side, repeat):
    """Print, ``repeat`` times: the prototype's and each half's points per CPU second, and their ratio."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    for _ in range(repeat):
        out = []
        for target, args in ((_cpu_prototype, (side,)), (_cpu_half, (side, 0)), (_cpu_half, (side, 1))):
            queue = ctx.Queue()
            proc = ctx.Process(target=target, args=(*args, queue))
            proc.start()
            out.append(queue.get())
            proc.join()
        (n0, c0), (na, ca), (nb, cb) = out
        sweep = (na + nb) / max(ca, cb)
        print(f"  CPU model: prototype {n0 / c0:.0f} points per CPU s; halves {na / ca:.0f}, {nb / cb:.0f}; "
              f"2 workers {sweep:.0f} points/s; ratio {sweep / (n0 / c0):.2f}; {_load()}", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=("costs", "sweep", "both", "cpu"), default="both")
    parser.add_argument("--points", type=int, default=2000, help="points per timed call (costs)")
    parser.add_argument("--repeat", type=int, default=3, help="interleaved repeats")
    parser.add_argument("--n", type=int, default=316, help="values per swept parameter (sweep; 316: 99,856 points)")
    args = parser.parse_args(argv)
    if args.part in ("costs", "both"):
        print_costs(point_costs(args.points, args.repeat), args.points, args.repeat)
    if args.part in ("sweep", "both"):
        print(f"end to end: sweep (default condensation, histories none, 2 workers) against the single-core "
              f"prototype of the paper's method, {args.repeat} interleaved runs")
        n_points, rows = sweep_against_prototype(args.n, args.repeat)
        ratios = [sweep / prototype for sweep, prototype, _ in rows]
        rates = [sweep for sweep, _, _ in rows]
        print(f"{n_points} points: {statistics.median(rates):.0f} points/s end to end (median; "
              f"{min(rates):.0f}-{max(rates):.0f}); sweep / prototype {statistics.median(ratios):.2f} "
              f"(median; {min(ratios):.2f}-{max(ratios):.2f})  (target >= 1.5: "
              f"{'PASS' if statistics.median(ratios) >= 1.5 else 'FAIL'})")
    if args.part == "cpu":
        print(f"CPU model of the sweep ({args.n} x {args.n} points) against the prototype, {args.repeat} runs")
        cpu_model(args.n, args.repeat)


if __name__ == "__main__":
    main()
