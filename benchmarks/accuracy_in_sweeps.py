"""Best estimates of ``[accuracy]`` as the product makes them: one S0 sweep per calibration family (issue #14).

Run (one sweep per family; all 14 families took 16 min wall at ``--budget 120`` and 50 min at the package's
default budget, 600 s, on a shared 2-core machine; a family whose result is up to date is reused, so an
interrupted run resumes)::

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python \
        benchmarks/accuracy_in_sweeps.py [--families NAME ...] [--budget 600] [--target 0.15] [--grid 12] \
        [--work outputs/accuracy_in_sweeps] [--force] [--table-only]
    ... benchmarks/accuracy_in_sweeps.py --atlas screening/data/error_atlas.nc [--condensation paper] \
        [--sweep-points 10000] [--budget 600] [--target 0.15] [--holdout-points 20] [--holdout-samples 1000]

``--atlas FILE``: the error atlas's held-out points instead of the calibration families.  Each atlas point
is predicted by the error model fitted *without its family* (grouped cross-validation,
:func:`screening.analysis.error_model.grouped_cross_validation`), and its best estimate is what
``[accuracy]`` makes of a point of a large sweep where no Monte Carlo ran
(:func:`screening.analysis.correction.best_estimates` with no escalated point: the linearization where its
band promises the target, else the atlas-corrected linearization, else ``unreliable``); it is compared with
the atlas's 500-sample reference.  Prints the fraction ``unreliable``, the fraction of points that need
Monte Carlo (the atlas interval wider than the target), and the hold rate (within the target or within 2
reported SE; and with the reference's own SE).  ``--sweep-points N`` (> 0) also runs the ``N``-point sweep of
``benchmarks/accuracy_escalation.py`` (the eps x S0 grid of ``bench_sweep.py``) with ``[accuracy]`` and
``--budget`` and prints its best-estimate methods and unreliable fraction, the probabilities' sources, which
quantity answers the points (``answer_quantity``: the variance, or near toppling the probabilities) with the
unreliable counts (variance; without any reliable answer), and the study's fragility surface; then, as
held-out truth for that surface, coupled Monte Carlo (``--holdout-samples``, the escalation's task and
settings, the study's seed + 1) at ``--holdout-points`` random points whose ``p_overturn`` came from the surface,
and the share within 2 combined standard errors (goal >= 90 %).  The sweep stores the histories the corrected
probabilities need (``c_eq`` among them: :data:`screening.sweep.probabilities.CORRECTION_HISTORIES`).

``benchmarks/accuracy_escalation.py`` corrects each calibration point from the *other* calibration points,
which belong to other blocks, beds and excitations: a stress test of the correction across families.  A
study, though, sweeps one block, bed and excitation over the intensity and corrects its points from the
escalated points of the *same* sweep.  This benchmark measures that.

The paper-condensation calibration points of ``screening/data/trust_calibration.nc`` (those with SL status
ok, the 58 of ``accuracy_escalation.py``) are grouped into *families* sharing block (m, b, h), bed (contact,
k, lam, eps) and excitation (kind, omega_g, zeta_g); for each family a study (condensation ``paper``,
exponential envelope T1 = 4 s, T2 = 2 s, 20 s records, output step 0.05 s, the histories the trust rule
reads) sweeps ``S0`` over the sorted union of ``geomspace(min S0 / 1.5, max S0 * 1.5, --grid)`` and the
family's calibration ``S0`` values, with ``[accuracy] target = --target, budget_s = --budget, seed = 0``,
and runs on two local workers (``run_sweep``; result ``--work/<family>.nc``).

At each calibration ``S0`` the best estimate (``best_peak_var_theta``, its standard error and
``best_method``) is compared with the point's 1000-sample coupled Monte Carlo reference from the
calibration file.  It *holds* as in ``accuracy_escalation.holds``: within the target, or
``|best - MCS| <= 2 SE_best``; the second column also counts the reference's own noise:
``|best - MCS| <= target MCS`` or ``<= 2 sqrt(SE_best^2 + SE_ref^2)``.  Prints the per-point table, counts
(all points, escalated, corrected, unreliable; per family), the Monte Carlo CPU seconds of each family's
escalation (cost model and measured) and its wall time; writes the table as markdown to
``--work/table.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

from accuracy_escalation import OUTPUT, holds  # noqa: E402

from screening.core.status import BestMethod  # noqa: E402
from screening.sweep.study import DEFAULT_BUDGET_S  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_WORK = ROOT / "outputs" / "accuracy_in_sweeps"
#: The coordinates of the calibration file that define a family (a block, a bed, an excitation).
FAMILY_KEYS = ("m", "b", "h", "contact", "k", "lam", "eps", "excitation_kind", "omega_g", "zeta_g")
#: The grid's margin beyond the family's calibration intensities (factor on S0).
MARGIN = 1.5
SEED = 0


def family_name(names):
    """A family's name: the points' common name prefix up to its last ``_`` (``statue_kt_p0.05`` and
    ``statue_kt_lockin1`` -> ``statue_kt``)."""
    prefix = os.path.commonprefix(list(names))
    return prefix.rsplit("_", 1)[0] if "_" in prefix else prefix


def calibration_families():
    """``{family: dict(points, S0, ref, ref_se, params)}`` of the paper-condensation calibration points
    with SL status ok, in the file's order."""
    from screening.analysis.trust import calibration_rows, shipped_calibration

    cal = shipped_calibration()
    rows = calibration_rows(cal)
    names = np.asarray(rows["point"])[np.asarray(rows["condensation"]) == "paper"]
    sel = cal.sel(point=names)
    groups = {}
    for i, name in enumerate(names):
        key = tuple(_key_value(sel[c].values[i]) for c in FAMILY_KEYS)
        groups.setdefault(key, []).append(i)
    out = {}
    for key, idx in groups.items():
        params = dict(zip(FAMILY_KEYS, key))
        fam = family_name(names[idx])
        out[fam] = dict(points=[str(names[i]) for i in idx], S0=sel["S0"].values[idx].astype(float),
                        ref=sel["coupled_peak_var_theta"].values[idx].astype(float),
                        ref_se=sel["coupled_peak_var_theta_se"].values[idx].astype(float),
                        ref_n=sel["coupled_n_samples"].values[idx].astype(float), params=params)
    return out


