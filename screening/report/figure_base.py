"""What every figure of a result shares: flag masks and their legend, grid labels, the response
drawn, figure creation and the atomic PNG write.

Every figure marks what is flagged or untrusted: points whose ``status`` is not ``ok`` are masked
(never drawn as ordinary values) and marked (grey hatched cells, grey crosses), points whose
linearization is ``untrusted`` (``sl_trust``, :class:`~screening.core.status.Trust`) are hatched or drawn
hollow, with a legend and the counts in the title (:func:`flag_summary`).  The response is drawn as
``var_theta`` [rad2], as ``sigma_theta`` [rad] or as a fraction of the slenderness angle
(``response = "var" | "sigma" | "fraction"``, :func:`response_values`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from screening.core.atomicfile import atomic_open
from screening.core.status import PointStatus, Trust

__all__ = []

DPI = 110

#: How the rotation response is drawn: its variance, its standard deviation, or that as a fraction
#: of the slenderness angle atan(b/h).
RESPONSES = ("var", "sigma", "fraction")
#: Marks of flagged (status != ok) and untrusted (sl_trust == untrusted) points.
FLAGGED_HATCH, UNTRUSTED_HATCH = "xx", "////"
FLAGGED_COLOR, UNTRUSTED_COLOR = "0.55", "C3"


# ----------------------------------------------------------------------------- flags and response
def point_flags(ds, index=None, order=None):
    """The flagged and the untrusted points over the grid (or its slice ``index``).

    Returns ``(flagged, untrusted)``: ``flagged`` status not ``ok``; ``untrusted`` status ``ok`` but the
    linearization ``untrusted`` (all False without ``sl_trust``).
    """
    def values(name):
        da = ds[name].isel(index) if index else ds[name]
        return np.asarray((da.transpose(*order) if order else da).values)

    flagged = values("status") != PointStatus.ok
    if "sl_trust" not in ds.variables:
        return flagged, np.zeros_like(flagged)
    return flagged, (values("sl_trust") == Trust.untrusted) & ~flagged


def flag_summary(ds):
    """The counts of the status and trust codes over the whole grid, in one line.

    Returns: e.g. ``"status: ok 95, k_eq_negative 5; linearization vs coupled model: trusted 3, check 29,
    untrusted 63"`` (trust: "not stored" for files without ``sl_trust``).
    """
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
    """The flag of one grid point as text: `` [flagged: <status>]``, `` [linearization <trust>]`` or ``""``.

    Returns: the text, with a leading space when not empty.
    """
    code = int(np.asarray(ds["status"].isel(index).values))
    if code != PointStatus.ok:
        return f" [flagged: {PointStatus(code).name if code in set(map(int, PointStatus)) else code}]"
    if "sl_trust" in ds.variables:
        trust = int(np.asarray(ds["sl_trust"].isel(index).values))
        return f" [linearization {Trust(trust).name if trust in set(map(int, Trust)) else trust}]"
    return ""


def response_values(ds, da, kind, index=None):
    """The rotation response as drawn, with its axis label.

    Returns ``(values, label)``: ``values`` the response; NaN where the variance is negative; ``label`` its
    axis label with units.
    """
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


def flag_legend(fig, ds, flagged, untrusted, curves=False):
    """Add the figure legend of the marks of flagged and untrusted points, with their counts."""
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
    """The grid dimensions of a result (the dimensions of ``status``).

    Returns: the dimension names.
    """
    return tuple(ds["status"].dims)


def grid_values(ds, dim):
    """Coordinate values of grid dimension ``dim`` (``k`` lives in ``k_value``; cases: index).

    Returns: its values in SI units (e.g. ``S0`` [m2 s-3]).
    """
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return np.asarray(ds[name].values)


def grid_units(ds, dim):
    """The CF units of grid dimension ``dim`` (``k`` lives in ``k_value``).

    Returns: its ``units`` attribute (e.g. ``"m2 s-3"`` for ``S0``); ``""`` when it has none.
    """
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return ds[name].attrs.get("units", "")


def spot_index(ds, i):
    """The grid index of Monte Carlo spot point ``i`` (the grid point nearest its ``spot_<dim>`` values).

    Returns: ``{dim: position}``.
    """
    index = {}
    for dim in grid_dims(ds):
        if dim == "case":
            index[dim] = int(ds["spot_case"].values[i])
        else:
            index[dim] = int(np.argmin(np.abs(grid_values(ds, dim) - ds[f"spot_{dim}"].values[i])))
    return index


def is_log_spaced(values):
    """Whether a grid axis is better drawn on a log scale: more than two positive values spanning > 50 x.

    Returns: True for a log axis.
    """
    values = np.asarray(values, dtype=float)
    return values.size > 2 and np.all(values > 0) and values.max() / values.min() > 50


def point_label(ds, index):
    """A grid point as text: ``"eps=6e+07, S0=2.4e-05"`` (or the case name).

    Returns: the label (values in SI units, 3 significant digits); ``"single point"`` for an empty index.
    """
    parts = []
    for dim, i in index.items():
        if dim == "case" and "case_name" in ds:
            parts.append(str(ds["case_name"].values[i]))
        else:
            parts.append(f"{dim}={float(grid_values(ds, dim)[i]):.3g}")
    return ", ".join(parts) if parts else "single point"




def new_figure(width, height):
    """A matplotlib figure with constrained layout and an Agg canvas (no pyplot, no display).

    Returns: the figure, at :data:`DPI` dots per inch.
    """
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path):
    """Write ``fig`` as PNG to ``path`` atomically (``<path>.tmp`` then rename).

    A failing write (disk full, permission) leaves no partial file behind and raises the ``OSError``.

    Returns: ``path``.
    """
    with atomic_open(path, "wb") as fh:                 # never through a planted link
        fig.savefig(fh, format="png")
    return Path(path)


def axis_label(ds, name):
    """The axis label of a variable: ``"name [units]"``, or its name when it has no units.

    Returns: the label.
    """
    units = ds[name].attrs.get("units")
    return f"{name} [{units}]" if units else name
