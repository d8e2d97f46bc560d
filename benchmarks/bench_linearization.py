"""Speed and accuracy of the stochastic-linearization solver on one core.

Run by hand:  .venv/bin/python benchmarks/bench_linearization.py [--points 10000] [--rtol 1e-7]

Prints: seconds for one 20 s record at one point (warm JIT), points per second for a batch
of white-noise points (100 eps x 100 S0 over the paper's range, paper block and bed), and
the accuracy of peak var_theta against a tightly converged solution (rtol 1e-11, h_max
1e-3 s).  The solver is single-threaded; parallelism comes from the sweep layer.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from screening.model.cases import paper_case
from screening.solvers.moments import DEFAULT_RTOL, solve_moments
from screening.model import Block, Foundation
from screening.model.excitation import WhiteNoise
from screening.solvers.timegrid import output_times


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--rtol", type=float, default=DEFAULT_RTOL)
    args = parser.parse_args(argv)
    t = output_times(20.0, 0.05)

    t0 = time.perf_counter()
    solve_moments(*paper_case("fig3_white_hardening_high"), t, rtol=args.rtol)
    print(f"first call (JIT load/compile): {time.perf_counter() - t0:.2f} s")

    for name in ("fig3_white_hardening_high", "fig7_kt_hardening_high"):
        reps = 50
        t0 = time.perf_counter()
        for _ in range(reps):
            one = solve_moments(*paper_case(name), t, rtol=args.rtol)
        per = (time.perf_counter() - t0) / reps
        ref = solve_moments(*paper_case(name), t, rtol=1e-11, h_max=1e-3)
        err = abs(one["peak_var_theta"] / ref["peak_var_theta"] - 1)
        print(f"one point, {name}: {per * 1e3:.2f} ms per 20 s record, "
              f"{int(one['n_steps'])} steps, peak var_theta rel. error {err:.1e}")

    side = int(round(np.sqrt(args.points)))
    eps = np.linspace(-6e5, 6e7, side)[:, None]
    S0 = np.logspace(-6, np.log10(2.4e-3), side)[None, :]
    block, fnd, exc = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, eps), WhiteNoise(S0)
    t0 = time.perf_counter()
    res = solve_moments(block, fnd, exc, t, rtol=args.rtol)
    elapsed = time.perf_counter() - t0
    ref = solve_moments(block, fnd, exc, t, rtol=1e-11, h_max=1e-3)
    ok = (res["status"] == 0) & (ref["status"] == 0)
    err = np.abs(res["peak_var_theta"][ok] / ref["peak_var_theta"][ok] - 1)
    print(f"batch of {side * side} white-noise points: {elapsed:.2f} s, "
          f"{side * side / elapsed:.0f} points/s on one core, "
          f"mean {res['n_steps'].mean():.0f} steps/point; "
          f"peak var_theta rel. error max {err.max():.1e}, median {np.median(err):.1e}; "
          f"status counts {np.bincount(res['status'].ravel(), minlength=5).tolist()}")


if __name__ == "__main__":
    main()
