"""Figures of the speed-accuracy trade study: error vs cost, and where SL stays within tolerance.

Matplotlib object API with the Agg canvas (no pyplot state); files are written atomically by
:func:`screening.report.figure_base.save_figure`.
"""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from screening.applications.metrics import classify_error, rule_error
from screening.applications.tradeoff_study import COMPARISONS, QUANTITIES
from screening.report.figure_base import save_figure

__all__ = []

DPI = 130


def _figure():
    """A 12 x 5 in figure with two panels sharing the y axis."""
    fig = Figure(figsize=(12, 5), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(1, 2, sharey=True)


def plot_error_vs_cost(ds, path):
    """Log-log error vs cost per point, one marker per method/setting (two panels:
    error against coupled MCS, the judge; and against condensed MCS, SL's own model).

    Notes
    -----
    A Monte Carlo marker's error is ``sqrt(bias^2 + (se / peak)^2)`` (plus the tolerance change for the
    tolerance variants), the bias being the relative difference of the model's largest-sample peak from
    the panel's reference; SL's is ``|SL / reference - 1|``, its modelling error.
    """
    fig, axes = _figure()
    models = list(ds.cv_model.values)
    nref = ds.sizes["n_samples"] - 1
    med = lambda a: float(np.nanmedian(np.asarray(a, dtype=float)))  # noqa: E731
    sl_cost = ds.cost.sel(approach="sl").values
    for ax, ref_model in zip(axes, ("coupled", "condensed")):
        if ref_model not in models:
            ax.set_visible(False)
            continue
        ref = ds.cv_peak_var_theta.sel(cv_model=ref_model).values[:, nref]          # per rep point
        # MCS vs sample count
        for model, color in (("coupled", "tab:red"), ("condensed", "tab:blue")):
            if model not in models or (ref_model == "condensed" and model == "coupled"):
                continue
            pk = ds.cv_peak_var_theta.sel(cv_model=model).values
            se = ds.cv_peak_var_theta_se.sel(cv_model=model).values
            own_ref = pk[:, nref]
            bias = own_ref / ref - 1.0 if model != ref_model else np.zeros_like(ref)
            err = np.sqrt(bias[:, None] ** 2 + (se / pk) ** 2)
            cost = ds.cv_cost.sel(cv_model=model).values
            x = np.nanmedian(cost, axis=0)
            y = np.nanmedian(err, axis=0)
            ax.plot(x, y, "o-", color=color, label=f"{model} MCS, n = {', '.join(map(str, ds.n_samples.values))}")
            for xi, yi, n_s in zip(x, y, ds.n_samples.values):
                ax.annotate(str(n_s), (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7, color=color)
            # tolerance variants
            tp = ds.tol_peak_var_theta.sel(cv_model=model).values
            tse = ds.tol_peak_var_theta_se.sel(cv_model=model).values
            tc = ds.tol_cost.sel(cv_model=model).values
            change = ds.tol_change_vs_tightest.sel(cv_model=model).values
            terr = np.sqrt(bias[:, None] ** 2 + (tse / tp) ** 2 + change ** 2)
            for c, f in enumerate(ds.rtol_factor.values):
                ax.plot(med(tc[:, c]), med(terr[:, c]), marker="^" if f > 1 else ("v" if f < 1 else "s"),
                        ls="none", color=color, mfc="none", ms=8,
                        label=f"{model} MCS rtol x {f:g} ({study_n(ds)} samples)")
        # SL
        sl_pk = ds.cv_sl_peak_var_theta.values
        sl_err = np.abs(sl_pk / ref - 1.0)
        ax.plot(med(sl_cost), med(sl_err), "*", color="k", ms=14, label="SL at the representative points")
        comp = "sl_vs_coupled" if ref_model == "coupled" else "sl_vs_condensed"
        g = np.abs(ds.peak_rel_error.sel(comparison=comp, quantity="var_theta").values)
        ax.errorbar(med(sl_cost), med(g), yerr=[[med(g) - np.nanmin(g)], [np.nanmax(g) - med(g)]], fmt="*",
                    color="0.5", mfc="none", ms=14, capsize=3, label="SL, whole grid (median, min-max)")
        last = 0.0
        for k in np.argsort([med(ds.sl_cost[k]) for k in range(ds.sizes["sl_setting"])]):
            h = float(ds.sl_h_max[k])
            tag = (f"rtol {float(ds.sl_rtol[k]):.0e}" if str(ds.sl_setting_kind.values[k]) == "rtol"
                   else f"h_max {h:g} s")
            xk = med(ds.sl_cost[k])
            ax.plot(xk, med(g), "|", color="0.3", ms=10)
            if xk > 1.25 * last:                       # label only settings of visibly different cost
                ax.annotate(tag, (xk, med(g)), textcoords="offset points", xytext=(0, 8), fontsize=5.5,
                            rotation=90, ha="center", va="bottom", color="0.3")
                last = xk
        if ref_model == "coupled":
            cg = np.abs(ds.peak_rel_error.sel(comparison="condensed_vs_coupled", quantity="var_theta").values)
            cc = ds.cost.sel(approach="condensed_mcs").values
            ax.errorbar(med(cc), med(cg), yerr=[[med(cg) - np.nanmin(cg)], [np.nanmax(cg) - med(cg)]], fmt="D",
                        color="tab:cyan", mfc="none", capsize=3, label="condensed MCS, whole grid (median, min-max)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("cost per point, one core [s]")
        ax.set_title(f"error of peak var_θ vs {ref_model} MCS reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, loc="lower left")
    axes[0].set_ylabel("relative error [1] (bias ⊕ standard error)")
    fig.suptitle("Speed–accuracy trade, peak var_θ.  MCS: median over the representative points (error = bias vs "
                 "the reference ⊕ standard error ⊕ tolerance change).\n"
                 "SL: | marks = its rtol / h_max settings (numerical "
                 "error is negligible; the error shown is the modelling error)", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def study_n(ds):
    """Sample count of the tolerance sub-study (from the dataset).

    Returns: the count [-], or ``"?"`` when the dataset does not say.
    """
    return int(ds.attrs.get("tol_samples", 0)) or "?"


def plot_validity(ds, rules, thresholds, path, metric="peak", quantity="var_theta"):
    """Map of SL's error class (within the smaller / larger threshold / beyond) against coupled
    and condensed MCS, over SL peak p_uplift (x, log) and the k_eq margin (y).

    One marker per point (its shape the point's family; filled for a hardening bed, a ring for a
    softening one), labelled with its error (``?`` where a threshold lies within two standard
    errors, the overturned fraction of coupled MCS where there is one); dashed lines at the
    largest SL peak p_uplift up to which every point passes (the rules of the ``all`` group).
    """
    t1, t2 = thresholds[0], thresholds[-1]
    x = ds.sl_peak_p_uplift.values
    y = ds.k_eq_margin.values
    fams = list(dict.fromkeys(ds.family.values))
    shapes = dict(zip(fams, "osD^vP<>"))
    fig, axes = _figure()
    iq = QUANTITIES.index(quantity)
    for ax, (comp, ref) in zip(axes, (("sl_vs_coupled", "coupled"), ("sl_vs_condensed", "condensed"))):
        c = list(COMPARISONS).index(comp)
        err = rule_error(ds.peak_rel_error.values[c, iq], ds.time_avg_rel_error.values[c, iq], metric)
        rse = ds.peak_rel_se.values[c, iq]
        for j in range(x.size):
            e = err[j]
            color = ("0.6" if not np.isfinite(e) else "tab:green" if e <= t1 else "gold" if e <= t2 else "tab:red")
            hard = ds.eps.values[j] > 0
            ax.scatter(x[j], y[j], marker=shapes[ds.family.values[j]], s=70, edgecolors="k",
                       facecolors=color if hard else "white", linewidths=1.0 if hard else 2.0)
            if not hard:
                ax.scatter(x[j], y[j], marker=shapes[ds.family.values[j]], s=28, color=color)
            lab = "n/a" if not np.isfinite(e) else f"{100 * e:.0f}%"
            cls = classify_error(e, rse[j], t1) if np.isfinite(e) else "undefined"
            if cls == "ambiguous" or classify_error(e, rse[j], t2) == "ambiguous":
                lab += "?"
            ov = float(ds.overturned_fraction.sel(mcs_model="coupled").values[j])
            if ov > 0 and ref == "coupled":
                lab += f" (ov {ov:.0%})"
            ax.annotate(lab, (x[j], y[j]), textcoords="offset points", xytext=(6, 4) if hard else (6, -11),
                        fontsize=6.5)
        for r in rules:
            if r["reference"] == ref and r["group"] == "all" and np.isfinite(r["p_safe"]):
                ax.axvline(r["p_safe"], color="tab:green" if r["threshold"] == t1 else "goldenrod", ls="--", lw=1)
                ax.text(r["p_safe"], 1.01 if r["threshold"] == t1 else 0.03, f"all within {r['threshold']:.0%} "
                        "up to here ", fontsize=6.5, ha="right", transform=ax.get_xaxis_transform())
        ax.set_xscale("log")
        ax.set_xlabel("SL peak p_uplift [1]")
        ax.set_title(f"|SL error| of {metric} {quantity} vs {ref} MCS", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("k_eq margin = min_k_eq / k_eq(t=0) [1]")
    handles = [Line2D([], [], marker="o", ls="none", color=c, mec="k", label=lab) for c, lab in (
        ("tab:green", f"<= {t1:.0%}"), ("gold", f"{t1:.0%}-{t2:.0%}"), ("tab:red", f"> {t2:.0%}"),
        ("0.6", "undefined"))]
    handles += [Line2D([], [], marker=shapes[f], ls="none", color="0.8", mec="k", label=f) for f in fams]
    handles += [Line2D([], [], marker="o", ls="none", mfc="0.8", mec="k", label="eps > 0 (filled)"),
                Line2D([], [], marker="o", ls="none", mfc="white", mec="k", mew=2, label="eps < 0 (ring)")]
    axes[1].legend(handles=handles, fontsize=7, loc="lower left")
    fig.suptitle("Where SL stays within tolerance (labels: |error|; ? = a threshold lies within 2 SE; ov = coupled "
                 "samples overturned, statistics over survivors;\ndashed: largest tested SL peak p_uplift up to which "
                 "every point passes, all beds)", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
