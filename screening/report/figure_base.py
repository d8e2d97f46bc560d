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

__all__ = ["DPI", "RESPONSES", "FLAGGED_HATCH", "UNTRUSTED_HATCH", "FLAGGED_COLOR", "UNTRUSTED_COLOR",
           "point_flags", "flag_summary", "point_flag_text", "response_values", "flag_legend", "grid_dims",
           "grid_values", "grid_units", "spot_index", "is_log_spaced", "point_label", "new_figure", "save_figure",
           "axis_label"]

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

    Parameters
    ----------
    ds : xarray.Dataset
        A result with ``status`` (and optionally ``sl_trust``) on the grid.
    index : dict of str to int, optional
        A slice of the grid (``ds.isel(index)``).
    order : sequence of str, optional
        The order of the dimensions of the arrays returned.

    Returns
    -------
    flagged : numpy.ndarray of bool
        Status not ``ok``.
    untrusted : numpy.ndarray of bool
        Status ``ok`` but the linearization ``untrusted`` (all False without ``sl_trust``).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> [a.tolist() for a in point_flags(ds)]
    [[False, True, False], [False, False, True]]
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

    Parameters
    ----------
    ds : xarray.Dataset
        A result with ``status`` (and optionally ``sl_trust``).

    Returns
    -------
    str
        E.g. ``"status: ok 95, k_eq_negative 5; linearization vs coupled model: trusted 3, check 29,
        untrusted 63"`` (trust: "not stored" for files without ``sl_trust``).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> flag_summary(ds)
    'status: ok 2, k_eq_negative 1; linearization vs coupled model: trusted 2, check 0, untrusted 1'
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

    Parameters
    ----------
    ds : xarray.Dataset
        A result with ``status`` (and optionally ``sl_trust``).
    index : dict of str to int
        The grid point.

    Returns
    -------
    str
        The text, with a leading space when not empty.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> point_flag_text(ds, {"S0": 1}), point_flag_text(ds, {"S0": 2})
    (' [flagged: k_eq_negative]', ' [linearization untrusted]')
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

    Parameters
    ----------
    ds : xarray.Dataset
        The result (its ``slenderness`` [rad] for ``kind="fraction"``).
    da : xarray.DataArray
        A ``var_theta`` [rad2], already sliced at ``index``.
    kind : {"var", "sigma", "fraction"}
        The variance [rad2], ``sigma_theta`` [rad] or ``sigma_theta / atan(b/h)`` [1]
        (:data:`RESPONSES`); ``ValueError`` otherwise.
    index : dict of str to int, optional
        The slice of the grid ``da`` was taken at (the slenderness is sliced alike).

    Returns
    -------
    values : xarray.DataArray
        The response; NaN where the variance is negative.
    label : str
        Its axis label with units.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> ds = xr.Dataset({"slenderness": 0.2})
    >>> values, label = response_values(ds, xr.DataArray([1e-4, 4e-4], dims="S0"), "fraction")
    >>> [round(float(v), 6) for v in values], label
    ([0.05, 0.1], 'sigma_theta / atan(b/h) [1]')
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
    """Add the figure legend of the marks of flagged and untrusted points, with their counts.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (constrained layout: the legend goes below the axes).
    ds : xarray.Dataset
        The result drawn (unused by the legend itself; kept for a uniform call).
    flagged, untrusted : array_like of bool
        The marks (:func:`point_flags`); their counts [-] are shown.
    curves : bool
        Markers (line plots) rather than hatched patches (maps).

    Returns
    -------
    None

    References
    ----------
    .. [1] [hunter2007] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> fig = new_figure(4.0, 3.0)
    >>> flag_legend(fig, None, [True, False], [False, False])
    >>> [t.get_text() for t in fig.legends[0].get_texts()]
    ['flagged (status != ok, not a value): 1', 'linearization untrusted: 0']
    """
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

    Parameters
    ----------
    ds : xarray.Dataset
        A result with ``status``.

    Returns
    -------
    tuple of str
        The dimension names.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> grid_dims(ds)
    ('S0',)
    """
    return tuple(ds["status"].dims)


def grid_values(ds, dim):
    """Coordinate values of grid dimension ``dim`` (``k`` lives in ``k_value``; cases: index).

    Parameters
    ----------
    ds : xarray.Dataset
        A result.
    dim : str
        A grid dimension.

    Returns
    -------
    numpy.ndarray
        Its values in SI units (e.g. ``S0`` [m2 s-3]).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> grid_values(ds, "S0").tolist()
    [0.0001, 0.0002, 0.0004]
    """
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return np.asarray(ds[name].values)


def grid_units(ds, dim):
    """The CF units of grid dimension ``dim`` (``k`` lives in ``k_value``).

    Parameters
    ----------
    ds : xarray.Dataset
        A result.
    dim : str
        A grid dimension.

    Returns
    -------
    str
        Its ``units`` attribute (e.g. ``"m2 s-3"`` for ``S0``); ``""`` when it has none.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> grid_units(ds, "S0")
    'm2 s-3'
    """
    name = f"{dim}_value" if f"{dim}_value" in ds.variables else dim
    return ds[name].attrs.get("units", "")


def spot_index(ds, i):
    """The grid index of Monte Carlo spot point ``i`` (the grid point nearest its ``spot_<dim>`` values).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with spot checks.
    i : int
        The spot point.

    Returns
    -------
    dict of str to int
        ``{dim: position}``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> spot_index(ds.assign_coords(spot_S0=("spot", [2e-4])), 0)
    {'S0': 1}
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

    Parameters
    ----------
    values : array_like
        The axis values (any units).

    Returns
    -------
    bool
        True for a log axis.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> bool(is_log_spaced([1e-5, 1e-4, 1e-3])), bool(is_log_spaced([1.0, 2.0, 3.0]))
    (True, False)
    """
    values = np.asarray(values, dtype=float)
    return values.size > 2 and np.all(values > 0) and values.max() / values.min() > 50


def point_label(ds, index):
    """A grid point as text: ``"eps=6e+07, S0=2.4e-05"`` (or the case name).

    Parameters
    ----------
    ds : xarray.Dataset
        A result.
    index : dict of str to int
        The grid point.

    Returns
    -------
    str
        The label (values in SI units, 3 significant digits); ``"single point"`` for an empty index.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> point_label(ds, {"S0": 2}), point_label(ds, {})
    ('S0=0.0004', 'single point')
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

    Parameters
    ----------
    width, height : float
        Size [inch].

    Returns
    -------
    matplotlib.figure.Figure
        The figure, at :data:`DPI` dots per inch.

    References
    ----------
    .. [1] [hunter2007] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> fig = new_figure(4.0, 3.0)
    >>> [float(x) for x in fig.get_size_inches()], float(fig.dpi)
    ([4.0, 3.0], 110.0)
    """
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path):
    """Write ``fig`` as PNG to ``path`` atomically (``<path>.tmp`` then rename).

    A failing write (disk full, permission) leaves no partial file behind and raises the ``OSError``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The PNG file.

    Returns
    -------
    pathlib.Path
        ``path``.

    References
    ----------
    .. [1] [hunter2007] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     out = save_figure(new_figure(2.0, 2.0), pathlib.Path(tmp) / "f.png")
    ...     out.read_bytes()[:4], sorted(p.name for p in pathlib.Path(tmp).iterdir())
    (b'\\x89PNG', ['f.png'])
    """
    with atomic_open(path, "wb") as fh:                 # never through a planted link
        fig.savefig(fh, format="png")
    return Path(path)


def axis_label(ds, name):
    """The axis label of a variable: ``"name [units]"``, or its name when it has no units.

    Parameters
    ----------
    ds : xarray.Dataset
        A result.
    name : str
        A variable or coordinate.

    Returns
    -------
    str
        The label.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import xarray as xr
    >>> from screening.core.status import PointStatus, Trust
    >>> ds = xr.Dataset({"status": ("S0", [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok]),
    ...                  "sl_trust": ("S0", [Trust.trusted, Trust.trusted, Trust.untrusted])},
    ...                 coords={"S0": ("S0", [1e-4, 2e-4, 4e-4], {"units": "m2 s-3"})})
    >>> axis_label(ds, "S0"), axis_label(ds, "status")
    ('S0 [m2 s-3]', 'status')
    """
    units = ds[name].attrs.get("units")
    return f"{name} [{units}]" if units else name
