"""Text reports of the speed-accuracy trade study: markdown tables, CSV rows, rules and the summary.

Everything here reads a trade-study dataset (made by :func:`screening.report.tradeoff.run_tradeoff`, or a
saved file through :func:`~screening.report.tradeoff.from_file_layout`) and the rules of
:func:`screening.applications.metrics.derive_rules`; nothing is recomputed.
"""

from __future__ import annotations

import csv

import numpy as np

from screening._version import __version__
from screening.applications.metrics import peak_with_se, relative_difference
from screening.applications.tradeoff_study import COMPARISONS, METHODS, QUANTITIES
from screening.core.atomicfile import atomic_open
from screening.core.status import PointStatus

__all__ = []


def rule_text(rule, metric, quantity):
    """One-line statement of a rule from :func:`~screening.applications.metrics.derive_rules`.

    Returns: the statement.
    """
    what = {"peak": f"peak {quantity}", "time_avg": f"time-averaged {quantity}",
            "worst": f"peak and time-averaged {quantity}"}[metric]
    head = f"[{rule['group']}] SL within {rule['threshold']:.0%} of {rule['reference']} MCS ({what})"
    fail = (f"first failure at p = {rule['fail_p']:.2g} ({rule['fail_name']}: {100 * rule['fail_error']:+.0f} %)"
            if rule["fail_name"] else "")
    if not rule["fail_name"]:
        s = f"{head}: at every tested point ({rule['n']}, SL peak p_uplift up to {rule['p_max']:.2g})"
    elif rule["n_safe"] == 0:
        s = f"{head}: no safe p_uplift range - {fail}, the lowest tested level"
    else:
        s = (f"{head}: for SL peak p_uplift <= {rule['p_safe']:.2g} ({rule['n_safe']} tested points, all pass); "
             f"{fail}")
    s += f"; {rule['n_pass']}/{rule['n']} pass overall"
    if rule["fail_name"] and rule["n_margin"] > 0:
        s += f"; margin rule min_k_eq/k_eq(0) > {rule['margin_bound']:.2f} covers {rule['n_margin']} points"
    return s


def recommendation(rules):
    """The recommended screening rule in two sentences, from the ``all``-group rules.

    Uses the loosest threshold against coupled MCS (where SL alone is acceptable) and the
    tightest against condensed MCS (where the linearization itself is accurate).

    Returns: the recommendation.
    """
    def pick(ref, thr_fn):
        cands = [r for r in rules if r["group"] == "all" and r["reference"] == ref]
        if not cands:
            return None
        thr = thr_fn(r["threshold"] for r in cands)
        return next(r for r in cands if r["threshold"] == thr)

    def bound(r):
        if r is None:
            return "n/a"
        if not r["fail_name"]:
            return f"every tested SL peak p_uplift (up to {r['p_max']:.2g})"
        if r["n_safe"] == 0:
            return "no tested SL peak p_uplift"
        return f"SL peak p_uplift <= {r['p_safe']:.2g}"

    coup, cond = pick("coupled", max), pick("condensed", min)
    parts = []
    if coup is not None:
        parts.append(f"Use SL alone for {bound(coup)}: there it stays within {coup['threshold']:.0%} of coupled "
                     f"MCS at every tested point; beyond, check with coupled MCS")
    if cond is not None:
        parts.append(f"the linearization itself (SL vs condensed MCS) stays within {cond['threshold']:.0%} for "
                     f"{bound(cond)}; where SL misses coupled MCS inside that range, the error is the "
                     f"condensation's (condensed vs coupled MCS), not the linearization's")
    return "; ".join(parts) + "."


def _pct(x, sig=None):
    if x is None or not np.isfinite(x):
        return "n/a"
    s = f"{100 * x:+.0f} %"
    return s + ("*" if sig else "")


def _pct_abs(x, sig=None):
    if x is None or not np.isfinite(x):
        return "n/a"
    return f"{100 * x:.0f} %" + ("*" if sig else "")


def _sci(x, digits=3):
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


