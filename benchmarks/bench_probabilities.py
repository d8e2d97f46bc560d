"""Worker cost of the probabilities of a sweep point (docs/outputs_probabilities.md).

Run::

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python \\
        benchmarks/bench_probabilities.py [--points 200]

Prints the wall time of one batch task (:func:`screening.workflow.execution.solve_batch`) of the paper
block over an eps x S0 grid (20 s records, 0.05 s output, all histories): plain (every sweep: the
linearization, trust, intensity measures and ``p_rocking_start``), with ``p_overturn`` (``[accuracy]``),
and with ``p_overturn`` and two ``[fragility]`` thresholds; and the first-call cost of the crossing
tables of ``p_rocking_start`` (one per distinct input and band limit).  Best of three runs each.
"""

from __future__ import annotations

import argparse
import time

STUDY = """
title = "probabilities cost"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = {{start = -6e5, stop = 6e7, num = 10}}
[excitation]
kind = "white"
S0 = {{start = 1e-5, stop = 2.4e-3, num = {n_s0}, log = true}}
[time]
t_end = 20.0
dt = 0.05
[fragility]
thresholds = [0.1, 0.5]
relative_to = "slenderness"
"""


def main():
    from screening.analysis.trust import shipped_table
    from screening.workflow.execution import batch_rocking_start, solve_batch
    from screening.workflow.grid import batch_models, plan_batches
    from screening.workflow.study import parse_study

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=200, help="points of the batch (a multiple of 10)")
    args = parser.parse_args()
    study = parse_study(STUDY.format(n_s0=max(args.points // 10, 1)))
    batch = plan_batches(study, study.n_points)[0]
    models = batch_models(study, batch)
    cond = study.cases[0].condensation_model
    start = time.perf_counter()
    batch_rocking_start(*models, cond, study.times, batch.size)
    print(f"p_rocking_start crossing tables, first call: {time.perf_counter() - start:.3f} s "
          f"for 10 beds (10 band limits)")
    table = shipped_table()
    base = (*models, cond, study.times, study.rtol, study.max_steps, study.output.stored)
    solve_batch(*base, None, table)                                  # compile and warm the caches
    for label, fragility, probabilities in (("plain", None, False), ("with p_overturn", None, True),
                                            ("with p_overturn and 2 thresholds", study.fragility, True)):
        times = []
        for _ in range(3):
            start = time.perf_counter()
            solve_batch(*base, fragility, table, (), probabilities)
            times.append(time.perf_counter() - start)
        print(f"{label:<34} {min(times):.3f} s per {batch.size}-point batch")


if __name__ == "__main__":
    main()
