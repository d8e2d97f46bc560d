"""One self-contained HTML page of a collection (``screening report``): the objects ranked by risk at a site (or by
median capacity without a hazard curve), each object's fragility curves with the points that vouch for them, which
model answered each point and how far to trust it, and the inputs.  Figures are embedded as base64 PNG.
"""

from __future__ import annotations

import base64
import html
import io
import math

import numpy as np
from matplotlib.ticker import FuncFormatter
from scipy import special

from screening.analysis.fragility import unvouched_points
from screening.applications.im_fragility import case_values, curves_by_object, fragility_intensity, limit_state_name
from screening.applications.risk import risk_table
from screening.core.atomicfile import atomic_open
from screening.report.figure_base import new_figure

__all__ = []

#: Marker of each probability source (``p_source`` flag meaning); others get ``"P"``.
MARKERS = {"linearization_gaussian": "o", "corrected_linearization_gaussian": "s", "study_fragility_surface": "D",
           "monte_carlo_coupled": "^", "monte_carlo_condensed": "v", "monte_carlo_stiff_bed": ">",
           "monte_carlo_stiff_bed_fast": "<", "unreliable": "X"}
COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown")
STYLE = ("body{font-family:sans-serif;max-width:70em;margin:1em auto;color:#222}"
         "table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 6px;"
         "text-align:right}th{background:#eee}td.t{text-align:left}img{max-width:100%}pre{background:#f6f6f6;"
         "padding:0.5em;font-size:0.8em;overflow-x:auto}.warn{color:#a00}.note{font-size:0.8em}")


def _flags(da):
    """``{code: meaning}`` of a CF flag variable."""
    return dict(zip(np.atleast_1d(da.attrs.get("flag_values", [])).tolist(),
                    str(da.attrs.get("flag_meanings", "")).split()))


def _state(frag, s):
    """The curve of limit state ``s`` (a dataset without ``limit_state``)."""
    return frag.sel(limit_state=s) if "limit_state" in frag.dims else frag


def report_objects(ds, frags, rows=None):
    """The objects of a collection, ranked: by annual frequency of their first limit state with ``rows``
    (:func:`~screening.applications.risk.risk_table`), else by median capacity (lowest first).

    Returns: ``name``, ``labels`` (``{dim: value}`` of the curve), ``curves`` (``[(frag, state, curve
    row)]``), ``risk`` (``{state: row}``), ``values`` (``{name: (value, units)}``), in rank order.
    """
    objects = {}
    per_case = case_values(ds)[1] if "case" in ds.dims else {}
    for frag in frags:
        states, curves = curves_by_object(frag)
        for fid, by_state in curves.items():
            labels = by_state["labels"]
            name = fid.removeprefix("screening_").replace("case=", "") if labels else "screening"
            obj = objects.setdefault(name, {"name": name, "labels": labels, "curves": [], "risk": {},
                                            "values": per_case.get(labels.get("case"), {}).get("values", {})})
            obj["curves"] += [(frag, s, by_state[s]) for s in states]
    for row in rows or ():
        if row["object"] in objects:
            objects[row["object"]]["risk"][row["limit_state"]] = row

    def key(obj):
        frag, state, curve = obj["curves"][0]
        if rows is not None:
            rate = obj["risk"].get(state, {}).get("annual_rate", math.nan)
            return (not np.isfinite(rate), -np.nan_to_num(rate))
        return (not np.isfinite(curve["median"]) or curve["flag"] != 0, np.nan_to_num(curve["median"], nan=np.inf))

    return sorted(objects.values(), key=key)


