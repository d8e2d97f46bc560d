"""Risk at a site: each object's fragility convolved with the site's hazard curve (``screening risk``).

:func:`annual_frequency` is the integral (mean annual frequency of a limit state, with the share that
comes from outside the range the fragility was vouched over and monotone bounds there);
:func:`read_hazard` reads a hazard curve (OpenQuake's hazard-curve CSV or a plain table) and
checks it line by line before any work; :func:`risk_table` runs the integral over every curve of a
fragility dataset.  Method and its checks: ``docs/fragility.md#risk-at-a-site``.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import special

from screening.applications.im_fragility import (IMS, curves_by_object, export_problem, fragility_intensity,
                                                 fragility_over_im, im_key, stack_limit_states)
from screening.core.status import FitFlag

__all__ = []

#: Standard gravity [m s-2]: OpenQuake's accelerations are in g.
G = 9.80665

#: Steps of the integration grid per unit of ln(IM) (the midpoint rule's relative error is about
#: (h / beta)^2 / 24: 1e-5 at h = 0.005, beta = 0.3).
STEPS_PER_LOG_UNIT = 200


def _lognormal(x, median, beta):
    return special.ndtr(np.log(x / median) / beta)


def annual_frequency(im, rate, median, beta, im_min=None, im_max=None):
    """Mean annual frequency of a limit state: a lognormal fragility convolved with a hazard curve.

    Parameters
    ----------
    im : array_like
        Intensity levels of the hazard curve [IM units], > 0, strictly increasing.
    rate : array_like
        Annual rate of exceeding each level [1/yr], > 0, strictly decreasing.
    median : float
        Median of the fragility [IM units], > 0.
    beta : float
        Its lognormal dispersion [1], > 0.
    im_min, im_max : float, optional
        The range the fragility was vouched over [IM units] (default: the hazard curve's range).

    Returns
    -------
    dict
        ``rate`` [1/yr]: the whole integral with the fitted curve (what an engine computes);
        ``rate_vouched`` [1/yr]: its part from intensities inside ``[im_min, im_max]``;
        ``share_outside`` [1]: ``1 - rate_vouched / rate``; ``rate_low``, ``rate_high`` [1/yr]: bounds
        that use the fitted curve only inside the vouched range and, outside it, only that the
        fragility does not fall with the intensity (0 .. ``P(im_min)`` below, ``P(im_max)`` .. 1 above).

    Notes
    -----
    ``lambda = int P(x) |dH/dx| dx`` with ``P(x) = Phi(ln(x / median) / beta)`` and ``H`` the hazard
    curve, interpolated linearly in ``ln H`` over ``ln x`` between its levels; computed by the midpoint
    rule on a grid of :data:`STEPS_PER_LOG_UNIT` steps per unit of ``ln x``:
    ``sum_j P(x_j+1/2) (H(x_j) - H(x_j+1))``, plus ``P(x_N) H(x_N)`` for the intensities above the
    last level (a lower bound there, as ``P`` only grows).  Below the first level the hazard curve
    says nothing: that part is left out (give a curve down to intensities where ``P`` is negligible).
    For a power-law hazard ``H = k0 x^-k`` over all ``x > 0``:
    ``lambda = k0 median^-k exp(k^2 beta^2 / 2)`` [1].

    """
    x = np.asarray(im, dtype=float)
    h = np.asarray(rate, dtype=float)
    lo = x[0] if im_min is None or not np.isfinite(im_min) else max(float(im_min), x[0])
    hi = x[-1] if im_max is None or not np.isfinite(im_max) else min(float(im_max), x[-1])
    lx, lh = np.log(x), np.log(h)
    n = max(int(math.ceil((lx[-1] - lx[0]) * STEPS_PER_LOG_UNIT)), 1)
    edges = np.unique(np.concatenate([np.linspace(lx[0], lx[-1], n + 1), np.log([lo, hi])[np.array([lo, hi]) > 0]]))
    edges = edges[(edges >= lx[0]) & (edges <= lx[-1])]
    hz = np.exp(np.interp(edges, lx, lh))
    mid = np.exp(0.5 * (edges[1:] + edges[:-1]))
    dh = hz[:-1] - hz[1:]
    p = _lognormal(mid, median, beta)
    inside = (mid >= lo) & (mid <= hi)
    below, above = mid < lo, mid > hi
    tail = float(_lognormal(x[-1], median, beta) * h[-1])
    total = float(np.sum(p * dh)) + tail
    vouched = float(np.sum((p * dh)[inside])) + (tail if hi >= x[-1] else 0.0)
    p_lo, p_hi = float(_lognormal(lo, median, beta)), float(_lognormal(hi, median, beta))
    rate_low = vouched + p_hi * float(np.sum(dh[above])) + (0.0 if hi >= x[-1] else p_hi * h[-1])
    rate_high = vouched + p_lo * float(np.sum(dh[below])) + float(np.sum(dh[above])) + \
        (0.0 if hi >= x[-1] else h[-1])
    return {"rate": total, "rate_vouched": vouched,
            "share_outside": 1.0 - vouched / total if total > 0 else math.nan,
            "rate_low": rate_low, "rate_high": rate_high}


# ----------------------------------------------------------------------------- hazard curves
class HazardError(ValueError):
    """A hazard curve that cannot be used: the message names the file, the line and the field."""


@dataclass(frozen=True)
class HazardCurve:
    """A site's hazard curve: ``imt`` (OpenQuake's name: ``PGA``, ``SA(0.3)``), ``im`` [``units``] and the
    annual rate of exceeding each level ``rate`` [1/yr]; ``source`` says where it came from."""
    imt: str
    units: str
    im: np.ndarray
    rate: np.ndarray
    source: str


_OQ_META = re.compile(r"(\w+)\s*=\s*'?([^,']+)'?")
_PLAIN_HEADER = re.compile(r"^\s*([A-Za-z]+(?:\([0-9.eE+-]+\))?)\s*\[([^\]]+)\]\s*$")
_UNITS = {"g": "g", "m s-2": "m s-2", "m/s2": "m s-2", "m/s^2": "m s-2", "m s-1": "m s-1", "m/s": "m s-1",
          "cm/s": "cm s-1", "cm s-1": "cm s-1"}


def _fail(path, line, field, problem):
    raise HazardError(f"{path}:{line}: {field}: {problem}")


def _number(path, line, field, text):
    try:
        value = float(text)
    except ValueError:
        _fail(path, line, field, f"not a number ({text.strip()!r})")
    if not math.isfinite(value):
        _fail(path, line, field, f"not finite ({text.strip()!r})")
    return value


def _check_curve(path, lines, im, rate, im_field, rate_field):
    for i in range(len(im)):
        if not im[i] > 0:
            _fail(path, lines[i], im_field, f"intensity {im[i]:g} must be > 0")
        if not rate[i] > 0:
            _fail(path, lines[i], rate_field, f"{rate[i]:g} must be > 0 (leave out the levels never exceeded)")
        if i and not im[i] > im[i - 1]:
            _fail(path, lines[i], im_field, f"intensity {im[i]:g} is not above the one before ({im[i - 1]:g})")
        if i and not rate[i] < rate[i - 1]:
            _fail(path, lines[i], rate_field, f"the hazard curve is not decreasing: {rate[i]:g} after "
                                              f"{rate[i - 1]:g}")
    if len(im) < 2:
        _fail(path, lines[-1] if lines else 1, im_field, "a hazard curve needs two levels or more")


def read_hazard(path, site=None):
    """Read a site's hazard curve: OpenQuake's hazard-curve CSV or a plain table.

    OpenQuake (``hazard_curve-mean-PGA_*.csv``): a first line with ``investigation_time`` and ``imt``,
    a header ``lon,lat,depth,poe-<iml>,...`` and one row per site (``site``: the row, counted from 0;
    needed where there are several); accelerations in g.  The probabilities of exceedance ``poe`` over
    ``T = investigation_time`` become annual rates ``-ln(1 - poe) / T`` (Poisson); levels with ``poe`` 0
    or 1 carry no finite rate and are left out.  Plain table: a
    header ``PGA [g], annual_rate [1/yr]`` (the IMT as OpenQuake names it and its units in
    brackets: ``g``, ``m s-2``), then one ``level, rate`` per line; ``#`` starts a comment.

    Returns a :class:`HazardCurve`.

    Raises
    ------
    HazardError
        One line naming the file, the line and the field: not a number, a level not increasing, a
        curve not decreasing, no level above 0, a missing header, a site not in the file.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise HazardError(f"{path}: cannot read the hazard curve ({exc})") from None
    lines = text.splitlines()
    if lines and "investigation_time" in lines[0]:
        return _read_openquake(path, lines, site)
    return _read_plain(path, lines)


