"""PNG figures of a sweep result (matplotlib, object API with the Agg canvas: no pyplot state).

:func:`plot_histories` (moments against time at representative points), :func:`plot_peaks` (peaks and
status over the grid) and :func:`plot_result` (these and the spot-check figures of a result file).
Flagged and untrusted points are marked (:mod:`screening.report.figure_base`); only the slices drawn are read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.transforms import blended_transform_factory

from screening.report.figure_base import (
    FLAGGED_COLOR, FLAGGED_HATCH, RESPONSES, UNTRUSTED_COLOR, UNTRUSTED_HATCH, axis_label, flag_legend,
    flag_summary, grid_dims, grid_units, grid_values, is_log_spaced, new_figure, point_flags,
    point_label, response_values, save_figure)
from screening.report.spot_figures import (
    MAX_SPOT_FIGURES, SPOT_PANEL_HISTORIES, plot_spot_panels, plot_spots, spot_file_label)
from screening.core.status import PointStatus

__all__ = []

HISTORY_PANELS = ("var_theta", "var_theta_dot", "c_eq", "k_eq", "p_uplift")
PEAK_PANELS = ("peak_var_theta", "peak_p_uplift", "min_k_eq", "status")
LOG_PANELS = ("var_theta", "var_theta_dot", "peak_var_theta")

def representative_points(ds, n=4):
    """Up to ``n`` grid points worth drawing as time histories.

    The status-ok points with the smallest, median and largest ``peak_var_theta`` [rad2] and the
    largest ``peak_p_uplift`` [1] (any points if none is ok), without repeats.

    Returns: grid index dicts ``{dim: position}``.
    """
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


def plot_histories(ds, path, points=None, response="var"):
    """Time histories of the linearization at a few grid points, as a PNG.

    Panels ``var_theta`` (drawn as ``response``), ``var_theta_dot`` [rad2 s-2], ``c_eq``
    [N m s rad-1], ``k_eq`` [N m rad-1] and ``p_uplift`` [1] against ``t`` [s].  A flagged point is
    drawn grey and dotted up to where it stopped, an untrusted one dashed; both say so in the legend.

    Returns: ``path``.

    Notes
    -----
    The moments are those of the Lyapunov equation of the linearized system, eq. (45) in [1].
    """
    points = representative_points(ds) if points is None else points
    fig = new_figure(8.0, 11.0)
    axes = fig.subplots(len(HISTORY_PANELS), 1, sharex=True)
    t = ds["t"].values
    drawn = {name: [] for name in HISTORY_PANELS}
    labels = {}
    names = {int(m): m.name for m in PointStatus}
    for index in points:
        flagged, untrusted = (np.ravel(a)[0] for a in point_flags(ds, index))
        label = point_label(ds, index)
        style = {"lw": 1.2}
        if flagged:
            code = int(np.asarray(ds["status"].isel(index).values))
            label += f" [flagged: {names.get(code, code)}]"
            style.update(ls=":", color=FLAGGED_COLOR)
        elif untrusted:
            label += " [linearization untrusted]"
            style.update(ls="--")
        for ax, name in zip(axes, HISTORY_PANELS):
            y = ds[name].isel(index)
            if name == "var_theta":
                y, labels[name] = response_values(ds, y, response, index)
            y = np.asarray(y.values, dtype=float)
            if name in LOG_PANELS:
                y = np.where(y > 0, y, np.nan)
            drawn[name].append(y)
            ax.plot(t, y, label=label, **style)
    for ax, name in zip(axes, HISTORY_PANELS):
        ax.set_ylabel(labels.get(name, axis_label(ds, name)))
        _scale(ax, drawn[name], log=name in LOG_PANELS)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nstochastic linearization: representative points\n"
                 f"{flag_summary(ds)}", fontsize=8)
    save_figure(fig, path)
    return Path(path)


def _scale(ax, drawn, log):
    """Log y axis when asked and something finite and positive was drawn; otherwise a linear axis
    with a note (a result whose points are all flagged, or all NaN, still gets its figures)."""
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


def plot_peaks(ds, path, response="var"):
    """Peak statistics over the grid as a PNG: curves along one swept dimension, maps over two.

    The rotation is drawn as ``response``; flagged points are masked and hatched grey, untrusted ones
    hatched red (maps) or drawn hollow (curves); the status colours are named.

    Returns: ``path``; ``None`` (nothing written) for a single-point result.
    """
    dims = grid_dims(ds)
    if not dims:
        return None
    fig = new_figure(11.0, 8.6)
    axes = fig.subplots(2, 2).ravel()
    if len(dims) == 1:
        _curves(ds, dims[0], axes, response)
        flagged, untrusted = point_flags(ds)
        note = ""
    else:
        ydim, xdim = dims[0], dims[1]
        rest = {d: ds.sizes[d] // 2 for d in dims[2:]}
        note = ("; " + ", ".join(f"{d}={float(grid_values(ds, d)[i]):.3g}" for d, i in rest.items())
                if rest else "")
        flagged, untrusted = point_flags(ds, rest, (ydim, xdim))
        for ax, name in zip(axes, PEAK_PANELS):
            _map(ds, name, ydim, xdim, rest, ax, fig, response)
    flag_legend(fig, ds, flagged, untrusted, curves=len(dims) == 1)
    fig.suptitle(f"{ds.attrs.get('title', '')}\npeak statistics over the grid{note}\n{flag_summary(ds)}",
                 fontsize=8)
    save_figure(fig, path)
    return Path(path)


def _peak_values(ds, name, response, index=None, order=None):
    """``(values, label)`` of a peak panel at ``index`` with dims in ``order`` (the rotation in
    ``response``)."""
    da = ds[name].isel(index) if index else ds[name]
    label = axis_label(ds, name)
    if name == "peak_var_theta":
        da, what = response_values(ds, da, response, index)
        label = f"peak {what}"
    return np.asarray((da.transpose(*order) if order else da).values, dtype=float), label


def _status_colours(ds):
    """A discrete colour map and norm with one colour per status code, and the codes' names."""
    codes = np.asarray(ds["status"].attrs["flag_values"], dtype=float)
    names = str(ds["status"].attrs["flag_meanings"]).split()
    palette = {PointStatus.ok: "C2", PointStatus.task_failed: "0.2"}
    others = iter(["C1", "C3", "C4", "C5", "C6", "C7", "C8", "C9"])
    colours = [palette.get(int(c), None) or next(others, "0.5") for c in codes]
    bounds = np.concatenate([codes - 0.5, [codes[-1] + 0.5]])
    return ListedColormap(colours), BoundaryNorm(bounds, len(colours)), codes, names


