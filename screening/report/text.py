"""Text reports of a sweep result: :func:`describe` (what ``screening info`` prints)."""

from __future__ import annotations

import numpy as np

from screening.analysis.beds import bed_summary, format_bed_summary
from screening.analysis.fragility import parameter
from screening.analysis.intensity import intensity_measures
from screening.analysis.probabilities import source_codes, TOPPLING_FRACTION
from screening.core import laws
from screening.core.model import Block, Foundation
from screening.core.status import BestMethod, PointStatus, SpotStatus, Trust
from screening.report.figure_base import grid_dims, grid_units, grid_values, point_label, spot_index
from screening.solvers.outputs import info_variables

__all__ = []


def _fmt(value):
    return f"{value:.4g}" if isinstance(value, (float, np.floating)) else str(value)


def describe(ds, path="result"):
    """Plain-text summary of a result dataset (what ``screening info`` prints).

    Returns: lines on the grid, the fixed parameters (SI units), the models, the block on its bed, the input
    intensity, the status counts, the ranges of ``peak_var_theta`` [rad2] and friends, the probabilities and
    the Monte Carlo spot checks.
    """
    dims = grid_dims(ds)
    lines = [f"{path}: {ds.attrs.get('title', '')}",
             f"  screening {ds.attrs.get('screening_version', '?')}, study {ds.attrs.get('study_file', '?')}, "
             f"created {ds.attrs.get('date_created', '?')}"]
    sizes = ", ".join(f"{d} ({n})" for d, n in ds.sizes.items())
    n_points = int(np.prod([ds.sizes[d] for d in dims], dtype=np.int64))
    lines.append(f"dimensions: {sizes}; {n_points} grid point(s)")
    lines.append("swept parameters:" if dims else "swept parameters: none")
    for d in dims:
        if d == "case":
            names = [str(s) for s in ds["case_name"].values]
            lines.append(f"  case     {len(names)} cases: {', '.join(names)}")
            continue
        v = grid_values(ds, d)
        units = grid_units(ds, d)
        lines.append(f"  {d:<8} {v.size} values, {_fmt(float(v.min()))} .. {_fmt(float(v.max()))} {units}")
    fixed = [n for n, var in ds.coords.items() if var.ndim == 0 and np.issubdtype(var.dtype, np.number)]
    if fixed:
        lines.append("fixed parameters: " + ", ".join(
            f"{n} = {_fmt(float(ds[n]))} {ds[n].attrs.get('units', '')}".rstrip() for n in fixed))
    per_case = [n for n, var in ds.coords.items() if var.dims == ("case",) and n not in ("case", "case_name")]
    if per_case:
        lines.append("per-case parameters: " + ", ".join(
            n + (f" ({', '.join(str(v) for v in ds[n].values)})" if ds[n].dtype.kind in "OUS" else "")
            for n in per_case))
    labels = [f"{k} = {ds.attrs[k]}" for k in ("contact", "condensation", "excitation", "envelope") if k in ds.attrs]
    if labels:
        lines.append("models: " + ", ".join(labels))
    lines.extend(bed_lines(ds))
    lines.extend(intensity_lines(ds))
    t = ds["t"].values
    lines.append(f"time: {_fmt(float(t[0]))} .. {_fmt(float(t[-1]))} s, {t.size} output times")

    status = np.asarray(ds["status"].values).reshape(-1)
    codes = [int(c) for c in ds["status"].attrs["flag_values"]]
    meanings = str(ds["status"].attrs["flag_meanings"]).split()
    counts = ", ".join(f"{m} {int(np.sum(status == c))}" for c, m in zip(codes, meanings)
                       if np.any(status == c))
    lines.append(f"status: {counts}")
    if "sl_trust" in ds.variables:
        trust = np.asarray(ds["sl_trust"].values).reshape(-1)
        lines.append("linearization against the coupled model (docs/trust.md): " + ", ".join(
            f"{t.name} {int(np.sum(trust == t))}" for t in Trust if np.any(trust == t)))
    if "best_method" in ds.variables:
        lines.append(best_line(ds))
    ok = status == PointStatus.ok
    lines.append(f"summary over the {int(ok.sum())} status-ok point(s) (min / median / max):")
    for name in info_variables():
        v = np.asarray(ds[name].values, dtype=float).reshape(-1)[ok]
        units = ds[name].attrs.get("units", "")
        if v.size:
            lines.append(f"  {name:<17} {_fmt(v.min())} / {_fmt(float(np.median(v)))} / {_fmt(v.max())} {units}")
    lines.extend(probability_lines(ds))
    if "spot" in ds.dims and ds.sizes["spot"]:
        from screening.analysis.probabilities import TOPPLING_FRACTION, probability_text, spot_check_probabilities

        prob = spot_check_probabilities(ds) if "mcs_sample_state" in ds.variables else None
        star = ("" if prob is None else f"; * more than {100 * TOPPLING_FRACTION:g} % overturned: the variances are "
                "over the survivors only, the probabilities are the answer")
        lines.append(f"Monte Carlo spot checks ({ds.attrs.get('mcs_model')}, {ds.attrs.get('mcs_samples')} "
                     f"samples, seed {ds.attrs.get('mcs_seed')}; probabilities +- 1 standard error{star}):")
        for i in range(ds.sizes["spot"]):
            index = spot_index(ds, i)
            rel = float(ds["mcs_rel_error_peak_var_theta"].values[i])
            rel_dot = float(ds["mcs_rel_error_peak_var_theta_dot"].values[i])
            over = int(ds["mcs_n_overturned"].values[i])
            div = int(ds["mcs_n_diverged"].values[i])
            lines.append(f"  {point_label(ds, index)}: " + _spot_summary(
                rel, rel_dot, over, div, int(ds["mcs_n_used"].values[i]),
                bool("mcs_status" in ds and int(ds["mcs_status"].values[i]) != SpotStatus.ok)))
            if prob is not None:
                rel = "" if prob["relative_to"] == "None" else " " + prob["relative_to"]
                exceed = "".join(f", P(|theta| > {a:g}{rel}) "
                                 f"{probability_text(prob['p_exceed'][i, j], prob['p_exceed_se'][i, j])}"
                                 for j, a in enumerate(prob["thresholds"]))
                lines[-1] += (f"; P(overturn) {probability_text(prob['p_overturn'][i], prob['p_overturn_se'][i])}"
                              f"{exceed}{' *' if prob['near_toppling'][i] else ''}")
    return "\n".join(lines)


