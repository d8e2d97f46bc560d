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
* :func:`plot_result` — all but the fragility figure for a result file, next to it or in ``out_dir``
  (the rotation drawn as ``response``).

Every figure marks what is flagged or untrusted: points whose ``status`` is not ``ok`` are masked
(never drawn as ordinary values) and marked (grey hatched cells, grey crosses), points whose
linearization is ``untrusted`` (``sl_trust``, :class:`~screening.status.Trust`) are hatched or drawn
hollow, with a legend and the counts in the title (:func:`flag_summary`).  The response is drawn as
``var_theta`` [rad2], as ``sigma_theta`` [rad] or as a fraction of the slenderness angle
(``response = "var" | "sigma" | "fraction"``, :func:`response_values`).

Only the slices that are drawn are read from the file.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import blended_transform_factory

from screening.status import PointStatus, Trust

HISTORY_PANELS = ("var_theta", "var_theta_dot", "c_eq", "k_eq", "p_uplift")
PEAK_PANELS = ("peak_var_theta", "peak_p_uplift", "min_k_eq", "status")
LOG_PANELS = ("var_theta", "var_theta_dot", "peak_var_theta")
DPI = 110

#: How the rotation response is drawn: its variance, its standard deviation, or that as a fraction
#: of the slenderness angle atan(b/h).
RESPONSES = ("var", "sigma", "fraction")
#: Marks of flagged (status != ok) and untrusted (sl_trust == untrusted) points.
FLAGGED_HATCH, UNTRUSTED_HATCH = "xx", "////"
FLAGGED_COLOR, UNTRUSTED_COLOR = "0.55", "C3"


# ----------------------------------------------------------------------------- flags and response
def point_flags(ds, index=None, order=None):
    """``(flagged, untrusted)`` boolean arrays over the grid (or its slice ``index``, dims in ``order``):
    status not ``ok``; status ``ok`` but the linearization ``untrusted`` (all False without ``sl_trust``)."""
    def values(name):
        da = ds[name].isel(index) if index else ds[name]
        return np.asarray((da.transpose(*order) if order else da).values)

    flagged = values("status") != PointStatus.ok
    if "sl_trust" not in ds.variables:
        return flagged, np.zeros_like(flagged)
    return flagged, (values("sl_trust") == Trust.untrusted) & ~flagged


def flag_summary(ds):
    """``"status: ok 95, k_eq_negative 5; linearization vs coupled model: trusted 3, check 29, untrusted
    63"``: the counts over the whole grid (trust: "not stored" for files without ``sl_trust``)."""
    codes, counts = np.unique(np.asarray(ds["status"].values), return_counts=True)
    names = {int(m): m.name for m in PointStatus}
    status = ", ".join(f"{names.get(int(c), int(c))} {n}" for c, n in zip(codes, counts))
    if "sl_trust" in ds.variables:
        trust = np.asarray(ds["sl_trust"].values)
        text = ", ".join(f"{m.name} {int(np.sum(trust == m))}" for m in Trust)
    else:
        text = "not stored"
    return f"status: {status}; linearization vs coupled model: {text}"


def point_flag_text(ds, index):
    """`` [flagged: <status>]``, `` [linearization <trust>]`` or ``""`` for one grid point."""
    code = int(np.asarray(ds["status"].isel(index).values))
    if code != PointStatus.ok:
        return f" [flagged: {PointStatus(code).name if code in set(map(int, PointStatus)) else code}]"
    if "sl_trust" in ds.variables:
        trust = int(np.asarray(ds["sl_trust"].isel(index).values))
        return f" [linearization {Trust(trust).name if trust in set(map(int, Trust)) else trust}]"
    return ""


def response_values(ds, da, kind, index=None):
    """``(DataArray, label)``: ``da`` (a ``var_theta`` [rad2], already sliced at ``index``) drawn as the
    variance, as ``sigma_theta`` [rad] or as ``sigma_theta / atan(b/h)`` [1] (``kind`` in
    :data:`RESPONSES`; the slenderness sliced at ``index`` too and broadcast by dimension name)."""
    if kind == "var":
        return da, "var_theta [rad2]"
    sigma = np.sqrt(da.where(da >= 0))
    if kind == "sigma":
        return sigma, "sigma_theta [rad]"
    if kind != "fraction":
        raise ValueError(f"response must be one of {RESPONSES} (got {kind!r})")
    if "slenderness" not in ds.variables:
        raise ValueError("response 'fraction' needs the slenderness angle, which this result does not store")
    slender = ds["slenderness"]
    slender = slender.isel({d: i for d, i in (index or {}).items() if d in slender.dims})
    return sigma / slender, "sigma_theta / atan(b/h) [1]"


