"""Monte Carlo tolerance against the sampling error: the bias of the ensemble statistics per ``rtol``.

Run (one core, under the shared lock; each table is one run of at most 10 minutes on the loaded development
machine, about 7 (accuracy, 200 samples), 2 (oversampling) and 6 (speed) minutes):

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD \\
        .venv/bin/python benchmarks/bench_mc_tolerance.py --only accuracy [--samples 200] [--seed 0]

and the same with ``--only oversampling`` and ``--only speed`` (without ``--only``: all three in one run).

For each case (the paper block on the paper bed at light, moderate and heavy uplift under white noise and
the paper's Kanai-Tajimi filter; the statue block on k = 1e8 and 1e10) the coupled model is run on the
SAME samples (same seed) at ``rtol`` 1e-4, 1e-5, 1e-6, 1e-7 and at the reference 1e-10.  Per statistic
(peak ``var_theta``, ``E[peak |theta|]``, ``P(peak > a)`` at the reference's median and 90th percentile of
the peaks, ``P(overturn)``) it prints the bias against the reference and its paired standard error
(leave-one-out jackknife of the paired difference, :func:`paired_bias`), both in units of the plain
Monte Carlo standard error of that statistic at ``n = 500`` and at ``n = 10,000`` (the jackknife SE of the
reference scaled by ``sqrt(samples / n)``), the per-sample peak errors, and the CPU per 1000 samples.

Then the synthesis grid: oversampling 2 against 4 (different samples: the FFT length changes), the
difference of each statistic over its combined standard error, and the CPU of both.

The last table is the speed of each tolerance, of the rule :func:`screening.solvers.montecarlo.auto_rtol` and of
the rule on a synthesis grid of oversampling 2, against the fixed 1e-7 (ratios in one run): CPU per sample of
the paper block, and against bed stiffness (the statue block, k = 1e8 ... 1e11).
"""

from __future__ import annotations

import argparse
import math
import os
import time

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.solvers.montecarlo import AUTO_RTOL_SAMPLES, auto_rtol, monte_carlo  # noqa: E402

ENVELOPE = Envelope(4.0, 2.0)
PAPER = Block(m=8.67, b=0.035, h=0.21)
PAPER_BED = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
STATUE = Block(m=600.0, b=0.2, h=0.8)


def _kt10(S0):
    return KanaiTajimi(S0=S0, omega_g=10.0, zeta_g=0.4, envelope=ENVELOPE)


def _statue_bed(k):
    return Foundation(k=k, lam=30.0 * k, eps=0.0)


STATUE_MOTION = KanaiTajimi(S0=3e-3, omega_g=15.6, zeta_g=0.6, envelope=ENVELOPE)
#: The cases: the calibration's paper-bed points (``benchmarks/trust_calibration.py``: S0 of the SL peak
#: p_uplift 0.03 / 0.3 / 0.85 under white noise, 0.05 / 0.3 under the paper's filter; its p_uplift 0.7 point,
#: S0 = 1.01e-2, overturns 199 of 200 samples, so the heavy filtered case is S0 = 3.5e-3) and the statue.
CASES = {
    "paper white light (p_ul 0.03)": (PAPER, PAPER_BED, WhiteNoise(S0=3.58e-5, envelope=ENVELOPE)),
    "paper white moderate (p_ul 0.3)": (PAPER, PAPER_BED, WhiteNoise(S0=1.46e-4, envelope=ENVELOPE)),
    "paper white heavy (p_ul 0.85)": (PAPER, PAPER_BED, WhiteNoise(S0=1.93e-3, envelope=ENVELOPE)),
    "paper KT10 light (p_ul 0.05)": (PAPER, PAPER_BED, _kt10(7.89e-4)),
    "paper KT10 moderate (p_ul 0.3)": (PAPER, PAPER_BED, _kt10(2.56e-3)),
    "paper KT10 heavy (S0 3.5e-3)": (PAPER, PAPER_BED, _kt10(3.5e-3)),
    "statue k=1e8": (STATUE, _statue_bed(1e8), STATUE_MOTION),
    "statue k=1e10": (STATUE, _statue_bed(1e10), STATUE_MOTION),
}
RTOLS = (1e-4, 1e-5, 1e-6, 1e-7)
REFERENCE_RTOL = 1e-10
PLANNED = (500, 10_000)
T_END = 20.0
STATISTICS = ("peak var_theta", "E[peak]", "P(peak>a50)", "P(peak>a90)", "P(overturn)")


