"""What a paired cheap model saves the coupled Monte Carlo: the multi-fidelity savings table.

Run::

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python \\
        benchmarks/multifidelity_savings.py [--paired 200] [--cheap 800] [--points NAME,NAME|all]

For each calibration point (``screening/data/trust_calibration.nc``: block, bed, excitation, S0) the
coupled model runs ``--paired`` samples and the cheap model (``--cheap-model``, default the condensed
model with ``virtual_work``) ``--cheap`` samples
with the same seed, so that the first ``--paired`` cheap samples share their ground motions with the
coupled ones.  For each per-sample quantity (exceedance of ``a`` = 0.05, 0.1, 0.3, 0.5 of
``atan(b/h)``, overturned samples counted as exceeding; overturning; the peak ``|theta|`` itself, in
units of ``atan(b/h)`` and 1 for an overturned sample, a continuous quantity like the variance) it prints:

* ``rho``: the correlation of the two models' values over the paired samples;
* ``c_hi/c_lo``: CPU seconds per sample of each model (process time, one thread), and their ratio;
* ``r*``: the optimal cheap samples per coupled sample (:func:`screening.analysis.multifidelity.optimal_ratio`);
* ``speed-up``: plain coupled CPU / two-fidelity CPU at equal standard error, predicted from ``rho`` and
  the costs (:func:`~screening.analysis.multifidelity.speedup`; the escalation runs plain Monte Carlo
  where it is below 1);
* ``var ratio``: the realised variance of the two-fidelity estimate from this run over the plain one
  (same coupled samples), and both estimates.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from screening.analysis.multifidelity import control_variate_estimate, optimal_ratio, speedup  # noqa: E402
from screening.model import Block, Envelope, Foundation, KanaiTajimi, WhiteNoise  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CALIBRATION = ROOT / "screening" / "data" / "trust_calibration.nc"
LEVELS = (0.05, 0.1, 0.3, 0.5)
DEFAULT_POINTS = ("paper_h_white_p0.15", "paper_h_white_p0.85", "paper_s_kt40_p0.6", "paper_h_kt10_p0.7",
                  "heavy_white_p0.3", "heavy_kt10_p0.3", "paper_stiff9_white_p0.3", "statue_kt_p0.3")


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


def run_point(name, point, n_paired, n_cheap, cheap="condensed:virtual_work", seed=0):
    block, bed, excitation = models_at(point)
    alpha = math.atan(block.b / block.h)
    t0 = time.process_time()
    hi = monte_carlo(block, bed, excitation, n_samples=n_paired, model="coupled", seed=seed)
    c_hi = (time.process_time() - t0) / n_paired
    t0 = time.process_time()
    lo = monte_carlo(block, bed, excitation, n_samples=n_cheap, seed=seed, **cheap_run_options(cheap))
    c_lo = (time.process_time() - t0) / n_cheap
    y_all, x_all = per_sample(hi, alpha), per_sample(lo, alpha)
    rows = []
    for quantity, y in y_all.items():
        x = x_all[quantity]
        est = control_variate_estimate(y, x[:n_paired], x_extra=x[n_paired:])
        rho = 0.0 if not math.isfinite(est.correlation) else est.correlation
        rows.append(dict(point=name, quantity=quantity, rho=rho, c_hi=c_hi, c_lo=c_lo,
                         ratio=optimal_ratio(rho, c_hi, c_lo), speedup=speedup(rho, c_hi, c_lo),
                         var_ratio=(est.se / est.plain_se) ** 2 if est.plain_se > 0 else math.nan,
                         plain=est.plain_mean, plain_se=est.plain_se, mf=est.mean, mf_se=est.se))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paired", type=int, default=200)
    ap.add_argument("--cheap", type=int, default=800)
    ap.add_argument("--cheap-model", default="condensed:virtual_work",
                    help="the cheap model: 'condensed:CONDENSATION' or a registered Monte Carlo model name")
    ap.add_argument("--points", default=",".join(DEFAULT_POINTS), help="comma-separated names, or 'all'")
    args = ap.parse_args(argv)
    with xr.open_dataset(CALIBRATION) as ds:
        cal = ds.load()
    names = [str(v) for v in cal.point.values]
    chosen = names if args.points == "all" else args.points.split(",")
    unknown = sorted(set(chosen) - set(names))
    if unknown:
        print(f"unknown point(s) {unknown}; known: {names}", file=sys.stderr)
        return 2
    print(f"# paired coupled samples {args.paired}, {args.cheap_model} samples {args.cheap}; "
          f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS')}", flush=True)
    header = (f"{'point':24s} {'quantity':16s} {'rho':>6s} {'c_hi ms':>8s} {'c_lo ms':>8s} {'r*':>6s} "
              f"{'speed-up':>8s} {'var ratio':>9s} {'plain':>14s} {'two-fidelity':>14s}")
    print(header, flush=True)
    for name in chosen:
        point = cal.sel(point=name)
        for row in run_point(name, point, args.paired, args.cheap, args.cheap_model):
            print(f"{row['point']:24s} {row['quantity']:16s} {row['rho']:6.3f} {1e3 * row['c_hi']:8.2f} "
                  f"{1e3 * row['c_lo']:8.2f} {row['ratio']:6.1f} {row['speedup']:8.2f} {row['var_ratio']:9.3f} "
                  f"{row['plain']:7.3f}±{row['plain_se']:.3f} {row['mf']:7.3f}±{row['mf_se']:.3f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