def _curves(ds, dim, axes, response="var"):
    n = ds.sizes[dim]
    categorical = dim == "case"
    x = np.arange(n) if categorical else grid_values(ds, dim)
    flagged, untrusted = point_flags(ds)
    bottom = None
    for ax, name in zip(axes, PEAK_PANELS):
        if name == "status":
            cmap, norm, codes, names = _status_colours(ds)
            y = np.asarray(ds["status"].values, dtype=float)
            ax.scatter(x, y, c=y, cmap=cmap, norm=norm, s=16)
            ax.set_yticks(codes)
            ax.set_yticklabels(names, fontsize=7)
            ax.set_ylim(codes[0] - 0.5, codes[-1] + 0.5)
        else:
            y, label = _peak_values(ds, name, response)
            y = np.where(flagged, np.nan, y)
            y = np.where(y > 0, y, np.nan) if name in LOG_PANELS else y
            ax.plot(x, y, "o" if categorical else "o-", ms=4 if categorical else 3)
            ax.plot(x[untrusted], y[untrusted], "o", ms=7, mfc="none", mec=UNTRUSTED_COLOR, mew=1.2)
            bottom = blended_transform_factory(ax.transData, ax.transAxes)
            ax.plot(x[flagged], np.full(int(flagged.sum()), 0.03), "x", color=FLAGGED_COLOR, transform=bottom)
            ax.set_ylabel(label)
            _scale(ax, [y], log=name in LOG_PANELS)
        if categorical:
            ax.set_xticks(x)
            ax.set_xticklabels(_ticks(ds, dim, n), rotation=45, ha="right", fontsize=7)
        else:
            ax.set_xlabel(f"{dim} [{grid_units(ds, dim)}]")
            if is_log_spaced(x):
                ax.set_xscale("log")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)