def _key_value(v):
    v = v.item() if hasattr(v, "item") else v
    if isinstance(v, float) and np.isnan(v):
        return None
    return v


def sweep_values(S0, grid):
    """The sorted union of ``geomspace(min S0 / MARGIN, max S0 * MARGIN, grid)`` and the calibration ``S0``
    values themselves [m2 s-3]."""
    S0 = np.asarray(S0, dtype=float)
    base = np.geomspace(S0.min() / MARGIN, S0.max() * MARGIN, grid)
    return np.unique(np.concatenate([base, S0]))


def study_text(family, params, S0_values, target, budget):
    """The TOML of the family's sweep over ``S0_values`` with ``[accuracy]``."""
    p = params
    lines = [f'title = "accuracy in sweeps: {family}"', "", "[block]", f"m = {p['m']!r}", f"b = {p['b']!r}",
             f"h = {p['h']!r}", "", "[foundation]", f'contact = "{p["contact"]}"', 'condensation = "paper"',
             f"k = {p['k']!r}", f"lam = {p['lam']!r}", f"eps = {p['eps']!r}", "", "[excitation]",
             f'kind = "{p["excitation_kind"]}"']
    if p["excitation_kind"] == "kanai_tajimi":
        lines += [f"omega_g = {p['omega_g']!r}", f"zeta_g = {p['zeta_g']!r}"]
    lines += ["S0 = [" + ", ".join(repr(float(s)) for s in S0_values) + "]", 'envelope = "exponential"',
              "T1 = 4.0", "T2 = 2.0", "", "[time]", "t_end = 20.0", "dt = 0.05", "", OUTPUT,
              "[accuracy]", f"target = {target!r}", f"budget_s = {budget!r}", f"seed = {SEED}", ""]
    return "\n".join(lines)


