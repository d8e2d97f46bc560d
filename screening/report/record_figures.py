"""Figures of deterministic record analyses: one simulation's time histories, a cloud analysis."""

from __future__ import annotations

import numpy as np

from screening.report.figure_base import new_figure, save_figure

REGIME_LABELS = {0: "full contact", 1: "uplift +", 2: "uplift -", 3: "flight"}


def plot_simulation(ds, path):
    """Ground acceleration, ``theta / slenderness`` (with ``+-theta_ul``), ``z_cb`` and the contact regime."""
    fig = new_figure(8.0, 8.5)
    ax = fig.subplots(4, 1, sharex=True)
    t = ds["t"].values
    ax[0].plot(t, ds["ground_acceleration"].values / 9.80665, lw=0.7, color="0.3")
    ax[0].set_ylabel("ground acc. [g]\n(+: towards +x)")
    slender = float(ds["slenderness"])
    ax[1].plot(t, ds["theta"].values / slender, lw=0.8)
    tu = float(ds["theta_ul"]) / slender
    for s in (-1, 1):
        ax[1].axhline(s * tu, color="C1", lw=0.6, ls="--")
        ax[1].axhline(s, color="C3", lw=0.6)
    ax[1].set_ylabel("theta / atan(b/h)")
    if bool(ds["overturned"]):
        ax[1].axvline(float(ds["overturning_time"]), color="C3", ls=":")
        ax[1].set_title(f"overturned at t = {float(ds['overturning_time']):.3f} s", fontsize=9)
    ax[2].plot(t, ds["z_cb"].values * 1e3, lw=0.8, color="C2")
    ax[2].set_ylabel("z_cb [mm]")
    regime = ds["contact_regime"].values.astype(float)
    regime[regime < 0] = np.nan
    ax[3].step(t, regime, where="post", lw=0.8, color="C4")
    ax[3].set_yticks(list(REGIME_LABELS), list(REGIME_LABELS.values()))
    ax[3].set_xlabel("t [s]")
    fig.suptitle(f"{ds.attrs.get('record', '')}: {ds.attrs.get('model', '')} model, "
                 f"peak |theta| = {float(ds['peak_abs_theta']):.3g} rad", fontsize=10)
    return save_figure(fig, path)


def plot_im_fragility(frag, path, max_curves=8):
    """``p_exceed`` against the intensity measure of :func:`screening.analysis.im_fragility.fragility_over_im`
    (lognormal fits dashed), up to ``max_curves`` curves over the other dimensions."""
    from scipy.special import ndtr

    name, dim = frag.attrs["intensity_variable"], frag.attrs["intensity_dim"]
    p = frag["p_exceed"]
    x = frag[name].transpose(*p.dims)
    other = [d for d in p.dims if d != dim]
    flat_p = p.transpose(*other, dim).values.reshape(-1, p.sizes[dim])
    flat_x = x.transpose(*other, dim).values.reshape(-1, p.sizes[dim])
    med = frag["median"].transpose(*other).values.reshape(-1)
    beta = frag["beta"].transpose(*other).values.reshape(-1)
    picks = np.unique(np.linspace(0, flat_p.shape[0] - 1, min(max_curves, flat_p.shape[0])).round().astype(int))
    fig = new_figure(7.0, 4.8)
    ax = fig.subplots()
    shape = [p.sizes[d] for d in other]
    for n, j in enumerate(picks):
        index = dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}
        label = ", ".join(f"{d} = {frag[d].values[i]:.3g}" for d, i in index.items()) or "P(exceed)"
        ax.plot(flat_x[j], flat_p[j], "o-", color=f"C{n}", ms=3, lw=1.2, label=label)
        if np.isfinite(med[j]):
            xs = np.geomspace(np.nanmin(flat_x[j]), np.nanmax(flat_x[j]), 200)
            ax.plot(xs, ndtr(np.log(xs / med[j]) / beta[j]), "--", color=f"C{n}", lw=0.9,
                    label=f"lognormal: median {med[j]:.3g}, beta {beta[j]:.2f}")
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    units = frag[name].attrs.get("units", "")
    extra = f", T = {frag[name].attrs['period']:g} s" if "period" in frag[name].attrs else ""
    ax.set_xlabel(f"{name} [{units}]{extra}")
    overturn = frag.attrs.get("limit_state") == "overturn"
    ax.set_ylabel(f"probability of {'overturning' if overturn else 'exceedance'} [1]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.suptitle(f"Fragility over {name} (threshold {frag.attrs.get('threshold', ''):g}, "
                 f"relative to {frag.attrs.get('relative_to', 'None')})", fontsize=9)
    return save_figure(fig, path)
