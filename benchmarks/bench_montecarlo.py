"""Wall time and step accuracy of the Monte Carlo engine (screening.solvers.montecarlo).

Run:  NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_montecarlo.py [--samples 1000] [--case 1]

Prints, for the coupled model and the condensed SDOF, the wall seconds of ``n`` samples x
20 s on one core after JIT warm-up (synthesis included), and the accuracy of the default
integration tolerance: the ensemble peak of ``var_theta`` (and ``var_theta_dot``) against
a run on the same samples with ``rtol / 32`` — for the 5th-order pair that is the step
halved — expressed in units of the sampling standard error.
"""

from __future__ import annotations

import argparse
import os
import time

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation  # noqa: E402
from screening.solvers.montecarlo import auto_rtol, monte_carlo  # noqa: E402

BLOCK = Block(m=8.67, b=0.035, h=0.21)
CASES = {
    1: (6e7, WhiteNoise(S0=2.4e-5, envelope=Envelope(4.0, 2.0))),
    2: (6e7, WhiteNoise(S0=2.4e-3, envelope=Envelope(4.0, 2.0))),
    3: (-6e5, WhiteNoise(S0=5e-4, envelope=Envelope(4.0, 2.0))),
    5: (6e7, KanaiTajimi(S0=2.5e-4, omega_g=10.0, zeta_g=0.4, envelope=Envelope(4.0, 2.0))),
}


def peak(ds, name):
    i = int(np.nanargmax(ds[name].values))
    return float(ds[name][i]), float(ds[name + "_se"][i]), float(ds.t[i])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--case", type=int, default=1, choices=sorted(CASES))
    parser.add_argument("--no-accuracy", action="store_true", help="skip the rtol/32 runs")
    args = parser.parse_args()
    eps, excitation = CASES[args.case]
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=eps)
    import numba
    print(f"numba threads: {numba.get_num_threads()}  case {args.case}: eps={eps:g}, {excitation.kind}, "
          f"S0={excitation.S0:g}; {args.samples} samples x 20 s; default rtol (auto) "
          f"{ {m: auto_rtol(m, args.samples) for m in ('coupled', 'condensed')} }")

    t0 = time.perf_counter()
    for model in ("coupled", "condensed"):
        monte_carlo(BLOCK, foundation, excitation, n_samples=2, model=model, t_end=0.5, progress=False)
    print(f"JIT warm-up (cache load or compile): {time.perf_counter() - t0:.1f} s")

    for model in ("coupled", "condensed"):
        t0 = time.perf_counter()
        ds = monte_carlo(BLOCK, foundation, excitation, n_samples=args.samples, model=model, progress=False)
        wall = time.perf_counter() - t0
        v, v_se, v_t = peak(ds, "var_theta")
        vd, vd_se, _ = peak(ds, "var_theta_dot")
        print(f"\n[{model}] wall {wall:.2f} s  (mean step {ds.attrs['dt_integration_mean'] * 1e3:.3f} ms, "
              f"min step {ds.attrs['dt_integration_min'] * 1e3:.4f} ms, overturned {int(ds.n_overturned)}, "
              f"diverged {int(ds.n_diverged)})")
        print(f"  peak var_theta     {v:.5e} rad2 at t={v_t:.2f} s  (SE {v_se:.2e})")
        print(f"  peak var_theta_dot {vd:.5e} rad2 s-2        (SE {vd_se:.2e})")
        if args.no_accuracy:
            continue
        t0 = time.perf_counter()
        fine = monte_carlo(BLOCK, foundation, excitation, n_samples=args.samples, model=model, progress=False,
                           rtol=ds.attrs["rtol"] / 32)
        wall_fine = time.perf_counter() - t0
        fv, _, _ = peak(fine, "var_theta")
        fvd, _, _ = peak(fine, "var_theta_dot")
        max_rel = float(np.nanmax(np.abs(fine.var_theta - ds.var_theta) / ds.var_theta.max()))
        print(f"  rtol/32 (~ step/2): wall {wall_fine:.2f} s, mean step {fine.attrs['dt_integration_mean'] * 1e3:.3f} ms")
        print(f"    peak var_theta     {fv:.5e}: change {abs(fv - v) / v:.2e} relative = {abs(fv - v) / v_se:.3f} SE")
        print(f"    peak var_theta_dot {fvd:.5e}: change {abs(fvd - vd) / vd:.2e} relative = {abs(fvd - vd) / vd_se:.3f} SE")
        print(f"    max_t |var_theta change| / peak = {max_rel:.2e}; "
              f"overturned {int(fine.n_overturned)}, diverged {int(fine.n_diverged)}")


if __name__ == "__main__":
    main()