def _read_openquake(path, lines, site):
    meta = dict(_OQ_META.findall(lines[0]))
    T = _number(path, 1, "investigation_time", meta.get("investigation_time", "nan"))
    if not T > 0:
        _fail(path, 1, "investigation_time", f"{T:g} must be > 0")
    imt = meta.get("imt")
    if not imt:
        _fail(path, 1, "imt", "missing (the first line names the intensity measure type, e.g. imt='PGA')")
    if len(lines) < 3:
        _fail(path, len(lines), "header", "no site row after the header")
    header = next(csv.reader([lines[1]]))
    cols = [i for i, h in enumerate(header) if h.strip().startswith("poe-")]
    if not cols:
        _fail(path, 2, "header", "no poe-<level> column")
    rows = [(n, r) for n, r in enumerate(csv.reader(lines[2:]), start=3) if r and any(c.strip() for c in r)]
    if site is None and len(rows) > 1:
        _fail(path, rows[1][0], "site", f"the file has {len(rows)} sites: choose one with --site 0..{len(rows) - 1}")
    site = 0 if site is None else site
    if not 0 <= site < len(rows):
        _fail(path, 3, "site", f"--site {site} is not a row of the file (0..{len(rows) - 1})")
    n, row = rows[site]
    im = np.array([_number(path, 2, header[i], header[i].strip()[4:]) for i in cols])
    poe = np.array([_number(path, n, header[i], row[i]) for i in cols])
    bad = np.flatnonzero((poe < 0) | (poe > 1))
    if bad.size:
        _fail(path, n, header[cols[bad[0]]], f"probability of exceedance {poe[bad[0]]:g} must lie in [0, 1]")
    # levels never exceeded (poe 0) or certainly exceeded (poe 1, as printed) in the investigation time
    # carry no finite rate: left out
    keep = (poe > 0) & (poe < 1)
    rate = -np.log1p(-poe[keep]) / T
    fields = [header[i] for i, k in zip(cols, keep) if k]
    for i in range(1, len(rate)):
        if not rate[i] < rate[i - 1]:
            _fail(path, n, fields[i], f"the hazard curve is not decreasing: poe {poe[keep][i]:g} after "
                                      f"{poe[keep][i - 1]:g}")
    _check_curve(path, [n] * int(keep.sum()), im[keep], rate, "poe level", "poe")
    units = "g" if imt.startswith(("PGA", "SA", "AvgSA")) else "cm s-1" if imt == "PGV" else "m s-1"
    saturated = int(np.sum(poe >= 1))
    return HazardCurve(imt, units, im[keep], rate, f"{path} (OpenQuake, investigation_time {T:g} yr, site {site}"
                       + (f"; {saturated} level(s) with poe 1 left out" if saturated else "") + ")")