def point_rows(ds):
    """Per-point accuracy rows (list of dicts) for the markdown/CSV trade table.

    Returns: one row per point: its parameters, SL status, overturned fractions, the peak ``var_theta`` of
    each method with its standard error [rad2] (``sl_peak``, ``cond_peak``, ``coup_peak``, ...), the
    relative errors [1] of each comparison with their significance (``sl_vs_coupled_var_theta_peak``,
    ``..._sig``, ...) and the costs ``cost_<method>`` [s].
    """
    rows = []
    comp = {c: i for i, c in enumerate(ds.comparison.values)}
    for j in range(ds.sizes["point"]):
        def err(c, q, kind="peak"):
            sel = dict(comparison=comp[c], quantity=QUANTITIES.index(q), point=j)
            if kind == "peak":
                return float(ds.peak_rel_error[sel]), bool(ds.peak_significant[sel])
            return float(ds.time_avg_rel_error[sel]), bool(ds.time_avg_significant[sel])

        vt = ds.var_theta.isel(point=j)
        se = ds.var_theta_se.isel(point=j)
        peaks = {m: peak_with_se(vt.sel(approach=m).values, se.sel(approach=m).values) for m in METHODS}
        row = {
            "point": str(ds.point_name.values[j]),
            "eps": float(ds.eps[j]), "S0": float(ds.S0[j]),
            "sl_peak_p_uplift": float(ds.sl_peak_p_uplift[j]), "k_eq_margin": float(ds.k_eq_margin[j]),
            "sl_status": PointStatus(int(ds.sl_status[j])).name,
            "coupled_overturned": float(ds.overturned_fraction.sel(mcs_model="coupled")[j]),
            "condensed_overturned": float(ds.overturned_fraction.sel(mcs_model="condensed")[j]),
            "sl_peak": peaks["sl"][0], "cond_peak": peaks["condensed_mcs"][0], "cond_se": peaks["condensed_mcs"][1],
            "coup_peak": peaks["coupled_mcs"][0], "coup_se": peaks["coupled_mcs"][1],
        }
        for c in COMPARISONS:
            for q in QUANTITIES:
                row[f"{c}_{q}_peak"], row[f"{c}_{q}_peak_sig"] = err(c, q)
            row[f"{c}_var_theta_tavg"], row[f"{c}_var_theta_tavg_sig"] = err(c, "var_theta", "tavg")
        for m in METHODS:
            row[f"cost_{m}"] = float(ds.cost.sel(approach=m)[j])
        rows.append(row)
    return rows


def write_csv(rows, path):
    """Write the per-point rows as CSV (atomically)."""
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def cost_summary(ds):
    """Median / min / max cost per point of each method [s].

    Returns: ``{method: (median, min, max)}`` [s], ``sl_batched`` included.
    """
    out = {}
    for m in METHODS:
        c = ds.cost.sel(approach=m).values
        out[m] = (float(np.median(c)), float(np.min(c)), float(np.max(c)))
    out["sl_batched"] = (float(ds.sl_batched_cost),) * 3
    return out


