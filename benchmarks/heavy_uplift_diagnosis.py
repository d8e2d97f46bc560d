"""Which mechanism carries the condensation error in heavy uplift (issue #16, part 1).

Run::

    nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/heavy_uplift_diagnosis.py \
        [--samples 200] [--detail 40] [--seed 0] [--figure docs/heavy_uplift_diagnosis.png]

Prints the tables of ``docs/heavy_uplift.md`` and writes its figure.

1. **Free rocking** (deterministic, no input): the block released from ``theta0 = r theta_ul`` at
   rest.  Amplitude ratio of successive half cycles (one corner-to-corner transition each) of the
   coupled model (eqs. 7–8) and of the condensed model with the ``"paper"``, ``"cubic"`` and
   ``"virtual_work"`` condensations; the energy the bed dissipates in the first half cycle, split
   into the uplift phase and the full-contact phase (coupled: ``F_d z_cb' + M_d theta'`` with the
   damping parts of the exact contact resultants; condensed: ``C(theta) theta'^2``), as a fraction
   of the potential energy ``int_0^A K(theta) theta dtheta`` at the release amplitude; the largest
   gap between the coupled ``z_cb`` and its quasi-static value.
2. **Random shaking** at SL(paper) peak ``p_uplift`` 0.2, 0.5, 0.9: paper block on its linear bed
   under white noise and Kanai–Tajimi (40 rad/s), a 300 kg block on a stiff bed under white noise.
   Coupled and condensed (paper) Monte Carlo on the same samples (``--samples``): peak
   ``var_theta`` with standard errors, and SL (Gaussian closure) on the same condensed model.  On the
   first ``--detail`` samples, records of both models at 2 ms: time fractions in each contact
   regime, energy dissipated in the bed per corner-to-corner transition (zero crossing of theta)
   over the mean rocking energy ``(1/2) M theta'^2 + int K theta``, the share of it dissipated in
   uplift, and the rms gap of the coupled ``z_cb`` from its quasi-static value.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.core import condensation as condensations  # noqa: E402
from screening.applications.metrics import peak_with_se  # noqa: E402
from screening.report.tradeoff import calibrate_intensity  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.physics.contact import REGIME_FLIGHT, REGIME_FULL_CONTACT, contact_resultants  # noqa: E402
from screening.analysis.linearization import linearize  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402
from screening.solvers.simulate import simulate  # noqa: E402
from screening.solvers.synthesis import default_cutoff, ground_acceleration  # noqa: E402
from screening.solvers.timegrid import output_times  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
T_END, DT = 20.0, 0.05
ENVELOPE = Envelope(4.0, 2.0)
PAPER_BLOCK = Block(m=8.67, b=0.035, h=0.21)
PAPER_BED = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
HEAVY_BLOCK = Block(m=300.0, b=0.3, h=0.9)
HEAVY_BED = Foundation(k=1e9, lam=1e10, eps=0.0)
CONDENSED = ("paper", "cubic", "virtual_work")
FREE_RATIOS = (3.0, 10.0, 30.0)
TARGETS = (0.2, 0.5, 0.9)
FAMILIES = [
    ("paper block, white", PAPER_BLOCK, PAPER_BED, lambda s: WhiteNoise(s, ENVELOPE)),
    ("paper block, KT 40 rad/s", PAPER_BLOCK, PAPER_BED, lambda s: KanaiTajimi(s, 40.0, 0.4, ENVELOPE)),
    ("300 kg block, white", HEAVY_BLOCK, HEAVY_BED, lambda s: WhiteNoise(s, ENVELOPE)),
]


def theta_ul(block, bed):
    return float(condensations.get("paper").uplift_threshold(block, bed))


def potential(amplitude, block, bed, cond="paper"):
    """``int_0^A K(theta) theta dtheta`` [J] of a condensation."""
    th = np.linspace(0.0, amplitude, 4001)
    return float(np.trapezoid(condensations.get(cond).restoring_moment(th, block, bed), th))


def dissipated_power(ds, block, bed, model, cond="paper"):
    """Power [W] dissipated in the bed along a simulated record."""
    th, w = ds.theta.values, ds.theta_dot.values
    if model == "coupled":
        f, m = contact_resultants(th, w, ds.z_cb.values, ds.z_cb_dot.values, block.b, 0.0, 0.0, bed.damping,
                                  bed.winkler)
        return f * ds.z_cb_dot.values + m * w
    return condensations.get(cond).rocking_damping(th, block, bed) * w * w


def free_rocking(block, bed, ratio, model, cond="paper"):
    tu = theta_ul(block, bed)
    out_dt = 2e-5
    ds = simulate(block, bed, np.zeros(4), dt=0.1, model=model, condensation=cond, theta0=ratio * tu, t_end=1.5,
                  output_dt=out_dt)
    th = ds.theta.values
    turn = np.flatnonzero((th[1:-1] - th[:-2]) * (th[2:] - th[1:-1]) < 0) + 1
    amp = np.abs(th[turn])
    decay = float(np.mean(amp[1:4] / amp[:3])) if amp.size > 3 else float("nan")
    first = slice(0, turn[0] + 1)
    power = dissipated_power(ds, block, bed, model, cond)[first]
    up = np.abs(th[first]) > tu
    e0 = potential(ratio * tu, block, bed)
    gap = float("nan")
    if model == "coupled":
        from screening.core.condensation.cubic import quasi_static_indentation
        z_qs = quasi_static_indentation(th[first], block, bed)[0]
        gap = float(np.max(np.abs(ds.z_cb.values[first] - z_qs)) / (block.m * block.g / (2 * block.b * bed.k)))
    return dict(decay=decay, uplift=float(np.sum(power[up]) * out_dt / e0),
                contact=float(np.sum(power[~up]) * out_dt / e0), gap=gap)


def free_rocking_table():
    print("\n### Free rocking: amplitude ratio per half cycle and energy dissipated in the first half cycle\n")
    print("| block | theta0 / theta_ul | coupled | paper | cubic | virtual_work | dissipated in uplift: coupled / "
          "paper | in full contact: coupled / paper | max abs(z_cb - quasi-static) / z_st (coupled) |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for label, block, bed in (("paper block", PAPER_BLOCK, PAPER_BED), ("300 kg block", HEAVY_BLOCK, HEAVY_BED)):
        for r in FREE_RATIOS:
            c = free_rocking(block, bed, r, "coupled")
            cond = {name: free_rocking(block, bed, r, "condensed", name) for name in CONDENSED}
            rows.append(dict(block=label, ratio=r, coupled=c["decay"], **{n: cond[n]["decay"] for n in CONDENSED}))
            print(f"| {label} | {r:g} | {c['decay']:.3f} | {cond['paper']['decay']:.3f} | {cond['cubic']['decay']:.3f} "
                  f"| {cond['virtual_work']['decay']:.3f} | {c['uplift']:.3f} / {cond['paper']['uplift']:.3f} | "
                  f"{c['contact']:.3f} / {cond['paper']['contact']:.3f} | {c['gap']:.2f} |")
    return rows


def record_detail(block, bed, excitation, n_detail, seed):
    """Transition statistics of both models over the first ``n_detail`` synthesized records."""
    cutoff = default_cutoff(block, bed)
    t_acc, acc, _ = ground_acceleration(excitation, T_END, cutoff, n_detail, seed)
    dt_acc = float(t_acc[1] - t_acc[0])
    tu = theta_ul(block, bed)
    z_st = block.m * block.g / (2 * block.b * bed.k)
    out = {}
    for model in ("coupled", "condensed"):
        frac = np.zeros(3)
        per_transition, share_up, gaps = [], [], []
        for i in range(n_detail):
            ds = simulate(block, bed, acc[i], dt=dt_acc, model=model, t_end=T_END, output_dt=0.002)
            if ds.attrs["status"] != "ok":
                continue
            th, w = ds.theta.values, ds.theta_dot.values
            regime = ds.contact_regime.values
            strong = ds.t.values <= 12.0                     # the shaking (envelope above 5 % of its peak)
            frac += [np.mean(regime[strong] == REGIME_FULL_CONTACT), np.mean(regime[strong] == REGIME_FLIGHT), 0.0]
            frac[2] += np.mean((regime[strong] != REGIME_FULL_CONTACT) & (regime[strong] != REGIME_FLIGHT))
            power = dissipated_power(ds, block, bed, model)
            up = np.abs(th) > tu
            n_cross = max(int(np.count_nonzero(np.diff(np.sign(th[strong])) != 0)), 1)
            energy = 0.5 * block.m_sdof * w * w + np.interp(np.abs(th), *_potential_table(block, bed))
            per_transition.append(np.sum(power[strong]) * 0.002 / n_cross / np.mean(energy[strong]))
            share_up.append(np.sum(power[strong & up]) / np.sum(power[strong]))
            if model == "coupled":
                from screening.core.condensation.cubic import quasi_static_indentation
                z_qs = quasi_static_indentation(th[strong], block, bed)[0]
                gaps.append(np.sqrt(np.mean((ds.z_cb.values[strong] - z_qs) ** 2)) / z_st)
        n = len(per_transition)
        out[model] = dict(n=n, contact=frac[0] / max(n, 1), flight=frac[1] / max(n, 1), uplift=frac[2] / max(n, 1),
                          per_transition=float(np.mean(per_transition)),
                          per_transition_se=float(np.std(per_transition, ddof=1) / np.sqrt(n)),
                          share_up=float(np.mean(share_up)), gap=float(np.mean(gaps)) if gaps else float("nan"))
    return out


_TABLES = {}


def _potential_table(block, bed):
    key = (float(block.m), float(block.b), float(bed.k))
    if key not in _TABLES:
        th = np.linspace(0.0, float(block.slenderness), 20001)
        mom = condensations.get("paper").restoring_moment(th, block, bed)
        _TABLES[key] = (th, np.concatenate([[0.0], np.cumsum(0.5 * (mom[1:] + mom[:-1]) * np.diff(th))]))
    return _TABLES[key]


def random_table(samples, n_detail, seed):
    t_out = output_times(T_END, DT)
    results = []
    for label, block, bed, make_exc in FAMILIES:
        for target in TARGETS:
            S0 = calibrate_intensity(block, bed, make_exc, target, t_out)
            exc = make_exc(S0)
            row = dict(family=label, target=target, S0=S0)
            for model, cond in (("coupled", "paper"), ("condensed", "paper"), ("condensed", "virtual_work")):
                mc = monte_carlo(block, bed, exc, n_samples=samples, model=model, condensation=cond, t_end=T_END,
                                 dt=DT, seed=seed, progress=False)
                v, se = peak_with_se(mc.var_theta.values, mc.var_theta_se.values)
                row[f"{model}_{cond}"] = (float(v), float(se), int(mc.n_overturned), float(mc.p_uplift.max()))
            for cond in ("paper", "virtual_work"):
                ds = linearize(block, bed, exc, t_end=T_END, dt=DT, condensation=cond)
                row[f"sl_{cond}"] = (float(ds.peak_var_theta), int(ds.status), float(ds.peak_p_uplift))
            row["detail"] = record_detail(block, bed, exc, n_detail, seed)
            results.append(row)
            print(f"  {label} p{target:g} done", flush=True)

    print(f"\n### Random shaking: the two errors (Monte Carlo {samples} samples, seed {seed})\n")
    print("| family | SL(paper) p_uplift | coupled MCS peak var_theta [rad2] | overturned | condensed (paper) vs coupled "
          "| SL(paper) vs condensed (paper) | SL(paper) vs coupled | p_uplift coupled / condensed |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        cv, cse, cover, cp = r["coupled_paper"]
        dv, dse, _, dp = r["condensed_paper"]
        sl = r["sl_paper"][0]
        print(f"| {r['family']} | {r['sl_paper'][2]:.2f} | {cv:.3g} ± {cse:.1g} | {cover}/{samples} | "
              f"{100 * (dv / cv - 1):+.0f} % ± {100 * dv / cv * np.hypot(cse / cv, dse / dv):.0f} | "
              f"{100 * (sl / dv - 1):+.0f} % ± {100 * sl / dv * dse / dv:.0f} | {100 * (sl / cv - 1):+.0f} % | "
              f"{cp:.2f} / {dp:.2f} |")
    print("\n| family | SL(paper) p_uplift | condensed (virtual_work) vs coupled | SL(virtual_work) vs condensed "
          "(virtual_work) | SL(virtual_work) vs coupled | SL(virtual_work) p_uplift |")
    print("|---|---|---|---|---|---|")
    for r in results:
        cv, cse = r["coupled_paper"][:2]
        dv, dse = r["condensed_virtual_work"][:2]
        sl, st, sp = r["sl_virtual_work"]
        print(f"| {r['family']} | {r['sl_paper'][2]:.2f} | {100 * (dv / cv - 1):+.0f} % ± "
              f"{100 * dv / cv * np.hypot(cse / cv, dse / dv):.0f} | {100 * (sl / dv - 1):+.0f} % ± "
              f"{100 * sl / dv * dse / dv:.0f}{'*' if st else ''} | {100 * (sl / cv - 1):+.0f} % | {sp:.2f} |")
    print(f"\n### Random shaking: corner-to-corner transitions ({n_detail} records per point, 2 ms output, t <= 12 s)\n")
    print("| family | SL(paper) p_uplift | time in full contact / uplift / flight: coupled | same: condensed (paper) | "
          "dissipated per transition / mean rocking energy: coupled | condensed (paper) | share dissipated in uplift: "
          "coupled / condensed | rms abs(z_cb - quasi-static) / z_st |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        c, d = r["detail"]["coupled"], r["detail"]["condensed"]
        print(f"| {r['family']} | {r['sl_paper'][2]:.2f} | {c['contact']:.2f} / {c['uplift']:.2f} / {c['flight']:.3f} | "
              f"{d['contact']:.2f} / {d['uplift']:.2f} / {d['flight']:.3f} | {c['per_transition']:.3f} ± "
              f"{c['per_transition_se']:.3f} | {d['per_transition']:.3f} ± {d['per_transition_se']:.3f} | "
              f"{c['share_up']:.2f} / {d['share_up']:.2f} | {c['gap']:.2f} |")
    return results


def figure(free_rows, random_rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = {"coupled": ("k", "o"), "paper": ("tab:red", "s"), "cubic": ("tab:orange", "^"),
              "virtual_work": ("tab:blue", "D")}
    for block, ls in (("paper block", "-"), ("300 kg block", "--")):
        rows = [r for r in free_rows if r["block"] == block]
        for name, (color, marker) in styles.items():
            ax1.plot([r["ratio"] for r in rows], [r[name] for r in rows], ls, color=color, marker=marker,
                     label=f"{name} ({block})")
    ax1.set_xscale("log")
    ax1.set_xlabel("release amplitude theta0 / theta_ul [1]")
    ax1.set_ylabel("amplitude ratio per half cycle [1]")
    ax1.set_title("free rocking: amplitude kept per corner-to-corner transition", fontsize=10)
    ax1.legend(fontsize=6.5, ncol=2)
    for key, label, color, marker in (("condensed_paper", "condensed MCS, paper", "tab:red", "s"),
                                      ("sl_paper", "SL, paper", "tab:red", "x"),
                                      ("condensed_virtual_work", "condensed MCS, virtual_work", "tab:blue", "D"),
                                      ("sl_virtual_work", "SL, virtual_work", "tab:blue", "+")):
        xs, ys, flagged = [], [], []
        for r in random_rows:
            cv = r["coupled_paper"][0]
            xs.append(r["sl_paper"][2])
            ys.append(r[key][0] / cv)
            bad = (key.startswith("sl") and r[key][1] != 0) or r["coupled_paper"][2] > 0
            flagged.append(bad)
        xs, ys, flagged = np.array(xs), np.array(ys), np.array(flagged)
        ax2.scatter(xs, ys, color=color, marker=marker, label=label)
        if flagged.any():
            ax2.scatter(xs[flagged], ys[flagged], facecolor="none", edgecolor="grey", marker="o", s=110)
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.axhspan(0.85, 1.15, color="0.9", zorder=0)
    ax2.set_yscale("log")
    ax2.set_xlabel("SL (paper) peak p_uplift [1]")
    ax2.set_ylabel("peak var_theta / coupled MCS [1]")
    ax2.set_title("random shaking, against coupled MCS\n(grey ring: SL flagged or coupled samples overturned)",
                  fontsize=10)
    ax2.legend(fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"\nfigure: {path}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--detail", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--figure", type=Path, default=ROOT / "docs" / "heavy_uplift_diagnosis.png")
    args = ap.parse_args(argv)
    start = time.process_time()
    free_rows = free_rocking_table()
    random_rows = random_table(args.samples, args.detail, args.seed)
    figure(free_rows, random_rows, args.figure)
    print(f"CPU {time.process_time() - start:.0f} s")


if __name__ == "__main__":
    main()
