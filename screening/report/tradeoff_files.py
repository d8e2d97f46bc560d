"""The files of a speed-accuracy trade study: the netCDF layout and the writing of every report.

In memory the label dimensions (``approach``, ``comparison``, ...) carry string coordinates
(``ds.sel(approach="sl")``); in the file they are plain dimensions with a ``<dim>_name``
auxiliary coordinate (:func:`to_file_layout`, undone by :func:`from_file_layout`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from screening._version import __version__
from screening.core.atomicfile import atomic_open, atomic_path
from screening.applications.metrics import derive_rules
from screening.report.tradeoff_figures import plot_error_vs_cost, plot_validity
from screening.report.tradeoff_text import markdown_report, point_rows, rule_text, write_csv

__all__ = []

#: Dimensions labelled by strings in memory (``ds.sel(approach="sl")``); in the file they are
#: plain dimensions with a ``<dim>_name`` auxiliary coordinate (CF coordinate variables are numeric).
LABEL_DIMS = ("approach", "mcs_model", "comparison", "quantity", "cv_model")


def to_file_layout(ds):
    """The dataset as written: string-labelled dimensions as ``<dim>_name`` auxiliary coordinates.

    Integer index coordinates become int32.

    Returns: the file layout (CF coordinate variables are numeric).
    """
    out = ds.copy()
    for d in LABEL_DIMS:
        if d in out.coords:
            attrs = dict(out[d].attrs)
            out = out.assign_coords({f"{d}_name": (d, out[d].values.astype(str), attrs)}).drop_vars(d)
    for name in ("point", "sl_setting"):
        if name in out.coords:
            out = out.assign_coords({name: (name, out[name].values.astype(np.int32), dict(out[name].attrs))})
    out.attrs["label_coordinates"] = ("dimensions " + ", ".join(LABEL_DIMS) + " are labelled by the auxiliary "
                                      "coordinates <dim>_name (e.g. ds.swap_dims(approach='approach_name'))")
    out.attrs.setdefault("history", f"screening.report.tradeoff {__version__}: written by run_tradeoff")
    return out


def from_file_layout(ds):
    """Inverse of :func:`to_file_layout`: string labels back as dimension coordinates.

    Returns: with ``ds.sel(approach="sl")`` possible again.
    """
    out = ds.copy()
    for d in LABEL_DIMS:
        name = f"{d}_name"
        if name in out.coords:
            attrs = dict(out[name].attrs)
            out = out.drop_vars(name).assign_coords({d: (d, out[name].values.astype(str), attrs)})
    return out


def file_encoding(ds):
    """netCDF encoding: no fill value on float coordinates (CF 2.5.1), compression on the histories.

    Returns: ``{variable: encoding}`` for :meth:`xarray.Dataset.to_netcdf`.
    """
    enc = {name: {"_FillValue": None} for name in ds.coords if ds[name].dtype.kind == "f"}
    for name in ("var_theta", "var_theta_dot", "var_theta_se", "var_theta_dot_se", "p_uplift"):
        enc[name] = {"zlib": True, "complevel": 4}
    return enc


def output_paths(out_dir, stem):
    """The files a trade study writes: ``nc``, ``md``, ``csv``, ``error_vs_cost``, ``validity``.

    Returns: the paths.
    """
    out = Path(out_dir)
    return {"nc": out / f"{stem}.nc", "md": out / f"{stem}.md", "csv": out / f"{stem}.csv",
            "error_vs_cost": out / f"{stem}_error_vs_cost.png", "validity": out / f"{stem}_validity.png"}


def write_reports(study, ds, out_dir, stem, write_nc=True):
    """Derive the rules from ``ds`` and write the netCDF, markdown, CSV and plots.

    With ``write_nc=False`` only the reports are (re)written, e.g. from a saved dataset
    (:func:`screening.report.tradeoff.rerender_reports`).  Each file appears whole or not at all.

    Returns ``(paths, rules)``: ``paths`` ``{"nc", "md", "csv", "error_vs_cost", "validity"}`` ->
    :class:`pathlib.Path` (:func:`output_paths`); ``rules`` the validity rules of SL
    (:func:`screening.applications.metrics.derive_rules` with the study's ``rule`` thresholds, metric and
    quantity).
    """
    paths = output_paths(out_dir, stem)
    paths["nc"].parent.mkdir(parents=True, exist_ok=True)
    thr, metric, quantity = study.rule["thresholds"], study.rule["metric"], study.rule["quantity"]
    rules = derive_rules(ds, thr, metric, quantity)
    ds.attrs["rules"] = "\n".join(rule_text(r, metric, quantity) for r in rules)
    if write_nc:
        with atomic_path(paths["nc"]) as tmp:
            to_file_layout(ds).to_netcdf(tmp, engine="netcdf4", encoding=file_encoding(ds))
    wall = float(ds.attrs.get("wall_time_s", float("nan")))
    with atomic_open(paths["md"], "w", encoding="utf-8") as fh:
        fh.write(markdown_report(study, ds, rules) + f"\nTotal run time {wall:.0f} s.\n")
    write_csv(point_rows(ds), paths["csv"])
    plot_error_vs_cost(ds, paths["error_vs_cost"])
    plot_validity(ds, rules, thr, paths["validity"], metric, quantity)
    return paths, rules