def run(block, foundation, excitation, n, seed, **kw):
    """``(dataset, CPU seconds)`` of one coupled run with the samples' histories."""
    t0 = time.process_time()
    ds = monte_carlo(block, foundation, excitation, n_samples=n, t_end=T_END, seed=seed, progress=False,
                     sample_histories=True, **kw)
    return ds, time.process_time() - t0


def sample_arrays(ds):
    """The per-sample arrays the statistics are computed from."""
    return dict(theta=ds.theta_sample.values, peak=ds.peak_abs_theta.values, overturned=ds.overturned.values,
                diverged=ds.diverged.values)


def _peak_variance(theta, used):
    """Peak over time of the ensemble variance (``ddof = 1``) of the used rows, and its leave-one-out values."""
    x = np.where(used[:, None], theta, 0.0)
    n = int(used.sum())
    s1, s2 = x.sum(axis=0), (x * x).sum(axis=0)
    full = np.max((s2 - s1 * s1 / n) / (n - 1))
    m = n - used.astype(float)                       # rows left after leaving out row i
    l1, l2 = s1[None, :] - x, s2[None, :] - x * x
    loo = np.max((l2 - l1 * l1 / m[:, None]) / (m[:, None] - 1.0), axis=1)
    return full, loo


def _mean(values, rows):
    """Mean of ``values`` over ``rows`` and its leave-one-out values."""
    v = np.where(rows, values, 0.0).astype(float)
    n = int(rows.sum())
    m = n - rows.astype(float)
    return v.sum() / n, (v.sum() - v) / m


def statistics(arrays, levels):
    with np.errstate(invalid="ignore", divide="ignore"):
        return _statistics(arrays, levels)


def _statistics(arrays, levels):
    """``{name: (value, leave-one-out values)}`` of :data:`STATISTICS` (``levels``: the two ``a`` [rad]).

    Peak ``var_theta`` is over the samples that neither overturned nor diverged (as ``monte_carlo``); the
    others over the samples that did not diverge (an overturned sample's peak passes every level).
    """
    used = ~(arrays["overturned"] | arrays["diverged"])
    kept = ~arrays["diverged"]
    peak = np.where(arrays["overturned"], np.inf, arrays["peak"])
    out = {"peak var_theta": _peak_variance(arrays["theta"], used),
           "E[peak]": _mean(np.where(arrays["overturned"], 0.0, arrays["peak"]), used),
           "P(overturn)": _mean(arrays["overturned"], kept)}
    for name, a in zip(("P(peak>a50)", "P(peak>a90)"), levels):
        out[name] = _mean(peak > a, kept)
    return out


def jackknife_se(loo):
    """Leave-one-out jackknife standard error from the leave-one-out values."""
    n = loo.size
    return float(np.sqrt((n - 1.0) / n * np.sum((loo - loo.mean()) ** 2)))


def paired_bias(arrays, reference, levels):
    """``{name: (bias, its SE, the reference's SE)}`` of :data:`STATISTICS`: ``arrays`` minus ``reference``
    on the same samples, the bias's SE the jackknife of the paired difference (its sampling error), the
    reference's SE the jackknife of the statistic itself (the plain Monte Carlo SE at this sample count)."""
    got, ref = statistics(arrays, levels), statistics(reference, levels)
    return {name: (got[name][0] - ref[name][0], jackknife_se(got[name][1] - ref[name][1]),
                   jackknife_se(ref[name][1])) for name in STATISTICS}


def peak_levels(reference):
    """The two exceedance levels [rad]: the median and 90th percentile of the reference's surviving peaks."""
    used = ~(reference["overturned"] | reference["diverged"])
    return tuple(np.quantile(reference["peak"][used], (0.5, 0.9)))


def sample_peak_errors(arrays, reference):
    """Median and largest relative error of the per-sample peak ``|theta|`` (samples surviving in both)."""
    both = ~(arrays["overturned"] | arrays["diverged"] | reference["overturned"] | reference["diverged"])
    err = np.abs(arrays["peak"][both] / reference["peak"][both] - 1.0)
    flips = int(np.count_nonzero(arrays["overturned"] != reference["overturned"]))
    if not err.size:
        return math.nan, math.nan, flips
    return float(np.median(err)), float(np.max(err)), flips


