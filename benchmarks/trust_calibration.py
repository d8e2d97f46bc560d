"""Calibration of the per-point trust rule (issue #14, part 1): SL indicators vs coupled Monte Carlo.

Run (regenerates ``screening/data/trust_calibration.nc``; the per-point results are kept in
``--work`` so an interrupted run resumes where it stopped)::

    nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/trust_calibration.py \
        [--samples 1000] [--seed 0] [--points NAME ...] [--out screening/data/trust_calibration.nc] \
        [--work outputs/trust_calibration] [--condensed] [--list] [--assemble-only] [--markdown]

The shipped file was made with ``--samples 1000 --seed 0 --condensed`` (1000 coupled samples at
every point; 24 min of coupled MCS and 3 min of condensed MCS, wall on one core of a shared 2-core
machine).

For every calibration point of :data:`POINTS` (a documented list: the trade study's regimes on the
paper block and bed, extended to stiff beds, a heavy block, the museum statue, near-toppling and
past-toppling intensities, both error signs) it computes

* the stochastic linearization with the ``"paper"`` condensation and, where the condensation
  exists for the point, with ``"cubic"`` (one row per condensation in the file), and from it the
  indicators of :func:`screening.analysis.trust.trust_indicators` (peak ``p_uplift``, the ``k_eq``
  margin ``min k_eq / k_eq(0)``, ``sigma_theta`` at the peak over the slenderness angle, the
  late-record decay of ``var_theta`` against the envelope) and SL's peak ``var_theta``;
* coupled-model Monte Carlo (the judge): peak ``var_theta`` over the surviving samples, its
  standard error at the peak time, the overturned and diverged counts;
* with ``--condensed`` also the condensed-model Monte Carlo (paper condensation) for the
  points on the paper bed (cheap: ~1/3 of the coupled cost);

and the relative error of SL's peak ``var_theta`` against the coupled model,
``SL / MCS - 1``, with its standard error ``(SL / MCS) x SE / MCS``.

Intensities are given either as ``S0`` [m2 s-3] or as a target SL peak uplift probability
(``S0`` found by bisection on SL, :func:`screening.report.tradeoff.calibrate_intensity`,
optionally multiplied by ``factor`` to go past toppling).  Intensity convention
``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``; envelope ``q(t) = 4 (exp(-t/4) - exp(-t/2))``; 20 s
records, output step 0.05 s.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from screening.core import condensation as condensations  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.analysis.linearization import linearize  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "screening" / "data" / "trust_calibration.nc"
DEFAULT_WORK = ROOT / "outputs" / "trust_calibration"
T_END, DT = 20.0, 0.05
ENVELOPE = Envelope(4.0, 2.0)

# ----------------------------------------------------------------------------- the calibration points
PAPER_BLOCK = dict(m=8.67, b=0.035, h=0.21)             # the paper's block (section 3)
PAPER_BED = dict(k=2.89e7, lam=8.95e8)                  # the paper's bed
STATUE = dict(m=600.0, b=0.2, h=0.8)                    # museum statue (issue #16)
STATUE_BED = dict(k=1e10, lam=3e11, eps=0.0)
HEAVY = dict(m=300.0, b=0.3, h=0.9)                     # hospital equipment
HEAVY_BED = dict(k=1e9, lam=1e10, eps=0.0)
WHITE = dict(kind="white")
KT10 = dict(kind="kanai_tajimi", omega_g=10.0, zeta_g=0.4)     # the paper's filter
KT40 = dict(kind="kanai_tajimi", omega_g=40.0, zeta_g=0.4)     # tuned near the paper block's rocking frequency
KT_STATUE = dict(kind="kanai_tajimi", omega_g=15.6, zeta_g=0.6)


def _point(name, family, block, bed, excitation, target=None, S0=None, factor=1.0, samples=None, note=""):
    return dict(name=name, family=family, block=block, bed=bed, excitation=excitation, target=target, S0=S0,
                factor=factor, samples=samples, note=note)


def _family(prefix, family, block, bed, excitation, targets, **kw):
    return [_point(f"{prefix}_p{t:g}", family, block, bed, excitation, target=t, **kw) for t in targets]


#: The calibration points.  ``target``: SL peak p_uplift (S0 by bisection), ``factor``: times that
#: S0 (past toppling), ``S0``: given directly; ``samples``: coupled MCS samples (default ``--samples``).
POINTS = [
    # paper block on the paper bed, hardening / linear / softening, white noise (the trade study's
    # white family, eps = 0 added; past toppling: 3x the S0 of p_uplift 0.85)
    *_family("paper_h_white", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 6e7}, WHITE,
             [0.001, 0.03, 0.15, 0.3, 0.85]),
    _point("paper_h_white_topple", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 6e7}, WHITE, target=0.85,
           factor=3.0, note="past toppling"),
    *_family("paper_0_white", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 0.0}, WHITE, [0.001, 0.1, 0.5]),
    *_family("paper_s_white", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, WHITE,
             [0.001, 0.03, 0.15, 0.3, 0.85]),
    _point("paper_s_white_topple", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, WHITE, target=0.85,
           factor=3.0, note="past toppling"),
    # Kanai-Tajimi tuned near the rocking frequency and the paper's filter
    *_family("paper_h_kt40", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 6e7}, KT40, [0.003, 0.15, 0.6, 0.95]),
    *_family("paper_s_kt40", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, KT40, [0.003, 0.15, 0.6]),
    *_family("paper_h_kt10", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 6e7}, KT10, [0.05, 0.3, 0.7]),
    *_family("paper_s_kt10", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, KT10, [0.05, 0.3]),
    *_family("paper_0_kt10", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 0.0}, KT10, [0.2]),
    # more low-uplift points on the softening and linear paper bed (enough rows per cell for a held-out test)
    *_family("paper_s_white", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, WHITE, [0.01, 0.06, 0.12]),
    *_family("paper_s_kt40", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, KT40, [0.03, 0.1]),
    *_family("paper_s_kt10", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": -6e5}, KT10, [0.01, 0.15]),
    *_family("paper_0_white", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 0.0}, WHITE, [0.01, 0.03]),
    *_family("paper_0_kt40", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 0.0}, KT40, [0.003, 0.03, 0.15]),
    *_family("paper_0_kt10", "paper_bed", PAPER_BLOCK, {**PAPER_BED, "eps": 0.0}, KT10, [0.05]),
    # paper block on stiff beds
    *_family("paper_stiff9_white", "stiff_bed", PAPER_BLOCK, dict(k=1e9, lam=1e10, eps=0.0), WHITE,
             [0.01, 0.3, 0.8]),
    *_family("paper_stiff10_kt10", "stiff_bed", PAPER_BLOCK, dict(k=1e10, lam=3e11, eps=0.0), KT10,
             [0.05, 0.5]),
    # museum statue (issue #16: SL over-predicts, lock-in after the shaking)
    *_family("statue_kt", "statue", STATUE, STATUE_BED, KT_STATUE, [0.05, 0.3, 0.8, 0.97]),
    # past the bisection range: SL's k_eq margin collapses; on the statue SL holds the response after the
    # shaking (lock-in: decay_excess 31 and 310), then topples (status 1)
    _point("statue_kt_lockin1", "statue", STATUE, STATUE_BED, KT_STATUE, S0=0.0066, note="lock-in"),
    _point("statue_kt_lockin2", "statue", STATUE, STATUE_BED, KT_STATUE, S0=0.011, note="lock-in"),
    _point("statue_kt_topple", "statue", STATUE, STATUE_BED, KT_STATUE, S0=0.0275,
           note="SL topples"),
    _point("paper_stiff9_white_margin", "stiff_bed", PAPER_BLOCK, dict(k=1e9, lam=1e10, eps=0.0), WHITE,
           S0=3.67e-5, note="k_eq margin 0.1"),
    _point("heavy_white_margin", "heavy", HEAVY, HEAVY_BED, WHITE, S0=4.19e-4, note="k_eq margin 0.08"),
    # heavy block (hospital equipment)
    *_family("heavy_white", "heavy", HEAVY, HEAVY_BED, WHITE, [0.01, 0.3, 0.8]),
    *_family("heavy_kt10", "heavy", HEAVY, HEAVY_BED, KT10, [0.3]),
]


def point_by_name():
    return {p["name"]: p for p in POINTS}


def make_models(point, S0=None):
    block = Block(**point["block"])
    foundation = Foundation(**point["bed"])
    exc = point["excitation"]

    def make_exc(s0):
        if exc["kind"] == "white":
            return WhiteNoise(s0, ENVELOPE)
        return KanaiTajimi(s0, exc["omega_g"], exc["zeta_g"], ENVELOPE)

    return block, foundation, make_exc


def point_S0(point):
    """``S0`` of a point (bisection on SL for a target uplift probability)."""
    if point["S0"] is not None:
        return float(point["S0"])
    from screening.report.tradeoff import calibrate_intensity
    from screening.solvers.timegrid import output_times

    block, foundation, make_exc = make_models(point)
    S0 = calibrate_intensity(block, foundation, make_exc, point["target"], output_times(T_END, DT))
    return float(S0 * point["factor"])


# ----------------------------------------------------------------------------- measurements
def sl_row(block, foundation, excitation, condensation):
    """SL summaries and the trust indicators of one point under one condensation (None if the
    condensation does not apply)."""
    from screening.analysis.trust import indicators_from_dataset

    try:
        ds = linearize(block, foundation, excitation, t_end=T_END, dt=DT, condensation=condensation)
    except ValueError as exc:
        return {"error": str(exc)}
    ind = indicators_from_dataset(ds)
    row = {name: float(np.asarray(value)) for name, value in ind.items()}
    row.update(status=int(ds.status), peak_var_theta=float(ds.peak_var_theta),
               t_peak_var_theta=float(ds.t_peak_var_theta), t_stop=float(ds.t_stop))
    return row


def mcs_row(block, foundation, excitation, model, samples, seed):
    t0 = time.perf_counter()
    ds = monte_carlo(block, foundation, excitation, n_samples=samples, model=model, t_end=T_END, dt=DT, seed=seed,
                     progress=False)
    v = ds.var_theta.values
    if np.any(np.isfinite(v)):
        i = int(np.nanargmax(v))
        peak, se, t_peak = float(v[i]), float(ds.var_theta_se.values[i]), float(ds.t.values[i])
        late = float(v[-1])
    else:
        peak = se = t_peak = late = math.nan
    return dict(peak_var_theta=peak, peak_var_theta_se=se, t_peak_var_theta=t_peak, var_theta_end=late,
                peak_p_uplift=float(np.nanmax(ds.p_uplift.values)) if np.any(np.isfinite(ds.p_uplift.values))
                else math.nan,
                n_samples=samples, n_overturned=int(ds.n_overturned), n_diverged=int(ds.n_diverged),
                wall=time.perf_counter() - t0)


def run_point(point, samples, seed, condensed):
    t0 = time.perf_counter()
    S0 = point_S0(point)
    block, foundation, make_exc = make_models(point)
    excitation = make_exc(S0)
    out = {"name": point["name"], "S0": S0, "sl": {}, "seed": seed}
    for cond in ("paper", "cubic"):
        out["sl"][cond] = sl_row(block, foundation, excitation, cond)
    n = point["samples"] or samples
    out["coupled"] = mcs_row(block, foundation, excitation, "coupled", n, seed)
    if condensed and point["family"] == "paper_bed":
        out["condensed"] = mcs_row(block, foundation, excitation, "condensed", n, seed)
    out["wall"] = time.perf_counter() - t0
    return out


# ----------------------------------------------------------------------------- the labelled file
def assemble(work, names):
    """The calibration dataset from the per-point JSON files: dimensions ``point`` x ``condensation``."""
    from screening.solvers import schema
    from screening.analysis.trust import error_of, trust_table

    rows = []
    for name in names:
        path = Path(work) / f"{name}.json"
        if path.exists():
            rows.append((point_by_name()[name], json.loads(path.read_text())))
    if not rows:
        raise SystemExit(f"no point results in {work}")
    conds = ["paper", "cubic"]
    n, c = len(rows), len(conds)
    ind_names = ("peak_p_uplift", "k_eq_margin", "sigma_ratio", "decay_excess")

    def sl(name, fill=math.nan):
        a = np.full((n, c), fill, dtype=float)
        for i, (_, r) in enumerate(rows):
            for j, cond in enumerate(conds):
                a[i, j] = r["sl"][cond].get(name, fill)
        return a

    def mc(model, name):
        return np.array([r.get(model, {}).get(name, math.nan) for _, r in rows], dtype=float)

    data = {f"sl_{name}": (("point", "condensation"), sl(name)) for name in ind_names}
    data["sl_peak_var_theta"] = (("point", "condensation"), sl("peak_var_theta"))
    data["sl_status"] = (("point", "condensation"), sl("status", -2).astype(np.int8))
    for model in ("coupled", "condensed"):
        for name in ("peak_var_theta", "peak_var_theta_se", "n_overturned", "n_diverged", "n_samples",
                     "peak_p_uplift", "var_theta_end", "wall"):
            data[f"{model}_{name}"] = ("point", mc(model, name))
    err, err_se = error_of(data["sl_peak_var_theta"][1], data["coupled_peak_var_theta"][1][:, None],
                           data["coupled_peak_var_theta_se"][1][:, None])
    data["sl_error"] = (("point", "condensation"), err)
    data["sl_error_se"] = (("point", "condensation"), err_se)
    coords = {
        "point": ("point", [p["name"] for p, _ in rows]),
        "condensation": ("condensation", conds),
        "family": ("point", [p["family"] for p, _ in rows]),
        "excitation_kind": ("point", [p["excitation"]["kind"] for p, _ in rows]),
        "contact": ("point", ["hunt_crossley"] * n),
        "target_peak_p_uplift": ("point", [p["target"] if p["target"] is not None else math.nan for p, _ in rows]),
        "S0": ("point", [r["S0"] for _, r in rows]),
    }
    for name in ("m", "b", "h"):
        coords[name] = ("point", [p["block"][name] for p, _ in rows])
    for name in ("k", "lam", "eps"):
        coords[name] = ("point", [p["bed"][name] for p, _ in rows])
    for name in ("omega_g", "zeta_g"):
        coords[name] = ("point", [p["excitation"].get(name, math.nan) for p, _ in rows])
    ds = xr.Dataset(data, coords=coords)
    ds = schema.apply_schema(ds, table=schema.TRUST_CALIBRATION)
    ds.attrs.update(
        title="Calibration of the SL trust rule: SL indicators and peak var_theta vs coupled Monte Carlo",
        command="nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/trust_calibration.py "
                f"--samples {max(int(s) for s in data['coupled_n_samples'][1] if s == s)} --seed "
                f"{rows[0][1]['seed']}" + (" --condensed" if any("condensed" in r for _, r in rows) else ""),
        t_end=T_END, dt_output=DT, envelope="exponential T1 = 4 s, T2 = 2 s",
        error_definition="sl_error = SL peak var_theta / coupled MCS peak var_theta (survivors) - 1; "
                         "sl_error_se = (SL / MCS) x SE(MCS peak) / MCS peak",
    )
    table = trust_table(ds)
    ds.attrs["trust_table"] = json.dumps(table)
    return ds


def markdown_table(ds):
    """The calibration table (one line per point and condensation) with the rule's flag and band, as markdown."""
    from screening.analysis.trust import bed_law, sl_trust
    from screening.core.status import Trust

    table = json.loads(ds.attrs["trust_table"])
    lines = ["| point | cond. | S0 [m2 s-3] | p_uplift | k_eq margin | sigma/slend. | decay excess | SL error vs "
             "coupled (± SE) | overturned | flag | band |", "|" + "---|" * 11]
    for point in ds.point.values:
        for cond in ds.condensation.values:
            r = ds.sel(point=point, condensation=cond)
            if int(r.sl_status) == -2:
                continue
            ind = {k: float(r[f"sl_{k}"]) for k in ("peak_p_uplift", "k_eq_margin", "sigma_ratio", "decay_excess")}
            flag, lo, hi = sl_trust(ind, table, status=int(r.sl_status), condensation=str(cond), eps=float(r.eps))
            err = float(r.sl_error)
            err_text = (f"{100 * err:+.0f} % ± {100 * float(r.sl_error_se):.0f}" if np.isfinite(err) else "n/a")
            status = "" if int(r.sl_status) == 0 else f" (status {int(r.sl_status)})"
            band = f"[{100 * float(lo):+.0f}, {100 * float(hi):+.0f}] %" if np.isfinite(lo) else "none"
            lines.append(f"| {point} | {cond} | {float(r.S0):.3g} | {ind['peak_p_uplift']:.3f}{status} | "
                         f"{ind['k_eq_margin']:.2f} | {ind['sigma_ratio']:.3g} | {ind['decay_excess']:.3g} | "
                         f"{err_text} | {int(r.coupled_n_overturned)}/{int(r.coupled_n_samples)} | "
                         f"{Trust(int(flag)).name} | {band} |")
    return "\n".join(lines)


