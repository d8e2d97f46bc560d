"""The acceptance study: a museum collection screened cold, as ``screening run`` runs it.

Runs ``screening run STUDY --workers 2`` in a fresh process with a fresh numba cache folder (every kernel
compiled in the run: a cold start), then reads the result and prints what an engineer screening the
collection needs, with the targets of issue 40 (item 6):

* the wall time from start to finish (target: at most 600 s on 2 workers, aim 180 s);
* the points with a vouched ``P(overturn)`` (finite, its ``p_source`` not ``unreliable``) out of all, the
  largest standard error among them and the points above 0.03 (target: every point vouched, SE <= 0.03);
* per threshold of ``[fragility]`` the points with a vouched ``P(exceed)``;
* per object and base (each case) its overturning fragility curve: ``P(overturn)`` at every PGA (``-`` where
  not vouched), the lognormal fit on the vouched points (:func:`screening.analysis.fragility.fit_fragility_curve`)
  and how many points it stands on; the count of cases with a fitted curve;
* which Monte Carlo model ran at the escalated points (``esc_model``) and which model ``auto`` picks per case
  (:func:`screening.solvers.model_choice.choose`, with the reason).

Run (the shipped collection; the README's quickstart is its cut ``examples/collection_quick.toml``)::

    nice -n 10 env PYTHONPATH=. python benchmarks/collection_acceptance.py --study examples/collection.toml
    nice -n 10 env PYTHONPATH=. python benchmarks/collection_acceptance.py --study examples/collection_quick.toml

``--warm`` keeps the package's numba cache (no compile); ``--report FILE`` only reads an existing result.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from screening.analysis.fragility import fit_fragility_curve, fit_lognormal_fragility
from screening.core.model import Block, Foundation
from screening.core.status import EscalationModel, FitFlag, ProbabilitySource
from screening.solvers.model_choice import choose
from screening.sweep.study import load_study

ROOT = Path(__file__).resolve().parents[1]
#: Targets of the acceptance study: wall seconds (and the aim), and the standard error of every P(overturn).
WALL_TARGET_S, WALL_AIM_S, SE_TARGET = 600.0, 180.0, 0.03
G = 9.81


def run(study, out, workers, warm):
    """Run the study as ``screening run`` does, in a fresh process; returns the wall seconds.  A cold run has its
    own empty numba cache folder; the run's progress goes to stderr as it comes."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory(prefix="numba_cold_") as cache:
        if not warm:
            env["NUMBA_CACHE_DIR"] = cache
        command = [sys.executable, "-m", "screening.cli", "run", str(study), "--workers", str(workers),
                   "--out", str(out), "--force"]   # a fresh run, never the previous result reused
        print("$ " + ("" if warm else f"NUMBA_CACHE_DIR={cache} ") + " ".join(command), flush=True)
        start = time.monotonic()
        done = subprocess.run(command, env=env, check=False)
        wall = time.monotonic() - start
    if done.returncode != 0:
        raise SystemExit(f"screening run exited with {done.returncode} after {wall:.0f} s")
    return wall


def vouched(ds, name):
    """Where ``name`` (``p_overturn`` or ``p_exceed``) is an answer: finite, from a vouched source."""
    value = ds[name]
    source = ds["p_source"]
    if "threshold" in value.dims:
        source = source.broadcast_like(value)
    return np.isfinite(value) & (source != int(ProbabilitySource.unreliable))


def auto_choices(study):
    """``[(case name, model, reason)]``: what ``model = "auto"`` picks per case of the study."""
    out = []
    for case in study.cases:
        p = case.params
        block = Block(m=p["m"], b=p["b"], h=p["h"])
        bed = Foundation(k=p["k"], lam=p["lam"], eps=p.get("eps", 0.0))
        out.append((case.name, *choose(block, bed, p.get("kind", "kanai_tajimi"))))
    return out