def markdown_report(study, ds, rules):
    """The trade tables as markdown text.

    Returns: the report: accuracy per point, error summary, cost per point, Monte Carlo against sample count
    and tolerance, SL numerics and the validity rules (relative errors in %, costs in s).
    """
    rows = point_rows(ds)
    L = [f"# {study.title}", "",
         f"Study file `{study.source}`; screening {__version__}.  Records of {study.t_end:g} s, output step "
         f"{study.dt:g} s.  Monte Carlo: {study.mcs['samples']} samples, seed {study.mcs['seed']} (the same "
         f"input samples for both models), rtol coupled {study.mcs['rtol_coupled']:g} / condensed "
         f"{study.mcs['rtol_condensed']:g}, {study.mcs['threads']} numba thread(s).  SL rtol {study.sl['rtol']:g}.",
         "Relative errors are estimate / reference - 1 of the peak over the record; `*` = significant "
         "(|diff| > 2 SE of the Monte Carlo estimate(s)).  Time-averaged errors: int |a - b| dt / int b dt "
         "(`*` = above twice the sampling-noise floor).  MCS statistics are over survivors "
         "(see the overturned fraction).  Intensity convention E[xi(t) xi(s)] = 2 pi S0 delta(t - s).", "",
         "## Accuracy per point (peak var_theta)", "",
         "| point | S0 [m²/s³] | SL peak p_uplift | k_eq margin | coupled overturned | SL peak var_θ [rad²] "
         "| condensed MCS | coupled MCS | SL vs coupled | SL vs condensed | condensed vs coupled "
         "| time-avg SL vs coupled | time-avg SL vs condensed | var_θ̇: SL vs coupled | SL vs condensed "
         "| condensed vs coupled |",
         "|" + "---|" * 16]
    for r in rows:
        L.append(
            f"| {r['point']} | {_sci(r['S0'])} | {_sci(r['sl_peak_p_uplift'], 2)} | {r['k_eq_margin']:.2f} "
            f"| {r['coupled_overturned']:.1%} | {_sci(r['sl_peak'])} "
            f"| {_sci(r['cond_peak'])} ± {_sci(r['cond_se'], 1)} | {_sci(r['coup_peak'])} ± {_sci(r['coup_se'], 1)} "
            f"| {_pct(r['sl_vs_coupled_var_theta_peak'], r['sl_vs_coupled_var_theta_peak_sig'])} "
            f"| {_pct(r['sl_vs_condensed_var_theta_peak'], r['sl_vs_condensed_var_theta_peak_sig'])} "
            f"| {_pct(r['condensed_vs_coupled_var_theta_peak'], r['condensed_vs_coupled_var_theta_peak_sig'])} "
            f"| {_pct_abs(r['sl_vs_coupled_var_theta_tavg'], r['sl_vs_coupled_var_theta_tavg_sig'])} "
            f"| {_pct_abs(r['sl_vs_condensed_var_theta_tavg'], r['sl_vs_condensed_var_theta_tavg_sig'])} "
            f"| {_pct(r['sl_vs_coupled_var_theta_dot_peak'], r['sl_vs_coupled_var_theta_dot_peak_sig'])} "
            f"| {_pct(r['sl_vs_condensed_var_theta_dot_peak'], r['sl_vs_condensed_var_theta_dot_peak_sig'])} "
            f"| {_pct(r['condensed_vs_coupled_var_theta_dot_peak'], r['condensed_vs_coupled_var_theta_dot_peak_sig'])}"
            " |")
    # summary of errors
    comp = list(ds.comparison.values)
    L += ["", "## Error summary over the grid (|relative error| of peak var_θ)", "",
          "| comparison | median | max | points within 10 % | within 25 % | significant (> 2 SE) |",
          "|---|---|---|---|---|---|"]
    for c in comp:
        e = ds.peak_rel_error.sel(comparison=c, quantity="var_theta").values
        s = ds.peak_significant.sel(comparison=c, quantity="var_theta").values
        a = np.abs(e[np.isfinite(e)])
        L.append(f"| {c} | {np.median(a):.1%} | {np.max(a):.1%} | {int(np.sum(a <= 0.10))}/{e.size} "
                 f"| {int(np.sum(a <= 0.25))}/{e.size} | {int(np.sum(s))}/{e.size} |")
    # cost
    cs = cost_summary(ds)
    sl_med = cs["sl"][0]
    L += ["", "## Cost per point (one core)", "",
          "| method | median [s] | min [s] | max [s] | ratio to SL (median) |", "|---|---|---|---|---|"]
    labels = {"sl": "SL (single-point solve_moments)", "sl_batched": "SL (batched over a family)",
              "condensed_mcs": f"condensed MCS, {study.mcs['samples']} samples",
              "coupled_mcs": f"coupled MCS, {study.mcs['samples']} samples"}
    for m in ("sl", "sl_batched", "condensed_mcs", "coupled_mcs"):
        med, lo, hi = cs[m]
        L.append(f"| {labels[m]} | {med:.3g} | {lo:.3g} | {hi:.3g} | {med / sl_med:,.0f} |")
    L.append("")
    L.append(f"Cost ratio SL : condensed MCS : coupled MCS (medians) = 1 : {cs['condensed_mcs'][0] / sl_med:,.0f} : "
             f"{cs['coupled_mcs'][0] / sl_med:,.0f}.")
    # convergence
    L += ["", f"## Monte Carlo vs sample count (representative points; reference = {ds.n_samples.values[-1]} "
              "samples of the same model, nested: same seed)", "",
          "| point | model | samples | peak var_θ ± SE | rel. SE | deviation vs reference | cost [s] "
          "| overturned | bias vs coupled ref. | SL vs this ref. |", "|---|---|---|---|---|---|---|---|---|---|"]
    for a in range(ds.sizes["rep_point"]):
        coup_ref = (float(ds.cv_peak_var_theta.isel(rep_point=a, n_samples=-1).sel(cv_model="coupled"))
                    if "coupled" in ds.cv_model.values else float("nan"))
        for b, model in enumerate(ds.cv_model.values):
            ref_peak = float(ds.cv_peak_var_theta[a, b, -1])
            for c, n_s in enumerate(ds.n_samples.values):
                pk, se = float(ds.cv_peak_var_theta[a, b, c]), float(ds.cv_peak_var_theta_se[a, b, c])
                bias = relative_difference(pk, coup_ref) if c == ds.sizes["n_samples"] - 1 else float("nan")
                sl_b = relative_difference(float(ds.cv_sl_peak_var_theta[a]), ref_peak) if c == ds.sizes[
                    "n_samples"] - 1 else float("nan")
                L.append(f"| {ds.rep_point_name.values[a]} | {model} | {n_s} | {_sci(pk)} ± {_sci(se, 2)} "
                         f"| {se / pk:.1%} | {_pct(float(ds.cv_deviation_vs_reference[a, b, c]))} "
                         f"| {float(ds.cv_cost[a, b, c]):.2f} | {int(ds.cv_n_overturned[a, b, c])} "
                         f"| {_pct(bias)} | {_pct(sl_b)} |")
    L += ["", f"## Monte Carlo vs integrator tolerance ({study.convergence['rtol_samples']} samples, same seed: "
              "paired)", "",
          "| point | model | rtol | peak var_θ ± SE | change vs tightest | overturned | cost [s] |",
          "|---|---|---|---|---|---|---|"]
    for a in range(ds.sizes["rep_point"]):
        for b, model in enumerate(ds.cv_model.values):
            base = study.mcs[f"rtol_{model}"]
            for c, f in enumerate(ds.rtol_factor.values):
                pk, se = float(ds.tol_peak_var_theta[a, b, c]), float(ds.tol_peak_var_theta_se[a, b, c])
                L.append(f"| {ds.rep_point_name.values[a]} | {model} | {base * f:.3g} | {_sci(pk)} ± {_sci(se, 2)} "
                         f"| {float(ds.tol_change_vs_tightest[a, b, c]):+.2%} | {int(ds.tol_n_overturned[a, b, c])} "
                         f"| {float(ds.tol_cost[a, b, c]):.2f} |")
    L += ["", f"## SL numerics (error vs rtol = {study.sl['reference_rtol']:g}, all grid points)", "",
          "| setting | rtol | h_max [s] | median cost [ms] | median steps | max abs peak error "
          "| max time-avg error |", "|---|---|---|---|---|---|---|"]
    for s in range(ds.sizes["sl_setting"]):
        h = float(ds.sl_h_max[s])
        L.append(f"| {ds.sl_setting_kind.values[s]} | {float(ds.sl_rtol[s]):.0e} "
                 f"| {'default' if not np.isfinite(h) else f'{h:g}'} "
                 f"| {1e3 * float(np.median(ds.sl_cost[s])):.2f} | {float(np.median(ds.sl_n_steps[s])):.0f} "
                 f"| {float(np.max(np.abs(ds.sl_numerical_peak_error[s]))):.1e} "
                 f"| {float(np.max(ds.sl_numerical_time_avg_error[s])):.1e} |")
    L += ["", f"## Validity rules (derived from the data; metric: {study.rule['metric']} {study.rule['quantity']})",
          ""]
    L += [f"**Recommended:** {recommendation(rules)}", ""]
    L += [f"* {rule_text(r, study.rule['metric'], study.rule['quantity'])}" for r in rules]
    L.append("")
    return "\n".join(L)




