"""Worker cost of the probabilities of a sweep point (docs/outputs_probabilities.md).

Run::

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python \\
        benchmarks/bench_probabilities.py

Prints the wall time of one batch task (:func:`screening.sweep.execution.solve_batch`) of the whole grid
of ``studies/quick.toml`` (paper block, 10 x 10 eps x S0, 20 s records, 0.05 s output, all histories):
plain (every sweep: the linearization, trust, intensity measures and ``p_rocking_start``), with
``p_overturn`` (``[accuracy]``), and with ``p_overturn`` and two ``[fragility]`` thresholds; and the
first-call cost of the crossing tables of ``p_rocking_start`` (one per distinct input and band limit).  Best of three runs each.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

#: The quick study (100 points) with two ``[fragility]`` thresholds.
FRAGILITY = '\n[fragility]\nthresholds = [0.1, 0.5]\nrelative_to = "slenderness"\n'


def main():
    from screening.analysis.trust import trust_models
    from screening.sweep.execution import batch_rocking_start, solve_batch
    from screening.sweep.grid import batch_models, plan_batches
    from screening.sweep.study import parse_study

    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    source = Path(__file__).resolve().parent.parent / "studies" / "quick.toml"
    study = parse_study(source.read_text() + FRAGILITY, source=str(source))
    batch = plan_batches(study, study.n_points)[0]
    models = batch_models(study, batch)
    cond = study.cases[0].condensation_model
    start = time.perf_counter()
    batch_rocking_start(*models, cond, study.times, batch.size)
    print(f"p_rocking_start crossing tables, first call: {time.perf_counter() - start:.3f} s "
          f"for 10 beds (10 band limits)")
    table = trust_models(cond.name)
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