def rule_table(ds):
    """The rule's cells as markdown (flag, band, number of calibration rows)."""
    from screening.analysis.trust import BED_LAWS, CONDENSATIONS, P_EDGES
    from screening.core.status import Trust

    table = json.loads(ds.attrs["trust_table"])
    bins = [f"{P_EDGES[i]:g}–{P_EDGES[i + 1]:g}" for i in range(len(P_EDGES) - 1)]
    lines = ["| condensation | bed | " + " | ".join(f"p_uplift {b}" for b in bins) + " |",
             "|" + "---|" * (2 + len(bins))]
    for cond in CONDENSATIONS:
        for law in BED_LAWS:
            cells = []
            for b in range(len(bins)):
                c = table["cells"][f"{cond}|{law}|{b}"]
                band = (f"[{100 * c['band'][0]:+.0f}, {100 * c['band'][1]:+.0f}] %" if np.isfinite(c["band"][0])
                        else "no band")
                cells.append(f"{Trust(c['flag']).name} {band} (n={c['n']})")
            lines.append(f"| {cond} | {law} | " + " | ".join(cells) + " |")
    for name, o in table["overrides"].items():
        band = f"[{100 * o['band'][0]:+.0f}, {100 * o['band'][1]:+.0f}] %" if np.isfinite(o["band"][0]) else "no band"
        lines.append(f"\n{name}: untrusted, band {band} (n={o['n']})")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000, help="coupled MCS samples (points may ask fewer)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--points", nargs="+", default=None, help="subset of point names (default: all)")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    parser.add_argument("--work", default=str(DEFAULT_WORK), help="per-point JSON results (resumable)")
    parser.add_argument("--condensed", action="store_true", help="also condensed MCS on the paper bed")
    parser.add_argument("--force", action="store_true", help="recompute points already in --work")
    parser.add_argument("--list", action="store_true", help="list the points and exit")
    parser.add_argument("--assemble-only", action="store_true", help="only build --out from --work")
    parser.add_argument("--markdown", action="store_true", help="print the calibration and rule tables of --out")
    args = parser.parse_args(argv)
    names = args.points or [p["name"] for p in POINTS]
    unknown = sorted(set(names) - set(point_by_name()))
    if unknown:
        parser.error(f"unknown points {unknown}")
    if args.list:
        for p in POINTS:
            print(p["name"], p["family"], p["excitation"], p["target"], p["factor"], p["note"])
        return
    if args.markdown:
        with xr.open_dataset(args.out) as ds:
            print(markdown_table(ds))
            print()
            print(rule_table(ds))
        return
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    if not args.assemble_only:
        total = time.perf_counter()
        for name in names:
            path = work / f"{name}.json"
            if path.exists() and not args.force:
                res = json.loads(path.read_text())
                point = point_by_name()[name]
                if args.condensed and point["family"] == "paper_bed" and "condensed" not in res:
                    block, foundation, make_exc = make_models(point)       # add the condensed MCS only
                    res["condensed"] = mcs_row(block, foundation, make_exc(res["S0"]), "condensed",
                                               point["samples"] or args.samples, args.seed)
                    path.write_text(json.dumps(res, indent=1))
                    mc, cd = res["coupled"], res["condensed"]
                    print(f"{name}: condensed MCS {100 * (cd['peak_var_theta'] / mc['peak_var_theta'] - 1):+.0f} % vs "
                          f"coupled, overturned {cd['n_overturned']}/{cd['n_samples']}, wall {cd['wall']:.0f} s",
                          flush=True)
                continue
            try:
                res = run_point(point_by_name()[name], args.samples, args.seed, args.condensed)
            except Exception as exc:                         # keep going: one bad point must not stop the run
                print(f"{name}: FAILED {type(exc).__name__}: {exc}", flush=True)
                continue
            path.write_text(json.dumps(res, indent=1))
            sl, mc = res["sl"]["paper"], res["coupled"]
            err = sl.get("peak_var_theta", math.nan) / mc["peak_var_theta"] - 1.0
            print(f"{name}: S0 {res['S0']:.3g} SL p_up {sl.get('peak_p_uplift', math.nan):.3f} status "
                  f"{sl.get('status')} err {100 * err:+.0f} % (SE {100 * mc['peak_var_theta_se'] / mc['peak_var_theta']:.0f} %)"
                  f" overturned {mc['n_overturned']}/{mc['n_samples']} wall {res['wall']:.0f} s "
                  f"(total {time.perf_counter() - total:.0f} s)", flush=True)
    ds = assemble(work, [p["name"] for p in POINTS])
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(out)
    print(f"wrote {out} ({ds.sizes['point']} points)", file=sys.stderr)


if __name__ == "__main__":
    main()
