"""PNG figures of a sweep result (matplotlib, object API with the Agg canvas: no pyplot state).

* :func:`plot_histories` — ``var_theta``, ``var_theta_dot``, ``c_eq``, ``k_eq``, ``p_uplift``
  against time for a few representative points (:func:`representative_points`);
* :func:`plot_peaks` — ``peak_var_theta``, ``peak_p_uplift``, ``min_k_eq`` and ``status`` over the
  grid: maps over the first two grid dimensions (further dimensions at their middle index),
  curves for a one-dimensional grid;
* :func:`plot_spots` — linearization against Monte Carlo (with +-2 standard errors) at the spot
  points;
* :func:`plot_result` — all of the above for a result file, next to it or in ``out_dir``.

Only the slices that are drawn are read from the file.
"""

from __future__ import annotations

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


def _label(ds, name):
    units = ds[name].attrs.get("units")
    return f"{name} [{units}]" if units else name


def plot_histories(ds, path, points=None):
    """Time histories at ``points`` (grid index dicts; default :func:`representative_points`)."""
    points = representative_points(ds) if points is None else points
    fig = _new_figure(8.0, 11.0)
    axes = fig.subplots(len(HISTORY_PANELS), 1, sharex=True)
    t = ds["t"].values
    for index in points:
        label = point_label(ds, index)
        for ax, name in zip(axes, HISTORY_PANELS):
            y = np.asarray(ds[name].isel(index).values, dtype=float)
            if name in LOG_PANELS:
                y = np.where(y > 0, y, np.nan)
            ax.plot(t, y, label=label, lw=1.2)
    for ax, name in zip(axes, HISTORY_PANELS):
        ax.set_ylabel(_label(ds, name))
        if name in LOG_PANELS:
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nstochastic linearization: representative points", fontsize=9)
    fig.savefig(path)
    return Path(path)


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
    fig.savefig(path)
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
            ax.plot(x, np.where(y > 0, y, np.nan) if name in LOG_PANELS else y, "o" if categorical else "o-",
                    ms=4 if categorical else 3)
            ax.set_ylabel(_label(ds, name))
            if name in LOG_PANELS:
                ax.set_yscale("log")
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
    """Linearization vs Monte Carlo at the spot points; ``None`` if the result has none."""
    if "spot" not in ds.dims or ds.sizes["spot"] == 0:
        return None
    n = min(ds.sizes["spot"], 8)
    fig = _new_figure(10.0, 2.6 * n + 0.8)
    axes = np.atleast_2d(fig.subplots(n, 2, sharex=True, squeeze=False))
    t = ds["t"].values
    for i in range(n):
        index = spot_index(ds, i)
        for ax, name in zip(axes[i], ("var_theta", "var_theta_dot")):
            lin = np.asarray(ds[name].isel(index).values, dtype=float)
            mcs = np.asarray(ds[f"mcs_{name}"].values[i], dtype=float)
            se = np.asarray(ds[f"mcs_{name}_se"].values[i], dtype=float)
            ax.fill_between(t, mcs - 2 * se, mcs + 2 * se, color="C1", alpha=0.25, lw=0)
            ax.plot(t, mcs, color="C1", lw=1.0, label=f"Monte Carlo ({ds.attrs.get('mcs_model', '')}, "
                                                      f"{ds.attrs.get('mcs_samples', '')} samples) +-2 se")
            ax.plot(t, lin, color="C0", lw=1.4, label="stochastic linearization")
            rel = float(ds[f"mcs_rel_error_peak_{name}"].values[i])
            ax.set_title(f"{point_label(ds, index)}: peak rel. error {100 * rel:+.1f} %", fontsize=8)
            ax.set_ylabel(_label(ds, name))
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nspot checks against Monte Carlo", fontsize=9)
    fig.savefig(path)
    return Path(path)


def plot_result(ds, stem, out_dir):
    """Write all figures of dataset ``ds`` as ``out_dir/<stem>_<kind>.png``; returns the paths."""
    out_dir = Path(out_dir)
    paths = [plot_histories(ds, out_dir / f"{stem}_histories.png"),
             plot_peaks(ds, out_dir / f"{stem}_peaks.png"),
             plot_spots(ds, out_dir / f"{stem}_spots.png")]
    return [p for p in paths if p is not None]