def _in_planned(bias, bias_se, se, n):
    """``"b ± s"``: the bias and its SE in units of the plain SE at each planned sample count."""
    if se == 0.0:
        return " | ".join("0 (no spread)" if bias == 0.0 else "n/a" for _ in PLANNED)
    return " | ".join(f"{bias / (se * np.sqrt(n / N)):+.3f} ± {bias_se / (se * np.sqrt(n / N)):.3f}"
                      for N in PLANNED)


def accuracy_table(n, seed):
    """Table 1: bias per rtol against the reference, in units of the planned SE.  Returns the rows."""
    rows = []
    print(f"\n== 1. bias against rtol {REFERENCE_RTOL:g} on the same {n} samples (seed {seed}); "
          f"each bias ± its paired SE, in units of the plain Monte Carlo SE at n = {PLANNED[0]} | {PLANNED[1]}")
    print("| case | rtol | steps/sample | CPU s/1000 | per-sample peak err median / max | overturn flips | "
          + " | ".join(f"{s} /SE({N})" for s in STATISTICS for N in PLANNED) + " |")
    print("|---|---|---|---|---|---|" + "---|" * (len(STATISTICS) * len(PLANNED)))
    for case, (block, bed, exc) in CASES.items():
        ref_ds, ref_cpu = run(block, bed, exc, n, seed, rtol=REFERENCE_RTOL)
        ref = sample_arrays(ref_ds)
        levels = peak_levels(ref)
        print(f"| {case} | {REFERENCE_RTOL:g} | {float(ref_ds.n_steps.mean()):,.0f} | {1e3 * ref_cpu / n:.2f} "
              f"| reference | {int(ref['overturned'].sum())} overturned |" + " |" * (len(STATISTICS) * len(PLANNED)),
              flush=True)
        for rtol in RTOLS:
            ds, cpu = run(block, bed, exc, n, seed, rtol=rtol)
            arrays = sample_arrays(ds)
            bias = paired_bias(arrays, ref, levels)
            med, big, flips = sample_peak_errors(arrays, ref)
            rows.append(dict(case=case, rtol=rtol, bias=bias, n=n, cpu=cpu / n, steps=float(ds.n_steps.mean())))
            print(f"| {case} | {rtol:g} | {float(ds.n_steps.mean()):,.0f} | {1e3 * cpu / n:.2f} | {med:.1e} / {big:.1e} "
                  f"| {flips} | " + " | ".join(_in_planned(*bias[s], n) for s in STATISTICS) + " |", flush=True)
    return rows


def admissible(row, N, fraction=0.1):
    """Whether every bias of an accuracy ``row`` is consistent with ``|bias| <= fraction x SE(N)`` at two paired
    SEs (``|bias| - 2 SE(bias) <= fraction x SE(N)``), and whether it is shown so (``|bias| + 2 SE(bias)``)."""
    consistent = shown = True
    for b, bse, se in row["bias"].values():
        if not (math.isfinite(b) and math.isfinite(bse)):
            continue                                   # no statistic (every sample overturned)
        bound = fraction * se * math.sqrt(row["n"] / N)
        consistent &= abs(b) - 2.0 * bse <= bound
        shown &= abs(b) + 2.0 * bse <= bound
    return consistent, shown


def largest_admissible(rows, planned=(500, 4000, 10_000), fraction=0.1):
    """Per case and planned n, the loosest rtol that, with every tighter one, meets :func:`admissible`."""
    print(f"\n== 1b. loosest rtol (it and every tighter one) whose biases are consistent with |bias| <= {fraction:g} "
          f"x plain SE at 2 paired SEs; in brackets: shown to be (|bias| + 2 SE(bias) within), per sample count")
    print("| case | " + " | ".join(f"n = {N:,}" for N in planned) + " |")
    print("|---|" + "---|" * len(planned))
    for case in CASES:
        mine = sorted((r for r in rows if r["case"] == case), key=lambda r: r["rtol"])
        cells = []
        for N in planned:
            best = {0: None, 1: None}
            for which in (0, 1):
                for r in mine:
                    if not admissible(r, N, fraction)[which]:
                        break
                    best[which] = r["rtol"]
            loosest = f"{best[0]:g}" if best[0] else f"< {mine[0]['rtol']:g}"
            cells.append(f"{loosest} ({best[1]:g})" if best[1] else f"{loosest} (unresolved)")
        print(f"| {case} | " + " | ".join(cells) + " |")