def _read_plain(path, lines):
    body = [(n, line.split("#", 1)[0].strip()) for n, line in enumerate(lines, start=1)]
    body = [(n, line) for n, line in body if line]
    if not body:
        _fail(path, 1, "header", "empty file")
    n0, head = body[0]
    cells = [c.strip() for c in re.split(r"[,;\t]", head)]
    match = _PLAIN_HEADER.match(cells[0]) if len(cells) == 2 else None
    if match is None:
        _fail(path, n0, "header", f"expected 'IMT [units], annual_rate [1/yr]' (e.g. 'PGA [g], annual_rate "
                                  f"[1/yr]'), got {head!r}")
    imt, units = match.group(1), match.group(2).strip()
    if units not in _UNITS:
        _fail(path, n0, cells[0], f"unknown units {units!r} (use g, m s-2, m s-1 or cm/s)")
    im, rate, numbers = [], [], []
    for n, line in body[1:]:
        parts = [c for c in re.split(r"[,;\s]+", line) if c]
        if len(parts) != 2:
            _fail(path, n, "row", f"expected two numbers (level, annual rate), got {line!r}")
        im.append(_number(path, n, cells[0], parts[0]))
        rate.append(_number(path, n, cells[1], parts[1]))
        numbers.append(n)
    im, rate = np.array(im), np.array(rate)
    _check_curve(path, numbers or [n0], im, rate, cells[0], cells[1])
    return HazardCurve(imt, _UNITS[units], im, rate, f"{path} (plain table)")


