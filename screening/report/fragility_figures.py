"""The fragility figure: exceedance probabilities over a swept intensity, their lognormal fit, the
Monte Carlo probabilities at the spot points and, for a result with ``[accuracy]``, the best estimates
with their band and the method behind each point; flagged and untrusted points marked."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.ticker import NullFormatter

from screening.report.figure_base import (
    FLAGGED_COLOR, UNTRUSTED_COLOR, flag_summary, grid_units, grid_values, is_log_spaced, new_figure,
    point_flags, point_label, save_figure)
from screening.core.status import MONTE_CARLO_SOURCE_BASE, BestMethod, FitFlag

__all__ = []


def plot_fragility(frag, dim, path, max_curves=8, flags=None):
    """Fragility curves as a PNG, with their lognormal fits and the Monte Carlo checks.

    ``p_exceed`` of a :func:`screening.analysis.fragility.fragility_dataset` along the swept intensity
    ``dim`` (lognormal fit dashed), with the Monte Carlo probabilities at the spot points (+-2
    standard errors) in the colour of the curve they lie on (black when that curve is not drawn).
    Up to ``max_curves`` curves, the other grid dimensions sampled evenly.  Where ``frag`` has
    ``best_p_exceed`` (``[accuracy]``), each drawn curve also gets its best estimates, the band
    ``best_p_exceed_low..high`` shaded and one marker per :class:`~screening.core.status.BestMethod`
    (points without a vouched estimate: a red ``?``, no band).  A result with :data:`PANEL_CASES` cases
    or more gets one panel per case (its name as the title, shared axes; the first panel's legend
    explains the marks, the others name their fits), so that 15 or 50 objects stay readable.

    Returns: ``path``; ``None`` if ``dim`` is not a dimension of ``p_exceed``.

    Notes
    -----
    The fit drawn is ``P(IM) = Phi(ln(IM / median) / beta)``.
    """
    p = frag["p_exceed"]
    if dim not in p.dims:
        return None
    if "case" in p.dims and dim != "case" and frag.sizes["case"] >= PANEL_CASES:
        return _plot_panels(frag, dim, path, max_curves, flags)
    fig = new_figure(7.0, 5.4)
    ax = fig.subplots()
    _draw_curves(ax, frag, dim, max_curves, flags, legend_size=7)
    fig.suptitle(_title(frag, dim, flags), fontsize=8)
    save_figure(fig, path)
    return Path(path)


class _Everything(set):
    """A set that holds every label: nothing more goes into a legend."""

    def __contains__(self, item):
        return True


_LABELLED_ALREADY = _Everything()

#: From this many cases on, the fragility figure draws one panel per case (small multiples).
PANEL_CASES = 4


def _plot_panels(frag, dim, path, max_curves, flags):
    """One panel per case, each with its curves, fits and checks, on shared axes; the legend of each panel
    names only its fits (the markers are those of the one-panel figure, explained in the first panel)."""
    n = frag.sizes["case"]
    ncols = int(np.ceil(np.sqrt(n * 1.4)))
    nrows = int(np.ceil(n / ncols))
    width = min(2.6 * ncols + 1.0, 30.0)
    fig = new_figure(width, min(2.2 * nrows + 1.2, 40.0))
    axes = np.atleast_1d(fig.subplots(nrows, ncols, sharex=True, sharey=True)).ravel()
    names = [str(v) for v in frag["case_name"].values] if "case_name" in frag.coords else [
        str(v) for v in frag["case"].values]
    for i in range(n):
        sub = _one_case(frag, i)
        sub_flags = flags.isel(case=i) if flags is not None and "case" in flags.dims else flags
        _draw_curves(axes[i], sub, dim, max_curves, sub_flags, legend_size=5, short=True)
        axes[i].set_title(names[i], fontsize=8)
        if i % ncols:
            axes[i].set_ylabel("")
        if i < n - ncols:
            axes[i].set_xlabel("")
    for ax in axes[n:]:
        ax.set_visible(False)
    key = textwrap.fill(f"one panel per case ({n}); " + PANEL_KEY, width=int(14 * width))   # ~14 characters an inch
    fig.suptitle(_title(frag, dim, flags) + "\n" + key, fontsize=9)
    save_figure(fig, path)
    return Path(path)


#: What the marks of a panel mean (the one-panel figure says it in its legend).
PANEL_KEY = ("solid: P per point; dashed: lognormal fit (median, beta in the panel; [n left out]: points nothing "
             "vouches for, left out of the fit); filled squares: Monte Carlo answers (p_source); hollow red circles: "
             "linearization untrusted; grey x: flagged; open squares: Monte Carlo spot checks +-2 se; shaded: "
             "best-estimate band")


def _one_case(frag, i):
    """The fragility dataset of case ``i``, with only the Monte Carlo spot points on that case."""
    sub = frag.isel(case=i)
    if "spot" in frag.dims and "spot_case" in frag:
        keep = np.flatnonzero(np.asarray(frag["spot_case"].values, dtype=int) == i)
        sub = sub.isel(spot=keep)
    return sub


def _title(frag, dim, flags):
    name = frag.attrs.get("intensity_variable")
    overturn = frag.attrs.get("limit_state") == "overturn"
    rel = frag.attrs.get("relative_to", "None")
    what = (f"{frag.attrs['threshold']:.3g} rad" if rel == "None"
            else f"{frag.attrs['threshold']:.3g} x {rel}")
    summary = f"\n{flag_summary(flags)}" if flags is not None else ""
    over = f" over {name}" if name else ""
    event = "overturning, max |theta| > atan(b/h)" if overturn else f"max |theta| > {what}"
    return f"Fragility{over}: P({event}) over the record ({frag.attrs.get('method', '')}){summary}"


def _draw_curves(ax, frag, dim, max_curves, flags, legend_size=7, short=False):
    """The curves of ``frag`` along ``dim`` on ``ax`` (:func:`plot_fragility`); ``short``: the legend names
    the fits only."""
    from scipy.special import ndtr

    p = frag["p_exceed"]
    other = [d for d in p.dims if d != dim]
    flat = p.transpose(*other, dim).values.reshape(-1, p.sizes[dim])
    name = frag.attrs.get("intensity_variable")
    if name:                                    # fitted over an intensity measure: its values per curve
        xflat = frag[name].broadcast_like(p).transpose(*other, dim).values.reshape(flat.shape)
    else:
        xflat = np.broadcast_to(grid_values(frag, dim), flat.shape)
    if flags is not None:
        flagged, untrusted = (a.reshape(flat.shape) for a in point_flags(flags, None, (*other, dim)))
    else:
        flagged = untrusted = np.zeros(flat.shape, dtype=bool)
    monte_carlo = np.zeros(flat.shape, dtype=bool)     # answered by Monte Carlo: the linearization's marks do not apply
    if flags is not None and "p_source" in flags:
        monte_carlo = (flags["p_source"].transpose(*other, dim).values.reshape(flat.shape) >= MONTE_CARLO_SOURCE_BASE)
        flagged, untrusted = flagged & ~monte_carlo, untrusted & ~monte_carlo
    picks = np.unique(np.linspace(0, flat.shape[0] - 1, min(max_curves, flat.shape[0])).round().astype(int))
    shape = [p.sizes[d] for d in other]
    median, beta, unvouched, flag = (frag[v].transpose(*other).values.reshape(-1) if v in frag else None
                                     for v in ("fit_median", "beta", "fit_n_unvouched", "fit_flag"))
    best = _best_arrays(frag, other, dim) if "best_p_exceed" in frag else None
    colour, labelled = {}, set()

    def lab(text):
        return None if short else text

    for n, j in enumerate(picks):
        colour[int(j)] = f"C{n}"
        index = dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}
        label = point_label(frag, index) if other else (
            "P(overturn)" if frag.attrs.get("limit_state") == "overturn" else "P(|theta| > threshold)")
        x = xflat[j]
        ax.plot(x, flat[j], "o-", color=f"C{n}", ms=3, lw=1.2, label=lab(label))
        ax.plot(x[untrusted[j]], flat[j][untrusted[j]], "o", ms=7, mfc="none", mec=UNTRUSTED_COLOR, mew=1.2)
        ax.plot(x[flagged[j]], flat[j][flagged[j]], "x", ms=7, color=FLAGGED_COLOR, mew=1.5)
        ax.plot(x[monte_carlo[j]], flat[j][monte_carlo[j]], "s", ms=4, color=f"C{n}")
        if best is not None:
            _draw_best(ax, x, best, j, f"C{n}", _LABELLED_ALREADY if short else labelled)
        if median is not None and np.isfinite(median[j]) and np.isfinite(beta[j]):
            xs = np.geomspace(np.nanmin(x), np.nanmax(x), 200)
            left = int(unvouched[j]) if unvouched is not None else 0
            ax.plot(xs, ndtr(np.log(xs / median[j]) / beta[j]), "--", color=f"C{n}", lw=0.9,
                    label=(f"median {median[j]:.3g}, beta {beta[j]:.2f}" if short else
                           f"lognormal fit: median {median[j]:.3g}, beta {beta[j]:.2f}")
                          + (f" [{left} point(s) left out: nothing vouches for them]" if left and not short
                             else f" [{left} left out]" if left else ""))
        elif flag is not None:
            left = int(unvouched[j]) if unvouched is not None else 0
            ax.plot([], [], " ", label=f"no lognormal fit: {FitFlag(int(flag[j])).name}"
                    + (f" [{left} point(s) left out: nothing vouches for them]" if left else ""))
    if "mcs_p_exceed" in frag and f"spot_{dim}" in frag and frag.sizes.get("spot", 0):
        pm, se = frag["mcs_p_exceed"].values, frag["mcs_p_exceed_se"].values
        curve = _spot_curves(frag, other, shape)
        for c in sorted(set(curve.tolist())):
            on = curve == c
            drawn = c in colour
            ax.errorbar(xflat[c][_spot_position(frag, dim)[on]], pm[on], yerr=2 * se[on], fmt="s", ms=6, capsize=3,
                        color=colour.get(c, "k"), mfc="white" if drawn else "k", mew=1.5,
                        label=lab("Monte Carlo (+-2 se)" + (f": {point_label(frag, _curve_index(other, shape, c))}"
                                                            if other else "")
                                  + ("" if drawn else " (curve not drawn)")))
    if best is not None and not short:
        method = best[3]
        counts = ", ".join(f"{m.name} {int(np.sum(method == m))}" for m in BestMethod if np.any(method == m))
        ax.plot([], [], " ", label=f"best estimates (all points): {counts}")
    if flags is not None and not short:
        if monte_carlo.any():
            ax.plot([], [], "s", color="k", ms=4, label=f"Monte Carlo answer (p_source): {int(monte_carlo.sum())}")
        ax.plot([], [], "x", color=FLAGGED_COLOR, label=f"flagged (status != ok): {int(flagged.sum())} of {flagged.size}")
        ax.plot([], [], "o", mfc="none", mec=UNTRUSTED_COLOR, label=f"linearization untrusted: {int(untrusted.sum())}")
    if is_log_spaced(grid_values(frag, dim)) or name:
        ax.set_xscale("log")
        if short:                                # narrow panels: the minor labels would run into each other
            ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_ylim(-0.02, 1.02)
    if name:
        extra = f", T = {frag[name].attrs['period']:g} s" if "period" in frag[name].attrs else ""
        ax.set_xlabel(f"{name} [{frag[name].attrs.get('units', '')}]{extra} (swept along {dim})",
                      fontsize=8 if short else None)
    else:
        ax.set_xlabel(f"{dim} [{grid_units(frag, dim)}]")
    overturn = frag.attrs.get("limit_state") == "overturn"
    ax.set_ylabel(f"probability of {'overturning' if overturn else 'exceedance'} [1]")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=legend_size, loc="best")


#: Marker of a best estimate by its source (``best_method``).
BEST_MARKERS = {BestMethod.linearization: ("o", "best: linearization"),
                BestMethod.corrected_linearization: ("^", "best: corrected Gaussian (linearization x correction)"),
                BestMethod.condensed_monte_carlo: ("s", "best: condensed Monte Carlo (binomial band)"),
                BestMethod.coupled_monte_carlo: ("D", "best: coupled Monte Carlo (binomial band)"),
                BestMethod.stiff_bed_monte_carlo: ("P", "best: stiff-bed Monte Carlo (binomial band)"),
                BestMethod.unreliable: ("$?$", "best: none vouched for (unreliable, no band)")}


def _best_arrays(frag, other, dim):
    """``best_p_exceed``, its band and ``best_method`` as (curves x points) arrays like ``p_exceed``."""
    return tuple(frag[name].transpose(*other, dim).values.reshape(-1, frag.sizes[dim])
                 for name in ("best_p_exceed", "best_p_exceed_low", "best_p_exceed_high", "best_method"))


def _draw_best(ax, x, best, j, colour, labelled):
    """Curve ``j`` 's best estimates: the band shaded, a marker per method (each legend entry once;
    ``labelled`` holds the entries already made)."""
    def once(label):
        new = label not in labelled
        labelled.add(label)
        return label if new else None

    p, low, high, method = (a[j] for a in best)
    ax.fill_between(x, low, high, color=colour, alpha=0.15, lw=0, label=once("best estimate band (+-2 se)"))
    for m, (marker, label) in BEST_MARKERS.items():
        on = method == m
        if on.any():
            unreliable = m == BestMethod.unreliable
            ax.plot(x[on], p[on], marker=marker, ms=9 if unreliable else 6, mfc="none",
                    mec=UNTRUSTED_COLOR if unreliable else colour, mew=1.2, ls="none", label=once(label))


def _curve_index(other, shape, j):
    return dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}


def _spot_position(frag, d):
    """Index along the grid dimension ``d`` of each spot point."""
    if d == "case":
        return np.asarray(frag["spot_case"].values, dtype=int)
    grid = grid_values(frag, d)
    return np.abs(grid[None, :] - np.asarray(frag[f"spot_{d}"].values)[:, None]).argmin(axis=1)


def _spot_curves(frag, other, shape):
    """Flat index (over the dims ``other``) of the fragility curve each spot point lies on."""
    n = frag.sizes["spot"]
    if not other:
        return np.zeros(n, dtype=int)
    return np.ravel_multi_index([_spot_position(frag, d) for d in other], shape)
