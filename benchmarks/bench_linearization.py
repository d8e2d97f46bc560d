"""Speed and accuracy of the stochastic-linearization solver on one core, per state size.

Run by hand:  .venv/bin/python benchmarks/bench_linearization.py [--points 10000] [--rtol 1e-8]
              [--reference-points 400] [--histories all|none]

Prints, for white noise (3 moments) and Kanai-Tajimi (10 moments), a batch of ``--points`` points
(eps x S0 over the paper's range, paper block and bed, 20 s records, dt 0.05 s): points per
second of CPU time on one core (``time.process_time``, best of ``--repeat``), mean steps per point,
and the relative error of peak var_theta against a tightly converged solution (rtol 1e-11, h_max
1e-3 s) on an evenly spaced subsample of ``--reference-points`` points (the reference costs ~20x
a point).  ``--histories none`` times the solver without the output histories (summaries only,
what a history-free screen runs).  The solver is single-threaded; parallelism comes from the
sweep layer.  Targets (issue 12): >= 5,000 white-noise and >= 2,000 Kanai-Tajimi points/s per
core with the peak error <= 1e-7.  Numbers on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from screening.core.model import Block, Foundation
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.solvers.moments import DEFAULT_RTOL, solve_moments
from screening.solvers.timegrid import output_times


def points(n):
    """Flat eps, S0 arrays of about ``n`` points over the paper's ranges."""
    side = int(round(np.sqrt(n)))
    eps, S0 = np.meshgrid(np.linspace(-6e5, 6e7, side), np.logspace(-6, np.log10(2.4e-3), side), indexing="ij")
    return eps.ravel(), S0.ravel()


def excitation(kind, S0):
    return WhiteNoise(S0) if kind == "white" else KanaiTajimi(S0, 15.6, 0.6)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--rtol", type=float, default=DEFAULT_RTOL)
    parser.add_argument("--reference-points", type=int, default=400)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--histories", choices=("all", "none"), default="all")
    args = parser.parse_args(argv)
    t = output_times(20.0, 0.05)
    block = Block(8.67, 0.035, 0.21)
    eps, S0 = points(args.points)
    n = eps.size
    store = args.histories == "all"

    t0 = time.perf_counter()
    solve_moments(block, Foundation(2.89e7, 8.95e8, eps[:2]), WhiteNoise(S0[:2]), t, rtol=args.rtol)
    print(f"first call (JIT load/compile): {time.perf_counter() - t0:.2f} s")
    print(f"rtol {args.rtol:g}, histories {args.histories}, {n} points, 20 s records, {t.size} output times")
    for kind, states in (("white", 3), ("kanai_tajimi", 10)):
        exc = excitation(kind, S0)
        fnd = Foundation(2.89e7, 8.95e8, eps)
        best = np.inf
        for _ in range(args.repeat):
            c0 = time.process_time()
            res = solve_moments(block, fnd, exc, t, rtol=args.rtol, histories=store)
            best = min(best, time.process_time() - c0)
        sub = np.unique(np.linspace(0, n - 1, min(args.reference_points, n)).astype(int))
        ref = solve_moments(block, Foundation(2.89e7, 8.95e8, eps[sub]), excitation(kind, S0[sub]), t, rtol=1e-11, h_max=1e-3,
                            histories=False)
        ok = (res["status"][sub] == 0) & (ref["status"] == 0)
        err = np.abs(res["peak_var_theta"][sub][ok] / ref["peak_var_theta"][ok] - 1)
        print(f"{kind:>12} ({states:2d} moments): {n / best:8.0f} points/s per core, "
              f"{best / n * 1e6:7.1f} us/point, mean {res['n_steps'].mean():.0f} steps/point "
              f"({best / res['n_steps'].sum() * 1e9:.0f} ns/step); peak var_theta rel. error vs rtol 1e-11 "
              f"({ok.sum()} points): max {err.max():.1e}, median {np.median(err):.1e}; "
              f"status counts {np.bincount(res['status'].ravel(), minlength=5).tolist()}")


if __name__ == "__main__":
    main()