def _png(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _object_figure(obj, ds):
    """The object's curves: points by source (filled: vouched), +-2 SE, the fit (dashed outside its vouched range)."""
    fig = new_figure(8.5, 4.6)
    ax = fig.add_subplot(1, 1, 1)
    source = ds["p_source"] if "p_source" in ds.variables else None
    meanings = _flags(source) if source is not None else {}
    seen = set()
    for j, (frag, state, curve) in enumerate(obj["curves"]):
        colour = COLOURS[j % len(COLOURS)]
        name, units, _ = fragility_intensity(frag)
        one = _state(frag, state).isel({d: _index(frag, d, v) for d, v in obj["labels"].items() if d in frag.dims})
        x = np.asarray(one[name].values, dtype=float)
        p = np.asarray(one["p_exceed"].values, dtype=float)
        se = np.asarray(one["p_exceed_se"].values, dtype=float) if "p_exceed_se" in one else np.full_like(p, np.nan)
        grid = {d: _index(ds, d, v) for d, v in obj["labels"].items() if d in ds.dims}
        bad = np.asarray(unvouched_points(ds).isel({d: i for d, i in grid.items()
                                                    if d in unvouched_points(ds).dims}).values, dtype=bool)
        bad = np.broadcast_to(bad, p.shape)
        codes = (np.asarray(source.isel(grid).values) if source is not None else np.full(p.shape, -1)).reshape(p.shape)
        for code in np.unique(codes):
            label = meanings.get(int(code), "linearization")
            for vouched in (True, False):
                sel = (codes == code) & (bad != vouched) & np.isfinite(p)
                if not sel.any():
                    continue
                ax.errorbar(x[sel], p[sel], yerr=np.where(np.isfinite(se[sel]), 2 * se[sel], 0.0), fmt="none",
                            ecolor=colour, alpha=0.5, lw=0.8)
                ax.scatter(x[sel], p[sel], marker=MARKERS.get(label, "P"), s=30, edgecolors=colour,
                           facecolors=colour if vouched else "none", zorder=3,
                           label=f"{label}{'' if vouched else ' (not vouched)'}" if (label, vouched) not in seen
                           else None)
                seen.add((label, vouched))
        if curve["flag"] == 0 and np.isfinite(curve["median"]):
            xs = np.geomspace(np.nanmin(x), np.nanmax(x), 200)
            fit = special.ndtr(np.log(xs / curve["median"]) / curve["beta"])
            inside = (xs >= curve["im_min"]) & (xs <= curve["im_max"])
            ax.plot(xs, np.where(inside, fit, np.nan), color=colour, lw=1.5,
                    label=f"{_label(frag, state)}: median {curve['median']:.3g} {units}, beta {curve['beta']:.2f}")
            ax.plot(xs, fit, color=colour, lw=1.0, ls=":")
        else:
            ax.plot([], [], color=colour, label=f"{_label(frag, state)}: no fit ({curve['flag'].name})")
        ax.set_xlabel(f"{name} [{units}]")
        if np.nanmin(x) > 0:
            ax.set_xscale("log")
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
    ax.set_ylabel("probability [1]")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    ax.set_title(f"{obj['name']}: points by the model that answered (hollow: not vouched), +-2 SE, fit dotted "
                 "outside its vouched range", fontsize=8)
    return _png(fig)


def _index(ds, dim, value):
    values = np.asarray(ds[dim].values) if dim in ds.coords else np.arange(ds.sizes[dim])
    return int(np.flatnonzero(values == value)[0])


def _num(v, fmt=".3g"):
    return "-" if v is None or not np.isfinite(v) else format(v, fmt)


def _table(head, body):
    rows = "".join("<tr>" + "".join(f"<td class=t>{html.escape(str(c))}</td>" if i == 0 else
                                    f"<td>{html.escape(str(c))}</td>" for i, c in enumerate(r)) + "</tr>" for r in body)
    return "<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + f"</tr>{rows}</table>"


def _point_table(obj, ds):
    """Each point of the object: intensity, probabilities with SE, the source, the trust and the status."""
    frag = obj["curves"][0][0]
    name, units, _ = fragility_intensity(frag)
    grid = {d: _index(ds, d, v) for d, v in obj["labels"].items() if d in ds.dims}
    one = ds.isel(grid)
    dim = frag.attrs.get("intensity_dim", "pga")
    cols = [(f"{name} [{units}]", np.asarray(frag.isel({d: _index(frag, d, v) for d, v in obj["labels"].items()
                                                        if d in frag.dims})[name].values, dtype=float))]
    for frag_, state, curve in obj["curves"]:
        c = _state(frag_, state).isel({d: _index(frag_, d, v) for d, v in obj["labels"].items() if d in frag_.dims})
        cols.append((f"P({_label(frag_, state)})", np.asarray(c["p_exceed"].values, dtype=float)))
        if "p_exceed_se" in c:
            cols.append(("SE", np.asarray(c["p_exceed_se"].values, dtype=float)))
    texts = []
    for var, title in (("p_source", "answered by"), ("sl_trust", "linearization trust"), ("status", "status")):
        if var in one.variables and dim in one[var].dims:
            m = _flags(one[var])
            texts.append((title, [m.get(int(v), str(v)) for v in one[var].values]))
    if "sl_error_low" in one.variables and dim in one["sl_error_low"].dims:
        band = zip(one["sl_error_low"].values, one["sl_error_high"].values)
        texts.append(("linearization error of peak var_theta, 90 %",
                      [f"{100 * lo:+.0f} % .. {100 * hi:+.0f} %" if np.isfinite(lo) and np.isfinite(hi) else "open"
                       if np.isfinite(lo) or np.isfinite(hi) else "-" for lo, hi in band]))
    n = cols[0][1].size
    body = [[_num(c[1][i], ".4g") for c in cols] + [t[1][i] for t in texts] for i in range(n)]
    return _table([c[0] for c in cols] + [t[0] for t in texts], body)


def _label(frag, state):
    """``overturn``, or the threshold as the study gave it (``theta_0.3_slenderness``)."""
    if state != "theta_exceeds_threshold" or "threshold" not in frag.attrs:
        return state
    relative_to = str(frag.attrs.get("relative_to", ""))
    return limit_state_name(frag.attrs["threshold"], None if relative_to in ("", "None") else relative_to)


def _ranking(objects, years, with_risk):
    head, body, notes = ["rank", "object"], [], {}
    for rank, obj in enumerate(objects, start=1):
        row = [rank, obj["name"]]
        for frag, state, curve in obj["curves"]:
            units = frag["fit_median"].attrs.get("units", "")
            fitted = curve["flag"] == 0 and np.isfinite(curve["median"])
            if not fitted:
                notes[curve["flag"].name] = curve["reason"]
            row += [f"{_num(curve['median'])} {units}" if fitted else f"no fit ({curve['flag'].name})",
                    _num(curve["beta"], ".2f") if fitted else ""]
            if rank == 1:
                head += [f"{_label(frag, state)}: median", "beta"]
            if with_risk:
                r = obj["risk"].get(state, {})
                row += [_num(r.get("annual_rate", math.nan)), _num(r.get("probability", math.nan)),
                        _num(100 * r.get("share_outside_vouched", math.nan), ".0f")]
                if rank == 1:
                    head += ["annual rate [1/yr]", f"P({years:g} yr)", "% from outside the vouched range"]
        body.append(row)
    return _table(head, body) + "".join(f"<p class=note><b>{html.escape(k)}</b>: {html.escape(v)}</p>"
                                        for k, v in notes.items())


def write_report(ds, path, source="", curve=None, years=50.0, frags=(), hazard_path="hazard"):
    """Write the collection's report as one self-contained HTML page.

    Returns: :func:`report_objects`, in rank order.
    """
    rows = [r for frag in frags for r in risk_table(frag, curve, years, hazard_path)] if curve is not None else None
    objects = report_objects(ds, list(frags), rows)
    title = ds.attrs.get("title", "") or source
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p>Result <code>{html.escape(source)}</code>, screening {html.escape(ds.attrs.get('screening_version', ''))}"
             f", {len(objects)} object(s). "
             + (f"Ranked by the annual frequency of {html.escape(objects[0]['curves'][0][1])} at the site of "
                f"<code>{html.escape(curve.source)}</code> (probabilities over {years:g} years, Poisson)."
                if curve is not None and objects else "Ranked by median capacity (lowest first): no hazard curve given.")
             + "</p><h2>Ranking</h2>", _ranking(objects, years, rows is not None)]
    for note in ("accuracy_note", "answer_note", "probabilities_note"):
        if ds.attrs.get(note):
            parts.append(f"<p class=warn>{html.escape(str(ds.attrs[note]))}</p>")
    parts.append("<h2>Objects</h2><p>Each point is marked by the model that answered it; a hollow marker is a point "
                 "nothing vouches for (left out of the fit); bars are two standard errors.  The fit is solid over "
                 "the range its vouched points cover and dotted outside.</p>")
    for obj in objects:
        values = ", ".join(f"{k} = {v:.4g} {u}".strip() for k, (v, u) in obj["values"].items())
        parts += [f"<h3>{html.escape(obj['name'])}</h3><p>{html.escape(values)}</p>",
                  f"<img alt='curves of {html.escape(obj['name'])}' src='data:image/png;base64,"
                  f"{_object_figure(obj, ds)}'>", _point_table(obj, ds)]
    parts.append("<h2>Inputs</h2><pre>" + html.escape(str(ds.attrs.get("study_text", "(no study text stored)")))
                 + "</pre>" + (f"<p>Hazard: <code>{html.escape(curve.source)}</code> ({html.escape(curve.imt)} "
                               f"[{html.escape(curve.units)}]).</p>" if curve is not None else "") + "</body></html>")
    with atomic_open(path, "w") as fh:
        fh.write("\n".join(parts))
    return objects