def run_family(family, fam, args):
    """Run (or reuse) the family's sweep; returns the sidecar info (wall time, escalation report)."""
    from screening.sweep.study import parse_study
    from screening.sweep.run import run_sweep

    out = args.work / f"{family}.nc"
    side = args.work / f"{family}.json"
    text = study_text(family, fam["params"], sweep_values(fam["S0"], args.grid), args.target, args.budget)
    (args.work / f"{family}.toml").write_text(text)
    study = parse_study(text, name=family)
    start = time.perf_counter()
    report = run_sweep(study, out, workers=2, force=args.force, progress=False,
                       log=lambda m: print(f"    [{family}] {m}", file=sys.stderr, flush=True))
    wall = time.perf_counter() - start
    if report.reused and side.exists():
        return json.loads(side.read_text())
    info = dict(family=family, wall_s=wall, n_points=study.n_points, accuracy=report.accuracy)
    side.write_text(json.dumps(info, indent=1, default=float))
    return info


def family_rows(family, fam, path, target):
    """Per calibration point of the family: SL, band, trust, the best estimate and the reference."""
    import xarray as xr

    from screening.core.status import Trust

    rows = []
    with xr.open_dataset(path) as ds:
        grid = ds["S0"].values
        escalated = set(int(i) for i in ds["esc_grid_index"].values) if "esc_grid_index" in ds else set()
        for name, s0, ref, ref_se, n in zip(fam["points"], fam["S0"], fam["ref"], fam["ref_se"], fam["ref_n"]):
            i = int(np.argmin(np.abs(grid / s0 - 1)))
            if not np.isclose(grid[i], s0, rtol=1e-9, atol=0):
                raise SystemExit(f"{path}: no grid point at the calibration S0 {s0!r} of {name} (nearest {grid[i]!r})")
            sl = float(ds["peak_var_theta"].values[i])
            best = float(ds["best_peak_var_theta"].values[i])
            se = float(ds["best_peak_var_theta_se"].values[i])
            rows.append(dict(point=name, family=family, samples=int(n), sl_error=sl / ref - 1,
                             low=float(ds["sl_error_low"].values[i]), high=float(ds["sl_error_high"].values[i]),
                             trust=Trust(int(ds["sl_trust"].values[i])).name, best_error=best / ref - 1,
                             best_rel_se=se / best, mc_rel_se=ref_se / ref,
                             method=BestMethod(int(ds["best_method"].values[i])).name, escalated=i in escalated,
                             best=best, best_se=se, ref=ref, ref_se=ref_se))
        attrs = dict(cost_s=float(ds.attrs.get("accuracy_cost_s", np.nan)),
                     cpu_s=float(ds.attrs.get("accuracy_cpu_s", np.nan)),
                     n_escalated=int(ds.attrs.get("accuracy_n_escalated", len(escalated))),
                     n_points=int(grid.size), budget_s=float(ds.attrs.get("accuracy_budget_s", np.nan)))
    return rows, attrs


def holds_with_reference(row, target):
    """Within the target, or the error within 2 combined standard errors (the best estimate's and the
    reference's: ``|best - MCS| <= 2 sqrt(SE_best^2 + SE_ref^2)``).  An ``unreliable`` point (NaN SE) holds
    only if within the target."""
    diff = abs(row["best"] - row["ref"])
    return bool(diff <= target * row["ref"] or diff <= 2 * np.hypot(row["best_se"], row["ref_se"]))


def _yes(ok, row):
    return "yes" if ok else ("no (flagged)" if row["method"] == "unreliable" else "NO")


COLUMNS = ("point", "family", "SL err", "band", "sl_trust", "best err", "best SE", "ref SE", "best_method",
           "escalated", "holds", "holds (ref noise)")


