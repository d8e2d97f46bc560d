"""How well ``[accuracy] budget_s`` (wall seconds) bounds the accuracy stage on the real clock.

Runs a study (default ``studies/accuracy.toml``) at each ``--budget`` on ``--workers`` local workers and
prints, per budget: the stage's wall time measured around it (``timings["accuracy"]``, the Monte Carlo
kernels' compilation included) and as the stage measures it (``accuracy_wall_s``: from the compiled
kernels to the last run), their ratio to the budget, the points escalated / in the transition / cut by
the budget, the cost model's and the measured CPU seconds, and the first progress and plan lines.

    PYTHONPATH=$PWD NUMBA_NUM_THREADS=1 nice -n 10 .venv/bin/python benchmarks/accuracy_budget.py \\
        --budget 30 60 --workers 2
"""

import argparse
import io
import sys
import tempfile
import time
from pathlib import Path

from screening.sweep.study import load_study, parse_study
from screening.sweep.run import run_sweep


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default=str(Path(__file__).resolve().parents[1] / "studies" / "accuracy.toml"))
    ap.add_argument("--budget", type=float, nargs="+", default=[30.0, 60.0])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    text = Path(args.study).read_text()
    base = load_study(args.study)
    print(f"study {args.study}: {base.n_points} points, {args.workers} workers")
    print("budget_s | stage wall s (measured around) | accuracy_wall_s | ratio | escalated | transition | cut "
          "| cost-model CPU s | measured CPU s")
    for budget in args.budget:
        lines = [line for line in text.splitlines() if not line.startswith("budget_s")]
        at = lines.index("[accuracy]")
        lines.insert(at + 1, f"budget_s = {budget:g}")
        study = parse_study("\n".join(lines) + "\n", name=base.name)
        log, err = [], io.StringIO()
        with tempfile.TemporaryDirectory() as folder:
            stderr, sys.stderr = sys.stderr, err
            t0 = time.perf_counter()
            try:
                report = run_sweep(study, Path(folder) / "r.nc", workers=args.workers, progress=True,
                                   log=log.append)
            finally:
                sys.stderr = stderr
            total = time.perf_counter() - t0
        acc, stage = report.accuracy, report.timings["accuracy"]
        print(f"{budget:g} | {stage:.1f} | {acc['wall_s']:.1f} | {acc['wall_s'] / budget:.2f} | {acc['n_escalated']}"
              f" | {acc['n_transition']} | {acc['n_cut']} | {acc['cost_s']:.1f} | {acc['cpu_s']:.1f}   "
              f"(run {total:.0f} s; compiling the Monte Carlo kernels {acc['warm_up_s']:.0f} s)")
        progress = [x for x in err.getvalue().splitlines() if x.startswith("accuracy")]
        print("   plan:", next((m for m in log if m.startswith("accuracy:")), "-"))
        print(f"   progress lines: {len(progress)}; first: {progress[0] if progress else '-'}")
        print(f"   last: {progress[-1] if progress else '-'}")


if __name__ == "__main__":
    main()
