"""Subset simulation (screening.solvers.tail) against long crude Monte Carlo runs on the stiff-bed model.

The case: the statue (m = 1200 kg, b = 0.25 m, h = 0.9 m) on a stiff bed (k = 1e10 N/m3, 5 % vertical damping)
under a Kanai-Tajimi input (omega_g = 15.6 rad/s, zeta_g = 0.6, the default 25 Hz band) at S0 = 0.011 m2/s3,
20 s records, where P(peak |theta| > 0.12 rad) ~ 1.5e-2 and P(overturn) ~ 1.4e-3 (100,000 crude samples of
``--model stiff_bed_fast``, the default; docs/tail.md).

``--crude N`` integrates N crude samples of ``--model`` (chunks of 5,000, each its own seed) and appends their
peaks to the cache file (``--cache``, one per model; NaN diverged, inf overturned), so a long crude run can be
spread over several calls.  ``--roughness`` prints how far one chain step moves the peak, by its spread.
Without it the script runs subset simulation ``--runs`` times (independent seeds) and prints, per probability:
the subset estimate, its CoV (Au & Beck, with the chain correlation) and the empirical CoV over the runs, the
crude estimate and its standard error from the cache, the crude sample count that would give the subset's CoV
at that probability, ``(1 - p) / (p cov^2)``, and the cost ratio (subset samples / that count; the CPU time per
sample of both is printed too: they run the same integrator on the same record), then the same ratio at the
runs' CoV (the honest one: Au & Beck's neglects the correlation between levels).

Run (one numba thread)::

    flock /work/bench.lock nice -n 10 env PYTHONPATH=. NUMBA_NUM_THREADS=1 python benchmarks/tail_estimator.py --crude 100000
    flock /work/bench.lock nice -n 10 env PYTHONPATH=. NUMBA_NUM_THREADS=1 python benchmarks/tail_estimator.py --runs 4
    flock /work/bench.lock nice -n 10 env PYTHONPATH=. NUMBA_NUM_THREADS=1 python benchmarks/tail_estimator.py --roughness
"""

from __future__ import annotations

import argparse
import math
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
from screening.solvers.montecarlo import monte_carlo, sample_setup  # noqa: E402
from screening.solvers.tail import _model_response, tail_probability  # noqa: E402

STATUE = Block(m=1200.0, b=0.25, h=0.9)
BED = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, STATUE.m, STATUE.b, 0.05)))
QUAKE = KanaiTajimi(S0=0.011, omega_g=15.6, zeta_g=0.6)
THRESHOLDS = (0.12,)                      # [rad]: P ~ 2e-2
CHUNK = 5000


def crude(n, cache, model):
    """Append ``n`` crude peaks of ``model`` to ``cache``; return the seconds per sample."""
    old = np.load(cache)["peak"] if os.path.exists(cache) else np.empty(0)
    start, peaks = time.process_time(), [old]
    for c in range(0, n, CHUNK):
        seed = 1000 + (old.size + c) // CHUNK
        ds = monte_carlo(STATUE, BED, QUAKE, n_samples=min(CHUNK, n - c), model=model, seed=seed,
                         progress=False)
        pk = ds.peak_abs_theta.values.copy()
        pk[ds.overturned.values] = np.inf
        pk[ds.diverged.values] = np.nan
        peaks.append(pk)
        np.savez(cache, peak=np.concatenate(peaks), cpu_per_sample=(time.process_time() - start) / (c + pk.size))
        print(f"crude: {old.size + c + pk.size} samples, {(time.process_time() - start) / (c + pk.size) * 1e3:.2f} "
              f"ms CPU a sample", flush=True)