def _flag_legend(fig, ds, flagged, untrusted, curves=False):
    """The figure legend of the marks, with their counts."""
    if curves:
        handles = [Line2D([], [], ls="", marker="x", color=FLAGGED_COLOR, label=f"flagged (status != ok, not a value): "
                                                                                 f"{int(np.sum(flagged))}"),
                   Line2D([], [], ls="", marker="o", mfc="none", mec=UNTRUSTED_COLOR,
                          label=f"linearization untrusted: {int(np.sum(untrusted))}")]
    else:
        handles = [Patch(facecolor="0.9", edgecolor=FLAGGED_COLOR, hatch=FLAGGED_HATCH,
                         label=f"flagged (status != ok, not a value): {int(np.sum(flagged))}"),
                   Patch(facecolor="none", edgecolor=UNTRUSTED_COLOR, hatch=UNTRUSTED_HATCH,
                         label=f"linearization untrusted: {int(np.sum(untrusted))}")]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=8, frameon=False)


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


def plot_histories(ds, path, points=None, response="var"):
    """Time histories at ``points`` (grid index dicts; default :func:`representative_points`); the
    rotation panel as ``response`` (:data:`RESPONSES`).  A flagged point is drawn grey and dotted up
    to where it stopped, an untrusted one dashed; both say so in the legend."""
    points = representative_points(ds) if points is None else points
    fig = _new_figure(8.0, 11.0)
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
        ax.set_ylabel(labels.get(name, _label(ds, name)))
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


def plot_peaks(ds, path, response="var"):
    """Peak statistics over the grid (the rotation as ``response``, :data:`RESPONSES`); ``None``
    (nothing written) for a single-point result.  Flagged points are masked and hatched grey,
    untrusted ones hatched red (maps) or drawn hollow (curves); the status colours are named."""
    dims = grid_dims(ds)
    if not dims:
        return None
    fig = _new_figure(11.0, 8.6)
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
    _flag_legend(fig, ds, flagged, untrusted, curves=len(dims) == 1)
    fig.suptitle(f"{ds.attrs.get('title', '')}\npeak statistics over the grid{note}\n{flag_summary(ds)}",
                 fontsize=8)
    save_figure(fig, path)
    return Path(path)


def _peak_values(ds, name, response, index=None, order=None):
    """``(values, label)`` of a peak panel at ``index`` with dims in ``order`` (the rotation in
    ``response``)."""
    da = ds[name].isel(index) if index else ds[name]
    label = _label(ds, name)
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
            if _is_log(x):
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
            ax.set_title(f"{point_label(ds, index)}{point_flag_text(ds, index)}: peak rel. error {100 * rel:+.1f} %",
                         fontsize=8)
            ax.set_ylabel(_label(ds, name if name in ds.variables else f"mcs_{name}"))
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    fig.suptitle(f"{ds.attrs.get('title', '')}\nspot checks against Monte Carlo\n{flag_summary(ds)}", fontsize=8)
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
    fig.suptitle(f"{point_label(ds, index)}{point_flag_text(ds, index)}  ({over} of {ds.attrs.get('mcs_samples', '?')} "
                 "Monte Carlo samples overturned, excluded from the ensemble)", fontsize=9)
    save_figure(fig, path)
    return Path(path)