def table_lines(rows, target):
    """The per-point table as text lines and as markdown lines."""
    text = [f"{'point':26s} {'family':18s} {'SL err':>8s} {'band':>17s} {'sl_trust':>9s} | {'best err':>8s} "
            f"{'best SE':>8s} {'ref SE':>6s} {'best_method':>24s} {'esc':>3s} {'holds':>12s} {'+ref noise':>12s}"]
    md = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for r in rows:
        a, b = holds(r, target), holds_with_reference(r, target)
        cells = (r["point"], r["family"], f"{r['sl_error']:+.1%}", f"[{r['low']:+.1%}, {r['high']:+.1%}]", r["trust"],
                 f"{r['best_error']:+.1%}", f"{r['best_rel_se']:.1%}", f"{r['mc_rel_se']:.1%}", r["method"],
                 "yes" if r["escalated"] else "no", _yes(a, r), _yes(b, r))
        text.append(f"{cells[0]:26s} {cells[1]:18s} {cells[2]:>8s} {cells[3]:>17s} {cells[4]:>9s} | {cells[5]:>8s} "
                    f"{cells[6]:>8s} {cells[7]:>6s} {cells[8]:>24s} {cells[9]:>3s} {cells[10]:>12s} {cells[11]:>12s}")
        md.append("| " + " | ".join(cells) + " |")
    return text, md


def count_line(label, rows, target):
    n = len(rows)
    a = sum(holds(r, target) for r in rows)
    b = sum(holds_with_reference(r, target) for r in rows)
    return (f"{label:34s} {n:3d} points: holds {a:3d} ({a / max(n, 1):4.0%}), "
            f"with reference noise {b:3d} ({b / max(n, 1):4.0%})")


def summary_lines(rows, info, target):
    """Counts on all points, escalated / corrected / unreliable ones, per family; cost per family."""
    lines = [f"best estimate holds (within {target:.0%} or |error| <= 2 SE_best; second count: or <= 2 sqrt(SE_best^2 "
             f"+ SE_ref^2)):", count_line("all", rows, target),
             count_line("escalated here (Monte Carlo)", [r for r in rows if r["escalated"]], target),
             count_line("corrected (not escalated, vouched)",
                        [r for r in rows if not r["escalated"] and r["method"] != "unreliable"], target),
             count_line("unreliable (flagged)", [r for r in rows if r["method"] == "unreliable"], target)]
    sl_within = sum(abs(r["sl_error"]) <= target for r in rows)
    lines.append(f"(SL itself within {target:.0%}: {sl_within} of {len(rows)})")
    wrong = [r["point"] for r in rows if not holds(r, target) and r["method"] != "unreliable"]
    lines.append(f"wrong without the unreliable flag: {len(wrong)}" + (f" ({', '.join(wrong)})" if wrong else ""))
    lines += ["", "per family:", f"{'family':20s} {'grid':>4s} {'esc':>4s} {'MC cost s':>9s} {'MC CPU s':>8s} "
              f"{'wall s':>7s}  holds / points (with ref noise)"]
    total = dict(cost=0.0, cpu=0.0, wall=0.0)
    for fam, (attrs, side) in info.items():
        fr = [r for r in rows if r["family"] == fam]
        a = sum(holds(r, target) for r in fr)
        b = sum(holds_with_reference(r, target) for r in fr)
        wall = float(side.get("wall_s", np.nan)) if side else np.nan
        total["cost"] += attrs["cost_s"]
        total["cpu"] += attrs["cpu_s"]
        total["wall"] += wall
        lines.append(f"{fam:20s} {attrs['n_points']:4d} {attrs['n_escalated']:4d} {attrs['cost_s']:9.1f} "
                     f"{attrs['cpu_s']:8.1f} {wall:7.1f}  {a} / {len(fr)} ({b})")
    lines.append(f"{'total':20s} {'':4s} {'':4s} {total['cost']:9.1f} {total['cpu']:8.1f} {total['wall']:7.1f}")
    return lines