def probability_lines(ds):
    """Lines on the probabilities stored on the points of a result.

    Where the points' ``p_overturn`` and ``p_exceed`` come from (``p_source``), their ranges, the
    points near toppling, which quantity answers the points (the ``answer_note`` attribute), and the range
    of ``p_rocking_start``.

    Returns: the lines (probabilities [1]); ``[]`` for a result without them.
    """
    lines = []
    if "p_source" in ds.variables:
        source = np.asarray(ds["p_source"].values).reshape(-1)
        names = {code: name for name, code in source_codes().items()}
        counts = ", ".join(f"{names.get(int(c), c)} {int(np.sum(source == c))}" for c in np.unique(source))
        p = np.asarray(ds["p_overturn"].values, dtype=float).reshape(-1)
        vouched = np.isfinite(np.asarray(ds["p_overturn_se"].values, dtype=float).reshape(-1))
        near = int(np.sum(vouched & (p > TOPPLING_FRACTION)))
        lines.append(f"probability of overturning and of exceedance (p_overturn, p_exceed, with *_se) by source: "
                     f"{counts}")
        if vouched.any():
            lines.append(f"  p_overturn where vouched for: {_fmt(float(p[vouched].min()))} .. "
                         f"{_fmt(float(p[vouched].max()))}; {near} point(s) above {100 * TOPPLING_FRACTION:g} % "
                         "(near toppling: read the probabilities, not the variances over the survivors)")
        if "answer_note" in ds.attrs:           # which quantity answers each point (answer_quantity)
            lines.append(f"  {ds.attrs['answer_note']} (answer_quantity)")
    if "p_rocking_start" in ds.variables:
        p = np.asarray(ds["p_rocking_start"].values, dtype=float).reshape(-1)
        if np.isfinite(p).any():
            lines.append(f"probability that rocking starts (ground acceleration beyond the uplift acceleration): "
                         f"{_fmt(float(np.nanmin(p)))} .. {_fmt(float(np.nanmax(p)))}")
    return lines


