"""Figures of record analyses: one simulation's time histories, an excitation fit, the multiple-stripe and
cloud fragility results."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import NullFormatter
from scipy.special import ndtr

from screening.applications.fit_excitation import envelope_energy, husid, smoothed_psd
from screening.core.excitations.kanai_tajimi import kanai_tajimi_psd
from screening.core.records import Record
from screening.report.figure_base import new_figure, save_figure

__all__ = []

REGIME_LABELS = {0: "full contact", 1: "uplift +", 2: "uplift -", 3: "flight"}


def plot_simulation(ds, path):
    """A simulation as a PNG: ground acceleration, ``theta / slenderness`` (with ``+-theta_ul``), ``z_cb``
    and the contact regime.

    Returns: ``path``.
    """
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


def plot_excitation_fit(record, fit, path):
    """The goodness of a :func:`screening.applications.fit_excitation.fit_excitation` as a PNG.

    The record's Husid curve against the fitted envelope's, and its smoothed periodogram against the
    fitted spectrum.

    Returns: ``path``.
    """
    a = record.acceleration - record.acceleration.mean()
    t = np.arange(a.size) * record.dt
    fig = new_figure(7.0, 7.0)
    ax = fig.subplots(2, 1)
    model = envelope_energy(t, fit["T1"], fit["T2"])
    ax[0].plot(t, husid(a, record.dt), color="k", lw=1.0, label="record")
    ax[0].plot(t, model / model[-1], "--", color="C1", lw=1.2,
               label=f"fitted envelope T1 = {fit['T1']:.3g} s, T2 = {fit['T2']:.3g} s")
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("Husid curve [1]")
    ax[0].set_title(f"worst gap {fit['husid_max_deviation']:.3f}; zero crossings {fit['zero_crossing_rate_record']:.3g}"
                    f"/s (record) vs {fit['zero_crossing_rate_model']:.3g}/s (model)", fontsize=8)
    ax[0].legend(fontsize=7)

    w, s = smoothed_psd(Record(a, record.dt), fit["T1"], fit["T2"])
    use = w > 0
    ax[1].loglog(w[use], s[use], color="k", lw=0.8, label="record (smoothed periodogram / 2 pi int q^2)")
    shape = kanai_tajimi_psd(w[use], 1.0, fit["omega_g"], fit["zeta_g"]) if fit["kind"] == "kanai_tajimi" else np.ones(use.sum())
    ax[1].loglog(w[use], fit["S0"] * shape, "--", color="C1", lw=1.2,
                 label=f"fitted {fit['kind']}: S0 = {fit['S0']:.3g} m2 s-3"
                       + (f", omega_g = {fit['omega_g']:.3g} rad/s, zeta_g = {fit['zeta_g']:.3g}"
                          if fit["kind"] == "kanai_tajimi" else ""))
    ax[1].set_xlabel("omega [rad/s]")
    ax[1].set_ylabel("S [m2 s-3]")
    ax[1].legend(fontsize=7)
    flags = fit.get("flags", [])
    fig.suptitle(f"fit-excitation: {record.name}" + (f"\n{len(flags)} warning(s): see the command's output"
                                                     if flags else ""), fontsize=9)
    return save_figure(fig, path)


def plot_stripes(ds, path):
    """A multiple-stripe result as a PNG: the fraction of records exceeding at each level (+-2 binomial
    standard errors) and the fitted lognormal curve.

    Returns: ``path``.

    Notes
    -----
    The curve is ``P(exceed | im) = Phi(ln(im / median) / beta)``, fitted by binomial maximum
    likelihood over the stripes [1]_.
    """
    x = ds["level"].values
    n, k = ds["n_used"].values, ds["n_exceed"].values
    frac = np.where(n > 0, k / np.maximum(n, 1), np.nan)
    se = np.sqrt(frac * (1 - frac) / np.maximum(n, 1))
    fig = new_figure(7.0, 4.8)
    ax = fig.subplots()
    ax.errorbar(x, frac, yerr=2 * se, fmt="s", color="k", capsize=3, label="stripes: fraction exceeding (+-2 se)")
    med, beta = float(ds["fit_median"]), float(ds["beta"])
    if np.isfinite(med):
        xs = np.geomspace(x.min() / 1.5, x.max() * 1.5, 200)
        ax.plot(xs, ndtr(np.log(xs / med) / beta), color="C1",
                label=f"binomial MLE: median {med:.3g} +- {float(ds['fit_median_se']):.2g}, "
                      f"beta {beta:.2f} +- {float(ds['beta_se']):.2f}")
    ax.set_xscale("log")
    ax.set_ylim(-0.05, 1.05)
    name = ds.attrs["intensity_variable"]
    ax.set_xlabel(f"{name} [{ds[name].attrs.get('units', '')}]")
    ax.set_ylabel("P(exceed)")
    ax.legend(fontsize=7)
    fig.suptitle(ds.attrs.get("title", ""), fontsize=9)
    return save_figure(fig, path)


def plot_cloud(ds, path):
    """A cloud result as a PNG: the cloud (peak ``|theta|`` / slenderness against the intensity measure)
    and the fitted lognormal fragility curve.

    Returns: ``path``.

    Notes
    -----
    The curve is ``P(exceed | im) = Phi(ln(im / median) / beta)``, fitted by maximum likelihood on the
    exceed / not-exceed outcome of each record [1]_.
    """
    name = ds.attrs["intensity_variable"]
    x = ds[name].values
    fig = new_figure(7.0, 7.5)
    ax = fig.subplots(2, 1, sharex=True)
    slender = float(ds["slenderness"])
    ratio = np.where(ds["overturned"].values, np.nan, ds["peak_abs_theta"].values / slender)
    ax[0].scatter(x[~ds["overturned"].values], ratio[~ds["overturned"].values], s=18, label="survived")
    over = ds["overturned"].values
    if over.any():
        ax[0].scatter(x[over], np.ones(over.sum()), marker="x", color="C3", s=30, label="overturned (plotted at 1)")
    ax[0].axhline(float(ds["threshold_rad"]) / slender, color="0.4", ls="--", lw=0.8, label="threshold")
    ax[0].set_yscale("log")
    ax[0].set_ylabel("peak |theta| / atan(b/h)")
    ax[0].legend(fontsize=7)
    ax[1].scatter(x, ds["exceed"].values.astype(float), s=18, color="k", label="records (exceed = 1)")
    med, beta = float(ds["fit_median"]), float(ds["beta"])
    if np.isfinite(med):
        xs = np.geomspace(x.min() / 1.5, x.max() * 1.5, 200)
        ax[1].plot(xs, ndtr(np.log(xs / med) / beta), color="C1",
                   label=f"lognormal MLE: median {med:.3g} {ds['fit_median'].attrs['units']}, beta {beta:.2f}")
    ax[1].set_xscale("log")
    ax[1].xaxis.set_minor_formatter(NullFormatter())
    ax[1].set_ylim(-0.05, 1.05)
    units = ds[name].attrs.get("units", "")
    ax[1].set_xlabel(f"{name} [{units}]")
    ax[1].set_ylabel("P(exceed)")
    ax[1].legend(fontsize=7)
    fig.suptitle(ds.attrs.get("title", ""), fontsize=9)
    return save_figure(fig, path)
