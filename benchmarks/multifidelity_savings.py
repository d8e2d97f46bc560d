"""What a paired cheap model saves the coupled Monte Carlo: the multi-fidelity savings table.

Run::

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python \\
        benchmarks/multifidelity_savings.py [--paired 200] [--cheap 800] [--points NAME,NAME|all] \\
        [--stiff-points NAME,NAME|none] [--beds LABEL,LABEL|none]

In one run: the calibration points (``--points``) with ``--cheap-model`` (default the condensed model,
``virtual_work``), then the statue calibration points (``--stiff-points``) and the statue / cabinet beds
of ``benchmarks/stiff_bed_validity.py`` (``--beds``) with the stiff-bed model.

For each calibration point (``screening/data/trust_calibration.nc``: block, bed, excitation, S0) the
coupled model runs ``--paired`` samples and the cheap model (``--cheap-model``, default the condensed
model with ``virtual_work``) ``--cheap`` samples
with the same seed, so that the first ``--paired`` cheap samples share their ground motions with the
coupled ones.  For each per-sample quantity (exceedance of ``a`` = 0.05, 0.1, 0.3, 0.5 of
``atan(b/h)``, overturned samples counted as exceeding; overturning; the peak ``|theta|`` itself, in
units of ``atan(b/h)`` and 1 for an overturned sample, a continuous quantity like the variance; and the
peak of the ensemble variance ``var_theta``, the quantity the escalation plans for, estimated from the
sample histories by :func:`screening.analysis.multifidelity.multifidelity_variance`) it prints:

* ``rho``: the correlation of the two models' values over the paired samples;
* ``c_hi/c_lo``: CPU seconds per sample of each model (process time, one thread), and their ratio;
* ``r*``: the optimal cheap samples per coupled sample (:func:`screening.analysis.multifidelity.optimal_ratio`);
* ``speed-up``: plain coupled CPU / two-fidelity CPU at equal standard error, predicted from ``rho`` and
  the costs (:func:`~screening.analysis.multifidelity.speedup`; the escalation runs plain Monte Carlo
  where it is below 1);
* ``var ratio``: the realised variance of the two-fidelity estimate from this run over the plain one
  (same coupled samples), and both estimates;
* ``w(3x)``: the cost ratio ``c_hi/c_lo`` at which this ``rho`` would give a 3x speed-up
  (:func:`~screening.analysis.multifidelity.cost_ratio_needed`; ``inf``: no cost ratio can).

Rows where either model's values are constant over the paired samples (no information) are left out.
Last, a summary: per model pair the median cost ratio, and the best predicted speed-up where ``rho >= 0.9``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from screening.analysis.multifidelity import (control_variate_estimate, cost_ratio_needed,  # noqa: E402
                                              multifidelity_variance, optimal_ratio, speedup)
from screening.core.model import Block, Envelope, Foundation  # noqa: E402
from screening.core.excitations import KanaiTajimi, WhiteNoise
from screening.solvers.montecarlo import monte_carlo  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CALIBRATION = ROOT / "screening" / "data" / "trust_calibration.nc"
LEVELS = (0.05, 0.1, 0.3, 0.5)
DEFAULT_POINTS = ("paper_h_white_p0.15", "paper_h_white_p0.85", "paper_s_kt40_p0.6", "paper_h_kt10_p0.7",
                  "heavy_white_p0.3", "heavy_kt10_p0.3", "paper_stiff9_white_p0.3", "statue_kt_p0.3")
STIFF_POINTS = ("statue_kt_p0.3", "statue_kt_p0.8")
STIFF_BEDS = ("statue k=1e10", "cabinet pads k=2.1e9 eps=2e9")
TARGET_SPEEDUP = 3.0


def models_at(point):
    p = {name: point[name].item() for name in ("m", "b", "h", "k", "lam", "eps", "S0", "omega_g", "zeta_g")}
    block = Block(m=p["m"], b=p["b"], h=p["h"])
    if str(point["contact"].item()) == "winkler":
        bed = Foundation(k=p["k"], c=p["lam"], eps=p["eps"])
    else:
        bed = Foundation(k=p["k"], lam=p["lam"], eps=p["eps"])
    envelope = Envelope(4.0, 2.0)
    if str(point["excitation_kind"].item()) == "white":
        excitation = WhiteNoise(S0=p["S0"], envelope=envelope)
    else:
        excitation = KanaiTajimi(S0=p["S0"], omega_g=p["omega_g"], zeta_g=p["zeta_g"], envelope=envelope)
    return block, bed, excitation


def per_sample(ds, alpha):
    over = ds.overturned.values.astype(bool)
    out = {f"P(>{a:g} alpha)": ((ds.peak_abs_theta.values > a * alpha) | over).astype(float) for a in LEVELS}
    out["P(overturn)"] = over.astype(float)
    out["E[peak]/alpha"] = np.where(over, 1.0, np.minimum(ds.peak_abs_theta.values / alpha, 1.0))
    return out


def cheap_run_options(spec):
    """``"condensed:virtual_work"`` -> model and condensation; any other registered model by its name."""
    model, _, condensation = spec.partition(":")
    return {"model": model, **({"condensation": condensation} if condensation else {})}


def run_point(name, models, n_paired, n_cheap, cheap="condensed:virtual_work", seed=0):
    """Rows of the savings table at one point: ``models = (block, bed, excitation)``."""
    block, bed, excitation = models
    alpha = math.atan(block.b / block.h)
    for spec in ("coupled", cheap):                      # compile outside the timings
        monte_carlo(block, bed, excitation, n_samples=2, t_end=0.5, seed=seed, **cheap_run_options(spec))
    t0 = time.process_time()
    hi = monte_carlo(block, bed, excitation, n_samples=n_paired, model="coupled", seed=seed, sample_histories=True)
    c_hi = (time.process_time() - t0) / n_paired
    t0 = time.process_time()
    lo = monte_carlo(block, bed, excitation, n_samples=n_cheap, seed=seed, sample_histories=True,
                     **cheap_run_options(cheap))
    c_lo = (time.process_time() - t0) / n_cheap
    y_all, x_all = per_sample(hi, alpha), per_sample(lo, alpha)
    estimates = {}
    for quantity, y in y_all.items():
        x = x_all[quantity]
        estimates[quantity] = control_variate_estimate(y, x[:n_paired], x_extra=x[n_paired:])
    var = multifidelity_variance(hi.theta_sample.values, ~(hi.overturned.values | hi.diverged.values),
                                 lo.theta_sample.values, ~(lo.overturned.values | lo.diverged.values))
    if np.any(np.isfinite(var.mean)):
        at = int(np.nanargmax(var.plain_mean))                       # the peak time of the plain estimate
        estimates["peak var_theta"] = type(var)(*(float(np.asarray(getattr(var, f))[at]) for f in (
            "mean", "se", "plain_mean", "plain_se", "weight", "correlation")), var.n_paired, var.n_cheap)
    rows = []
    for quantity, est in estimates.items():
        if not math.isfinite(est.correlation):        # either model constant over the paired samples: no information
            continue
        rho = est.correlation
        rows.append(dict(point=name, quantity=quantity, rho=rho, c_hi=c_hi, c_lo=c_lo,
                         ratio=optimal_ratio(rho, c_hi, c_lo), speedup=speedup(rho, c_hi, c_lo),
                         var_ratio=(est.se / est.plain_se) ** 2 if est.plain_se > 0 else math.nan,
                         needed=cost_ratio_needed(rho, TARGET_SPEEDUP),
                         plain=est.plain_mean, plain_se=est.plain_se, mf=est.mean, mf_se=est.se))
    return rows


def stiff_beds(labels):
    """``{label: (block, bed, excitation)}`` of the statue / cabinet beds of ``benchmarks/stiff_bed_validity.py``."""
    if not labels:
        return {}
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import stiff_bed_validity as sbv

    known = {label: (block, bed, KanaiTajimi(S0=s0, **sbv.FILTER)) for label, block, bed, s0 in sbv.scene_beds()}
    unknown = sorted(set(labels) - set(known))
    if unknown:
        raise SystemExit(f"unknown bed(s) {unknown}; known: {sorted(known)}")
    return {label: known[label] for label in labels}


def print_row(row, cheap):
    print(f"{row['point']:28s} {cheap:24s} {row['quantity']:15s} {row['rho']:6.3f} {1e3 * row['c_hi']:8.2f} "
          f"{1e3 * row['c_lo']:8.2f} {row['c_hi'] / row['c_lo']:6.2f} {row['ratio']:6.1f} {row['speedup']:8.2f} "
          f"{row['var_ratio']:9.3f} {row['needed']:7.1f} "
          f"{row['plain']:.3g}±{row['plain_se']:.2g} {row['mf']:.3g}±{row['mf_se']:.2g}", flush=True)


def _names(arg, default, known=None):
    if arg == "none":
        return []
    if arg == "all" and known is not None:
        return list(known)
    return list(default) if arg is None else arg.split(",")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paired", type=int, default=200)
    ap.add_argument("--cheap", type=int, default=800)
    ap.add_argument("--cheap-model", default="condensed:virtual_work",
                    help="the cheap model at --points: 'condensed:CONDENSATION' or a registered Monte Carlo model name")
    ap.add_argument("--points", default=None, help="comma-separated calibration points, 'all' or 'none'")
    ap.add_argument("--stiff-points", default=None, help="calibration points run with the stiff-bed model, or 'none'")
    ap.add_argument("--beds", default=None,
                    help="beds of stiff_bed_validity.py run with the stiff-bed model, or 'none'")
    args = ap.parse_args(argv)
    with xr.open_dataset(CALIBRATION) as ds:
        cal = ds.load()
    names = [str(v) for v in cal.point.values]
    chosen = _names(args.points, DEFAULT_POINTS, names)
    stiff = _names(args.stiff_points, STIFF_POINTS, names)
    unknown = sorted(set(chosen + stiff) - set(names))
    if unknown:
        print(f"unknown point(s) {unknown}; known: {names}", file=sys.stderr)
        return 2
    beds = stiff_beds(_names(args.beds, STIFF_BEDS))
    print(f"# paired coupled samples {args.paired}, cheap samples {args.cheap}; "
          f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS')}; w(3x): cost ratio c_hi/c_lo for a "
          f"{TARGET_SPEEDUP:g}x speed-up at this rho", flush=True)
    print(f"{'point':28s} {'cheap model':24s} {'quantity':15s} {'rho':>6s} {'c_hi ms':>8s} {'c_lo ms':>8s} "
          f"{'c_hi/lo':>6s} {'r*':>6s} {'speed-up':>8s} {'var ratio':>9s} {'w(3x)':>7s} plain  two-fidelity",
          flush=True)
    jobs = ([(name, models_at(cal.sel(point=name)), args.cheap_model) for name in chosen]
            + [(name, models_at(cal.sel(point=name)), "stiff_bed") for name in stiff]
            + [(label, models, "stiff_bed") for label, models in beds.items()])
    rows = []
    for name, models, cheap in jobs:
        for row in run_point(name, models, args.paired, args.cheap, cheap):
            row["cheap"] = cheap
            print_row(row, cheap)
            rows.append(row)
    print("# summary", flush=True)
    for cheap in dict.fromkeys(r["cheap"] for r in rows):
        mine = [r for r in rows if r["cheap"] == cheap]
        ratio = float(np.median([r["c_hi"] / r["c_lo"] for r in mine]))
        good = [r for r in mine if r["rho"] >= 0.9]
        best = max(good, key=lambda r: r["speedup"]) if good else None
        line = f"{cheap}: median cost ratio c_hi/c_lo {ratio:.2f}; {len(good)} of {len(mine)} rows with rho >= 0.9"
        if best is not None:
            line += (f", best predicted speed-up {best['speedup']:.2f} ({best['point']}, {best['quantity']}, rho "
                     f"{best['rho']:.3f}; {TARGET_SPEEDUP:g}x needs c_hi/c_lo >= {best['needed']:.1f}); the median "
                     f"w(3x) of those rows {float(np.median([r['needed'] for r in good])):.1f}")
        print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
