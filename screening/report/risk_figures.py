"""The risk figure of ``screening risk``: the annual frequency of each object and limit state, ranked."""

from __future__ import annotations

import textwrap

import numpy as np

from screening.report.figure_base import new_figure, save_figure

__all__ = []


def plot_risk(rows, path, title="", years=50.0):
    """The ranked annual frequencies as a PNG: one bar per object and limit state (log scale), its
    bounds from the vouched range as a line, the share from outside that range written beside it.

    Returns: ``path``; ``None`` when no row has a rate.
    """
    rows = [r for r in rows if np.isfinite(r["annual_rate"]) and r["annual_rate"] > 0]
    if not rows:
        return None
    n = len(rows)
    fig = new_figure(9.0, min(2.4 + 0.3 * n, 40.0))
    ax = fig.add_subplot(1, 1, 1)
    y = np.arange(n)[::-1]
    rate = np.array([r["annual_rate"] for r in rows])
    low = np.array([r["annual_rate_low"] for r in rows])
    high = np.array([r["annual_rate_high"] for r in rows])
    shaky = np.array([bool(r.get("note")) for r in rows])
    ax.barh(y[~shaky], rate[~shaky], color="tab:blue", alpha=0.7,
            label="annual frequency (fitted curve over the hazard curve)")
    if shaky.any():
        ax.barh(y[shaky], rate[shaky], color="none", edgecolor="tab:red", hatch="//",
                label="fit not exported (untrusted or degenerate): see the CSV's note")
    floor = rate.min() / 100
    ax.hlines(y, np.maximum(low, floor), high, color="k", lw=1.2,
              label="bounds: fitted curve only where vouched, monotone outside")
    se = np.array([r.get("annual_rate_se", np.nan) for r in rows], dtype=float)
    ok = np.isfinite(se)
    if ok.any():
        ax.errorbar(rate[ok], y[ok], xerr=np.minimum(2 * se[ok], 0.999 * rate[ok]), fmt="none", ecolor="tab:orange",
                    capsize=3, label="+-2 standard errors (fragility fit)")
    for yi, r in zip(y, rows):
        share = r.get("share_outside_vouched", np.nan)
        text = f"P({years:g} yr) = {-np.expm1(-r['annual_rate'] * years):.2g}"
        if np.isfinite(share) and share >= 0.005:
            text += f"; {100 * share:.0f} % from outside the vouched range"
        ax.annotate(text, (max(r["annual_rate_high"], r["annual_rate"]), yi), xytext=(4, 0),
                    textcoords="offset points", va="center", fontsize=7)
    ax.set_yticks(y, [f"{r['object']}  {r['limit_state']}" for r in rows], fontsize=8 if n < 30 else 6)
    ax.set_xscale("log")
    ax.set_xlim(floor, high.max() * 3000)
    ax.set_xlabel("mean annual frequency [1/yr]")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12 if n > 4 else -0.25), fontsize=7, ncol=2)
    ax.set_title(textwrap.fill(title or "risk at the site, ranked", 110), fontsize=8)
    return save_figure(fig, path)
