"""PNG figures of a sweep result (matplotlib, object API with the Agg canvas: no pyplot state).

* :func:`plot_histories` — ``var_theta``, ``var_theta_dot``, ``c_eq``, ``k_eq``, ``p_uplift``
  against time for a few representative points (:func:`representative_points`);
* :func:`plot_peaks` — ``peak_var_theta``, ``peak_p_uplift``, ``min_k_eq`` and ``status`` over the
  grid: maps over the first two grid dimensions (further dimensions at their middle index),
  curves for a one-dimensional grid;
* :func:`plot_spots` — linearization against Monte Carlo (with +-2 standard errors) at the spot
  points;
* :func:`plot_spot_panels` — the paper's panels at one spot point (``c_eq``/``k_eq``; variances
  with the Monte Carlo 95 % band; ``p_uplift``), one PNG per spot point;
* :func:`plot_fragility` — fragility curves over a swept intensity with their lognormal fit;
* :func:`plot_result` — all but the fragility figure for a result file, next to it or in ``out_dir``.

Only the slices that are drawn are read from the file.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

HISTORY_PANELS = ("var_theta", "var_theta_dot", "c_eq", "k_eq", "p_uplift")
PEAK_PANELS = ("peak_var_theta", "peak_p_uplift", "min_k_eq", "status")
LOG_PANELS = ("var_theta", "var_theta_dot", "peak_var_theta")
DPI = 110


def grid_dims(ds):
    """The grid dimensions of a result (the dimensions of ``status``)."""
    return tuple(ds["status"].dims)


def grid_values(ds, dim):
    """Coordinate values of grid dimension ``dim`` (``k`` lives in ``k_value``; cases: index)."""
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return np.asarray(ds[name].values)


def grid_units(ds, dim):
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return ds[name].attrs.get("units", "")


def spot_index(ds, i):
    """Grid index dict of spot point ``i``."""
    index = {}
    for dim in grid_dims(ds):
        if dim == "case":
            index[dim] = int(ds["spot_case"].values[i])
        else:
            index[dim] = int(np.argmin(np.abs(grid_values(ds, dim) - ds[f"spot_{dim}"].values[i])))
    return index


def _is_log(values):
    values = np.asarray(values, dtype=float)
    return values.size > 2 and np.all(values > 0) and values.max() / values.min() > 50


def point_label(ds, index):
    """``"eps=6e+07, S0=2.4e-05"`` (or the case name) for a grid index dict."""
    parts = []
    for dim, i in index.items():
        if dim == "case" and "case_name" in ds:
            parts.append(str(ds["case_name"].values[i]))
        else:
            parts.append(f"{dim}={float(grid_values(ds, dim)[i]):.3g}")
    return ", ".join(parts) if parts else "single point"


def representative_points(ds, n=4):
    """Up to ``n`` grid index dicts: status-ok points with the smallest, median and largest
    ``peak_var_theta`` and the largest ``peak_p_uplift`` (any points if none is ok)."""
    dims = grid_dims(ds)
    shape = ds["status"].shape
    status = np.asarray(ds["status"].values).reshape(-1)
    peak = np.asarray(ds["peak_var_theta"].values, dtype=float).reshape(-1)
    upl = np.asarray(ds["peak_p_uplift"].values, dtype=float).reshape(-1)
    ok = np.flatnonzero((status == 0) & np.isfinite(peak))
    if ok.size == 0:
        picks = list(range(min(n, status.size)))
    else:
        order = ok[np.argsort(peak[ok], kind="stable")]
        picks = [order[0], order[order.size // 2], order[-1], ok[np.nanargmax(upl[ok])]]
    seen, out = set(), []
    for j in picks:
        if int(j) not in seen:
            seen.add(int(j))
            out.append(dict(zip(dims, (int(i) for i in np.unravel_index(int(j), shape)))
                            ) if dims else {})
    return out[:n]


def _new_figure(width, height):
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def save_figure(fig, path):
    """Write ``fig`` as PNG to ``path`` atomically (``<path>.tmp`` then rename): a failing write
    (disk full, permission) leaves no partial file behind and raises the ``OSError``."""
    import tempfile

    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)   # never a planted link
    tmp = Path(tmp)
    try:
        with os.fdopen(fd, "wb") as fh:
            fig.savefig(fh, format="png")
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def _label(ds, name):
    units = ds[name].attrs.get("units")
    return f"{name} [{units}]" if units else name


def plot_histories(ds, path, points=None):
    """Time histories at ``points`` (grid index dicts; default :func:`representative_points`)."""
    points = representative_points(ds) if points is None else points
    fig = _new_figure(8.0, 11.0)
    axes = fig.subplots(len(HISTORY_PANELS), 1, sharex=True)
    t = ds["t"].values
    drawn = {name: [] for name in HISTORY_PANELS}
    for index in points:
        label = point_label(ds, index)
        for ax, name in zip(axes, HISTORY_PANELS):
            y = np.asarray(ds[name].isel(index).values, dtype=float)
            if name in LOG_PANELS:
                y = np.where(y > 0, y, np.nan)
            drawn[name].append(y)
            ax.plot(t, y, label=label, lw=1.2)
    for ax, name in zip(axes, HISTORY_PANELS):
        ax.set_ylabel(_label(ds, name))
        _scale(ax, drawn[name], log=name in LOG_PANELS)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nstochastic linearization: representative points", fontsize=9)
    save_figure(fig, path)
    return Path(path)


def _scale(ax, drawn, log):
    """Log y axis when asked and something finite and positive was drawn; otherwise a linear axis
    with a note (a result whose points are all flagged, or all NaN, still gets its figures: B4)."""
    values = np.concatenate([np.ravel(v) for v in drawn]) if drawn else np.array([])
    finite = np.isfinite(values)
    if not finite.any():
        ax.text(0.5, 0.5, "no finite values (every point flagged or not computed)", transform=ax.transAxes,
                ha="center", va="center", fontsize=8, color="0.4")
        return
    if log and (values[finite] > 0).any():
        ax.set_yscale("log")


def _ticks(ds, dim, n):
    if dim == "case" and "case_name" in ds:
        return [str(s) for s in ds["case_name"].values]
    return [f"{float(v):.3g}" for v in grid_values(ds, dim)[:n]]


def plot_peaks(ds, path):
    """Peak statistics over the grid; ``None`` (nothing written) for a single-point result."""
    dims = grid_dims(ds)
    if not dims:
        return None
    fig = _new_figure(11.0, 8.0)
    axes = fig.subplots(2, 2).ravel()
    if len(dims) == 1:
        _curves(ds, dims[0], axes)
        note = ""
    else:
        ydim, xdim = dims[0], dims[1]
        rest = {d: ds.sizes[d] // 2 for d in dims[2:]}
        note = ("; " + ", ".join(f"{d}={float(grid_values(ds, d)[i]):.3g}" for d, i in rest.items())
                if rest else "")
        for ax, name in zip(axes, PEAK_PANELS):
            _map(ds, name, ydim, xdim, rest, ax, fig)
    fig.suptitle(f"{ds.attrs.get('title', '')}\npeak statistics over the grid{note}", fontsize=9)
    save_figure(fig, path)
    return Path(path)


def _curves(ds, dim, axes):
    n = ds.sizes[dim]
    categorical = dim == "case"
    x = np.arange(n) if categorical else grid_values(ds, dim)
    for ax, name in zip(axes, PEAK_PANELS):
        y = np.asarray(ds[name].values, dtype=float)
        if name == "status":
            ax.plot(x, y, "o")
            ax.set_yticks(ds["status"].attrs["flag_values"])
            ax.set_yticklabels(str(ds["status"].attrs["flag_meanings"]).split(), fontsize=7)
        else:
            y = np.where(y > 0, y, np.nan) if name in LOG_PANELS else y
            ax.plot(x, y, "o" if categorical else "o-", ms=4 if categorical else 3)
            ax.set_ylabel(_label(ds, name))
            _scale(ax, [y], log=name in LOG_PANELS)
        if categorical:
            ax.set_xticks(x)
            ax.set_xticklabels(_ticks(ds, dim, n), rotation=45, ha="right", fontsize=7)
        else:
            ax.set_xlabel(f"{dim} [{grid_units(ds, dim)}]")
            if _is_log(x):
                ax.set_xscale("log")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)


def _map(ds, name, ydim, xdim, rest, ax, fig):
    da = ds[name].isel(rest) if rest else ds[name]
    z = np.asarray(da.transpose(ydim, xdim).values, dtype=float)
    ny, nx = z.shape
    if name in LOG_PANELS:
        z = np.log10(np.where(z > 0, z, np.nan))
        title = f"log10 {name} [{ds[name].attrs.get('units', '')}]"
    else:
        title = _label(ds, name)
    mesh = ax.pcolormesh(np.arange(nx + 1) - 0.5, np.arange(ny + 1) - 0.5, np.ma.masked_invalid(z),
                         cmap="tab10" if name == "status" else "viridis", shading="flat")
    bar = fig.colorbar(mesh, ax=ax)
    if name == "status":
        mesh.set_clim(-1.5, 8.5)
        codes = np.asarray(ds["status"].attrs["flag_values"])
        bar.set_ticks(codes)
        bar.set_ticklabels(str(ds["status"].attrs["flag_meanings"]).split(), fontsize=7)
    for axis, dim, n in (("x", xdim, nx), ("y", ydim, ny)):
        step = max(1, n // 8)
        ticks = np.arange(0, n, step)
        labels = _ticks(ds, dim, n)
        getattr(ax, f"set_{axis}ticks")(ticks)
        getattr(ax, f"set_{axis}ticklabels")([labels[i] for i in ticks], fontsize=7,
                                              rotation=45 if axis == "x" else 0)
        getattr(ax, f"set_{axis}label")(f"{dim} [{grid_units(ds, dim)}]" if dim != "case" else "case")
    ax.set_title(title, fontsize=9)


def plot_spots(ds, path):
    """Linearization vs Monte Carlo at the spot points; ``None`` if the result has none.  The
    linearization's history is drawn where the result stores it (on the grid, or as ``spot_<name>``
    with ``[output] histories = "spots"``); the peak error is always in the title."""
    if "spot" not in ds.dims or ds.sizes["spot"] == 0:
        return None
    n = min(ds.sizes["spot"], 8)
    fig = _new_figure(10.0, 2.6 * n + 0.8)
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
            ax.set_title(f"{point_label(ds, index)}: peak rel. error {100 * rel:+.1f} %", fontsize=8)
            ax.set_ylabel(_label(ds, name if name in ds.variables else f"mcs_{name}"))
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nspot checks against Monte Carlo", fontsize=9)
    save_figure(fig, path)
    return Path(path)


#: Two-sided 95 % normal quantile, for the Monte Carlo bands of :func:`plot_spot_panels`.
Z95 = 1.959964
MAX_SPOT_FIGURES = 12


def spot_file_label(ds, i):
    """File-name label of spot point ``i``: its case name, or its grid values."""
    label = point_label(ds, spot_index(ds, i)).replace(", ", "__").replace("=", "_")
    return "".join(c if c.isalnum() or c in "._-+" else "_" for c in label) or f"spot{i}"


def plot_spot_panels(ds, i, path):
    """The paper's panels at spot point ``i`` (its figs. 2-9): ``c_eq(t)`` and ``k_eq(t)``;
    ``var_theta(t)`` and ``var_theta_dot(t)`` of the linearization with the Monte Carlo
    ensemble and its 95 % confidence band (+-1.96 standard errors); ``p_uplift(t)``."""
    index = spot_index(ds, i)
    t = ds["t"].values
    fig = _new_figure(10.0, 7.5)
    (ax_c, ax_v), (ax_p, ax_vd) = fig.subplots(2, 2, sharex=True)
    ax_c.plot(t, np.asarray(ds["c_eq"].isel(index).values, dtype=float), color="C0", lw=1.4)
    ax_c.set_ylabel(_label(ds, "c_eq"), color="C0")
    ax_k = ax_c.twinx()
    ax_k.plot(t, np.asarray(ds["k_eq"].isel(index).values, dtype=float), color="C3", lw=1.4)
    ax_k.set_ylabel(_label(ds, "k_eq"), color="C3")
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
        ax.set_ylabel(_label(ds, name))
    ax_v.legend(fontsize=7)
    ax_p.plot(t, np.asarray(ds["p_uplift"].isel(index).values, dtype=float), color="C2", lw=1.4)
    ax_p.set_ylabel(_label(ds, "p_uplift"))
    ax_p.set_title("uplift occupancy P(|theta| > theta_ul), eq. (58)", fontsize=8)
    for ax in (ax_c, ax_v, ax_p, ax_vd):
        ax.grid(alpha=0.3)
    ax_p.set_xlabel("t [s]")
    ax_vd.set_xlabel("t [s]")
    over = int(ds["mcs_n_overturned"].values[i])
    fig.suptitle(f"{point_label(ds, index)}  ({over} of {ds.attrs.get('mcs_samples', '?')} Monte Carlo "
                 f"samples overturned, excluded from the ensemble)", fontsize=9)
    save_figure(fig, path)
    return Path(path)


def plot_fragility(frag, dim, path, max_curves=8):
    """Fragility curves: ``p_exceed`` of a :func:`screening.analysis.fragility.fragility_dataset` along
    the swept intensity ``dim`` (lognormal fit dashed), with the Monte Carlo probabilities at
    the spot points (+-2 standard errors).  Up to ``max_curves`` curves, the other grid
    dimensions sampled evenly.  ``None`` if ``dim`` is not a dimension of ``p_exceed``."""
    from scipy.special import ndtr

    p = frag["p_exceed"]
    if dim not in p.dims:
        return None
    other = [d for d in p.dims if d != dim]
    flat = p.transpose(*other, dim).values.reshape(-1, p.sizes[dim])
    picks = np.unique(np.linspace(0, flat.shape[0] - 1, min(max_curves, flat.shape[0])).round().astype(int))
    x = grid_values(frag, dim)
    fig = _new_figure(7.0, 4.8)
    ax = fig.subplots()
    shape = [p.sizes[d] for d in other]
    median = frag["median"].transpose(*other).values.reshape(-1) if "median" in frag else None
    beta = frag["beta"].transpose(*other).values.reshape(-1) if "beta" in frag else None
    xs = np.geomspace(x.min(), x.max(), 200) if np.all(x > 0) else np.linspace(x.min(), x.max(), 200)
    for n, j in enumerate(picks):
        index = dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}
        label = point_label(frag, index) if other else "P(|theta| > threshold)"
        ax.plot(x, flat[j], "o-", color=f"C{n}", ms=3, lw=1.2, label=label)
        if median is not None and np.isfinite(median[j]) and np.isfinite(beta[j]):
            ax.plot(xs, ndtr(np.log(xs / median[j]) / beta[j]), "--", color=f"C{n}", lw=0.9,
                    label=f"lognormal fit: median {median[j]:.3g}, beta {beta[j]:.2f}")
    if "mcs_p_exceed" in frag and f"spot_{dim}" in frag:
        pm, se = frag["mcs_p_exceed"].values, frag["mcs_p_exceed_se"].values
        ax.errorbar(frag[f"spot_{dim}"].values, pm, yerr=2 * se, fmt="ks", ms=5, capsize=3,
                    label="Monte Carlo at the spot points (+-2 se)")
    if _is_log(x):
        ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(f"{dim} [{grid_units(frag, dim)}]")
    ax.set_ylabel("probability of exceedance [1]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    rel = frag.attrs.get("relative_to", "None")
    what = (f"{frag.attrs['threshold']:.3g} rad" if rel == "None"
            else f"{frag.attrs['threshold']:.3g} x {rel}")
    fig.suptitle(f"Fragility: P(max |theta| > {what}) over the record ({frag.attrs.get('method', '')})",
                 fontsize=9)
    save_figure(fig, path)
    return Path(path)


#: Grid histories the spot-point panels draw.
SPOT_PANEL_HISTORIES = ("c_eq", "k_eq", "var_theta", "var_theta_dot", "p_uplift")


def plot_result(ds, stem, out_dir):
    """Write all figures of dataset ``ds`` as ``out_dir/<stem>_<kind>.png``; returns the paths.

    All or nothing: if one figure fails (unreadable data, failing write), the figures this
    call created are removed before the error propagates.  Figures of histories the result does
    not store (``[output]`` of the study) are not drawn.
    """
    out_dir = Path(out_dir)
    jobs = [(plot_histories, out_dir / f"{stem}_histories.png")] if set(HISTORY_PANELS) <= set(ds.variables) else []
    jobs += [(plot_peaks, out_dir / f"{stem}_peaks.png"),
             (plot_spots, out_dir / f"{stem}_spots.png")]
    has_panels = set(SPOT_PANEL_HISTORIES) <= set(ds.variables)
    n_spots = ds.sizes.get("spot", 0) if has_panels else 0
    for i in range(min(n_spots, MAX_SPOT_FIGURES)):
        path = out_dir / f"{stem}_spot{i}_{spot_file_label(ds, i)}.png"
        jobs.append((lambda d, p, i=i: plot_spot_panels(d, i, p), path))
    existed = {path for _, path in jobs if path.exists()}
    paths = []
    try:
        for make, path in jobs:
            paths.append(make(ds, path))
    except BaseException:
        for path in paths:
            if path is not None and path not in existed:
                Path(path).unlink(missing_ok=True)
        raise
    return [p for p in paths if p is not None]