def _cells(ax, mask, **style):
    """Hatch the cells of a map where ``mask`` (rows y, columns x) is true."""
    if not mask.any():
        return
    # one hatched region per connected patch (a contour of the mask at 1/2, which runs along the cell
    # edges), not one hatched cell per point: a 316 x 316 map drew in 76 s per cell, under a second so
    ny, nx = mask.shape
    padded = np.pad(mask.astype(float), 1, mode="edge")
    x = np.concatenate(([-0.5], np.arange(nx), [nx - 0.5]))
    y = np.concatenate(([-0.5], np.arange(ny), [ny - 0.5]))
    hatch, edgecolor = style.pop("hatch"), style.pop("edgecolor")
    face = style.pop("cmap").colors[0]
    patch = ax.contourf(x, y, padded, levels=[0.5, 1.5], colors=[face], hatches=[hatch])
    for collection in getattr(patch, "collections", [patch]):
        collection.set_edgecolor(edgecolor)
        collection.set_linewidth(0)


def _map(ds, name, ydim, xdim, rest, ax, fig, response="var"):
    flagged, untrusted = point_flags(ds, rest, (ydim, xdim))
    if name == "status":
        z = np.asarray((ds[name].isel(rest) if rest else ds[name]).transpose(ydim, xdim).values, dtype=float)
        cmap, norm, codes, names = _status_colours(ds)
        title = "status"
    else:
        z, title = _peak_values(ds, name, response, rest, (ydim, xdim))
        z = np.where(flagged, np.nan, z)
        if name in LOG_PANELS:
            z = np.log10(np.where(z > 0, z, np.nan))
            title = f"log10 {title}"
        cmap, norm = "viridis", None
    ny, nx = z.shape
    mesh = ax.pcolormesh(np.arange(nx + 1) - 0.5, np.arange(ny + 1) - 0.5, np.ma.masked_invalid(z),
                         cmap=cmap, norm=norm, shading="flat")
    bar = fig.colorbar(mesh, ax=ax)
    if name == "status":
        bar.set_ticks(codes)
        bar.set_ticklabels(names, fontsize=7)
    else:
        _cells(ax, flagged, cmap=ListedColormap(["0.9"]), hatch=FLAGGED_HATCH, edgecolor=FLAGGED_COLOR)
        _cells(ax, untrusted, cmap=ListedColormap(["none"]), hatch=UNTRUSTED_HATCH, edgecolor=UNTRUSTED_COLOR)
    for axis, dim, n in (("x", xdim, nx), ("y", ydim, ny)):
        step = max(1, n // 8)
        ticks = np.arange(0, n, step)
        labels = _ticks(ds, dim, n)
        getattr(ax, f"set_{axis}ticks")(ticks)
        getattr(ax, f"set_{axis}ticklabels")([labels[i] for i in ticks], fontsize=7,
                                              rotation=45 if axis == "x" else 0)
        getattr(ax, f"set_{axis}label")(f"{dim} [{grid_units(ds, dim)}]" if dim != "case" else "case")
    ax.set_title(title, fontsize=9)


def plot_result(ds, stem, out_dir, response="var"):
    """Write all figures of a result as ``out_dir/<stem>_<kind>.png``.

    All or nothing: if one figure fails (unreadable data, failing write), the figures this call
    created are removed before the error propagates.  Figures of histories the result does not store
    (``[output]`` of the study) are not drawn.

    Returns: the files written.
    """
    out_dir = Path(out_dir)
    if response not in RESPONSES:
        raise ValueError(f"response must be one of {RESPONSES} (got {response!r})")
    jobs = ([(lambda d, p: plot_histories(d, p, response=response), out_dir / f"{stem}_histories.png")]
            if set(HISTORY_PANELS) <= set(ds.variables) else [])
    jobs += [(lambda d, p: plot_peaks(d, p, response=response), out_dir / f"{stem}_peaks.png"),
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