def atlas_rows(atlas, condensation, target):
    """Per atlas point (with a reference and the linearization at status ok or stopped): the best estimate of a
    point of a sweep without Monte Carlo there, from the error model fitted without the point's family."""
    import xarray as xr

    from screening.analysis import error_model as em
    from screening.analysis.correction import best_estimates

    ds = xr.load_dataset(atlas)
    s = ds.sel(condensation=condensation)
    t = em.targets(ds, condensation)
    x = em.atlas_features(ds, condensation)
    est, lo, hi = em.grouped_cross_validation(x, t["log_var_ratio"], ds["family"].values, clip=em.LOG_CLIP)
    # the model's interval at every point whose features are finite, whether or not its error is known
    missing = ~np.isfinite(est) & np.all(np.isfinite(x), axis=1)
    if missing.any():
        for fam in np.unique(ds["family"].values[missing]):
            held = ds["family"].values == fam
            train = ~held & np.isfinite(t["log_var_ratio"])
            model = em.fit_error_model(x[train], t["log_var_ratio"][train], ds["family"].values[train], clip=em.LOG_CLIP)
            pick = held & missing
            est[pick], lo[pick], hi[pick] = em.predict(model, x[pick])
    status = s["sl_status"].values.astype(int)
    est, lo, hi = em.open_ended(est, lo, hi)
    low, high = np.where(status == 0, np.expm1(lo), np.nan), np.where(status == 0, np.expm1(hi), np.nan)
    trust = np.where(status == 0, em.trust_from_interval(lo, hi), 2)
    sl = s["sl_peak_var_theta"].values
    n = sl.size
    value, se, method, _ = best_estimates(sl, status, trust, low, high, target, np.zeros((n, 1)),
                                          np.zeros(0, dtype=int), np.zeros(0), np.zeros(0), np.zeros(0))
    ref, ref_se = ds["mc_peak_var_theta"].values, ds["mc_peak_var_theta_se"].values
    keep = np.isfinite(ref) & (ref > 0) & em.valid_reference(ds)
    return dict(value=value[keep], se=se[keep], method=method[keep], ref=ref[keep], ref_se=ref_se[keep],
                needs_mc=~(linearization_or_atlas(trust, low, high, target) & (status == 0))[keep],
                status=status[keep], p=s["sl_peak_p_uplift"].values[keep])


def linearization_or_atlas(trust, low, high, target):
    """True where [accuracy] needs no Monte Carlo at a point (:func:`screening.analysis.escalation.escalation_candidates`
    is False)."""
    from screening.analysis.correction import atlas_promises, linearization_promises

    return linearization_promises(trust, low, high, target) | atlas_promises(low, high, target)


def atlas_summary(r, target, label):
    """Printed lines: unreliable fraction, Monte Carlo need and hold rates of :func:`atlas_rows`."""
    n = r["value"].size
    with np.errstate(invalid="ignore", divide="ignore"):
        err = r["value"] / r["ref"] - 1
        within = np.abs(err) <= target
        by_se = np.abs(r["value"] - r["ref"]) <= 2 * r["se"]
        by_both = np.abs(r["value"] - r["ref"]) <= 2 * np.sqrt(r["se"] ** 2 + r["ref_se"] ** 2)
    holds = within | by_se
    holds_ref = within | by_both
    unreliable = r["method"] == BestMethod.unreliable
    stopped = r["status"] != 0
    lines = [f"{label}: {n} held-out atlas points with a reference",
             f"  unreliable (no Monte Carlo at the point): {unreliable.sum()} ({unreliable.mean():.1%}); of which the "
             f"linearization stopped: {np.sum(unreliable & stopped)}; atlas interval too wide (se > MAX_SE): "
             f"{np.sum(unreliable & ~stopped)}",
             f"  need Monte Carlo (atlas interval wider than the target {target:.0%}, or stopped): "
             f"{r['needs_mc'].sum()} ({r['needs_mc'].mean():.1%})",
             f"  best estimate holds (within {target:.0%} or 2 reported SE): {holds.sum()} of {n} ({holds.mean():.1%}); "
             f"with the reference's SE: {holds_ref.sum()} ({holds_ref.mean():.1%}); on the vouched-for points: "
             f"{np.sum(holds & ~unreliable)} of {np.sum(~unreliable)} ({np.mean(holds[~unreliable]):.1%}), with the "
             f"reference's SE {np.mean(holds_ref[~unreliable]):.1%}",
             f"  within the target itself: {within.sum()} ({within.mean():.1%}); by method: " + ", ".join(
                 f"{BestMethod(int(c)).name} {k}" for c, k in zip(*np.unique(r["method"], return_counts=True)))]
    for lo, hi in ((0, 0.2), (0.2, 0.7), (0.7, 1.01)):
        b = (r["p"] >= lo) & (r["p"] < hi) & ~unreliable
        if b.any():
            lines.append(f"  peak p_uplift {lo:g}-{hi:g}: {b.sum()} vouched-for points, hold {np.mean(holds[b]):.1%} "
                         f"(with the reference's SE {np.mean(holds_ref[b]):.1%}), median reported relative SE "
                         f"{np.median(r['se'][b] / r['value'][b]):.1%}")
    return lines