def oversampling_table(n, seed, rtol):
    """Table 2: synthesis grid oversampling 2 against 4 (different samples), at ``rtol``."""
    print(f"\n== 2. synthesis oversampling 2 against 4 ({n} samples each, seed {seed}, rtol {rtol:g}; different "
          f"samples): (statistic at 2 - at 4) / combined SE")
    print("| case | CPU s/1000 x4 | CPU s/1000 x2 | " + " | ".join(STATISTICS) + " |")
    print("|---|---|---|" + "---|" * len(STATISTICS))
    for case, (block, bed, exc) in CASES.items():
        res = {}
        for os_ in (4, 2):
            ds, cpu = run(block, bed, exc, n, seed, rtol=rtol, oversampling=os_)
            res[os_] = (sample_arrays(ds), cpu)
        levels = peak_levels(res[4][0])
        s4, s2 = statistics(res[4][0], levels), statistics(res[2][0], levels)
        cells = []
        for s in STATISTICS:
            se = np.hypot(jackknife_se(s4[s][1]), jackknife_se(s2[s][1]))
            cells.append(f"{(s2[s][0] - s4[s][0]) / se:+.2f}" if se > 0 else "0 (no spread)")
        print(f"| {case} | {1e3 * res[4][1] / n:.2f} | {1e3 * res[2][1] / n:.2f} | " + " | ".join(cells) + " |",
              flush=True)


#: The settings timed by :func:`speed_table`: ``(label, rtol, oversampling)``; the first is today's fixed tolerance.
SPEED_SETTINGS = (("1e-7 x4", 1e-7, 4), ("1e-6 x4", 1e-6, 4), ("1e-5 x4", 1e-5, 4), ("1e-4 x4", 1e-4, 4),
                  ("auto x4", "auto", 4), ("auto x2", "auto", 2))


def speed_table(n, seed, repeat=3):
    """Table 3: CPU per sample at each of :data:`SPEED_SETTINGS` against the fixed 1e-7 (ratios in one run): the
    paper block, and the statue on k = 1e8 ... 1e11; the median of ``repeat`` identical runs."""
    print(f"\n== 3. speed: CPU ms per sample (steps per sample) and speed-up over rtol 1e-7, oversampling 4; "
          f"{n} samples each, seed {seed}, median of {repeat}; auto = {auto_rtol('coupled', n):g} at this n "
          f"(the same up to {AUTO_RTOL_SAMPLES} samples)")
    print("| case | " + " | ".join(label for label, _, _ in SPEED_SETTINGS) + " |")
    print("|---|" + "---|" * len(SPEED_SETTINGS))
    runs = [("paper block, paper bed, white S0=2.4e-4", PAPER, PAPER_BED, WhiteNoise(S0=2.4e-4, envelope=ENVELOPE))]
    runs += [(f"statue k={k:g}", STATUE, _statue_bed(k), STATUE_MOTION) for k in (1e8, 1e9, 1e10, 1e11)]
    for name, block, bed, exc in runs:
        cells, base = [], None
        for _, rtol, oversampling in SPEED_SETTINGS:
            cpu = []
            for _ in range(repeat):
                t0 = time.process_time()
                ds = monte_carlo(block, bed, exc, n_samples=n, t_end=T_END, seed=seed, progress=False, rtol=rtol,
                                 oversampling=oversampling)
                cpu.append(time.process_time() - t0)
            c = float(np.median(cpu)) / n
            base = base or c
            cells.append(f"{1e3 * c:.2f} ({float(ds.n_steps.mean()):,.0f}) {base / c:.2f}x")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--speed-samples", type=int, default=48)
    ap.add_argument("--oversampling-rtol", type=float, default=1e-5, help="rtol of the oversampling table")
    ap.add_argument("--only", choices=("accuracy", "oversampling", "speed"), default=None)
    ap.add_argument("--cases", default=None, help="only the cases whose name contains this text")
    args = ap.parse_args()
    if args.cases:
        for name in [name for name in CASES if args.cases not in name]:
            del CASES[name]
    monte_carlo(PAPER, PAPER_BED, WhiteNoise(S0=1e-4, envelope=ENVELOPE), n_samples=2, t_end=1.0, progress=False)
    if args.only in (None, "accuracy"):
        largest_admissible(accuracy_table(args.samples, args.seed))
    if args.only in (None, "oversampling"):
        oversampling_table(args.samples, args.seed, args.oversampling_rtol)
    if args.only in (None, "speed"):
        speed_table(args.speed_samples, args.seed)


if __name__ == "__main__":
    main()
