"""Evaluation of the ``"virtual_work"`` condensation against coupled Monte Carlo (issue #16, part 3).

Run::

    nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/heavy_uplift_evaluation.py \
        [--samples 400] [--seed 0] [--work outputs/heavy_uplift] [--calibration-only | --held-out-only]

Two sets of points, SL peak ``var_theta`` with the ``"paper"``, ``"cubic"`` and ``"virtual_work"``
condensations against the coupled model:

* the trade-study / trust-calibration points (``screening/data/trust_calibration.nc``, 59 points):
  the coupled MCS is the stored one (1000 samples on the paper bed, 500 elsewhere, seed 0);
* held-out points the method was never looked at on (another block, other beds, other
  Kanai–Tajimi filters; intensities by bisection on SL with the paper's condensation): coupled
  MCS here (``--samples``, seed ``--seed``), also peak ``var_theta_dot`` and the probabilities that
  ``|theta|`` exceeds 3 and 10 ``theta_ul`` during the record (SL: Vanmarcke up-crossings).

Prints markdown tables (relative error ``SL / MCS - 1`` with the MCS standard error; ``*``: SL
stopped, status != ok) and the CPU cost of SL per point.  Held-out MCS results are cached as JSON
in ``--work`` so a rerun only recomputes what is missing.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from screening.applications.metrics import peak_with_se  # noqa: E402
from screening.report.tradeoff import calibrate_intensity  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.analysis.linearization import linearize  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402
from screening.solvers.timegrid import output_times  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CALIBRATION = ROOT / "screening" / "data" / "trust_calibration.nc"
T_END, DT = 20.0, 0.05
ENVELOPE = Envelope(4.0, 2.0)
CONDENSATIONS = ("paper", "cubic", "virtual_work")
#: Exceedance thresholds of the held-out table, in units of theta_ul.
THRESHOLDS = (3.0, 10.0)

#: Held-out points: (name, block, bed, excitation, SL(paper) target peak p_uplift).
MEDIUM = dict(m=50.0, b=0.1, h=0.4)                      # a 50 kg block, b/h = 0.25
HELD_OUT = [
    *[(f"medium_white_p{t:g}", MEDIUM, dict(k=1e8, lam=3e9, eps=0.0), dict(kind="white"), t)
      for t in (0.2, 0.4, 0.7, 0.9)],
    *[(f"medium_kt25_p{t:g}", MEDIUM, dict(k=1e8, lam=3e9, eps=0.0),
       dict(kind="kanai_tajimi", omega_g=25.0, zeta_g=0.5), t) for t in (0.4, 0.8)],
    *[(f"paper_soft7_kt30_p{t:g}", dict(m=8.67, b=0.035, h=0.21), dict(k=1e7, lam=2e8, eps=0.0),
       dict(kind="kanai_tajimi", omega_g=30.0, zeta_g=0.3), t) for t in (0.3, 0.7)],
]


def make_excitation(exc, S0):
    if exc["kind"] == "white":
        return WhiteNoise(S0, ENVELOPE)
    return KanaiTajimi(S0, exc["omega_g"], exc["zeta_g"], ENVELOPE)


def sl_peaks(block, bed, excitation):
    """``{condensation: (peak var_theta, peak var_theta_dot, p_exceed, peak p_uplift, status, cpu s,
    var_theta(t_end) / peak var_theta)}``."""
    out = {}
    for cond in CONDENSATIONS:
        try:
            t0 = time.process_time()
            ds = linearize(block, bed, excitation, t_end=T_END, dt=DT, condensation=cond)
            cpu = time.process_time() - t0
        except ValueError:
            continue
        p_ex = [float(ds.rocking.exceedance_probability(x, relative_to="theta_ul")) for x in THRESHOLDS]
        end = float(ds.var_theta.values[-1]) / float(ds.peak_var_theta)
        out[cond] = (float(ds.peak_var_theta), float(ds.var_theta_dot.max()), p_ex, float(ds.peak_p_uplift),
                     int(ds.status), cpu, end)
    return out


def fmt(err, se=None, flag=False):
    if not np.isfinite(err):
        return "n/a"
    text = f"{100 * err:+.0f} %"
    if se is not None:
        text += f" ± {100 * se:.0f}"
    return text + ("*" if flag else "")


def calibration_table():
    cal = xr.open_dataset(CALIBRATION)
    print("\n### Trade-study and calibration points (stored coupled MCS)\n")
    print("| point | S0 [m2 s-3] | SL(paper) p_uplift | coupled MCS peak var_theta [rad2] | overturned | "
          "paper | cubic | virtual_work | virtual_work p_uplift | var_theta(t_end) / peak: coupled, paper, "
          "virtual_work |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for name in cal.point.values:
        c = cal.sel(point=name)
        block = Block(m=float(c.m), b=float(c.b), h=float(c.h))
        bed = Foundation(k=float(c.k), lam=float(c.lam), eps=float(c.eps))
        exc = make_excitation(dict(kind=str(c.excitation_kind.values), omega_g=float(c.omega_g),
                                   zeta_g=float(c.zeta_g)), float(c.S0))
        mc, se = float(c.coupled_peak_var_theta), float(c.coupled_peak_var_theta_se)
        sl = sl_peaks(block, bed, exc)
        cells = []
        for cond in CONDENSATIONS:
            if cond not in sl:
                cells.append("n/a")
                continue
            v = sl[cond]
            cells.append(fmt(v[0] / mc - 1.0, v[0] / mc * se / mc, v[4] != 0))
        p_paper = float(c.sel(condensation="paper").sl_peak_p_uplift)
        rows.append(dict(name=str(name), p=p_paper, over=int(c.coupled_n_overturned),
                         n=int(c.coupled_n_samples), **{k: v[0] / mc - 1.0 for k, v in sl.items()},
                         **{k + "_status": v[4] for k, v in sl.items()}))
        print(f"| {name} | {float(c.S0):.3g} | {p_paper:.3f} | {mc:.3g} ± {se:.1g} | {int(c.coupled_n_overturned)}/"
              f"{int(c.coupled_n_samples)} | " + " | ".join(cells) + f" | {sl['virtual_work'][3]:.2f} | "
              f"{float(c.coupled_var_theta_end) / mc:.2g}, {sl['paper'][6]:.2g}, {sl['virtual_work'][6]:.2g} |")
    return rows


def held_out_point(name, block_kw, bed_kw, exc, target, samples, seed, work):
    path = work / f"{name}_{samples}_{seed}_v3.json"
    if path.exists():
        return json.loads(path.read_text())
    block, bed = Block(**block_kw), Foundation(**bed_kw)
    S0 = calibrate_intensity(block, bed, lambda s: make_excitation(exc, s), target, output_times(T_END, DT))
    excitation = make_excitation(exc, S0)
    res = dict(name=name, S0=S0, target=target)
    t0 = time.process_time()
    mc = monte_carlo(block, bed, excitation, n_samples=samples, model="coupled", t_end=T_END, dt=DT, seed=seed,
                     progress=False)
    res["coupled_cpu"] = time.process_time() - t0
    v, v_se = peak_with_se(mc.var_theta.values, mc.var_theta_se.values)
    w, w_se = peak_with_se(mc.var_theta_dot.values, mc.var_theta_dot_se.values)
    n_used = int(mc.n_used)
    tu = float(block.m * block.g / (2 * block.b**2 * bed.k))         # theta_ul, eq. 19
    peak = mc.peak_abs_theta.values
    survived = ~(mc.overturned.values | mc.diverged.values)
    p_ex = [float(np.mean(peak[survived] > x * tu)) if survived.any() else float("nan") for x in THRESHOLDS]
    res.update(coupled=dict(var_theta=float(v), var_theta_se=float(v_se), var_theta_dot=float(w),
                            var_theta_dot_se=float(w_se), p_exceed=p_ex,
                            p_exceed_se=[float(np.sqrt(p * (1 - p) / max(n_used, 1))) for p in p_ex],
                            overturned=int(mc.n_overturned), n=samples,
                            var_theta_end=float(mc.var_theta.values[-1]), peak_p_uplift=float(mc.p_uplift.max())))
    mcv = monte_carlo(block, bed, excitation, n_samples=samples, model="condensed", condensation="virtual_work",
                      t_end=T_END, dt=DT, seed=seed, progress=False)
    cv, cv_se = peak_with_se(mcv.var_theta.values, mcv.var_theta_se.values)
    res["condensed_virtual_work"] = dict(var_theta=float(cv), var_theta_se=float(cv_se))
    sl = sl_peaks(block, bed, excitation)
    res["sl"] = {k: dict(var_theta=x[0], var_theta_dot=x[1], p_exceed=x[2], peak_p_uplift=x[3], status=x[4],
                         cpu=x[5], end_over_peak=x[6]) for k, x in sl.items()}
    work.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(res, indent=1))
    return res


def held_out_table(samples, seed, work):
    results = []
    for name, blk, bed, exc, target in HELD_OUT:
        t0 = time.time()
        results.append(held_out_point(name, blk, bed, exc, target, samples, seed, work))
        print(f"  {name}: {time.time() - t0:.0f} s", flush=True)
    print(f"\n### Held-out points (coupled MCS {samples} samples, seed {seed})\n")
    print("| point | S0 [m2 s-3] | SL p_uplift paper / virtual_work | coupled peak var_theta [rad2] | overturned | "
          "paper | cubic | virtual_work | condensed MCS (virtual_work) vs coupled | var_theta(t_end) / peak: "
          "coupled, paper, virtual_work |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        c = r["coupled"]
        cells = [fmt(r["sl"][k]["var_theta"] / c["var_theta"] - 1.0,
                     r["sl"][k]["var_theta"] / c["var_theta"] * c["var_theta_se"] / c["var_theta"],
                     r["sl"][k]["status"] != 0) if k in r["sl"] else "n/a" for k in CONDENSATIONS]
        cv = r["condensed_virtual_work"]
        print(f"| {r['name']} | {r['S0']:.3g} | {r['sl']['paper']['peak_p_uplift']:.2f} / "
              f"{r['sl']['virtual_work']['peak_p_uplift']:.2f} | {c['var_theta']:.3g} ± {c['var_theta_se']:.1g} | "
              f"{c['overturned']}/{c['n']} | " + " | ".join(cells) + f" | {fmt(cv['var_theta'] / c['var_theta'] - 1.0)} | "
              f"{c['var_theta_end'] / c['var_theta']:.2g}, {r['sl']['paper']['end_over_peak']:.2g}, "
              f"{r['sl']['virtual_work']['end_over_peak']:.2g} |")
    print("\n| point | coupled peak var_theta_dot [rad2 s-2] | paper | virtual_work | "
          + " | ".join(f"coupled P(max abs theta > {x:g} theta_ul) | paper | virtual_work" for x in THRESHOLDS) + " |")
    print("|---|---|---|---|" + "---|---|---|" * len(THRESHOLDS))
    for r in results:
        c = r["coupled"]
        dots = [fmt(r["sl"][k]["var_theta_dot"] / c["var_theta_dot"] - 1.0) for k in ("paper", "virtual_work")]
        pex = [f"{c['p_exceed'][j]:.2f} ± {c['p_exceed_se'][j]:.2f} | {r['sl']['paper']['p_exceed'][j]:.2f} | "
               f"{r['sl']['virtual_work']['p_exceed'][j]:.2f}" for j in range(len(THRESHOLDS))]
        print(f"| {r['name']} | {c['var_theta_dot']:.3g} ± {c['var_theta_dot_se']:.1g} | {dots[0]} | {dots[1]} | "
              + " | ".join(pex) + " |")
    cpu = {k: np.median([r["sl"][k]["cpu"] for r in results if k in r["sl"]]) for k in CONDENSATIONS}
    print("\nSL CPU per point, one point per call (tables built for it): "
          + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in cpu.items()) + " (median)")
    return results


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=400)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--work", type=Path, default=ROOT / "outputs" / "heavy_uplift")
    ap.add_argument("--calibration-only", action="store_true")
    ap.add_argument("--held-out-only", action="store_true")
    args = ap.parse_args(argv)
    if not args.held_out_only:
        calibration_table()
    if not args.calibration_only:
        held_out_table(args.samples, args.seed, args.work)


if __name__ == "__main__":
    main()
