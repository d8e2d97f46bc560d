"""PNG figures of the Monte Carlo spot checks of a sweep result.

* :func:`plot_spots` — linearization against Monte Carlo (with +-2 standard errors) at the spot
  points;
* :func:`plot_spot_panels` — the paper's panels at one spot point (``c_eq``/``k_eq``; variances
  with the Monte Carlo 95 % band; ``p_uplift``), one PNG per spot point.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from screening.analysis.probabilities import probability_text, spot_check_probabilities, TOPPLING_FRACTION
from screening.report.figure_base import (axis_label, flag_summary, new_figure, point_flag_text, point_label,
                                          save_figure, spot_index)

__all__ = []

def plot_spots(ds, path):
    """Linearization vs Monte Carlo at the spot points, as a PNG.

    The linearization's history is drawn where the result stores it (on the grid, or as
    ``spot_<name>`` with ``[output] histories = "spots"``); the peak error is always in the title.

    Returns: ``path``; ``None`` (nothing written) if the result has no spot point.
    """
    if "spot" not in ds.dims or ds.sizes["spot"] == 0:
        return None
    n = min(ds.sizes["spot"], 8)
    prob = _spot_probabilities(ds)
    fig = new_figure(10.0, 2.6 * n + 0.8)
    axes = np.atleast_2d(fig.subplots(n, 2, sharex=True, squeeze=False))
    t = ds["t"].values
    for i in range(n):
        index = spot_index(ds, i)
        for ax, name in zip(axes[i], ("var_theta", "var_theta_dot")):
            lin = (np.asarray(ds[name].isel(index).values, dtype=float) if name in ds.variables else
                   np.asarray(ds[f"spot_{name}"].values[i], dtype=float) if f"spot_{name}" in ds.variables else None)
            mcs = np.asarray(ds[f"mcs_{name}"].values[i], dtype=float)
            se = np.asarray(ds[f"mcs_{name}_se"].values[i], dtype=float)
            ax.fill_between(t, mcs - 2 * se, mcs + 2 * se, color="C1", alpha=0.25, lw=0)
            ax.plot(t, mcs, color="C1", lw=1.0, label=f"Monte Carlo ({ds.attrs.get('mcs_model', '')}, "
                                                      f"{ds.attrs.get('mcs_samples', '')} samples) +-2 se")
            if lin is not None:
                ax.plot(t, lin, color="C0", lw=1.4, label="stochastic linearization")
            rel = float(ds[f"mcs_rel_error_peak_{name}"].values[i])
            ax.set_title(f"{point_label(ds, index)}{point_flag_text(ds, index)}: peak rel. error {100 * rel:+.1f} %"
                         + (f"\n{_probability_text(prob, i)[0 if name == 'var_theta' else 1]}" if prob is not None
                            else ""), fontsize=8,
                         color="C3" if prob is not None and prob["near_toppling"][i] else "black")
            ax.set_ylabel(axis_label(ds, name if name in ds.variables else f"mcs_{name}"))
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nspot checks against Monte Carlo\n{flag_summary(ds)}", fontsize=8)
    save_figure(fig, path)
    return Path(path)


def _spot_probabilities(ds):
    """:func:`screening.analysis.probabilities.spot_check_probabilities`, or None for a result without sample states."""
    return spot_check_probabilities(ds) if "mcs_sample_state" in ds.variables else None


def _probability_text(prob, i):
    """``(P(overturn) p +- se [NEAR TOPPLING ...], P(|theta| > a) p +- se, ...)`` of spot ``i``."""
    rel = "" if prob["relative_to"] == "None" else f" {prob['relative_to']}"
    over = f"P(overturn) {probability_text(prob['p_overturn'][i], prob['p_overturn_se'][i])}"
    if prob["near_toppling"][i]:
        over += f"\nNEAR TOPPLING (> {100 * TOPPLING_FRACTION:g} % overturned: variances over the survivors only)"
    exceed = "\n".join(f"P(|theta| > {a:g}{rel}) {probability_text(prob['p_exceed'][i, j], prob['p_exceed_se'][i, j])}"
                       for j, a in enumerate(prob["thresholds"]))
    return over, exceed


#: Two-sided 95 % normal quantile, for the Monte Carlo bands of :func:`plot_spot_panels`.
Z95 = 1.959964
MAX_SPOT_FIGURES = 12


def spot_file_label(ds, i):
    """File-name label of spot point ``i``: its case name, or its grid values.

    Returns: letters, digits and ``._-+`` only (values in SI units).
    """
    label = point_label(ds, spot_index(ds, i)).replace(", ", "__").replace("=", "_")
    return "".join(c if c.isalnum() or c in "._-+" else "_" for c in label) or f"spot{i}"


def plot_spot_panels(ds, i, path):
    """The paper's panels at spot point ``i`` (its figs. 2-9): ``c_eq(t)`` and ``k_eq(t)``;
    ``var_theta(t)`` and ``var_theta_dot(t)`` of the linearization with the Monte Carlo
    ensemble and its 95 % confidence band (+-1.96 standard errors); ``p_uplift(t)``.

    The title names the point, its flags, the Monte Carlo samples that overturned (excluded from
    the ensemble) and, where the result stores the sample states, the probabilities of overturning
    and of exceedance with their standard errors.

    Returns: ``path``.

    Notes
    -----
    The band is ``mcs +- Z95 se`` with ``Z95 = 1.959964``, the two-sided 95 % quantile of the normal
    distribution, and ``se`` the standard error of the Monte Carlo variance estimate;
    ``p_uplift = P(|theta| > theta_ul)`` is eq. (58) in [1]_.
    """
    index = spot_index(ds, i)
    t = ds["t"].values
    fig = new_figure(10.0, 7.5)
    (ax_c, ax_v), (ax_p, ax_vd) = fig.subplots(2, 2, sharex=True)
    ax_c.plot(t, np.asarray(ds["c_eq"].isel(index).values, dtype=float), color="C0", lw=1.4)
    ax_c.set_ylabel(axis_label(ds, "c_eq"), color="C0")
    ax_k = ax_c.twinx()
    ax_k.plot(t, np.asarray(ds["k_eq"].isel(index).values, dtype=float), color="C3", lw=1.4)
    ax_k.set_ylabel(axis_label(ds, "k_eq"), color="C3")
    ax_c.set_title("equivalent damping (left) and stiffness (right)", fontsize=8)
    mcs_label = f"Monte Carlo ({ds.attrs.get('mcs_model', '')}, {ds.attrs.get('mcs_samples', '')} samples), 95 % band"
    for ax, name in ((ax_v, "var_theta"), (ax_vd, "var_theta_dot")):
        mcs = np.asarray(ds[f"mcs_{name}"].values[i], dtype=float)
        se = np.asarray(ds[f"mcs_{name}_se"].values[i], dtype=float)
        ax.fill_between(t, mcs - Z95 * se, mcs + Z95 * se, color="C1", alpha=0.25, lw=0)
        ax.plot(t, mcs, color="C1", lw=1.0, label=mcs_label)
        ax.plot(t, np.asarray(ds[name].isel(index).values, dtype=float), color="C0", lw=1.4,
                label="stochastic linearization")
        rel = float(ds[f"mcs_rel_error_peak_{name}"].values[i])
        ax.set_title(f"{name}: peak rel. error of the linearization {100 * rel:+.1f} %", fontsize=8)
        ax.set_ylabel(axis_label(ds, name))
    ax_v.legend(fontsize=7)
    ax_p.plot(t, np.asarray(ds["p_uplift"].isel(index).values, dtype=float), color="C2", lw=1.4)
    ax_p.set_ylabel(axis_label(ds, "p_uplift"))
    ax_p.set_title("uplift occupancy P(|theta| > theta_ul), eq. (58)", fontsize=8)
    for ax in (ax_c, ax_v, ax_p, ax_vd):
        ax.grid(alpha=0.3)
    ax_p.set_xlabel("t [s]")
    ax_vd.set_xlabel("t [s]")
    over = int(ds["mcs_n_overturned"].values[i])
    prob = _spot_probabilities(ds)
    fig.suptitle(f"{point_label(ds, index)}{point_flag_text(ds, index)}  ({over} of {ds.attrs.get('mcs_samples', '?')} "
                 "Monte Carlo samples overturned, excluded from the ensemble)"
                 + ("\n" + "\n".join(t for t in _probability_text(prob, i) if t) if prob is not None else ""),
                 fontsize=8,
                 color="C3" if prob is not None and prob["near_toppling"][i] else "black")
    save_figure(fig, path)
    return Path(path)


#: Grid histories the spot-point panels draw.
SPOT_PANEL_HISTORIES = ("c_eq", "k_eq", "var_theta", "var_theta_dot", "p_uplift")