def hazard_levels(curve, name, units, period, hazard_path):
    """The hazard's levels [``units``] for a fragility over the intensity variable ``name`` [``units``].

    Units: ``period`` [s].

    Returns: the levels in ``units``.

    Raises
    ------
    HazardError
        One line naming the file, line 1 and the field (``imt``, ``units``) when the hazard curve is
        for another intensity measure, another period or in units that cannot be converted.
    """
    key = im_key(name)
    if key is None or IMS[key][2] is None:
        raise HazardError(f"{hazard_path}:1: imt: the fragility is over {name!r}, which has no OpenQuake IMT; "
                          "fit it over pga or sa (screening fragility --im pga)")
    imt = IMS[key][2]
    if imt in ("SA", "AvgSA") and period not in ("", None):
        imt = f"{imt}({float(period):g})"
    if _norm_imt(curve.imt) != _norm_imt(imt):
        raise HazardError(f"{hazard_path}:1: imt: the hazard curve is for {curve.imt}, the fragility for {imt} "
                          f"(its {name})")
    to_fragility = {("g", "m s-2"): G, ("m s-2", "m s-2"): 1.0, ("cm s-1", "m s-1"): 0.01,
                    ("m s-1", "m s-1"): 1.0}.get((curve.units, units))
    if to_fragility is None:
        raise HazardError(f"{hazard_path}:1: units: the hazard curve is in {curve.units}, the fragility's "
                          f"{name} in {units}")
    return curve.im * to_fragility


def _norm_imt(imt):
    m = re.match(r"^(\w+)(?:\(([^)]*)\))?$", imt.strip())
    if not m:
        return imt
    return m.group(1).upper() + (f"({float(m.group(2)):g})" if m.group(2) else "")


# ----------------------------------------------------------------------------- over a fragility
#: Columns of the risk CSV, in order.
RISK_COLUMNS = ("rank", "object", "limit_state", "median", "beta", "units", "annual_rate", "annual_rate_se",
                "annual_rate_vouched", "share_outside_vouched", "annual_rate_low", "annual_rate_high",
                "years", "probability", "probability_low", "probability_high", "im_min", "im_max", "note")


def _se(im, rate, median, beta, median_se, beta_se, lo, hi):
    """Standard error of the rate by the delta method (independent errors of ln median and beta)."""
    if not (np.isfinite(median_se) and np.isfinite(beta_se)):
        return math.nan
    d = 1e-4
    base = annual_frequency(im, rate, median, beta, lo, hi)["rate"]
    dm = (annual_frequency(im, rate, median * math.exp(d), beta, lo, hi)["rate"] - base) / d
    db = (annual_frequency(im, rate, median, beta * (1 + d), lo, hi)["rate"] - base) / (beta * d)
    return math.sqrt((dm * median_se / median) ** 2 + (db * beta_se) ** 2)


def _position(frag, dim, label):
    """Index along ``dim`` of a curve label of :func:`~screening.applications.im_fragility.curve_table`."""
    if dim not in frag.coords:
        return int(label)
    return int(np.flatnonzero(np.asarray(frag[dim].values) == label)[0])