#: ``[output]`` of the 10,000-point sweep: the histories the trust rule reads and those the corrected
#: probabilities need (``CORRECTION_HISTORIES``: without ``c_eq`` every corrected point's p_source is unreliable).
SWEEP_OUTPUT = ("[output]\nvariables = [" + ", ".join(f'"{name}"' for name in (
    "var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq")) + "]\n")


def sweep_unreliable(points, budget, target, work, workers=2):
    """Printed lines of the ``points``-point sweep of ``accuracy_escalation.py`` (the eps x S0 grid of
    ``bench_sweep.py``) run with ``[accuracy] target, budget_s``; the study and its result path."""
    from bench_sweep import STUDY

    from screening.sweep.probabilities import CORRECTION_HISTORIES
    from screening.sweep.study import parse_study
    from screening.sweep.run import run_sweep

    assert all(f'"{name}"' in SWEEP_OUTPUT for name in CORRECTION_HISTORIES)
    n = max(int(round(np.sqrt(points))), 1)
    study = parse_study(STUDY.format(n=n, output=SWEEP_OUTPUT) + f"\n[accuracy]\ntarget = {target}\n"
                        f"budget_s = {budget}\n", name="atlas_sweep")
    work.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    out = work / "atlas_sweep.nc"
    report = run_sweep(study, out, workers=workers, force=True, progress=False,
                       log=lambda m: print("   ", m, file=sys.stderr))
    wall = time.perf_counter() - start
    acc = report.accuracy
    total = n * n
    return [f"{total}-point sweep, [accuracy] target {target}, budget_s {budget:g}: {wall:.0f} s wall, "
            f"{acc['n_candidates']} points need Monte Carlo ({acc['n_candidates'] / total:.1%}), Monte Carlo at "
            f"{acc['n_escalated']} ({acc['cost_s']:.0f} CPU s by the cost model, {acc['cpu_s']:.0f} measured)",
            f"  unreliable: {acc['n_unreliable']} ({acc['n_unreliable'] / total:.1%}); best estimates: {acc['methods']}",
            f"  probabilities by source: {report.probabilities}"], study, out


def answer_lines(path):
    """Printed lines: which quantity answers the sweep's points, the unreliable counts (variance; any answer)
    and the study's fragility surface."""
    import xarray as xr

    from screening.analysis.probabilities import reliable_answer
    from screening.core.status import AnswerQuantity, ProbabilitySource

    with xr.open_dataset(path) as ds:
        answer = ds["answer_quantity"].values.reshape(-1)
        source = ds["p_source"].values.reshape(-1)
        variance_ok = ds["best_method"].values.reshape(-1) != BestMethod.unreliable
        note, surface_note = ds.attrs["answer_note"], ds.attrs.get("fragility_surface_note", "")
    total = answer.size
    reliable = reliable_answer(answer, variance_ok, source)
    probs = answer != AnswerQuantity.variance
    lines = [f"  {note}",
             f"  unreliable: {np.sum(~variance_ok)} variance ({np.mean(~variance_ok):.1%}), {np.sum(~reliable)} "
             f"without any reliable answer ({np.mean(~reliable):.1%}) of {total}",
             f"  answered by the probabilities: {probs.sum()}, of which p_source "
             + ", ".join(f"{s.name} {np.sum(probs & (source == s))}" for s in ProbabilitySource
                         if np.any(probs & (source == s)))
             + f", Monte Carlo {np.sum(probs & (source >= 10))}",
             f"  fragility surface: {surface_note}"]
    return lines


