"""Figures of deterministic record analyses: one simulation's time histories, a cloud analysis."""

from __future__ import annotations

import numpy as np

from screening.report.figures import _new_figure, save_figure

REGIME_LABELS = {0: "full contact", 1: "uplift +", 2: "uplift -", 3: "flight"}


def plot_simulation(ds, path):
    """Ground acceleration, ``theta / slenderness`` (with ``+-theta_ul``), ``z_cb`` and the contact regime."""
    fig = _new_figure(8.0, 8.5)
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