def risk_table(frag, curve, years, hazard_path="hazard"):
    """The risk of every curve of a fragility dataset at the site of ``curve``, ranked.

    Units: ``years`` [yr].

    Returns: one per object and limit state (:data:`RISK_COLUMNS`), highest ``annual_rate`` first; curves
    without a usable fit come last with a NaN rate and the reason in ``note``.

    Notes
    -----
    Per curve :func:`annual_frequency`; ``probability = 1 - exp(-annual_rate years)`` (Poisson
    occurrences), ``probability_low`` / ``_high`` from the monotone bounds of the rate.  ``annual_rate_se``
    from the fragility's standard errors ``fit_median_se``, ``beta_se`` (where it has them) by the delta
    method.
    """
    name, _, _ = fragility_intensity(frag)
    im = hazard_levels(curve, *fragility_intensity(frag), hazard_path)
    states, objects = curves_by_object(frag)
    # a fit without its own vouched range (cloud, stripes): the intensities of its records or stripes
    whole = np.asarray(frag[name].values, dtype=float) if name in frag else np.array([])
    whole = whole[np.isfinite(whole)]
    med_se = frag["fit_median_se"] if "fit_median_se" in frag else None
    beta_se = frag["beta_se"] if "beta_se" in frag else None
    units = frag["fit_median"].attrs.get("units", "")
    dims = frag["fit_median"].dims
    out = []
    for fid, by_state in objects.items():
        obj = fid.removeprefix("screening_").replace("case=", "") if by_state["labels"] else "screening"
        for state in states:
            r = by_state[state]
            problem = export_problem(r)
            row = {"object": obj, "limit_state": state, "median": r["median"], "beta": r["beta"], "units": units,
                   "years": years, "im_min": r["im_min"], "im_max": r["im_max"], "note": problem}
            if r["flag"] != FitFlag.ok:
                row.update({k: math.nan for k in RISK_COLUMNS if k.startswith(("annual_rate", "probability", "share"))})
                out.append(row)
                continue
            if "fit_im_min" not in frag and whole.size:
                r = {**r, "im_min": float(whole.min()), "im_max": float(whole.max())}
                row.update(im_min=r["im_min"], im_max=r["im_max"])
            res = annual_frequency(im, curve.rate, r["median"], r["beta"], r["im_min"], r["im_max"])
            if "fit_im_min" in frag and not (np.isfinite(r["im_min"]) and np.isfinite(r["im_max"])):
                # no point of the curve is vouched: all of the rate is from outside, bounded by 0 and the rate
                # of the lowest hazard level
                res.update(rate_vouched=0.0, share_outside=1.0, rate_low=0.0, rate_high=float(curve.rate[0]))
            sel = {d: _position(frag, d, v) for d, v in r["labels"].items() if d in dims}
            mse = float(med_se[sel]) if med_se is not None else math.nan
            bse = float(beta_se[sel]) if beta_se is not None else math.nan
            row.update(annual_rate=res["rate"], annual_rate_vouched=res["rate_vouched"],
                       share_outside_vouched=res["share_outside"], annual_rate_low=res["rate_low"],
                       annual_rate_high=res["rate_high"],
                       annual_rate_se=_se(im, curve.rate, r["median"], r["beta"], mse, bse, r["im_min"],
                                          r["im_max"]),
                       probability=-math.expm1(-res["rate"] * years),
                       probability_low=-math.expm1(-res["rate_low"] * years),
                       probability_high=-math.expm1(-res["rate_high"] * years))
            out.append(row)
    out.sort(key=lambda row: (not np.isfinite(row["annual_rate"]), -np.nan_to_num(row["annual_rate"])))
    for rank, row in enumerate(out, start=1):
        row["rank"] = rank if np.isfinite(row["annual_rate"]) else ""
    return out


def write_risk_csv(rows, path):
    """Write :func:`risk_table`'s rows as CSV (:data:`RISK_COLUMNS`; empty cells for missing values).

    Returns: ``path``.
    """
    from screening.core.atomicfile import atomic_open

    def cell(v):
        if isinstance(v, float):
            return f"{v:.6g}" if math.isfinite(v) else ""
        return v

    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(RISK_COLUMNS)
        for r in rows:
            w.writerow([cell(r.get(c, "")) for c in RISK_COLUMNS])
    return path


def limit_state_fragilities(ds, im="pga", period=None, thresholds=(), relative_to=None):
    """The fragilities of a sweep result over ``im``: overturning (where it stores ``p_overturn``) and the
    exceedance of each threshold (one dataset on ``limit_state``).

    Units: ``im`` [m s-2], ``period`` [s], ``thresholds`` [rad].

    Returns: :func:`~screening.applications.im_fragility.fragility_over_im` of each limit state; empty when
    the result has neither.
    """
    frags = []
    if "p_overturn" in ds.variables:
        frags.append(fragility_over_im(ds, 1.0, im, period=period, limit_state="overturn")[0])
    if len(thresholds):
        thresholds = sorted(float(t) for t in thresholds)
        frags.append(stack_limit_states([fragility_over_im(ds, t, im, relative_to=relative_to, period=period)[0]
                                         for t in thresholds], thresholds, relative_to))
    return frags