def summary_text(study, ds, rules):
    """Costs, cost ratios and the derived rules as printable text.

    What ``screening tradeoff`` prints at its end: the median cost per point of each method and
    their ratio (:func:`cost_summary`), the recommendation (:func:`recommendation`), one line per
    rule (:func:`rule_text`) and the run time of the study.

    Returns: the lines (costs in ms for SL, s for Monte Carlo).
    """
    cs = cost_summary(ds)
    lines = [f"cost per point (median, one core): SL {1e3 * cs['sl'][0]:.2f} ms, condensed MCS "
             f"{cs['condensed_mcs'][0]:.2f} s, coupled MCS {cs['coupled_mcs'][0]:.2f} s "
             f"({study.mcs['samples']} samples) -> SL : condensed : coupled = 1 : "
             f"{cs['condensed_mcs'][0] / cs['sl'][0]:,.0f} : {cs['coupled_mcs'][0] / cs['sl'][0]:,.0f}",
             "Recommended: " + recommendation(rules),
             "Rules (from the data):"]
    lines += ["  - " + rule_text(r, study.rule["metric"], study.rule["quantity"]) for r in rules]
    lines.append(f"total run time of the study {float(ds.attrs.get('wall_time_s', float('nan'))):.0f} s")
    return "\n".join(lines)
