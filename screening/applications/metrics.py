"""Error metrics of the speed-accuracy trade study: pure, NaN-aware functions of numpy arrays.

Histories share a time grid ``t`` [s] on the last axis.  Peak relative error with its Monte Carlo
standard error, time-averaged relative error with its noise floor, significance (``|diff| > 2 SE``;
the sum in quadrature for MCS vs MCS, conservative), classification against a tolerance and the validity
rules of SL derived from a trade-study dataset (:func:`derive_rules`).  ``docs/validation.md``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = []

#: Error a validity rule is judged on (:func:`rule_error`).
RULE_METRICS = ("peak", "time_avg", "worst")

_trapezoid = getattr(np, "trapezoid", None) or np.trapz     # numpy >= 2 renamed trapz


def peak_with_se(values, se=None, axis=-1):
    """Peak ``max_t values`` over the finite entries and the standard error at the peak time.

    Units: ``values`` [any unit].

    Returns: in the unit of ``values``; both NaN where no entry is finite.
    """
    v = np.asarray(values, dtype=float)
    v = np.moveaxis(v, axis, -1)
    finite = np.isfinite(v)
    any_finite = finite.any(axis=-1)
    filled = np.where(finite, v, -np.inf)
    idx = np.argmax(filled, axis=-1)
    peak = np.take_along_axis(filled, idx[..., None], axis=-1)[..., 0]
    peak = np.where(any_finite, peak, np.nan)
    if se is None:
        s = np.where(any_finite, 0.0, np.nan)
    else:
        s_arr = np.moveaxis(np.asarray(se, dtype=float), axis, -1)
        s = np.take_along_axis(s_arr, idx[..., None], axis=-1)[..., 0]
        s = np.where(any_finite, s, np.nan)
    if peak.ndim == 0:
        return float(peak), float(s)
    return peak, s


def relative_difference(estimate, reference):
    """``estimate / reference - 1`` [1]; NaN where the reference is zero or not finite.

    Returns: the relative difference [1].
    """
    e = np.asarray(estimate, dtype=float)
    r = np.asarray(reference, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where((r != 0) & np.isfinite(r), e / r - 1.0, np.nan)
    return float(out) if out.ndim == 0 else out


def peak_relative_error(estimate, reference, axis=-1):
    """Relative error of the peak over time: ``max_t estimate / max_t reference - 1`` [1].

    Units: estimate, reference [same unit].

    Returns: the relative error [1].
    """
    return relative_difference(peak_with_se(estimate, axis=axis)[0], peak_with_se(reference, axis=axis)[0])


def _common_mask(a, b):
    return np.isfinite(a) & np.isfinite(b)


def time_averaged_relative_error(estimate, reference, t):
    """``int |estimate - reference| dt / int |reference| dt`` [1] (trapezoidal rule).

    Only the instants where both histories are finite count (e.g. the part of the record where
    the Monte Carlo ensemble is defined).

    Units: estimate, reference [same unit], ``t`` [s].

    Returns: the error [1]; NaN if nothing is left or ``int |reference| = 0``.
    """
    a = np.asarray(estimate, dtype=float)
    b = np.asarray(reference, dtype=float)
    a, b = np.broadcast_arrays(a, b)
    mask = _common_mask(a, b)
    num = _trapezoid(np.where(mask, np.abs(a - b), 0.0), t, axis=-1)
    den = _trapezoid(np.where(mask, np.abs(b), 0.0), t, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(den > 0, num / den, np.nan)
    return float(out) if out.ndim == 0 else out


def time_averaged_relative_se(se, reference, t, estimate=None):
    """Time-averaged relative standard error ``int SE dt / int |reference| dt`` [1].

    The noise floor of :func:`time_averaged_relative_error`, on the same mask (where ``reference``
    and, if given, ``estimate`` are finite).  Pure sampling noise gives a time-averaged error of
    about ``sqrt(2/pi) ~ 0.8`` times this value.

    Units: ``se`` [unit of ``reference``], ``t`` [s].

    Returns: the noise floor [1].

    Notes
    -----
    ``E|N(0, s^2)| = s sqrt(2/pi)`` gives the factor 0.8.
    """
    s = np.asarray(se, dtype=float)
    b = np.asarray(reference, dtype=float)
    a = b if estimate is None else np.asarray(estimate, dtype=float)
    s, a, b = np.broadcast_arrays(s, a, b)
    mask = _common_mask(a, b) & np.isfinite(s)
    num = _trapezoid(np.where(mask, s, 0.0), t, axis=-1)
    den = _trapezoid(np.where(mask, np.abs(b), 0.0), t, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(den > 0, num / den, np.nan)
    return float(out) if out.ndim == 0 else out


def combined_se(*standard_errors):
    """Standard errors added in quadrature, ``sqrt(sum se_i^2)``.

    Exact for independent estimates; conservative for positively correlated ones such as two
    models on the same samples.

    Units: ``*standard_errors`` [same unit].

    Returns: the combined standard error [same unit].
    """
    return np.sqrt(sum(np.asarray(s, dtype=float) ** 2 for s in standard_errors))


def is_significant(difference, se, k=2.0):
    """``|difference| > k se``: the difference is larger than the sampling noise (default 2 SE).

    Units: ``difference`` [any unit], ``se`` [same unit], ``k`` [1].

    Returns: False where either is NaN.
    """
    d = np.abs(np.asarray(difference, dtype=float))
    s = np.asarray(se, dtype=float)
    out = np.isfinite(d) & np.isfinite(s) & (d > k * s)
    return bool(out) if out.ndim == 0 else out


def classify_error(error, relative_se, threshold, k=2.0):
    """Class of a relative error against a tolerance ``threshold`` [1].

    Units: ``error`` [1], ``relative_se`` [1], ``threshold`` [1], ``k`` [1].

    Returns: ``"within"`` if ``|error| + k se <= threshold``, ``"outside"`` if ``|error| - k se >
    threshold``, ``"ambiguous"`` otherwise (the tolerance lies within ``k`` standard errors), and
    ``"undefined"`` for a NaN error.
    """
    e, s = abs(float(error)), float(relative_se)
    if not math.isfinite(e):
        return "undefined"
    s = s if math.isfinite(s) else 0.0
    if e + k * s <= threshold:
        return "within"
    if e - k * s > threshold:
        return "outside"
    return "ambiguous"


def threshold_rule(indicator, passed, direction="below"):
    """The largest one-sided region of a scalar indicator in which every point passed.

    Units: ``indicator`` [any unit].

    Returns ``(bound, n_covered)``: ``bound`` ``X`` [unit of the indicator]; ``n_covered`` the number of
    points inside (all of which passed).
    """
    x = np.asarray(indicator, dtype=float)
    ok = np.asarray(passed, dtype=bool)
    if direction == "below":
        bound = float(np.min(x[~ok])) if np.any(~ok) else math.inf
        covered = int(np.count_nonzero(x < bound))
    elif direction == "above":
        bound = float(np.max(x[~ok])) if np.any(~ok) else -math.inf
        covered = int(np.count_nonzero(x > bound))
    else:
        raise ValueError(f"parameter 'direction' must be 'below' or 'above' (got {direction!r})")
    return bound, covered


def rule_error(peak_error, time_avg_error, metric="peak"):
    """The error a validity rule is judged on: ``|peak|``, ``time_avg`` or the worse of the two.

    Units: ``peak_error`` [1], ``time_avg_error`` [1].

    Returns: the error [1] (NaN for ``"worst"`` where either is NaN).
    """
    p = np.abs(np.asarray(peak_error, dtype=float))
    ta = np.asarray(time_avg_error, dtype=float)
    if metric == "peak":
        return p
    if metric == "time_avg":
        return ta
    if metric == "worst":
        with np.errstate(invalid="ignore"):
            return np.where(np.isfinite(p) & np.isfinite(ta), np.maximum(p, ta), np.nan)
    raise ValueError(f"parameter 'metric' must be one of {RULE_METRICS} (got {metric!r})")

def compare(estimate, reference, t, est_se=None, ref_se=None):
    """All error measures of one history against a reference, as a dict (units [1]).

    Units: estimate, reference [same unit], ``t`` [s], est_se, ref_se [same unit].

    Returns: ``peak_estimate``, ``peak_reference`` [unit of the histories], ``peak_rel_error``,
    ``peak_rel_se`` (SE of the difference of the peaks over the reference peak), ``peak_significant``
    (``|diff| > 2 SE``), ``time_avg_rel_error``, ``time_avg_rel_se`` (noise floor) and
    ``time_avg_significant`` (error > 2 x floor).
    """
    pe, se_e = peak_with_se(estimate, est_se)
    pr, se_r = peak_with_se(reference, ref_se)
    se = float(combined_se(se_e, se_r))
    rel = relative_difference(pe, pr)
    rel_se = se / pr if (np.isfinite(pr) and pr != 0) else float("nan")
    noise = [s for s in (est_se, ref_se) if s is not None]
    se_t = combined_se(*noise) if noise else np.zeros_like(np.asarray(reference, dtype=float))
    ta = time_averaged_relative_error(estimate, reference, t)
    ta_se = time_averaged_relative_se(se_t, reference, t, estimate=estimate)
    return {"peak_estimate": pe, "peak_reference": pr, "peak_rel_error": rel, "peak_rel_se": rel_se,
            "peak_significant": is_significant(pe - pr, se), "time_avg_rel_error": ta, "time_avg_rel_se": ta_se,
            "time_avg_significant": bool(np.isfinite(ta) and np.isfinite(ta_se) and ta > 2.0 * ta_se)}



def safe_indicator_range(indicator, passed, tie=0.05):
    """Conservative upper bound of a "safe below" region of an indicator, from tested points.

    Values within a relative ``tie`` of the first failure count as the same tested level (so a
    level at which some points pass and some fail is not called safe).

    Units: ``indicator`` [any unit], ``tie`` [1].

    Returns ``(p_safe, n_safe, i_fail)``: ``p_safe`` the largest indicator value of a passing point below
    the first failure; NaN when no tested level is safe; ``n_safe`` the number of points with ``indicator <=
    p_safe`` (all passed); ``i_fail`` the index of the failing point with the smallest indicator (None if
    nothing failed).
    """
    x = np.asarray(indicator, dtype=float)
    ok = np.asarray(passed, dtype=bool)
    i_fail = None
    limit = math.inf
    if np.any(~ok):
        failing = np.flatnonzero(~ok)
        i_fail = int(failing[np.argmin(x[failing])])
        limit = x[i_fail] / (1.0 + tie)
    safe = ok & (x < limit)
    if not np.any(safe):
        return float("nan"), 0, i_fail
    p_safe = float(np.max(x[safe]))
    return p_safe, int(np.count_nonzero(x <= p_safe)), i_fail


def rule_groups(eps):
    """Point groups a rule is derived for: ``"all"`` and, with 2–4 distinct ``eps``, one per bed.

    Units: ``eps`` [m-2].

    Returns: ``{group name: mask}``.
    """
    eps = np.asarray(eps, dtype=float)
    groups = {"all": np.ones(eps.size, dtype=bool)}
    values = list(dict.fromkeys(eps.tolist()))
    if 2 <= len(values) <= 4:
        for v in values:
            groups[f"eps={v:g}"] = eps == v
    return groups


def derive_rules(ds, thresholds=(0.10, 0.25), metric="peak", quantity="var_theta", tie=0.05):
    """Validity rules of SL derived from a trade-study dataset.

    For each reference (condensed, coupled MCS), threshold and point group (:func:`rule_groups`):
    the safe range of SL peak p_uplift (:func:`safe_indicator_range`) and of the k_eq margin
    (:func:`threshold_rule`, "above"), judged on :func:`rule_error` of ``quantity``.

    Units: ``quantity`` [rad2].

    Returns: ``reference``, ``threshold``, ``group``, ``n``, ``n_pass``, ``p_safe``, ``n_safe``, ``p_max``
    (largest tested p), ``fail_p``, ``fail_name``, ``fail_error`` (the first failure in p),
    ``margin_bound``, ``n_margin``.
    """
    p_all = ds.sl_peak_p_uplift.values
    margin_all = ds.k_eq_margin.values
    names_all = np.asarray(ds.point_name.values).astype(str)
    rules = []
    for comp, ref_label in (("sl_vs_condensed", "condensed"), ("sl_vs_coupled", "coupled")):
        sel = {"comparison": comp, "quantity": quantity}
        err_all = rule_error(ds.peak_rel_error.sel(sel).values, ds.time_avg_rel_error.sel(sel).values, metric)
        signed_all = ds.peak_rel_error.sel(sel).values if metric == "peak" else err_all
        for thr in thresholds:
            for group, mask in rule_groups(ds.eps.values).items():
                p, margin, err = p_all[mask], margin_all[mask], err_all[mask]
                passed = np.isfinite(err) & (err <= thr)
                p_safe, n_safe, i_fail = safe_indicator_range(p, passed, tie)
                y, n_y = threshold_rule(margin, passed, "above")
                rules.append({
                    "reference": ref_label, "threshold": float(thr), "group": group, "n": int(p.size),
                    "n_pass": int(passed.sum()), "p_safe": p_safe, "n_safe": n_safe, "p_max": float(np.max(p)),
                    "fail_p": float("nan") if i_fail is None else float(p[i_fail]),
                    "fail_name": "" if i_fail is None else str(names_all[mask][i_fail]),
                    "fail_error": float("nan") if i_fail is None else float(signed_all[mask][i_fail]),
                    "margin_bound": y, "n_margin": n_y})
    return rules