def best_line(ds):
    """The ``[accuracy]`` best estimates of a result in one line.

    Counts by ``best_method`` and, where points were escalated, what the escalation spent [CPU s].

    Returns: the line.
    """
    method = np.asarray(ds["best_method"].values).reshape(-1)
    counts = ", ".join(f"{m.name} {int(np.sum(method == m))}" for m in BestMethod if np.any(method == m))
    line = f"best estimates ([accuracy] target {ds.attrs.get('accuracy_target', float('nan')):g}): {counts}"
    if "escalation" in ds.dims:
        line += (f"; Monte Carlo at {ds.sizes['escalation']} point(s), "
                 f"{int(ds.attrs.get('accuracy_n_short_of_target', 0))} short of the target's standard error, ")
        cost = float(ds.attrs.get("accuracy_cost_s", float("nan")))
        budget = float(ds.attrs.get("accuracy_budget_s", float("nan")))
        cpu = float(ds.attrs.get("accuracy_cpu_s", float("nan")))
        if "accuracy_wall_s" in ds.attrs:                  # the budget in wall seconds
            line += (f"{float(ds.attrs['accuracy_wall_s']):.0f} of {budget:g} wall s ({cost:.1f} CPU s by the "
                     f"cost model, {cpu:.1f} s measured)")
        else:                                              # a result of the CPU budget (before 2026-11-29)
            line += f"{cost:.1f} of {budget:g} CPU s by the cost model ({cpu:.1f} s measured)"
    if "interim_result" in ds.attrs:
        line += f"; INTERIM result: {ds.attrs['interim_result']}"
    return line


def _spot_summary(rel, rel_dot, n_overturned, n_diverged, n_used, failed):
    """One spot check in plain words: the relative errors, or why there are none."""
    n = n_overturned + n_diverged + n_used
    if failed:
        return "the Monte Carlo run failed (no statistics; see the run log)"
    if n_used == 0:
        if n_overturned == n:
            return f"all {n} samples overturned: no statistics (the block topples at this point)"
        if n_diverged == n:
            return f"all {n} samples diverged: no statistics"
        return f"no usable sample ({n_overturned} overturned, {n_diverged} diverged of {n}): no statistics"

    def pct(x):
        return f"{100 * x:+.1f} %" if np.isfinite(x) else "n/a (the linearization stopped)"

    return (f"peak var_theta rel. error {pct(rel)}, peak var_theta_dot {pct(rel_dot)}, "
            f"overturned {n_overturned}, diverged {n_diverged} of {n}")


def bed_lines(ds, max_points=400):
    """``block on its bed:`` lines of :func:`screening.analysis.beds.bed_summary`.

    Ranges over the grid where the block or bed is swept; nothing if the dataset lacks a parameter.

    Returns: the lines (indentation [mm], angles [rad], frequencies [rad/s], damping ratios [1]).

    Notes
    -----
    The uplift angle is ``theta_ul = m g / (2 b^2 k)``, eq. (19) in [1].
    """
    import xarray as xr


    law = ds.attrs.get("contact", "hunt_crossley")
    try:
        damping = laws.get(law).parameter
    except ValueError:
        return []
    names = ("m", "b", "h", "I_cm", "g", "k", damping, "eps")
    try:
        arrays = xr.broadcast(*(parameter(ds, n) for n in names))
    except KeyError:
        return []
    flat = np.unique(np.column_stack([np.asarray(a.values, dtype=float).ravel() for a in arrays]), axis=0)
    summaries = []
    for row in flat[:max_points]:
        p = dict(zip(names, row))
        try:
            bed = Foundation(k=p["k"], eps=p["eps"], law=law, **{damping: p[damping]})
            summaries.append(bed_summary(Block(m=p["m"], b=p["b"], h=p["h"], I_cm=p["I_cm"], g=p["g"]), bed))
        except ValueError:
            continue
    if not summaries:
        return []
    if len(summaries) == 1:
        return ["block on its bed:"] + ["  " + line for line in format_bed_summary(summaries[0]).splitlines()]
    units = {"static_indentation": "m", "uplift_angle": "rad", "uplift_angle_exact": "rad", "slenderness": "rad",
             "rocking_frequency": "rad/s", "vertical_frequency": "rad/s", "vertical_damping_ratio": "1",
             "rocking_damping_ratio": "1"}
    out = [f"block on its bed ({len(summaries)} block/bed combinations, min .. max):"]
    for key, unit in units.items():
        v = np.array([s[key] for s in summaries], dtype=float)
        if np.isfinite(v).any():
            out.append(f"  {key:<23} {_fmt(float(np.nanmin(v)))} .. {_fmt(float(np.nanmax(v)))} {unit}")
    return out