def plot_fragility(frag, dim, path, max_curves=8, flags=None):
    """Fragility curves: ``p_exceed`` of a :func:`screening.analysis.fragility.fragility_dataset` along
    the swept intensity ``dim`` (lognormal fit dashed), with the Monte Carlo probabilities at
    the spot points (+-2 standard errors) in the colour of the curve they lie on (black when that
    curve is not drawn).  Up to ``max_curves`` curves, the other grid dimensions sampled evenly.
    ``flags``: the result's ``status`` (and ``sl_trust``) on the same grid: flagged points are
    crossed grey, untrusted ones drawn hollow, counted in the legend.  ``None`` if ``dim`` is not a
    dimension of ``p_exceed``."""
    from scipy.special import ndtr

    p = frag["p_exceed"]
    if dim not in p.dims:
        return None
    other = [d for d in p.dims if d != dim]
    flat = p.transpose(*other, dim).values.reshape(-1, p.sizes[dim])
    if flags is not None:
        flagged, untrusted = (a.reshape(flat.shape) for a in point_flags(flags, None, (*other, dim)))
    else:
        flagged = untrusted = np.zeros(flat.shape, dtype=bool)
    picks = np.unique(np.linspace(0, flat.shape[0] - 1, min(max_curves, flat.shape[0])).round().astype(int))
    x = grid_values(frag, dim)
    fig = _new_figure(7.0, 5.4)
    ax = fig.subplots()
    shape = [p.sizes[d] for d in other]
    median = frag["median"].transpose(*other).values.reshape(-1) if "median" in frag else None
    beta = frag["beta"].transpose(*other).values.reshape(-1) if "beta" in frag else None
    xs = np.geomspace(x.min(), x.max(), 200) if np.all(x > 0) else np.linspace(x.min(), x.max(), 200)
    colour = {}
    for n, j in enumerate(picks):
        colour[int(j)] = f"C{n}"
        index = dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}
        label = point_label(frag, index) if other else "P(|theta| > threshold)"
        ax.plot(x, flat[j], "o-", color=f"C{n}", ms=3, lw=1.2, label=label)
        ax.plot(x[untrusted[j]], flat[j][untrusted[j]], "o", ms=7, mfc="none", mec=UNTRUSTED_COLOR, mew=1.2)
        ax.plot(x[flagged[j]], flat[j][flagged[j]], "x", ms=7, color=FLAGGED_COLOR, mew=1.5)
        if median is not None and np.isfinite(median[j]) and np.isfinite(beta[j]):
            ax.plot(xs, ndtr(np.log(xs / median[j]) / beta[j]), "--", color=f"C{n}", lw=0.9,
                    label=f"lognormal fit: median {median[j]:.3g}, beta {beta[j]:.2f}")
    if "mcs_p_exceed" in frag and f"spot_{dim}" in frag:
        pm, se = frag["mcs_p_exceed"].values, frag["mcs_p_exceed_se"].values
        curve = _spot_curves(frag, other, shape)
        for c in sorted(set(curve.tolist())):
            on = curve == c
            drawn = c in colour
            ax.errorbar(frag[f"spot_{dim}"].values[on], pm[on], yerr=2 * se[on], fmt="s", ms=6, capsize=3,
                        color=colour.get(c, "k"), mfc="white" if drawn else "k", mew=1.5,
                        label="Monte Carlo (+-2 se)" + (f": {point_label(frag, _curve_index(other, shape, c))}"
                                                        if other else "")
                              + ("" if drawn else " (curve not drawn)"))
    if flags is not None:
        ax.plot([], [], "x", color=FLAGGED_COLOR, label=f"flagged (status != ok): {int(flagged.sum())} of {flagged.size}")
        ax.plot([], [], "o", mfc="none", mec=UNTRUSTED_COLOR, label=f"linearization untrusted: {int(untrusted.sum())}")
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
    summary = f"\n{flag_summary(flags)}" if flags is not None else ""
    fig.suptitle(f"Fragility: P(max |theta| > {what}) over the record ({frag.attrs.get('method', '')}){summary}",
                 fontsize=8)
    save_figure(fig, path)
    return Path(path)


def _curve_index(other, shape, j):
    return dict(zip(other, (int(i) for i in np.unravel_index(j, shape)))) if other else {}


def _spot_curves(frag, other, shape):
    """Flat index (over the dims ``other``) of the fragility curve each spot point lies on."""
    n = frag.sizes["spot"]
    if not other:
        return np.zeros(n, dtype=int)
    position = []
    for d in other:
        if d == "case":
            position.append(np.asarray(frag["spot_case"].values, dtype=int))
        else:
            grid = grid_values(frag, d)
            position.append(np.abs(grid[None, :] - np.asarray(frag[f"spot_{d}"].values)[:, None]).argmin(axis=1))
    return np.ravel_multi_index(position, shape)


#: Grid histories the spot-point panels draw.
SPOT_PANEL_HISTORIES = ("c_eq", "k_eq", "var_theta", "var_theta_dot", "p_uplift")


def plot_result(ds, stem, out_dir, response="var"):
    """Write all figures of dataset ``ds`` as ``out_dir/<stem>_<kind>.png``; returns the paths.

    All or nothing: if one figure fails (unreadable data, failing write), the figures this
    call created are removed before the error propagates.  Figures of histories the result does
    not store (``[output]`` of the study) are not drawn.
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
