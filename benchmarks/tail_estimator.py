"""Subset simulation (screening.solvers.tail) against long crude Monte Carlo runs on the stiff-bed model.

The case: the statue (m = 1200 kg, b = 0.25 m, h = 0.9 m) on a stiff bed (k = 1e10 N/m3, 5 % vertical damping)
under a Kanai-Tajimi input (omega_g = 15.6 rad/s, zeta_g = 0.6) at S0 = 0.011 m2/s3, 20 s records, where
P(peak |theta| > 0.12 rad) ~ 2e-2 and P(overturn) ~ 2e-3 (measured by 40,000 crude samples).

``--crude N`` integrates N crude samples (chunks of 5,000, each its own seed) and appends their peaks to the
cache file (``--cache``; NaN diverged, inf overturned), so a long crude run can be spread over several calls.
Without it the script runs subset simulation ``--runs`` times (independent seeds) and prints, per probability:
the subset estimate, its CoV (Au & Beck, with the chain correlation) and the empirical CoV over the runs, the
crude estimate and its standard error from the cache, the crude sample count that would give the subset's CoV
at that probability, ``(1 - p) / (p cov^2)``, and the cost ratio (subset samples / that count; the CPU time per
sample of both is printed too: they run the same integrator on the same record).

Run (one numba thread)::

    flock /work/bench.lock nice -n 10 env PYTHONPATH=. NUMBA_NUM_THREADS=1 python benchmarks/tail_estimator.py --crude 100000
    flock /work/bench.lock nice -n 10 env PYTHONPATH=. NUMBA_NUM_THREADS=1 python benchmarks/tail_estimator.py --runs 4
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

if __name__ == "__main__":
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.analysis.beds import lam_from_vertical_damping  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.solvers.estimates import binomial_estimate  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402
from screening.solvers.tail import tail_probability  # noqa: E402

STATUE = Block(m=1200.0, b=0.25, h=0.9)
BED = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, STATUE.m, STATUE.b, 0.05)))
QUAKE = KanaiTajimi(S0=0.011, omega_g=15.6, zeta_g=0.6)
THRESHOLDS = (0.12,)                      # [rad]: P ~ 2e-2
CHUNK = 5000


def crude(n, cache):
    """Append ``n`` crude peaks to ``cache``; return the seconds per sample."""
    old = np.load(cache)["peak"] if os.path.exists(cache) else np.empty(0)
    start, peaks = time.process_time(), [old]
    for c in range(0, n, CHUNK):
        seed = 1000 + (old.size + c) // CHUNK
        ds = monte_carlo(STATUE, BED, QUAKE, n_samples=min(CHUNK, n - c), model="stiff_bed", seed=seed,
                         progress=False)
        pk = ds.peak_abs_theta.values.copy()
        pk[ds.overturned.values] = np.inf
        pk[ds.diverged.values] = np.nan
        peaks.append(pk)
        np.savez(cache, peak=np.concatenate(peaks), cpu_per_sample=(time.process_time() - start) / (c + pk.size))
        print(f"crude: {old.size + c + pk.size} samples, {(time.process_time() - start) / (c + pk.size) * 1e3:.2f} "
              f"ms CPU a sample", flush=True)


def crude_estimates(cache):
    data = np.load(cache)
    pk = data["peak"]
    pk = pk[~np.isnan(pk)]
    hits = [np.count_nonzero(np.isinf(pk))] + [np.count_nonzero(pk > t) for t in THRESHOLDS]
    p, se = binomial_estimate(np.array(hits), pk.size)
    return p, se, pk.size, float(data["cpu_per_sample"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--crude", type=int, default=0, help="crude samples to add to the cache")
    ap.add_argument("--cache", default="/tmp/tail_crude.npz")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--n-per-level", type=int, default=1000)
    ap.add_argument("--sampler", default="acs")
    ap.add_argument("--p0", type=float, default=0.1)
    args = ap.parse_args()
    warnings.simplefilter("ignore", UserWarning)
    if args.crude:
        crude(args.crude, args.cache)
        return
    names = ["P(overturn)"] + [f"P(|theta| > {t} rad)" for t in THRESHOLDS]
    est, cov, calls, cpu = [], [], [], []
    for r in range(args.runs):
        start = time.process_time()
        ds = tail_probability(STATUE, BED, QUAKE, thresholds=THRESHOLDS, model="stiff_bed",
                              n_per_level=args.n_per_level, p0=args.p0, seed=r, sampler=args.sampler,
                              progress=True)
        cpu.append((time.process_time() - start) / ds.attrs["n_model_runs"])
        est.append([float(ds.p_overturn), *ds.p_exceed.values])
        cov.append([float(ds.p_overturn_cov), *ds.p_exceed_cov.values])
        calls.append(ds.attrs["n_model_runs"])
        print(f"run {r}: {calls[-1]} samples, levels {np.round(ds.level_threshold.values, 4)}, gamma "
              f"{np.round(ds.level_gamma.values, 2)}, diverged {ds.attrs['n_diverged']}", flush=True)
    est, cov, n_ss = np.array(est), np.array(cov), float(np.mean(calls))
    p_c, se_c, n_c, cpu_c = crude_estimates(args.cache) if os.path.exists(args.cache) else (None,) * 4
    print(f"\nsubset: {args.runs} runs, {args.n_per_level} samples a level, p0 {args.p0:g} ({args.sampler}), {n_ss:.0f} samples a run, "
          f"{np.mean(cpu) * 1e3:.2f} ms CPU a sample; crude: {n_c} samples, "
          f"{cpu_c * 1e3 if cpu_c else float('nan'):.2f} ms CPU a sample")
    print(f"{'probability':<24}{'subset':>11}{'CoV':>7}{'CoV runs':>10}{'crude':>11}{'SE':>10}{'(p-c)/se':>10}"
          f"{'crude n at CoV':>16}{'cost ratio':>12}")
    for i, name in enumerate(names):
        p, c = est[:, i].mean(), cov[:, i].mean()
        spread = est[:, i].std(ddof=1) / p if args.runs > 1 else float("nan")
        need = (1.0 - p) / (p * c * c)
        line = f"{name:<24}{p:>11.3e}{c:>7.2f}{spread:>10.2f}"
        if p_c is not None:
            diff = (p - p_c[i]) / np.hypot(se_c[i], p * c / np.sqrt(args.runs))
            line += f"{p_c[i]:>11.3e}{se_c[i]:>10.1e}{diff:>10.2f}"
        print(line + f"{need:>16.0f}{n_ss / need:>12.3f}")


if __name__ == "__main__":
    main()