def intensity_lines(ds):
    """``input intensity`` lines of the inputs of a result.

    Ranges of the RVT median PGA, RMS acceleration, Arias intensity and median PGV (0.1 Hz
    high-pass) (:func:`screening.analysis.intensity.intensity_measures`).

    Returns: the lines (accelerations [m s-2] and [g], Arias intensity and PGV [m s-1]); nothing if they
    cannot be computed.
    """
    try:
        im = intensity_measures(ds)
    except (KeyError, ValueError):
        return []
    out = [f"input intensity (random-vibration theory, band limit: {im.attrs['cutoff_rad_s_source']}):"]
    for name in ("pga_median", "rms_acceleration", "arias_intensity", "pgv_median"):
        v = np.asarray(im[name].values, dtype=float)
        unit = im[name].attrs.get("units", "")
        extra = f" ({_fmt(float(np.nanmin(v)) / 9.80665)} .. {_fmt(float(np.nanmax(v)) / 9.80665)} g)" \
            if unit == "m s-2" else ""
        out.append(f"  {name:<17} {_fmt(float(np.nanmin(v)))} .. {_fmt(float(np.nanmax(v)))} {unit}{extra}")
    return out


#: Largest variable (values) of a file ``info`` describes as a product of simulate, cloud or fragility.
PRODUCT_MAX_VALUES = 50_000_000


def product_kind(ds):
    """Which other screening file ``ds`` is.

    Returns: ``"fragility"``, ``"cloud"``, ``"simulation"``, or ``None`` (a sweep result, or a variable of
    more than :data:`PRODUCT_MAX_VALUES` values [-]).
    """
    names = set(ds.variables)
    if "status" in names or any(v.size > PRODUCT_MAX_VALUES for v in ds.variables.values()):
        return None                 # a (damaged) sweep result, or a file too big to be one of these
    if "record" in ds.dims and "exceed" in names:
        return "cloud"
    if "p_exceed" in names or ("mcs_p_exceed" in names and "threshold_rad" in names):
        return "fragility"
    if {"theta", "peak_abs_theta"} <= names and "t" in ds.dims:
        return "simulation"
    return None


def describe_product(ds, path="file"):
    """Plain-text summary of a file of ``screening simulate``, ``cloud`` or ``fragility``.

    What ``screening info`` prints for them.

    Returns: the summary (threshold [rad], probabilities [1], fitted median in the units of the intensity);
    ``None`` for a file that is none of these (:func:`product_kind`).
    """
    kind = product_kind(ds)
    if kind is None:
        return None
    lines = [f"{path}: {ds.attrs.get('title', '')} ({kind} file)",
             f"  screening {ds.attrs.get('screening_version', '?')}; {ds.attrs.get('history', '')}".rstrip("; ")]
    lines.append("dimensions: " + (", ".join(f"{d} ({n})" for d, n in ds.sizes.items()) or "none"))
    if kind == "simulation":
        over = (f"overturned at t = {float(ds['overturning_time']):.4g} s" if bool(ds["overturned"]) else
                f"peak |theta| {float(ds['peak_abs_theta']):.4g} rad")
        lines.append(f"record {ds.attrs.get('record', '?')}, {ds.attrs.get('model', '?')} model, "
                     f"status {ds.attrs.get('status', '?')}: {over}")
        return "\n".join(lines)
    if kind == "cloud":
        n = ds.sizes["record"]
        stripes = f" x {ds.sizes['level']} stripe(s) ({ds.attrs.get('intensity_variable', '?')} levels)" \
            if "level" in ds.dims else ""
        lines.append(f"{n} record(s){stripes}: {int(ds['exceed'].sum())} run(s) exceed the threshold, "
                     f"{int(ds['overturned'].sum())} overturned, {int(ds['diverged'].sum())} left out (diverged)")
        if "beta_se" in ds:
            lines.append(f"standard errors (binomial likelihood): median {_fmt(float(ds['fit_median_se']))}, "
                         f"beta {_fmt(float(ds['beta_se']))}")
    else:
        p = np.asarray(ds["p_exceed"].values if "p_exceed" in ds else ds["mcs_p_exceed"].values, dtype=float)
        lines.append(f"threshold {ds.attrs.get('threshold', '?')} (relative to {ds.attrs.get('relative_to', '?')}), "
                     f"method {ds.attrs.get('method', '?')}; P(exceed) over {p.size} value(s): "
                     f"min {_fmt(float(np.nanmin(p)))}, max {_fmt(float(np.nanmax(p)))}"
                     if np.isfinite(p).any() else "P(exceed): no finite value")
    if "fit_median" in ds:
        from screening.applications.im_fragility import curve_count_text

        units = ds["fit_median"].attrs.get("units", "")
        fit = f"lognormal fit over {ds['fit_median'].attrs.get('intensity', '?')}: {curve_count_text(ds)}"
        if np.isfinite(ds["fit_median"].values).any():
            fit += (f"; median {_fmt(float(ds['fit_median'].median()))} {units}, "
                    f"beta {_fmt(float(ds['beta'].median()))} (medians over the fitted curves)")
        lines.append(fit)
    return "\n".join(lines)