def roughness(model, rtol=None, n=1000, n_seeds=100, seed=5):
    """How the peak moves under the chains' proposal ``sqrt(1 - s^2) U + s Z`` from the ``n_seeds`` largest of
    ``n`` samples: the share of candidates above the seeds' threshold (the acceptance) and the spread of
    ``log(peak)`` between seed and candidate, for spreads ``s`` from 1e-6 (a phase moved by ~2.5e-6 rad) to 1."""
    run = sample_setup(STATUE, BED, QUAKE, n, model, 20.0, 0.05, **({} if rtol is None else {"rtol": rtol}))
    response, dim = _model_response(run), run.read_plan.n_frequencies
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, dim))
    y = np.nan_to_num(response(u), nan=-1.0)
    top = np.argsort(y)[::-1]
    b, u, y = y[top[n_seeds]], u[top[:n_seeds]], y[top[:n_seeds]]
    print(f"{model}, rtol {run.opts['rtol']:g}: {dim} phases; level threshold {b:.4f} rad (top {n_seeds} of {n})")
    print(f"{'spread':>8}{'acceptance':>12}{'median |dlog peak|':>20}{'share |dlog peak| > 0.5':>25}")
    for s in (1e-6, 1e-4, 1e-2, 0.1, 0.3, 1.0):
        y_c = response(math.sqrt(1.0 - s * s) * u + s * rng.standard_normal(u.shape))
        ok = np.isfinite(y) & np.isfinite(y_c)
        change = np.abs(np.log(y_c[ok] / y[ok]))
        print(f"{s:>8.0e}{np.mean(np.nan_to_num(y_c, nan=-1.0) > b):>12.2f}{np.median(change):>20.3f}"
              f"{np.mean(change > 0.5):>25.2f}", flush=True)


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
    ap.add_argument("--model", default="stiff_bed_fast", help="the Monte Carlo model of both estimators")
    ap.add_argument("--cache", default=None, help="crude peaks (default /tmp/tail_crude_MODEL.npz)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--n-per-level", type=int, default=1000)
    ap.add_argument("--sampler", default="acs")
    ap.add_argument("--p0", type=float, default=0.1)
    ap.add_argument("--seed0", type=int, default=0, help="seed of the first run (run r: seed0 + r)")
    ap.add_argument("--rtol", type=float, default=None, help="the integrator's tolerance of --roughness")
    ap.add_argument("--roughness", action="store_true",
                    help="print how far the peak moves under the chains' proposal, by its spread")
    args = ap.parse_args()
    warnings.simplefilter("ignore", UserWarning)
    args.cache = args.cache or f"/tmp/tail_crude_{args.model}.npz"
    if args.crude:
        crude(args.crude, args.cache, args.model)
        return
    if args.roughness:
        roughness(args.model, args.rtol)
        return
    names = ["P(overturn)"] + [f"P(|theta| > {t} rad)" for t in THRESHOLDS]
    est, cov, calls, cpu = [], [], [], []
    for r in range(args.runs):
        start = time.process_time()
        ds = tail_probability(STATUE, BED, QUAKE, thresholds=THRESHOLDS, model=args.model,
                              n_per_level=args.n_per_level, runs=1, p0=args.p0, seed=args.seed0 + r, sampler=args.sampler,
                              progress=args.runs <= 5)
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
          f"{'crude n at CoV':>16}{'cost ratio':>12}{'at CoV runs':>13}")
    for i, name in enumerate(names):
        p, c = est[:, i].mean(), cov[:, i].mean()
        spread = est[:, i].std(ddof=1) / p if args.runs > 1 else float("nan")
        need = (1.0 - p) / (p * c * c)
        line = f"{name:<24}{p:>11.3e}{c:>7.2f}{spread:>10.2f}"
        if p_c is not None:
            diff = (p - p_c[i]) / np.hypot(se_c[i], p * max(c, spread if args.runs > 2 else 0.0) / np.sqrt(args.runs))
            line += f"{p_c[i]:>11.3e}{se_c[i]:>10.1e}{diff:>10.2f}"
        need_runs = (1.0 - p) / (p * spread * spread)
        print(line + f"{need:>16.0f}{n_ss / need:>12.3f}{n_ss / need_runs:>13.3f}")


if __name__ == "__main__":
    main()