def report(ds, wall=None, study=None):
    """The acceptance figures as lines of text."""
    lines = []
    p, se = ds["p_overturn"], ds["p_overturn_se"]
    ok = vouched(ds, "p_overturn")
    n, n_ok = int(p.size), int(ok.sum())
    se_ok = se.where(ok)
    se_max = float(se_ok.max()) if n_ok else float("nan")
    over = int((se_ok > SE_TARGET + 1e-12).sum())
    if wall is not None:
        lines.append(f"wall time, start to finish: {wall:.0f} s ({wall / 60:.1f} min) on the run's workers; target "
                     f"<= {WALL_TARGET_S:.0f} s (aim {WALL_AIM_S:.0f} s): "
                     + ("met" if wall <= WALL_TARGET_S else f"NOT met, {wall / WALL_TARGET_S:.2f}x the target"))
    lines.append(f"points with a vouched P(overturn): {n_ok} / {n}; its standard error: max {se_max:.3f}, "
                 f"{over} above {SE_TARGET}; target every point vouched with SE <= {SE_TARGET}: "
                 + ("met" if n_ok == n and over == 0 else "NOT met"))
    if "p_exceed" in ds:
        ex = vouched(ds, "p_exceed")
        per = ", ".join(f"{float(t):g}: {int(ex.sel(threshold=t).sum())}/{n}" for t in ds["threshold"].values)
        lines.append(f"points with a vouched P(exceed) per threshold ({ds['threshold'].attrs.get('long_name', 'threshold')}"
                     f"): {per}")
    if "esc_model" in ds:
        models = ds["esc_model"].values.ravel()
        counts = {m.name: int(np.sum(models == int(m))) for m in EscalationModel if np.sum(models == int(m))}
        lines.append(f"Monte Carlo model of the escalated points: {counts}")
    sources = ds["p_source"].values.ravel()
    names = dict(zip(np.atleast_1d(ds["p_source"].attrs["flag_values"]).tolist(),
                     ds["p_source"].attrs["flag_meanings"].split()))
    lines.append("P(overturn) by source: " + ", ".join(f"{names.get(int(v), v)} {int(np.sum(sources == v))}"
                                                      for v in np.unique(sources)))
    dim = "pga"
    pga = ds[dim].values
    lines.append("")
    lines.append("overturning fragility per object and base: P(overturn) at PGA " + " ".join(f"{x / G:.2f}" for x in pga)
                 + " g; lognormal fit on the vouched points")
    names = ds["case_name"].values if "case_name" in ds.coords else [str(c) for c in ds["case"].values]
    fitted = bounded = 0
    for i, name in enumerate(names):
        pi, oki = p.isel(case=i).values, ok.isel(case=i).values
        cells = " ".join(f"{v:.2f}" if good else "  - " for v, good in zip(pi, oki))
        fit = ""
        if oki.sum() >= 2:
            median, beta, flag = fit_fragility_curve(pga[oki], pi[oki])
            if np.isfinite(median) and np.isfinite(beta):
                fitted += 1
                fit = f"median {median / G:.3g} g, beta {beta:.2f}"
            elif flag == FitFlag.never_exceeded and oki.all():       # every point vouched: the median is above
                bounded += 1
                fit = f"never overturns up to {pga.max() / G:.2f} g: median above the range"
            elif flag == FitFlag.always_exceeded and oki.all():
                bounded += 1
                fit = f"overturns from {pga.min() / G:.2f} g: median below the range"
            elif flag == FitFlag.median_outside_data and oki.all():  # the lower tail measured, the median beyond
                bounded += 1
                median, beta = fit_lognormal_fragility(pga[oki], pi[oki])
                fit = (f"median above the range (extrapolated {median / G:.3g} g, beta {beta:.2f}; P "
                       f"{pi[oki][-1]:.2f} at {pga.max() / G:.2f} g)")
            else:
                fit = f"no fit ({FitFlag(int(flag)).name})"
        else:
            fit = "no fit: fewer than 2 vouched points"
        lines.append(f"  {str(name):22s} {cells} | {int(oki.sum())}/{len(pga)} vouched | {fit}")
    lines.append(f"overturning fragility answered for {fitted + bounded} of {len(names)} objects and bases "
                 f"({fitted} lognormal fits, {bounded} bounded: the median beyond the range, with every point vouched)")
    if study is not None:
        lines.append("")
        lines.append("model = \"auto\" per object and base (Kanai-Tajimi):")
        for name, model, why in auto_choices(study):
            lines.append(f"  {name:22s} {model:10s} {why[:150]}")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", default=str(ROOT / "examples" / "collection.toml"))
    parser.add_argument("--out", help="the result file (default outputs/<study name>.nc)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--warm", action="store_true", help="keep the package's numba cache (no cold start)")
    parser.add_argument("--report", help="read this result instead of running the study")
    args = parser.parse_args()
    study = load_study(args.study)
    if args.report:
        wall, out = None, Path(args.report)
    else:
        out = Path(args.out or ROOT / "outputs" / f"{Path(args.study).stem}.nc")
        out.parent.mkdir(parents=True, exist_ok=True)
        wall = run(args.study, out, args.workers, args.warm)
    with xr.open_dataset(out) as ds:
        print("\n".join(report(ds.load(), wall, study)))


if __name__ == "__main__":
    main()