def surface_holdout(study, path, points, samples, seed=2026, workers=2):
    """Held-out truth for the study's fragility surface: coupled Monte Carlo (``samples`` samples, the
    escalation's task and settings, the study's seed + 1 so that the samples are not those of the escalated
    points) at ``points`` random points whose p_overturn came from the surface.  Printed lines."""
    import xarray as xr
    from distributed import Client, LocalCluster

    from screening.solvers.estimates import binomial_estimate
    from screening.core.status import ProbabilitySource, SampleState
    from screening.sweep.config import build_models
    from screening.sweep.execution import escalation_task
    from screening.sweep.grid import point_values

    with xr.open_dataset(path) as ds:
        source = ds["p_source"].values.reshape(-1)
        p_s = ds["p_overturn"].values.reshape(-1)
        se_s = ds["p_overturn_se"].values.reshape(-1)
    pool = np.flatnonzero(source == ProbabilitySource.study_fragility_surface)
    if pool.size == 0:
        return ["  held-out check of the fragility surface: no point took its p_overturn from the surface"]
    pick = np.sort(np.random.default_rng(seed).choice(pool, size=min(points, pool.size), replace=False))
    start = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        futures = []
        for flat in pick:
            case, values = point_values(study, tuple(int(i) for i in np.unravel_index(int(flat), study.shape)))
            futures.append(client.submit(escalation_task, *build_models(study.cases[case], values, study.t_end),
                                         study.cases[case].condensation_model, int(samples), "coupled", study.t_end,
                                         study.dt, study.accuracy.seed + 1, pure=False))
        runs = client.gather(futures)
    wall = time.perf_counter() - start
    cpu = sum(float(r["cpu_time"]) for r in runs)
    lines = [f"  held-out check of the fragility surface: coupled Monte Carlo ({samples} samples, seed "
             f"{study.accuracy.seed + 1}) at {pick.size} random points of the {pool.size} whose p_overturn came "
             f"from the surface ({cpu:.0f} CPU s, {wall:.0f} s wall on {workers} workers)",
             f"    {'eps':>9s} {'S0':>9s} {'p surface':>16s} {'p Monte Carlo':>16s} {'z':>5s}"]
    ok = 0
    names = list(study.dims)
    for flat, r in zip(pick, runs):
        state = np.asarray(r["sample_state"])
        valid = (state == SampleState.standing) | (state == SampleState.overturned)
        p_mc, se_mc = binomial_estimate(int(np.sum(state == SampleState.overturned)), int(valid.sum()))
        z = abs(p_s[flat] - p_mc) / np.hypot(se_s[flat], se_mc)
        ok += bool(z <= 2)
        index = np.unravel_index(int(flat), study.shape)
        coords = [float(study.sweeps[d][i]) for d, i in zip(names, index)]
        lines.append(f"    {coords[0]:9.3g} {coords[-1]:9.3g} {p_s[flat]:8.3f} +- {se_s[flat]:5.3f} "
                     f"{float(p_mc):8.3f} +- {float(se_mc):5.3f} {z:5.2f}")
    lines.append(f"  |p_surface - p_MC| <= 2 sqrt(se_surface^2 + se_MC^2) at {ok} of {pick.size} held-out points "
                 f"({ok / pick.size:.0%}; goal >= 90 %)")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", nargs="+", default=None, metavar="NAME", help="subset of families")
    ap.add_argument("--budget", type=float, default=DEFAULT_BUDGET_S,
                    help=f"[accuracy] budget_s [s] of each sweep (default {DEFAULT_BUDGET_S:g}, the package's)")
    ap.add_argument("--target", type=float, default=0.15, help="[accuracy] target (relative error)")
    ap.add_argument("--grid", type=int, default=12, help="geometric S0 values besides the calibration ones")
    ap.add_argument("--work", type=Path, default=DEFAULT_WORK)
    ap.add_argument("--force", action="store_true", help="recompute families whose result is up to date")
    ap.add_argument("--table-only", action="store_true", help="only read the existing results")
    ap.add_argument("--atlas", type=Path, default=None, help="held-out points of this error atlas instead")
    ap.add_argument("--condensation", default="paper", help="with --atlas: the condensation (default paper)")
    ap.add_argument("--sweep-points", type=int, default=0, help="with --atlas: also run a sweep of this many points")
    ap.add_argument("--holdout-points", type=int, default=20,
                    help="with --sweep-points: coupled Monte Carlo at this many points whose p_overturn came from the "
                         "study's fragility surface, as held-out truth (0: none)")
    ap.add_argument("--holdout-samples", type=int, default=1000, help="samples of each held-out Monte Carlo run")
    args = ap.parse_args(argv)
    if not 0 < args.target <= 1:
        ap.error(f"--target must be in (0, 1] (got {args.target})")
    if not args.budget > 0:
        ap.error(f"--budget must be > 0 [s] (got {args.budget})")
    if args.holdout_points < 0:
        ap.error(f"--holdout-points must be >= 0 (got {args.holdout_points})")
    if not 1 <= args.holdout_samples <= 4000:
        ap.error(f"--holdout-samples must be in [1, 4000] (got {args.holdout_samples})")
    if args.grid < 2:
        ap.error(f"--grid must be >= 2 (got {args.grid})")
    if args.atlas is not None:
        print(f"== [accuracy] at held-out atlas points ({args.atlas}, condensation {args.condensation}, target "
              f"{args.target:.0%}; no Monte Carlo at the point)")
        print("\n".join(atlas_summary(atlas_rows(args.atlas, args.condensation, args.target), args.target,
                                      args.condensation)))
        if args.sweep_points > 0:
            start = time.perf_counter()
            lines, study, out = sweep_unreliable(args.sweep_points, args.budget, args.target, args.work)
            print("\n".join(lines + answer_lines(out)), flush=True)
            if args.holdout_points > 0:
                print("\n".join(surface_holdout(study, out, args.holdout_points, args.holdout_samples)))
            print(f"  whole sweep stage: {time.perf_counter() - start:.0f} s wall")
        return 0
    families = calibration_families()
    chosen = args.families or list(families)
    unknown = [f for f in chosen if f not in families]
    if unknown:
        ap.error(f"--families: unknown {', '.join(unknown)} (allowed: {', '.join(families)})")
    args.work.mkdir(parents=True, exist_ok=True)

    failed = {}
    if not args.table_only:
        for fam in chosen:
            print(f"== {fam}: {len(families[fam]['points'])} calibration point(s)", file=sys.stderr, flush=True)
            try:
                run_family(fam, families[fam], args)
            except Exception:                # noqa: BLE001 - record and go on with the next family
                import traceback

                failed[fam] = traceback.format_exc()
                print(f"== {fam} FAILED:\n{failed[fam]}", file=sys.stderr, flush=True)

    rows, info = [], {}
    for fam in chosen:
        path = args.work / f"{fam}.nc"
        if fam in failed or not path.exists():
            continue
        fr, attrs = family_rows(fam, families[fam], path, args.target)
        side = args.work / f"{fam}.json"
        rows += fr
        info[fam] = (attrs, json.loads(side.read_text()) if side.exists() else None)
    missing = [f for f in chosen if f not in info]
    text, md = table_lines(rows, args.target)
    summary = summary_lines(rows, info, args.target)
    budgets = sorted({f"{attrs['budget_s']:g}" for attrs, _ in info.values()}) or [f"{args.budget:g}"]
    head = (f"== best estimates in per-family S0 sweeps: target {args.target:.0%}, budget_s {' / '.join(budgets)} per "
            f"sweep, grid {args.grid} + calibration S0, reference: 1000-sample coupled MCS")
    print(head)
    print("\n".join(text))
    print()
    print("\n".join(summary))
    if missing:
        print(f"\nno result for: {', '.join(missing)}" + (f" (failed: {', '.join(failed)})" if failed else ""))
    (args.work / "table.md").write_text("\n".join([f"# {head[3:]}", "", *md, "", "```", *summary, "```", ""]))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
