"""Speed–accuracy trade study: stochastic linearization (SL) vs Monte Carlo (condensed, coupled).

Users choose between three methods for the second-order rocking statistics:

* **SL** — stochastic linearization + Lyapunov moment equations of the condensed SDOF
  (:func:`screening.solvers.moments.solve_moments`), ~1 ms per point;
* **condensed MCS** — Monte Carlo on the same condensed SDOF (eq. 22), which isolates the
  *linearization* error of SL (SL vs condensed MCS);
* **coupled MCS** — Monte Carlo on the full coupled rocking/vertical model (eqs. 7–8), the
  judge; condensed vs coupled MCS (same input samples, same seed) is the *condensation* error.

This module makes the choice measurable.  A study file (TOML, see
``studies/speed_accuracy.toml`` and :func:`parse_tradeoff_study`) defines the block, the bed,
a grid of excitation *families* x cubic parameters ``eps`` x intensities (given as ``S0`` or as
target SL peak uplift probabilities, calibrated by bisection on SL), the sample counts and
tolerances.  :func:`run_tradeoff` then measures, at every point, the errors of SL and of
condensed MCS against coupled MCS, with the Monte Carlo standard errors, the cost of each
method in seconds per point on one core, how the MCS error and cost move with the sample
count and the integrator tolerance at representative points, and how SL's numerical error
and cost move with its tolerance and maximum step.  It writes

* ``<out_dir>/<stem>.nc`` — every number, labelled, with units;
* ``<out_dir>/<stem>.md`` and ``<stem>.csv`` — the trade tables;
* ``<out_dir>/<stem>_error_vs_cost.png`` and ``<stem>_validity.png`` — the plots;

and derives a validity rule (e.g. "SL within 10 % of condensed MCS when SL peak p_uplift < X")
from the data.

Error metrics (pure functions, NaN-aware, on a common time grid ``t`` [s]):

* peak relative error ``max_t a / max_t b - 1`` (:func:`peak_relative_error`);
* time-averaged relative error ``int |a - b| dt / int |b| dt`` over the part of the record
  where both are defined (:func:`time_averaged_relative_error`);
* significance: a peak difference is significant when ``|diff| > 2 SE``
  (:func:`is_significant`), with ``SE`` the Monte Carlo standard error of the peak
  (the sum in quadrature for MCS vs MCS — conservative, as both use the same input samples
  and their errors are positively correlated); a time-averaged error is significant when it
  exceeds twice the time-averaged relative standard error ``int SE dt / int |b| dt``
  (pure sampling noise gives about 0.8 of it).

Monte Carlo statistics are over the samples that neither overturned nor diverged
(survivors); the overturned fraction is reported with every point.
"""

from __future__ import annotations

import argparse
import csv
import math
import numbers
import sys
import time
try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10: the same parser as the backport
    import tomli as tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from screening import __version__
from screening.model.excitation import Envelope, KanaiTajimi, WhiteNoise
from screening.solvers.moments import solve_moments
from screening.status import PointStatus

STATUS_MEANINGS = {int(s): s.name for s in PointStatus if s >= 0}
from screening.schema import PARAMETERS, TIME
from screening.model import Block, Foundation, WinklerFoundation
from screening.solvers.montecarlo import DEFAULT_RTOL as MCS_DEFAULT_RTOL
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.timegrid import output_times

METHODS = ("sl", "condensed_mcs", "coupled_mcs")
MCS_MODELS = ("condensed", "coupled")
#: (estimate, reference) method of each comparison.
COMPARISONS = {
    "sl_vs_coupled": ("sl", "coupled_mcs"),
    "sl_vs_condensed": ("sl", "condensed_mcs"),
    "condensed_vs_coupled": ("condensed_mcs", "coupled_mcs"),
}
QUANTITIES = ("var_theta", "var_theta_dot")
QUANTITY_UNITS = {"var_theta": "rad2", "var_theta_dot": "rad2 s-2"}
RULE_METRICS = ("peak", "time_avg", "worst")

_trapezoid = getattr(np, "trapezoid", None) or np.trapz     # numpy >= 2 renamed trapz


class TradeoffStudyError(ValueError):
    """A problem in a trade-study file; the message names the offending key."""


# ============================================================================ error metrics
def peak_with_se(values, se=None, axis=-1):
    """Peak ``max_t values`` over the finite entries and the standard error at the peak time.

    ``values`` [any unit] has time along ``axis``; ``se`` (same shape, same unit) is the
    standard error of each entry (None: the estimate is deterministic, SE 0).  Returns
    ``(peak, se_at_peak)``; both NaN where no entry is finite.
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
    """``estimate / reference - 1`` [1]; NaN where the reference is zero or not finite."""
    e = np.asarray(estimate, dtype=float)
    r = np.asarray(reference, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where((r != 0) & np.isfinite(r), e / r - 1.0, np.nan)
    return float(out) if out.ndim == 0 else out


def peak_relative_error(estimate, reference, axis=-1):
    """Relative error of the peak over time: ``max_t estimate / max_t reference - 1`` [1]."""
    return relative_difference(peak_with_se(estimate, axis=axis)[0], peak_with_se(reference, axis=axis)[0])


def _common_mask(a, b):
    return np.isfinite(a) & np.isfinite(b)


def time_averaged_relative_error(estimate, reference, t):
    """``int |estimate - reference| dt / int |reference| dt`` [1] (trapezoidal rule).

    Time runs along the last axis, on the grid ``t`` [s].  Only the instants where both
    histories are finite count (e.g. the part of the record where the Monte Carlo ensemble
    is defined); NaN if that leaves nothing or ``int |reference| = 0``.
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

    The noise floor of :func:`time_averaged_relative_error`: same mask (where ``reference``
    and, if given, ``estimate`` are finite).  Pure sampling noise gives a time-averaged
    error of about ``sqrt(2/pi) ~ 0.8`` times this value.
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
    """Standard errors added in quadrature, ``sqrt(sum se_i^2)`` (independent estimates;
    conservative for positively correlated ones such as two models on the same samples)."""
    return np.sqrt(sum(np.asarray(s, dtype=float) ** 2 for s in standard_errors))


def is_significant(difference, se, k=2.0):
    """``|difference| > k se``: the difference is larger than the sampling noise (default 2 SE).

    False where either is NaN.
    """
    d = np.abs(np.asarray(difference, dtype=float))
    s = np.asarray(se, dtype=float)
    out = np.isfinite(d) & np.isfinite(s) & (d > k * s)
    return bool(out) if out.ndim == 0 else out


def classify_error(error, relative_se, threshold, k=2.0):
    """Class of a relative error against a tolerance ``threshold`` [1].

    Returns ``"within"`` if ``|error| + k se <= threshold``, ``"outside"`` if
    ``|error| - k se > threshold``, ``"ambiguous"`` otherwise (the tolerance lies within
    ``k`` standard errors), and ``"undefined"`` for a NaN error.
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

    ``indicator`` [any unit] and boolean ``passed`` per point (a NaN error counts as failed).
    ``direction="below"``: returns ``(X, n_covered)`` with ``X`` the smallest indicator value
    among the failed points (``inf`` if none failed) and ``n_covered`` the number of points
    with ``indicator < X`` (all of which passed).  ``direction="above"``: ``X`` the largest
    indicator value among the failed points (``-inf`` if none) and the points with
    ``indicator > X``.
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
    """The error a validity rule is judged on: ``|peak|``, ``time_avg`` or the worse of the two."""
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


# ============================================================================ study file
@dataclass(frozen=True)
class Family:
    """An excitation family of the grid: points = ``eps`` x intensities.

    ``kind`` "white" or "kanai_tajimi" (``omega_g`` [rad/s], ``zeta_g`` [1]); intensities as
    ``S0`` [m2 s-3] values or as ``target_peak_p_uplift`` [1] values (the S0 at which SL's
    peak uplift probability equals the target, rounded to 3 significant digits).
    """

    name: str
    kind: str
    eps: tuple
    omega_g: float = float("nan")
    zeta_g: float = float("nan")
    S0: tuple | None = None
    target_peak_p_uplift: tuple | None = None

    @property
    def n_intensities(self):
        return len(self.S0 if self.S0 is not None else self.target_peak_p_uplift)


@dataclass(frozen=True)
class TradeoffStudy:
    """A validated trade study (see :func:`parse_tradeoff_study` for the keys and units)."""

    title: str
    block: dict
    foundation: dict
    envelope: dict
    t_end: float
    dt: float
    families: tuple
    sl: dict
    mcs: dict
    convergence: dict
    rule: dict
    source: str = "<string>"
    text: str = ""


_TOP = ("title", "description", "block", "foundation", "excitation", "time", "family", "sl", "mcs",
        "convergence", "rule")
_BLOCK = ("m", "b", "h", "I_cm", "g")
_FOUNDATION = ("contact", "k", "lam", "c")
_EXCITATION = ("envelope", "T1", "T2")
_TIME = ("t_end", "dt")
_FAMILY = ("name", "kind", "omega_g", "zeta_g", "eps", "S0", "target_peak_p_uplift")
_SL = ("rtol", "rtol_sweep", "h_max_sweep", "reference_rtol", "timing_repeats", "calibration_rtol")
_MCS = ("samples", "seed", "threads", "rtol_coupled", "rtol_condensed", "h_max", "chunk_size")
_CONVERGENCE = ("points", "samples", "rtol_factors", "rtol_samples", "models")
_POINT = ("family", "eps", "index")
_RULE = ("thresholds", "metric", "quantity")


def _fail(key, message):
    raise TradeoffStudyError(f"key '{key}': {message}")


def _check_keys(table, allowed, where):
    if not isinstance(table, dict):
        _fail(where, f"must be a table (got {type(table).__name__})")
    for key in table:
        if key not in allowed:
            full = f"{where}.{key}" if where else key
            _fail(full, f"unknown key; allowed: {', '.join(allowed)}")


def _number(value, key, lower=None, inclusive=False, upper=None, integer=False):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        _fail(key, f"must be a number (got {value!r})")
    if integer and (not isinstance(value, numbers.Integral)):
        _fail(key, f"must be an integer (got {value!r})")
    v = int(value) if integer else float(value)
    if not math.isfinite(v):
        _fail(key, f"must be finite (got {value!r})")
    if lower is not None and (v < lower or (v == lower and not inclusive)):
        _fail(key, f"must be {'>=' if inclusive else '>'} {lower:g} (got {value!r})")
    if upper is not None and v > upper:
        _fail(key, f"must be <= {upper:g} (got {value!r})")
    return v


def _number_list(value, key, **kw):
    if not isinstance(value, list) or not value:
        _fail(key, f"must be a non-empty list of numbers (got {value!r})")
    return tuple(_number(v, f"{key}[{i}]", **kw) for i, v in enumerate(value))


def _string(value, key, choices=None):
    if not isinstance(value, str) or not value:
        _fail(key, f"must be a non-empty string (got {value!r})")
    if choices is not None and value not in choices:
        _fail(key, f"must be one of {', '.join(choices)} (got {value!r})")
    return value


def _required(table, key, where):
    if key not in table:
        _fail(f"{where}.{key}", "is required")
    return table[key]


def _parse_family(raw, i):
    where = f"family[{i}]"
    _check_keys(raw, _FAMILY, where)
    name = _string(_required(raw, "name", where), f"{where}.name")
    kind = _string(_required(raw, "kind", where), f"{where}.kind", ("white", "kanai_tajimi"))
    omega_g = zeta_g = float("nan")
    if kind == "kanai_tajimi":
        omega_g = _number(_required(raw, "omega_g", where), f"{where}.omega_g", lower=0.0)
        zeta_g = _number(_required(raw, "zeta_g", where), f"{where}.zeta_g", lower=0.0)
    else:
        for key in ("omega_g", "zeta_g"):
            if key in raw:
                _fail(f"{where}.{key}", "applies only to kind = \"kanai_tajimi\"")
    eps = _number_list(_required(raw, "eps", where), f"{where}.eps")
    has_s0, has_target = "S0" in raw, "target_peak_p_uplift" in raw
    if has_s0 == has_target:
        _fail(f"{where}.S0", "give exactly one of 'S0' and 'target_peak_p_uplift'")
    S0 = _number_list(raw["S0"], f"{where}.S0", lower=0.0) if has_s0 else None
    target = (_number_list(raw["target_peak_p_uplift"], f"{where}.target_peak_p_uplift", lower=0.0, upper=0.99)
              if has_target else None)
    return Family(name=name, kind=kind, eps=eps, omega_g=omega_g, zeta_g=zeta_g, S0=S0,
                  target_peak_p_uplift=target)


def _parse_point(raw, i, families):
    where = f"convergence.points[{i}]"
    _check_keys(raw, _POINT, where)
    fam_name = _string(_required(raw, "family", where), f"{where}.family", [f.name for f in families])
    fam = next(f for f in families if f.name == fam_name)
    eps = _number(_required(raw, "eps", where), f"{where}.eps")
    if eps not in fam.eps:
        _fail(f"{where}.eps", f"must be one of the eps of family '{fam_name}' {list(fam.eps)} (got {eps!r})")
    index = _number(_required(raw, "index", where), f"{where}.index", lower=0, inclusive=True, integer=True)
    if index >= fam.n_intensities:
        _fail(f"{where}.index", f"must be < {fam.n_intensities}, the number of intensities of family "
                                f"'{fam_name}' (got {index})")
    return (fam_name, eps, index)


def parse_tradeoff_study(text, source="<string>"):
    """Parse and validate a trade-study TOML text; :class:`TradeoffStudyError` names any bad key.

    Keys (SI units):

    * ``title``; ``[block]`` ``m`` [kg], ``b`` [m] (half-width), ``h`` [m] (centre-of-mass
      height), optional ``I_cm`` [kg m2], ``g`` [m s-2];
    * ``[foundation]`` ``contact`` ("hunt_crossley" with ``lam`` [N s m-4] or "winkler" with
      ``c`` [N s m-2]), ``k`` [N m-2];
    * ``[excitation]`` ``envelope = "exponential"``, ``T1``, ``T2`` [s] (shared by all families);
    * ``[time]`` ``t_end``, ``dt`` [s];
    * ``[[family]]`` (one or more): ``name``, ``kind``, ``omega_g`` [rad s-1] and ``zeta_g`` [1]
      for Kanai–Tajimi, ``eps`` [m-2] list, and either ``S0`` [m2 s-3] list or
      ``target_peak_p_uplift`` [1] list;
    * ``[sl]`` ``rtol``, ``rtol_sweep`` (list), ``h_max_sweep`` [s] (list), ``reference_rtol``,
      ``timing_repeats``, optional ``calibration_rtol``;
    * ``[mcs]`` ``samples``, ``seed``, ``threads`` (numba threads while timing), optional
      ``rtol_coupled``, ``rtol_condensed``, ``h_max`` [s], ``chunk_size``;
    * ``[convergence]`` ``points`` (list of ``{family, eps, index}``), ``samples`` (list; its
      largest value is the reference), ``rtol_factors`` (list, must include 1), ``rtol_samples``
      (one of ``samples``), ``models`` (subset of "coupled", "condensed");
    * ``[rule]`` ``thresholds`` [1] (list), ``metric`` ("peak", "time_avg" or "worst"),
      ``quantity`` ("var_theta" or "var_theta_dot").
    """
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise TradeoffStudyError(f"{source}: TOML syntax error: {exc}") from None
    _check_keys(raw, _TOP, "")
    title = raw.get("title", "speed-accuracy trade study")
    if not isinstance(title, str):
        _fail("title", "must be a string")

    blk = raw.get("block", {})
    _check_keys(blk, _BLOCK, "block")
    block = {k: _number(_required(blk, k, "block"), f"block.{k}", lower=0.0) for k in ("m", "b", "h")}
    for k in ("I_cm", "g"):
        if k in blk:
            block[k] = _number(blk[k], f"block.{k}", lower=0.0)

    fnd = raw.get("foundation", {})
    _check_keys(fnd, _FOUNDATION, "foundation")
    contact = _string(fnd.get("contact", "hunt_crossley"), "foundation.contact", ("hunt_crossley", "winkler"))
    damp_key = "lam" if contact == "hunt_crossley" else "c"
    other = "c" if damp_key == "lam" else "lam"
    if other in fnd:
        _fail(f"foundation.{other}", f"does not apply to contact = \"{contact}\" (use '{damp_key}')")
    foundation = {"contact": contact,
                  "k": _number(_required(fnd, "k", "foundation"), "foundation.k", lower=0.0),
                  damp_key: _number(_required(fnd, damp_key, "foundation"), f"foundation.{damp_key}",
                                    lower=0.0, inclusive=True)}

    exc = raw.get("excitation", {})
    _check_keys(exc, _EXCITATION, "excitation")
    _string(exc.get("envelope", "exponential"), "excitation.envelope", ("exponential",))
    envelope = {"T1": _number(exc.get("T1", 4.0), "excitation.T1", lower=0.0),
                "T2": _number(exc.get("T2", 2.0), "excitation.T2", lower=0.0)}
    if envelope["T2"] >= envelope["T1"]:
        _fail("excitation.T2", f"must be smaller than T1 (got T1={envelope['T1']}, T2={envelope['T2']})")

    tim = raw.get("time", {})
    _check_keys(tim, _TIME, "time")
    t_end = _number(tim.get("t_end", 20.0), "time.t_end", lower=0.0)
    dt = _number(tim.get("dt", 0.05), "time.dt", lower=0.0)
    try:
        output_times(t_end, dt)
    except ValueError as err:
        _fail("time.dt", str(err))

    fams_raw = raw.get("family")
    if not isinstance(fams_raw, list) or not fams_raw:
        _fail("family", "at least one [[family]] table is required")
    families = tuple(_parse_family(f, i) for i, f in enumerate(fams_raw))
    names = [f.name for f in families]
    if len(set(names)) != len(names):
        _fail("family.name", f"family names must be unique (got {names})")

    sl_raw = raw.get("sl", {})
    _check_keys(sl_raw, _SL, "sl")
    sl = {
        "rtol": _number(sl_raw.get("rtol", 1e-7), "sl.rtol", lower=0.0, upper=1e-2),
        "rtol_sweep": _number_list(sl_raw.get("rtol_sweep", [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9]),
                                   "sl.rtol_sweep", lower=0.0, upper=1e-2),
        "h_max_sweep": _number_list(sl_raw.get("h_max_sweep", [1.0, 0.1, 0.02]), "sl.h_max_sweep", lower=0.0),
        "reference_rtol": _number(sl_raw.get("reference_rtol", 1e-11), "sl.reference_rtol", lower=0.0,
                                  upper=1e-2),
        "timing_repeats": _number(sl_raw.get("timing_repeats", 10), "sl.timing_repeats", lower=1,
                                  inclusive=True, integer=True),
        "calibration_rtol": _number(sl_raw.get("calibration_rtol", 1e-7), "sl.calibration_rtol", lower=0.0,
                                    upper=1e-2),
    }

    mc_raw = raw.get("mcs", {})
    _check_keys(mc_raw, _MCS, "mcs")
    mcs = {
        "samples": _number(mc_raw.get("samples", 1000), "mcs.samples", lower=2, inclusive=True, integer=True),
        "seed": _number(mc_raw.get("seed", 0), "mcs.seed", lower=0, inclusive=True, integer=True),
        "threads": _number(mc_raw.get("threads", 1), "mcs.threads", lower=1, inclusive=True, integer=True),
        "rtol_coupled": _number(mc_raw.get("rtol_coupled", MCS_DEFAULT_RTOL["coupled"]), "mcs.rtol_coupled",
                                lower=0.0, upper=1e-2),
        "rtol_condensed": _number(mc_raw.get("rtol_condensed", MCS_DEFAULT_RTOL["condensed"]),
                                  "mcs.rtol_condensed", lower=0.0, upper=1e-2),
    }
    for key in ("h_max",):
        if key in mc_raw:
            mcs[key] = _number(mc_raw[key], f"mcs.{key}", lower=0.0)
    if "chunk_size" in mc_raw:
        mcs["chunk_size"] = _number(mc_raw["chunk_size"], "mcs.chunk_size", lower=1, inclusive=True, integer=True)

    cv_raw = raw.get("convergence", {})
    _check_keys(cv_raw, _CONVERGENCE, "convergence")
    pts_raw = cv_raw.get("points", [])
    if not isinstance(pts_raw, list):
        _fail("convergence.points", "must be a list of {family, eps, index} tables")
    points = tuple(_parse_point(p, i, families) for i, p in enumerate(pts_raw))
    if len(set(points)) != len(points):
        _fail("convergence.points", "points must be distinct")
    samples = tuple(sorted(set(_number_list(cv_raw.get("samples", [100, 300, 1000, 3000]), "convergence.samples",
                                            lower=2, inclusive=True, integer=True))))
    factors = tuple(sorted(set(_number_list(cv_raw.get("rtol_factors", [1.0 / 32.0, 1.0, 32.0]),
                                            "convergence.rtol_factors", lower=0.0))))
    if 1.0 not in factors:
        _fail("convergence.rtol_factors", "must include 1 (the default tolerance)")
    rtol_samples = _number(cv_raw.get("rtol_samples", samples[0]), "convergence.rtol_samples", lower=2,
                           inclusive=True, integer=True)
    if rtol_samples not in samples:
        _fail("convergence.rtol_samples", f"must be one of convergence.samples {list(samples)} (got {rtol_samples})")
    models = cv_raw.get("models", list(MCS_MODELS))
    if not isinstance(models, list) or not models:
        _fail("convergence.models", "must be a non-empty list")
    models = tuple(_string(m, f"convergence.models[{i}]", MCS_MODELS) for i, m in enumerate(models))
    for model in models:
        key = f"rtol_{model}"
        if max(factors) * mcs[key] > 1e-2:
            _fail("convergence.rtol_factors", f"largest factor x mcs.{key} exceeds 1e-2")
    convergence = {"points": points, "samples": samples, "rtol_factors": factors, "rtol_samples": rtol_samples,
                   "models": models}

    ru_raw = raw.get("rule", {})
    _check_keys(ru_raw, _RULE, "rule")
    rule = {"thresholds": tuple(sorted(_number_list(ru_raw.get("thresholds", [0.10, 0.25]), "rule.thresholds",
                                                    lower=0.0))),
            "metric": _string(ru_raw.get("metric", "peak"), "rule.metric", RULE_METRICS),
            "quantity": _string(ru_raw.get("quantity", "var_theta"), "rule.quantity", QUANTITIES)}

    return TradeoffStudy(title=title, block=block, foundation=foundation, envelope=envelope, t_end=t_end, dt=dt,
                         families=families, sl=sl, mcs=mcs, convergence=convergence, rule=rule, source=source,
                         text=text)


def load_tradeoff_study(path):
    """Read and validate a trade-study file (see :func:`parse_tradeoff_study`)."""
    path = Path(path)
    return parse_tradeoff_study(path.read_text(encoding="utf-8"), source=str(path))


# ============================================================================ model set-up
def make_block(study):
    """The study's :class:`~screening.model.Block`."""
    return Block(**study.block)


def make_foundation(study, eps):
    """The study's bed with cubic parameter ``eps`` [m-2]."""
    f = dict(study.foundation)
    contact = f.pop("contact")
    return Foundation(eps=eps, **f) if contact == "hunt_crossley" else WinklerFoundation(eps=eps, **f)


def make_excitation(study, family, S0):
    """Excitation of ``family`` at intensity ``S0`` [m2 s-3] (two-sided PSD level)."""
    env = Envelope(study.envelope["T1"], study.envelope["T2"])
    if family.kind == "white":
        return WhiteNoise(S0, env)
    return KanaiTajimi(S0, family.omega_g, family.zeta_g, env)


def round_significant(x, digits=3):
    """``x`` rounded to ``digits`` significant digits."""
    if x == 0 or not math.isfinite(x):
        return x
    return float(f"{x:.{digits - 1}e}")


def calibrate_intensity(block, foundation, make_exc, target, t_out, rtol=1e-7, log10_bounds=(-10.0, 1.0)):
    """``S0`` [m2 s-3] at which SL's peak uplift probability equals ``target`` [1].

    Bisection (Brent) on ``log10 S0`` of ``log(peak_p_uplift) - log(target)``; a point whose
    SL integration stops (status != ok) counts as ``peak_p_uplift = 1``.  The result is
    rounded to 3 significant digits and must give status ok and a peak uplift probability
    within 10 % of the target, else ValueError.  ``make_exc(S0)`` builds the excitation.
    """
    from scipy.optimize import brentq

    def solve(log_s0):
        r = solve_moments(block, foundation, make_exc(10.0 ** log_s0), t_out, rtol=rtol)
        return int(r["status"]), float(r["peak_p_uplift"])

    def f(log_s0):
        status, p = solve(log_s0)
        p = 1.0 if status != 0 else max(p, 1e-300)
        return math.log(p) - math.log(target)

    lo, hi = log10_bounds
    if f(lo) >= 0 or f(hi) <= 0:
        raise ValueError(f"target_peak_p_uplift {target:g} is not bracketed by S0 in "
                         f"[1e{lo:g}, 1e{hi:g}] m2 s-3")
    x = brentq(f, lo, hi, xtol=1e-6)
    S0 = round_significant(10.0 ** x)
    status, p = solve(math.log10(S0))
    if status != 0 or abs(p / target - 1.0) > 0.1:
        raise ValueError(f"target_peak_p_uplift {target:g} is not reachable with SL status ok "
                         f"(at S0 = {S0:.3g}: status {STATUS_MEANINGS.get(status, status)}, peak p_uplift {p:.3g})")
    return S0


@dataclass(frozen=True)
class Point:
    """One grid point of the trade study."""

    name: str
    family: str
    kind: str
    omega_g: float
    zeta_g: float
    eps: float
    S0: float
    target: float
    index: int


def build_points(study, progress=None):
    """Expand the families into :class:`Point`s (calibrating intensities given as targets)."""
    block = make_block(study)
    t_out = output_times(study.t_end, study.dt)
    points = []
    for fam in study.families:
        for eps in fam.eps:
            bed = make_foundation(study, eps)
            for i in range(fam.n_intensities):
                if fam.S0 is not None:
                    S0, target = fam.S0[i], float("nan")
                else:
                    target = fam.target_peak_p_uplift[i]
                    try:
                        S0 = calibrate_intensity(block, bed, lambda s, fam=fam: make_excitation(study, fam, s),
                                                 target, t_out, rtol=study.sl["calibration_rtol"])
                    except ValueError as err:
                        raise TradeoffStudyError(f"key 'family[{study.families.index(fam)}]."
                                                 f"target_peak_p_uplift[{i}]' (family '{fam.name}', "
                                                 f"eps={eps:g}): {err}") from None
                label = f"p{target:g}" if fam.S0 is None else f"S0={S0:.3g}"
                points.append(Point(name=f"{fam.name} eps={eps:g} {label}", family=fam.name, kind=fam.kind,
                                    omega_g=fam.omega_g, zeta_g=fam.zeta_g, eps=float(eps), S0=float(S0),
                                    target=float(target), index=i))
                if progress:
                    progress(f"point {len(points)}: {points[-1].name}: S0 = {S0:.3g} m2 s-3")
    return points


def point_models(study, point):
    """``(block, foundation, excitation)`` of a :class:`Point`."""
    fam = next(f for f in study.families if f.name == point.family)
    return make_block(study), make_foundation(study, point.eps), make_excitation(study, fam, point.S0)


# ============================================================================ measurements
def time_call(fn, repeats=1):
    """``(result of the last call, median wall time [s] over repeats)``."""
    times = []
    result = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return result, float(np.median(times))


def run_sl(study, point, t_out, rtol=None, h_max=None, repeats=1):
    """SL at one point via :func:`~screening.solvers.moments.solve_moments`; ``(result dict, seconds)``."""
    block, bed, exc = point_models(study, point)
    rtol = study.sl["rtol"] if rtol is None else rtol
    return time_call(lambda: solve_moments(block, bed, exc, t_out, rtol=rtol, h_max=h_max), repeats)


def run_mcs(study, point, model, n_samples, rtol_factor=1.0):
    """Monte Carlo at one point: ``(dataset, wall seconds)`` (same seed for both models)."""
    block, bed, exc = point_models(study, point)
    numerics = {"rtol": rtol_factor * study.mcs[f"rtol_{model}"]}
    for key in ("h_max", "chunk_size"):
        if key in study.mcs:
            numerics[key] = study.mcs[key]
    return time_call(lambda: monte_carlo(block, bed, exc, n_samples=n_samples, model=model, t_end=study.t_end,
                                         dt=study.dt, seed=study.mcs["seed"], progress=False, **numerics))


def warm_up(study):
    """Compile (or load from cache) the SL and MCS kernels so that no timing includes it."""
    fam = study.families[0]
    pt = Point("warm-up", fam.name, fam.kind, fam.omega_g, fam.zeta_g, fam.eps[0], 1e-6, float("nan"), 0)
    block, bed, exc = point_models(study, pt)
    t_short = output_times(study.dt * 4, study.dt)
    solve_moments(block, bed, exc, t_short)
    for model in MCS_MODELS:
        monte_carlo(block, bed, exc, n_samples=2, model=model, t_end=study.dt * 4, dt=study.dt, progress=False)


def set_threads(n):
    """Limit numba to ``n`` threads (cost per core); returns the previous setting."""
    import numba
    previous = numba.get_num_threads()
    numba.set_num_threads(min(int(n), numba.config.NUMBA_NUM_THREADS))
    return previous


def _history(ds, name):
    return np.asarray(ds[name].values, dtype=float)


def compare(estimate, reference, t, est_se=None, ref_se=None):
    """All error measures of one history against a reference, as a dict (units [1]).

    ``peak_rel_error``, ``peak_rel_se`` (SE of the difference of the peaks over the reference
    peak), ``peak_significant`` (``|diff| > 2 SE``), ``time_avg_rel_error``,
    ``time_avg_rel_se`` (noise floor) and ``time_avg_significant`` (error > 2 x floor).
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


def _log(progress, msg):
    if progress:
        progress(msg)


def _stderr(msg):
    print(f"[tradeoff] {msg}", file=sys.stderr, flush=True)


def measure_grid(study, points, t_out, progress=None):
    """SL and both MCS models at every point: histories, costs and overturning counts."""
    n, nt = len(points), t_out.size
    hist = {q: np.full((len(METHODS), n, nt), np.nan) for q in QUANTITIES}
    se = {q: np.full((len(METHODS), n, nt), np.nan) for q in QUANTITIES}
    p_upl = np.full((len(METHODS), n, nt), np.nan)
    cost = np.full((len(METHODS), n), np.nan)
    n_over = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    n_div = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    n_used = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    sl_status = np.zeros(n, dtype=np.int8)
    sl_peak_p = np.full(n, np.nan)
    sl_margin = np.full(n, np.nan)
    sl_min_k = np.full(n, np.nan)
    sl_k0 = np.full(n, np.nan)
    mcs_runs = {}
    for j, pt in enumerate(points):
        res, sec = run_sl(study, pt, t_out, repeats=study.sl["timing_repeats"])
        hist["var_theta"][0, j] = res["var_theta"]
        hist["var_theta_dot"][0, j] = res["var_theta_dot"]
        p_upl[0, j] = res["p_uplift"]
        cost[0, j] = sec
        sl_status[j] = res["status"]
        sl_peak_p[j] = res["peak_p_uplift"]
        sl_min_k[j] = res["min_k_eq"]
        sl_k0[j] = res["k_eq"][0]
        sl_margin[j] = res["min_k_eq"] / res["k_eq"][0]
        for m, model in enumerate(MCS_MODELS):
            ds, sec = run_mcs(study, pt, model, study.mcs["samples"])
            mcs_runs[(j, model)] = (ds, sec)
            row = 1 + m
            for q in QUANTITIES:
                hist[q][row, j] = _history(ds, q)
                se[q][row, j] = _history(ds, q + "_se")
            p_upl[row, j] = _history(ds, "p_uplift")
            cost[row, j] = sec
            n_over[m, j], n_div[m, j], n_used[m, j] = int(ds.n_overturned), int(ds.n_diverged), int(ds.n_used)
            _log(progress, f"{j + 1}/{n} {pt.name}: {model} MCS {sec:.1f} s, overturned {n_over[m, j]}")
    return {"hist": hist, "se": se, "p_uplift": p_upl, "cost": cost, "n_overturned": n_over,
            "n_diverged": n_div, "n_used": n_used, "sl_status": sl_status, "sl_peak_p_uplift": sl_peak_p,
            "sl_margin": sl_margin, "sl_min_k_eq": sl_min_k, "sl_k_eq0": sl_k0, "mcs_runs": mcs_runs}


def grid_errors(grid, t_out):
    """:func:`compare` for every comparison x quantity x point; dict of arrays."""
    n = grid["cost"].shape[1]
    keys = ("peak_estimate", "peak_reference", "peak_rel_error", "peak_rel_se", "peak_significant",
            "time_avg_rel_error", "time_avg_rel_se", "time_avg_significant")
    out = {k: np.full((len(COMPARISONS), len(QUANTITIES), n), np.nan) for k in keys}
    for c, (est, ref) in enumerate(COMPARISONS.values()):
        ie, ir = METHODS.index(est), METHODS.index(ref)
        for iq, q in enumerate(QUANTITIES):
            for j in range(n):
                e_se = None if est == "sl" else grid["se"][q][ie, j]
                r = compare(grid["hist"][q][ie, j], grid["hist"][q][ir, j], t_out, est_se=e_se,
                            ref_se=grid["se"][q][ir, j])
                for k in keys:
                    out[k][c, iq, j] = r[k]
    for k in ("peak_significant", "time_avg_significant"):
        out[k] = out[k].astype(bool)
    return out


def measure_convergence(study, points, grid, t_out, progress=None):
    """MCS peak variance, SE and cost vs sample count and vs rtol factor at the chosen points."""
    cv = study.convergence
    idx = [next(j for j, p in enumerate(points) if (p.family, p.eps, p.index) == key) for key in cv["points"]]
    models, ns, factors = cv["models"], cv["samples"], cv["rtol_factors"]
    shape_n = (len(idx), len(models), len(ns))
    shape_f = (len(idx), len(models), len(factors))
    out = {name: np.full(shape_n, np.nan) for name in ("peak", "peak_se", "peak_dot", "peak_dot_se", "cost")}
    out["n_overturned"] = np.zeros(shape_n, dtype=np.int32)
    out.update({f"tol_{name}": np.full(shape_f, np.nan) for name in ("peak", "peak_se", "peak_dot", "cost")})
    out["tol_n_overturned"] = np.zeros(shape_f, dtype=np.int32)
    for a, j in enumerate(idx):
        for b, model in enumerate(models):
            runs = {}
            for c, n_s in enumerate(ns):
                if n_s == study.mcs["samples"]:
                    ds, sec = grid["mcs_runs"][(j, model)]
                else:
                    ds, sec = run_mcs(study, points[j], model, n_s)
                    _log(progress, f"convergence {points[j].name}: {model} n={n_s} {sec:.1f} s")
                runs[n_s] = (ds, sec)
                out["peak"][a, b, c], out["peak_se"][a, b, c] = peak_with_se(_history(ds, "var_theta"),
                                                                             _history(ds, "var_theta_se"))
                out["peak_dot"][a, b, c], out["peak_dot_se"][a, b, c] = peak_with_se(
                    _history(ds, "var_theta_dot"), _history(ds, "var_theta_dot_se"))
                out["cost"][a, b, c] = sec
                out["n_overturned"][a, b, c] = int(ds.n_overturned)
            for c, f in enumerate(factors):
                if f == 1.0:
                    ds, sec = runs[cv["rtol_samples"]]
                else:
                    ds, sec = run_mcs(study, points[j], model, cv["rtol_samples"], rtol_factor=f)
                    _log(progress, f"tolerance {points[j].name}: {model} rtol x {f:g} {sec:.1f} s")
                out["tol_peak"][a, b, c], out["tol_peak_se"][a, b, c] = peak_with_se(
                    _history(ds, "var_theta"), _history(ds, "var_theta_se"))
                out["tol_peak_dot"][a, b, c] = peak_with_se(_history(ds, "var_theta_dot"))[0]
                out["tol_cost"][a, b, c] = sec
                out["tol_n_overturned"][a, b, c] = int(ds.n_overturned)
    out["point_index"] = np.array(idx)
    # SL at the same points (for biases against the largest-sample reference)
    out["sl_peak"] = np.array([peak_with_se(grid["hist"]["var_theta"][0, j])[0] for j in idx])
    return out


def measure_sl_numerics(study, points, t_out):
    """SL numerical error (vs ``reference_rtol``) and cost per point over rtol and h_max settings."""
    ref = [run_sl(study, p, t_out, rtol=study.sl["reference_rtol"])[0] for p in points]
    settings = [("rtol", r, None) for r in study.sl["rtol_sweep"]]
    settings += [("h_max", study.sl["rtol"], h) for h in study.sl["h_max_sweep"]]
    n = len(points)
    out = {k: np.full((len(settings), n), np.nan) for k in ("cost", "peak_err", "time_avg_err", "n_steps")}
    for s, (_, rtol, h_max) in enumerate(settings):
        for j, p in enumerate(points):
            res, sec = run_sl(study, p, t_out, rtol=rtol, h_max=h_max, repeats=study.sl["timing_repeats"])
            out["cost"][s, j] = sec
            out["n_steps"][s, j] = res["n_steps"]
            out["peak_err"][s, j] = relative_difference(res["peak_var_theta"], ref[j]["peak_var_theta"])
            out["time_avg_err"][s, j] = time_averaged_relative_error(res["var_theta"], ref[j]["var_theta"], t_out)
    # the whole grid in batched calls, one per family (per-point cost of the batched form)
    fam_costs = []
    for fam in study.families:
        sel = [p for p in points if p.family == fam.name]
        block = make_block(study)
        bed = make_foundation(study, np.array([p.eps for p in sel]))
        exc = make_excitation(study, fam, np.array([p.S0 for p in sel]))
        _, sec = time_call(lambda: solve_moments(block, bed, exc, t_out, rtol=study.sl["rtol"]),
                           study.sl["timing_repeats"])
        fam_costs.append((sec, len(sel)))
    batched = sum(s for s, _ in fam_costs) / sum(k for _, k in fam_costs)
    out["settings"] = settings
    out["batched_cost"] = batched
    return out


# ============================================================================ rules
def safe_indicator_range(indicator, passed, tie=0.05):
    """Conservative upper bound of a "safe below" region of an indicator, from tested points.

    ``indicator`` [any unit] and boolean ``passed`` per point.  Returns ``(p_safe, n_safe,
    i_fail)``: ``i_fail`` the index of the failing point with the smallest indicator (None if
    nothing failed); ``p_safe`` the largest indicator value of a passing point below that
    failure, where values within a relative ``tie`` of the failure count as the same tested
    level (so a level at which some points pass and some fail is not called safe); ``n_safe``
    the number of points with ``indicator <= p_safe`` (all passed).  ``p_safe`` is NaN when
    no tested level is safe.
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
    """Point groups a rule is derived for: ``"all"`` and, with 2–4 distinct ``eps``, one per bed."""
    eps = np.asarray(eps, dtype=float)
    groups = {"all": np.ones(eps.size, dtype=bool)}
    values = list(dict.fromkeys(eps.tolist()))
    if 2 <= len(values) <= 4:
        for v in values:
            groups[f"eps={v:g}"] = eps == v
    return groups


def derive_rules(ds, thresholds=(0.10, 0.25), metric="peak", quantity="var_theta", tie=0.05):
    """Validity rules of SL derived from a trade-study dataset.

    For each reference (condensed, coupled MCS), threshold [1] and point group
    (:func:`rule_groups`): the safe range of SL peak p_uplift (:func:`safe_indicator_range`)
    and of the k_eq margin (:func:`threshold_rule`, "above"), judged on :func:`rule_error`
    of ``quantity``.  Returns a list of dicts: ``reference``, ``threshold``, ``group``, ``n``,
    ``n_pass``, ``p_safe``, ``n_safe``, ``p_max`` (largest tested p), ``fail_p``,
    ``fail_name``, ``fail_error`` (the first failure in p), ``margin_bound``, ``n_margin``.
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


def rule_text(rule, metric, quantity):
    """One-line statement of a rule from :func:`derive_rules`."""
    what = {"peak": f"peak {quantity}", "time_avg": f"time-averaged {quantity}",
            "worst": f"peak and time-averaged {quantity}"}[metric]
    head = f"[{rule['group']}] SL within {rule['threshold']:.0%} of {rule['reference']} MCS ({what})"
    fail = (f"first failure at p = {rule['fail_p']:.2g} ({rule['fail_name']}: {100 * rule['fail_error']:+.0f} %)"
            if rule["fail_name"] else "")
    if not rule["fail_name"]:
        s = f"{head}: at every tested point ({rule['n']}, SL peak p_uplift up to {rule['p_max']:.2g})"
    elif rule["n_safe"] == 0:
        s = f"{head}: no safe p_uplift range - {fail}, the lowest tested level"
    else:
        s = (f"{head}: for SL peak p_uplift <= {rule['p_safe']:.2g} ({rule['n_safe']} tested points, all pass); "
             f"{fail}")
    s += f"; {rule['n_pass']}/{rule['n']} pass overall"
    if rule["fail_name"] and rule["n_margin"] > 0:
        s += f"; margin rule min_k_eq/k_eq(0) > {rule['margin_bound']:.2f} covers {rule['n_margin']} points"
    return s


def recommendation(rules):
    """The recommended screening rule in two sentences, from the ``all``-group rules.

    Uses the loosest threshold against coupled MCS (where SL alone is acceptable) and the
    tightest against condensed MCS (where the linearization itself is accurate).
    """
    def pick(ref, thr_fn):
        cands = [r for r in rules if r["group"] == "all" and r["reference"] == ref]
        if not cands:
            return None
        thr = thr_fn(r["threshold"] for r in cands)
        return next(r for r in cands if r["threshold"] == thr)

    def bound(r):
        if r is None:
            return "n/a"
        if not r["fail_name"]:
            return f"every tested SL peak p_uplift (up to {r['p_max']:.2g})"
        if r["n_safe"] == 0:
            return "no tested SL peak p_uplift"
        return f"SL peak p_uplift <= {r['p_safe']:.2g}"

    coup, cond = pick("coupled", max), pick("condensed", min)
    parts = []
    if coup is not None:
        parts.append(f"Use SL alone for {bound(coup)}: there it stays within {coup['threshold']:.0%} of coupled "
                     f"MCS at every tested point; beyond, check with coupled MCS")
    if cond is not None:
        parts.append(f"the linearization itself (SL vs condensed MCS) stays within {cond['threshold']:.0%} for "
                     f"{bound(cond)}; where SL misses coupled MCS inside that range, the error is the "
                     f"condensation's (condensed vs coupled MCS), not the linearization's")
    return "; ".join(parts) + "."


# ============================================================================ dataset
def _attrs(units, long_name, **extra):
    a = {"units": units, "long_name": long_name}
    a.update(extra)
    return a


def build_dataset(study, points, t_out, grid, errors, conv, numerics, wall_time):
    """Assemble every measurement in one labelled :class:`xarray.Dataset` (units attributes)."""
    n = len(points)
    coords = {
        "t": ("t", t_out, {k: v for k, v in TIME.items() if k != "axis"}),
        "approach": ("approach", list(METHODS),
                     {"long_name": "method: sl (stochastic linearization), condensed_mcs, coupled_mcs"}),
        "mcs_model": ("mcs_model", list(MCS_MODELS), {"long_name": "Monte Carlo model"}),
        "comparison": ("comparison", list(COMPARISONS),
                       {"long_name": "estimate_vs_reference", "note": "relative errors are estimate/reference - 1"}),
        "quantity": ("quantity", list(QUANTITIES), {"long_name": "response variance compared"}),
        "point": ("point", np.arange(n), {"long_name": "grid point index"}),
        "point_name": ("point", [p.name for p in points], {"long_name": "grid point label"}),
        "family": ("point", [p.family for p in points], {"long_name": "excitation family"}),
        "excitation_kind": ("point", [p.kind for p in points], {"long_name": "excitation kind"}),
        "eps": ("point", [p.eps for p in points], dict(PARAMETERS["eps"])),
        "S0": ("point", [p.S0 for p in points], dict(PARAMETERS["S0"])),
        "omega_g": ("point", [p.omega_g for p in points], dict(PARAMETERS["omega_g"], note="NaN for white noise")),
        "zeta_g": ("point", [p.zeta_g for p in points], dict(PARAMETERS["zeta_g"], note="NaN for white noise")),
        "target_peak_p_uplift": ("point", [p.target for p in points],
                                 _attrs("1", "target SL peak uplift probability used to calibrate S0")),
    }
    dv = {}
    for q in QUANTITIES:
        dv[q] = (("approach", "point", "t"), grid["hist"][q], _attrs(QUANTITY_UNITS[q], f"{q} by each method",
                                                                 note="MCS: over surviving samples"))
        dv[q + "_se"] = (("approach", "point", "t"), grid["se"][q],
                         _attrs(QUANTITY_UNITS[q], f"Monte Carlo standard error of {q} (NaN for sl)"))
    dv["p_uplift"] = (("approach", "point", "t"), grid["p_uplift"], _attrs("1", "uplift probability / occupancy"))
    dv["cost"] = (("approach", "point"), grid["cost"],
                  _attrs("s", "wall time per point on one core",
                         note=f"sl: median of {study.sl['timing_repeats']} single-point solve_moments calls; "
                              f"MCS: one monte_carlo call with {study.mcs['samples']} samples, "
                              f"{study.mcs['threads']} numba thread(s)"))
    dv["n_overturned"] = (("mcs_model", "point"), grid["n_overturned"], _attrs("1", "overturned samples"))
    dv["n_diverged"] = (("mcs_model", "point"), grid["n_diverged"], _attrs("1", "diverged samples"))
    dv["n_used"] = (("mcs_model", "point"), grid["n_used"], _attrs("1", "samples in the statistics (survivors)"))
    dv["overturned_fraction"] = (("mcs_model", "point"), grid["n_overturned"] / study.mcs["samples"],
                                 _attrs("1", "fraction of samples that overturned (statistics are over survivors)"))
    dv["sl_status"] = (("point",), grid["sl_status"],
                       {"long_name": "SL solver status",
                        "flag_values": np.array(sorted(STATUS_MEANINGS), dtype=np.int8),
                        "flag_meanings": " ".join(STATUS_MEANINGS[k] for k in sorted(STATUS_MEANINGS))})
    dv["sl_peak_p_uplift"] = (("point",), grid["sl_peak_p_uplift"], _attrs("1", "SL peak uplift probability (eq. 58)"))
    dv["sl_min_k_eq"] = (("point",), grid["sl_min_k_eq"], _attrs("N m rad-1", "SL minimum equivalent stiffness"))
    dv["sl_k_eq0"] = (("point",), grid["sl_k_eq0"], _attrs("N m rad-1", "SL equivalent stiffness at t = 0"))
    dv["k_eq_margin"] = (("point",), grid["sl_margin"], _attrs("1", "min_k_eq / k_eq(t=0) from SL"))
    cq = ("comparison", "quantity", "point")
    err_meta = {
        "peak_rel_error": ("1", "relative error of the peak: max_t estimate / max_t reference - 1"),
        "peak_rel_se": ("1", "standard error of the peak difference / reference peak (quadrature for MCS vs MCS)"),
        "peak_significant": ("1", "1 if |peak difference| > 2 SE"),
        "time_avg_rel_error": ("1", "int |estimate - reference| dt / int |reference| dt where both are defined"),
        "time_avg_rel_se": ("1", "int SE dt / int |reference| dt (noise floor of time_avg_rel_error)"),
        "time_avg_significant": ("1", "1 if time_avg_rel_error > 2 time_avg_rel_se"),
    }
    for k, (u, ln) in err_meta.items():
        val = errors[k].astype(np.int8) if errors[k].dtype == bool else errors[k]
        dv[k] = (cq, val, _attrs(u, ln))
    for q in QUANTITIES:
        pk, pse = peak_with_se(grid["hist"][q], grid["se"][q])
        dv[f"peak_{q}"] = (("approach", "point"), pk, _attrs(QUANTITY_UNITS[q], f"peak over time of {q}"))
        dv[f"peak_{q}_se"] = (("approach", "point"), pse, _attrs(
            QUANTITY_UNITS[q], f"Monte Carlo standard error of peak_{q} (at the peak time; 0 for sl)"))
    # convergence sub-study
    cv = study.convergence
    coords["rep_point_index"] = ("rep_point", conv["point_index"].astype(np.int32),
                                 {"long_name": "grid point index of a representative point"})
    coords["rep_point_name"] = ("rep_point", [points[j].name for j in conv["point_index"]], {"long_name": "label"})
    coords["cv_model"] = ("cv_model", list(cv["models"]), {"long_name": "Monte Carlo model (convergence study)"})
    coords["n_samples"] = ("n_samples", np.array(cv["samples"], dtype=np.int32), _attrs("1", "Monte Carlo sample count"))
    coords["rtol_factor"] = ("rtol_factor", np.array(cv["rtol_factors"]),
                             _attrs("1", "factor on the model's default MCS rtol"))
    rn = ("rep_point", "cv_model", "n_samples")
    rf = ("rep_point", "cv_model", "rtol_factor")
    dv["cv_peak_var_theta"] = (rn, conv["peak"], _attrs("rad2", "MCS peak var_theta vs sample count"))
    dv["cv_peak_var_theta_se"] = (rn, conv["peak_se"], _attrs("rad2", "its standard error"))
    dv["cv_peak_var_theta_dot"] = (rn, conv["peak_dot"], _attrs("rad2 s-2", "MCS peak var_theta_dot"))
    dv["cv_peak_var_theta_dot_se"] = (rn, conv["peak_dot_se"], _attrs("rad2 s-2", "its standard error"))
    dv["cv_cost"] = (rn, conv["cost"], _attrs("s", "wall time per point, one core"))
    dv["cv_n_overturned"] = (rn, conv["n_overturned"], _attrs("1", "overturned samples"))
    ref = conv["peak"][:, :, -1:]
    dv["cv_deviation_vs_reference"] = (rn, conv["peak"] / ref - 1.0, _attrs(
        "1", "peak var_theta / peak at the largest sample count (same model) - 1",
        note="nested samples (same seed): the reference contains the smaller ensembles"))
    dv["cv_rel_se"] = (rn, conv["peak_se"] / conv["peak"], _attrs("1", "relative standard error of peak var_theta"))
    dv["tol_peak_var_theta"] = (rf, conv["tol_peak"], _attrs(
        "rad2", f"MCS peak var_theta vs tolerance ({cv['rtol_samples']} samples, same seed)"))
    dv["tol_peak_var_theta_se"] = (rf, conv["tol_peak_se"], _attrs("rad2", "its standard error"))
    dv["tol_cost"] = (rf, conv["tol_cost"], _attrs("s", "wall time per point, one core"))
    dv["tol_n_overturned"] = (rf, conv["tol_n_overturned"], _attrs("1", "overturned samples"))
    dv["tol_change_vs_tightest"] = (rf, conv["tol_peak"] / conv["tol_peak"][:, :, :1] - 1.0, _attrs(
        "1", "peak var_theta / peak at the tightest tolerance - 1 (paired samples)"))
    dv["cv_sl_peak_var_theta"] = (("rep_point",), conv["sl_peak"], _attrs("rad2", "SL peak var_theta"))
    # SL numerics
    coords["sl_setting"] = ("sl_setting", np.arange(len(numerics["settings"])), {"long_name": "SL numerics setting"})
    coords["sl_setting_kind"] = ("sl_setting", [s[0] for s in numerics["settings"]],
                                 {"long_name": "which parameter is varied"})
    coords["sl_rtol"] = ("sl_setting", [s[1] for s in numerics["settings"]], _attrs("1", "SL relative tolerance"))
    coords["sl_h_max"] = ("sl_setting", [np.nan if s[2] is None else s[2] for s in numerics["settings"]],
                          _attrs("s", "SL largest step (NaN: default t_end/20)"))
    sp = ("sl_setting", "point")
    dv["sl_cost"] = (sp, numerics["cost"], _attrs("s", "SL wall time per point (single-point call, median)"))
    dv["sl_n_steps"] = (sp, numerics["n_steps"], _attrs("1", "SL solver steps"))
    dv["sl_numerical_peak_error"] = (sp, numerics["peak_err"], _attrs(
        "1", f"SL peak var_theta / reference (rtol {study.sl['reference_rtol']:g}) - 1"))
    dv["sl_numerical_time_avg_error"] = (sp, numerics["time_avg_err"], _attrs(
        "1", "SL time-averaged relative error of var_theta vs the tight-tolerance reference"))
    dv["sl_batched_cost"] = ((), numerics["batched_cost"], _attrs("s", "SL wall time per point in batched calls"))
    attrs = {
        "title": study.title,
        "study_file": study.source,
        "study_toml": study.text,
        "screening_version": __version__,
        "intensity_convention": "E[xi(t) xi(s)] = 2 pi S0 delta(t - s), S0 two-sided PSD",
        "mcs_samples": study.mcs["samples"], "mcs_seed": study.mcs["seed"], "mcs_threads": study.mcs["threads"],
        "mcs_rtol_coupled": study.mcs["rtol_coupled"], "mcs_rtol_condensed": study.mcs["rtol_condensed"],
        "sl_rtol_default": study.sl["rtol"],
        "tol_samples": study.convergence["rtol_samples"],
        "statistics_note": "Monte Carlo moments are over surviving samples (neither overturned nor diverged); "
                           "condensed and coupled MCS use the same input samples (same seed)",
        "significance": "peak: |diff| > 2 SE; time-averaged: error > 2 x noise floor",
        "rule_metric": study.rule["metric"], "rule_quantity": study.rule["quantity"],
        "wall_time_s": float(wall_time),
        "block_m": study.block["m"], "block_b": study.block["b"], "block_h": study.block["h"],
        "foundation_contact": study.foundation["contact"], "foundation_k": study.foundation["k"],
        "envelope_T1": study.envelope["T1"], "envelope_T2": study.envelope["T2"],
        "t_end": study.t_end, "dt": study.dt,
    }
    if "lam" in study.foundation:
        attrs["foundation_lam"] = study.foundation["lam"]
    else:
        attrs["foundation_c"] = study.foundation["c"]
    return xr.Dataset(dv, coords=coords, attrs=attrs)


#: Dimensions labelled by strings in memory (``ds.sel(approach="sl")``); in the file they are
#: plain dimensions with a ``<dim>_name`` auxiliary coordinate (CF coordinate variables are numeric).
LABEL_DIMS = ("approach", "mcs_model", "comparison", "quantity", "cv_model")


def to_file_layout(ds):
    """The dataset as written: string-labelled dimensions -> ``<dim>_name`` auxiliary
    coordinates, integer index coordinates as int32, CF global attributes."""
    out = ds.copy()
    for d in LABEL_DIMS:
        if d in out.coords:
            attrs = dict(out[d].attrs)
            out = out.assign_coords({f"{d}_name": (d, out[d].values.astype(str), attrs)}).drop_vars(d)
    for name in ("point", "sl_setting"):
        if name in out.coords:
            out = out.assign_coords({name: (name, out[name].values.astype(np.int32), dict(out[name].attrs))})
    out.attrs["Conventions"] = "CF-1.8"
    out.attrs["label_coordinates"] = ("dimensions " + ", ".join(LABEL_DIMS) + " are labelled by the auxiliary "
                                      "coordinates <dim>_name (e.g. ds.swap_dims(approach='approach_name'))")
    out.attrs.setdefault("history", f"screening.analysis.tradeoff {__version__}: written by run_tradeoff")
    return out


def from_file_layout(ds):
    """Inverse of :func:`to_file_layout`: string labels back as dimension coordinates."""
    out = ds.copy()
    for d in LABEL_DIMS:
        name = f"{d}_name"
        if name in out.coords:
            attrs = dict(out[name].attrs)
            out = out.drop_vars(name).assign_coords({d: (d, out[name].values.astype(str), attrs)})
    return out


def file_encoding(ds):
    """netCDF encoding: no fill value on coordinates (CF 2.5.1), compression on the histories."""
    enc = {name: {"_FillValue": None} for name in ds.coords if ds[name].dtype.kind == "f"}
    for name in ("var_theta", "var_theta_dot", "var_theta_se", "var_theta_dot_se", "p_uplift"):
        enc[name] = {"zlib": True, "complevel": 4}
    return enc


# ============================================================================ tables
def _pct(x, sig=None):
    if x is None or not np.isfinite(x):
        return "n/a"
    s = f"{100 * x:+.0f} %"
    return s + ("*" if sig else "")


def _pct_abs(x, sig=None):
    if x is None or not np.isfinite(x):
        return "n/a"
    return f"{100 * x:.0f} %" + ("*" if sig else "")


def _sci(x, digits=3):
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


def point_rows(ds):
    """Per-point accuracy rows (list of dicts) for the markdown/CSV trade table."""
    rows = []
    comp = {c: i for i, c in enumerate(ds.comparison.values)}
    for j in range(ds.sizes["point"]):
        def err(c, q, kind="peak"):
            sel = dict(comparison=comp[c], quantity=QUANTITIES.index(q), point=j)
            if kind == "peak":
                return float(ds.peak_rel_error[sel]), bool(ds.peak_significant[sel])
            return float(ds.time_avg_rel_error[sel]), bool(ds.time_avg_significant[sel])

        vt = ds.var_theta.isel(point=j)
        se = ds.var_theta_se.isel(point=j)
        peaks = {m: peak_with_se(vt.sel(approach=m).values, se.sel(approach=m).values) for m in METHODS}
        row = {
            "point": str(ds.point_name.values[j]),
            "eps": float(ds.eps[j]), "S0": float(ds.S0[j]),
            "sl_peak_p_uplift": float(ds.sl_peak_p_uplift[j]), "k_eq_margin": float(ds.k_eq_margin[j]),
            "sl_status": STATUS_MEANINGS[int(ds.sl_status[j])],
            "coupled_overturned": float(ds.overturned_fraction.sel(mcs_model="coupled")[j]),
            "condensed_overturned": float(ds.overturned_fraction.sel(mcs_model="condensed")[j]),
            "sl_peak": peaks["sl"][0], "cond_peak": peaks["condensed_mcs"][0], "cond_se": peaks["condensed_mcs"][1],
            "coup_peak": peaks["coupled_mcs"][0], "coup_se": peaks["coupled_mcs"][1],
        }
        for c in COMPARISONS:
            for q in QUANTITIES:
                row[f"{c}_{q}_peak"], row[f"{c}_{q}_peak_sig"] = err(c, q)
            row[f"{c}_var_theta_tavg"], row[f"{c}_var_theta_tavg_sig"] = err(c, "var_theta", "tavg")
        for m in METHODS:
            row[f"cost_{m}"] = float(ds.cost.sel(approach=m)[j])
        rows.append(row)
    return rows


def write_csv(rows, path):
    """The per-point rows as CSV."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def cost_summary(ds):
    """Median / min / max cost per point of each method [s] and the ratios to SL."""
    out = {}
    for m in METHODS:
        c = ds.cost.sel(approach=m).values
        out[m] = (float(np.median(c)), float(np.min(c)), float(np.max(c)))
    out["sl_batched"] = (float(ds.sl_batched_cost),) * 3
    return out


def markdown_report(study, ds, rules):
    """The trade tables as markdown text."""
    rows = point_rows(ds)
    L = [f"# {study.title}", "",
         f"Study file `{study.source}`; screening {__version__}.  Records of {study.t_end:g} s, output step "
         f"{study.dt:g} s.  Monte Carlo: {study.mcs['samples']} samples, seed {study.mcs['seed']} (the same "
         f"input samples for both models), rtol coupled {study.mcs['rtol_coupled']:g} / condensed "
         f"{study.mcs['rtol_condensed']:g}, {study.mcs['threads']} numba thread(s).  SL rtol {study.sl['rtol']:g}.",
         "Relative errors are estimate / reference - 1 of the peak over the record; `*` = significant "
         "(|diff| > 2 SE of the Monte Carlo estimate(s)).  Time-averaged errors: int |a - b| dt / int b dt "
         "(`*` = above twice the sampling-noise floor).  MCS statistics are over survivors "
         "(see the overturned fraction).  Intensity convention E[xi(t) xi(s)] = 2 pi S0 delta(t - s).", "",
         "## Accuracy per point (peak var_theta)", "",
         "| point | S0 [m²/s³] | SL peak p_uplift | k_eq margin | coupled overturned | SL peak var_θ [rad²] "
         "| condensed MCS | coupled MCS | SL vs coupled | SL vs condensed | condensed vs coupled "
         "| time-avg SL vs coupled | time-avg SL vs condensed | var_θ̇: SL vs coupled | SL vs condensed "
         "| condensed vs coupled |",
         "|" + "---|" * 16]
    for r in rows:
        L.append(
            f"| {r['point']} | {_sci(r['S0'])} | {_sci(r['sl_peak_p_uplift'], 2)} | {r['k_eq_margin']:.2f} "
            f"| {r['coupled_overturned']:.1%} | {_sci(r['sl_peak'])} "
            f"| {_sci(r['cond_peak'])} ± {_sci(r['cond_se'], 1)} | {_sci(r['coup_peak'])} ± {_sci(r['coup_se'], 1)} "
            f"| {_pct(r['sl_vs_coupled_var_theta_peak'], r['sl_vs_coupled_var_theta_peak_sig'])} "
            f"| {_pct(r['sl_vs_condensed_var_theta_peak'], r['sl_vs_condensed_var_theta_peak_sig'])} "
            f"| {_pct(r['condensed_vs_coupled_var_theta_peak'], r['condensed_vs_coupled_var_theta_peak_sig'])} "
            f"| {_pct_abs(r['sl_vs_coupled_var_theta_tavg'], r['sl_vs_coupled_var_theta_tavg_sig'])} "
            f"| {_pct_abs(r['sl_vs_condensed_var_theta_tavg'], r['sl_vs_condensed_var_theta_tavg_sig'])} "
            f"| {_pct(r['sl_vs_coupled_var_theta_dot_peak'], r['sl_vs_coupled_var_theta_dot_peak_sig'])} "
            f"| {_pct(r['sl_vs_condensed_var_theta_dot_peak'], r['sl_vs_condensed_var_theta_dot_peak_sig'])} "
            f"| {_pct(r['condensed_vs_coupled_var_theta_dot_peak'], r['condensed_vs_coupled_var_theta_dot_peak_sig'])}"
            " |")
    # summary of errors
    comp = list(ds.comparison.values)
    L += ["", "## Error summary over the grid (|relative error| of peak var_θ)", "",
          "| comparison | median | max | points within 10 % | within 25 % | significant (> 2 SE) |",
          "|---|---|---|---|---|---|"]
    for c in comp:
        e = ds.peak_rel_error.sel(comparison=c, quantity="var_theta").values
        s = ds.peak_significant.sel(comparison=c, quantity="var_theta").values
        a = np.abs(e[np.isfinite(e)])
        L.append(f"| {c} | {np.median(a):.1%} | {np.max(a):.1%} | {int(np.sum(a <= 0.10))}/{e.size} "
                 f"| {int(np.sum(a <= 0.25))}/{e.size} | {int(np.sum(s))}/{e.size} |")
    # cost
    cs = cost_summary(ds)
    sl_med = cs["sl"][0]
    L += ["", "## Cost per point (one core)", "",
          "| method | median [s] | min [s] | max [s] | ratio to SL (median) |", "|---|---|---|---|---|"]
    labels = {"sl": "SL (single-point solve_moments)", "sl_batched": "SL (batched over a family)",
              "condensed_mcs": f"condensed MCS, {study.mcs['samples']} samples",
              "coupled_mcs": f"coupled MCS, {study.mcs['samples']} samples"}
    for m in ("sl", "sl_batched", "condensed_mcs", "coupled_mcs"):
        med, lo, hi = cs[m]
        L.append(f"| {labels[m]} | {med:.3g} | {lo:.3g} | {hi:.3g} | {med / sl_med:,.0f} |")
    L.append("")
    L.append(f"Cost ratio SL : condensed MCS : coupled MCS (medians) = 1 : {cs['condensed_mcs'][0] / sl_med:,.0f} : "
             f"{cs['coupled_mcs'][0] / sl_med:,.0f}.")
    # convergence
    L += ["", f"## Monte Carlo vs sample count (representative points; reference = {ds.n_samples.values[-1]} "
              "samples of the same model, nested: same seed)", "",
          "| point | model | samples | peak var_θ ± SE | rel. SE | deviation vs reference | cost [s] "
          "| overturned | bias vs coupled ref. | SL vs this ref. |", "|---|---|---|---|---|---|---|---|---|---|"]
    for a in range(ds.sizes["rep_point"]):
        coup_ref = (float(ds.cv_peak_var_theta.isel(rep_point=a, n_samples=-1).sel(cv_model="coupled"))
                    if "coupled" in ds.cv_model.values else float("nan"))
        for b, model in enumerate(ds.cv_model.values):
            ref_peak = float(ds.cv_peak_var_theta[a, b, -1])
            for c, n_s in enumerate(ds.n_samples.values):
                pk, se = float(ds.cv_peak_var_theta[a, b, c]), float(ds.cv_peak_var_theta_se[a, b, c])
                bias = relative_difference(pk, coup_ref) if c == ds.sizes["n_samples"] - 1 else float("nan")
                sl_b = relative_difference(float(ds.cv_sl_peak_var_theta[a]), ref_peak) if c == ds.sizes[
                    "n_samples"] - 1 else float("nan")
                L.append(f"| {ds.rep_point_name.values[a]} | {model} | {n_s} | {_sci(pk)} ± {_sci(se, 2)} "
                         f"| {se / pk:.1%} | {_pct(float(ds.cv_deviation_vs_reference[a, b, c]))} "
                         f"| {float(ds.cv_cost[a, b, c]):.2f} | {int(ds.cv_n_overturned[a, b, c])} "
                         f"| {_pct(bias)} | {_pct(sl_b)} |")
    L += ["", f"## Monte Carlo vs integrator tolerance ({study.convergence['rtol_samples']} samples, same seed: "
              "paired)", "",
          "| point | model | rtol | peak var_θ ± SE | change vs tightest | overturned | cost [s] |",
          "|---|---|---|---|---|---|---|"]
    for a in range(ds.sizes["rep_point"]):
        for b, model in enumerate(ds.cv_model.values):
            base = study.mcs[f"rtol_{model}"]
            for c, f in enumerate(ds.rtol_factor.values):
                pk, se = float(ds.tol_peak_var_theta[a, b, c]), float(ds.tol_peak_var_theta_se[a, b, c])
                L.append(f"| {ds.rep_point_name.values[a]} | {model} | {base * f:.3g} | {_sci(pk)} ± {_sci(se, 2)} "
                         f"| {float(ds.tol_change_vs_tightest[a, b, c]):+.2%} | {int(ds.tol_n_overturned[a, b, c])} "
                         f"| {float(ds.tol_cost[a, b, c]):.2f} |")
    L += ["", f"## SL numerics (error vs rtol = {study.sl['reference_rtol']:g}, all grid points)", "",
          "| setting | rtol | h_max [s] | median cost [ms] | median steps | max abs peak error "
          "| max time-avg error |", "|---|---|---|---|---|---|---|"]
    for s in range(ds.sizes["sl_setting"]):
        h = float(ds.sl_h_max[s])
        L.append(f"| {ds.sl_setting_kind.values[s]} | {float(ds.sl_rtol[s]):.0e} "
                 f"| {'default' if not np.isfinite(h) else f'{h:g}'} "
                 f"| {1e3 * float(np.median(ds.sl_cost[s])):.2f} | {float(np.median(ds.sl_n_steps[s])):.0f} "
                 f"| {float(np.max(np.abs(ds.sl_numerical_peak_error[s]))):.1e} "
                 f"| {float(np.max(ds.sl_numerical_time_avg_error[s])):.1e} |")
    L += ["", f"## Validity rules (derived from the data; metric: {study.rule['metric']} {study.rule['quantity']})",
          ""]
    L += [f"**Recommended:** {recommendation(rules)}", ""]
    L += [f"* {rule_text(r, study.rule['metric'], study.rule['quantity'])}" for r in rules]
    L.append("")
    return "\n".join(L)


# ============================================================================ plots
def plot_error_vs_cost(ds, path):
    """Log-log error vs cost per point, one marker per method/setting (two panels:
    error against coupled MCS, the judge; and against condensed MCS, SL's own model)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    models = list(ds.cv_model.values)
    nref = ds.sizes["n_samples"] - 1
    med = lambda a: float(np.nanmedian(np.asarray(a, dtype=float)))  # noqa: E731
    sl_cost = ds.cost.sel(approach="sl").values
    for ax, ref_model in zip(axes, ("coupled", "condensed")):
        if ref_model not in models:
            ax.set_visible(False)
            continue
        ref = ds.cv_peak_var_theta.sel(cv_model=ref_model).values[:, nref]          # per rep point
        # MCS vs sample count
        for model, color in (("coupled", "tab:red"), ("condensed", "tab:blue")):
            if model not in models or (ref_model == "condensed" and model == "coupled"):
                continue
            pk = ds.cv_peak_var_theta.sel(cv_model=model).values
            se = ds.cv_peak_var_theta_se.sel(cv_model=model).values
            own_ref = pk[:, nref]
            bias = own_ref / ref - 1.0 if model != ref_model else np.zeros_like(ref)
            err = np.sqrt(bias[:, None] ** 2 + (se / pk) ** 2)
            cost = ds.cv_cost.sel(cv_model=model).values
            x = np.nanmedian(cost, axis=0)
            y = np.nanmedian(err, axis=0)
            ax.plot(x, y, "o-", color=color, label=f"{model} MCS, n = {', '.join(map(str, ds.n_samples.values))}")
            for xi, yi, n_s in zip(x, y, ds.n_samples.values):
                ax.annotate(str(n_s), (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7, color=color)
            # tolerance variants
            tp = ds.tol_peak_var_theta.sel(cv_model=model).values
            tse = ds.tol_peak_var_theta_se.sel(cv_model=model).values
            tc = ds.tol_cost.sel(cv_model=model).values
            change = ds.tol_change_vs_tightest.sel(cv_model=model).values
            terr = np.sqrt(bias[:, None] ** 2 + (tse / tp) ** 2 + change ** 2)
            for c, f in enumerate(ds.rtol_factor.values):
                ax.plot(med(tc[:, c]), med(terr[:, c]), marker="^" if f > 1 else ("v" if f < 1 else "s"),
                        ls="none", color=color, mfc="none", ms=8,
                        label=f"{model} MCS rtol x {f:g} ({study_n(ds)} samples)")
        # SL
        sl_pk = ds.cv_sl_peak_var_theta.values
        sl_err = np.abs(sl_pk / ref - 1.0)
        ax.plot(med(sl_cost), med(sl_err), "*", color="k", ms=14, label="SL at the representative points")
        comp = "sl_vs_coupled" if ref_model == "coupled" else "sl_vs_condensed"
        g = np.abs(ds.peak_rel_error.sel(comparison=comp, quantity="var_theta").values)
        ax.errorbar(med(sl_cost), med(g), yerr=[[med(g) - np.nanmin(g)], [np.nanmax(g) - med(g)]], fmt="*",
                    color="0.5", mfc="none", ms=14, capsize=3, label="SL, whole grid (median, min-max)")
        last = 0.0
        for k in np.argsort([med(ds.sl_cost[k]) for k in range(ds.sizes["sl_setting"])]):
            h = float(ds.sl_h_max[k])
            tag = (f"rtol {float(ds.sl_rtol[k]):.0e}" if str(ds.sl_setting_kind.values[k]) == "rtol"
                   else f"h_max {h:g} s")
            xk = med(ds.sl_cost[k])
            ax.plot(xk, med(g), "|", color="0.3", ms=10)
            if xk > 1.25 * last:                       # label only settings of visibly different cost
                ax.annotate(tag, (xk, med(g)), textcoords="offset points", xytext=(0, 8), fontsize=5.5,
                            rotation=90, ha="center", va="bottom", color="0.3")
                last = xk
        if ref_model == "coupled":
            cg = np.abs(ds.peak_rel_error.sel(comparison="condensed_vs_coupled", quantity="var_theta").values)
            cc = ds.cost.sel(approach="condensed_mcs").values
            ax.errorbar(med(cc), med(cg), yerr=[[med(cg) - np.nanmin(cg)], [np.nanmax(cg) - med(cg)]], fmt="D",
                        color="tab:cyan", mfc="none", capsize=3, label="condensed MCS, whole grid (median, min-max)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("cost per point, one core [s]")
        ax.set_title(f"error of peak var_θ vs {ref_model} MCS reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, loc="lower left")
    axes[0].set_ylabel("relative error [1] (bias ⊕ standard error)")
    fig.suptitle("Speed–accuracy trade, peak var_θ.  MCS: median over the representative points (error = bias vs "
                 "the reference ⊕ standard error ⊕ tolerance change).\n"
                 "SL: | marks = its rtol / h_max settings (numerical "
                 "error is negligible; the error shown is the modelling error)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def study_n(ds):
    """Sample count of the tolerance sub-study (from the dataset)."""
    return int(ds.attrs.get("tol_samples", 0)) or "?"


def plot_validity(ds, rules, thresholds, path, metric="peak", quantity="var_theta"):
    """Map of SL's error class (within the smaller / larger threshold / beyond) against coupled
    and condensed MCS, over SL peak p_uplift (x, log) and the k_eq margin (y)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t1, t2 = thresholds[0], thresholds[-1]
    x = ds.sl_peak_p_uplift.values
    y = ds.k_eq_margin.values
    fams = list(dict.fromkeys(ds.family.values))
    shapes = dict(zip(fams, "osD^vP<>"))
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    iq = QUANTITIES.index(quantity)
    for ax, (comp, ref) in zip(axes, (("sl_vs_coupled", "coupled"), ("sl_vs_condensed", "condensed"))):
        c = list(COMPARISONS).index(comp)
        err = rule_error(ds.peak_rel_error.values[c, iq], ds.time_avg_rel_error.values[c, iq], metric)
        rse = ds.peak_rel_se.values[c, iq]
        for j in range(x.size):
            e = err[j]
            color = ("0.6" if not np.isfinite(e) else "tab:green" if e <= t1 else "gold" if e <= t2 else "tab:red")
            hard = ds.eps.values[j] > 0
            ax.scatter(x[j], y[j], marker=shapes[ds.family.values[j]], s=70, edgecolors="k",
                       facecolors=color if hard else "white", linewidths=1.0 if hard else 2.0)
            if not hard:
                ax.scatter(x[j], y[j], marker=shapes[ds.family.values[j]], s=28, color=color)
            lab = "n/a" if not np.isfinite(e) else f"{100 * e:.0f}%"
            cls = classify_error(e, rse[j], t1) if np.isfinite(e) else "undefined"
            if cls == "ambiguous" or classify_error(e, rse[j], t2) == "ambiguous":
                lab += "?"
            ov = float(ds.overturned_fraction.sel(mcs_model="coupled").values[j])
            if ov > 0 and ref == "coupled":
                lab += f" (ov {ov:.0%})"
            ax.annotate(lab, (x[j], y[j]), textcoords="offset points", xytext=(6, 4) if hard else (6, -11),
                        fontsize=6.5)
        for r in rules:
            if r["reference"] == ref and r["group"] == "all" and np.isfinite(r["p_safe"]):
                ax.axvline(r["p_safe"], color="tab:green" if r["threshold"] == t1 else "goldenrod", ls="--", lw=1)
                ax.text(r["p_safe"], 1.01 if r["threshold"] == t1 else 0.03, f"all within {r['threshold']:.0%} "
                        "up to here ", fontsize=6.5, ha="right", transform=ax.get_xaxis_transform())
        ax.set_xscale("log")
        ax.set_xlabel("SL peak p_uplift [1]")
        ax.set_title(f"|SL error| of {metric} {quantity} vs {ref} MCS", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("k_eq margin = min_k_eq / k_eq(t=0) [1]")
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], marker="o", ls="none", color=c, mec="k", label=lab) for c, lab in (
        ("tab:green", f"<= {t1:.0%}"), ("gold", f"{t1:.0%}-{t2:.0%}"), ("tab:red", f"> {t2:.0%}"),
        ("0.6", "undefined"))]
    handles += [Line2D([], [], marker=shapes[f], ls="none", color="0.8", mec="k", label=f) for f in fams]
    handles += [Line2D([], [], marker="o", ls="none", mfc="0.8", mec="k", label="eps > 0 (filled)"),
                Line2D([], [], marker="o", ls="none", mfc="white", mec="k", mew=2, label="eps < 0 (ring)")]
    axes[1].legend(handles=handles, fontsize=7, loc="lower left")
    fig.suptitle("Where SL stays within tolerance (labels: |error|; ? = a threshold lies within 2 SE; ov = coupled "
                 "samples overturned, statistics over survivors;\ndashed: largest tested SL peak p_uplift up to which "
                 "every point passes, all beds)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


# ============================================================================ runner
def output_paths(out_dir, stem):
    """The files a trade study writes: ``nc``, ``md``, ``csv``, ``error_vs_cost``, ``validity``."""
    out = Path(out_dir)
    return {"nc": out / f"{stem}.nc", "md": out / f"{stem}.md", "csv": out / f"{stem}.csv",
            "error_vs_cost": out / f"{stem}_error_vs_cost.png", "validity": out / f"{stem}_validity.png"}


def write_reports(study, ds, out_dir, stem, write_nc=True):
    """Derive the rules from ``ds`` and write the netCDF, markdown, CSV and plots.

    Returns ``(paths, rules)``.  With ``write_nc=False`` only the reports are (re)written,
    e.g. from a saved dataset (``main --from-nc``).
    """
    paths = output_paths(out_dir, stem)
    paths["nc"].parent.mkdir(parents=True, exist_ok=True)
    thr, metric, quantity = study.rule["thresholds"], study.rule["metric"], study.rule["quantity"]
    rules = derive_rules(ds, thr, metric, quantity)
    ds.attrs["rules"] = "\n".join(rule_text(r, metric, quantity) for r in rules)
    if write_nc:
        to_file_layout(ds).to_netcdf(paths["nc"], encoding=file_encoding(ds))
    wall = float(ds.attrs.get("wall_time_s", float("nan")))
    paths["md"].write_text(markdown_report(study, ds, rules) + f"\nTotal run time {wall:.0f} s.\n",
                           encoding="utf-8")
    write_csv(point_rows(ds), paths["csv"])
    plot_error_vs_cost(ds, paths["error_vs_cost"])
    plot_validity(ds, rules, thr, paths["validity"], metric, quantity)
    return paths, rules


def _stem(study):
    return Path(study.source).stem if study.source != "<string>" else "tradeoff"


def run_tradeoff(study_path, out_dir="outputs", progress=_stderr):
    """Run the whole trade study of ``study_path`` and write its outputs into ``out_dir``.

    ``study_path`` may also be a parsed :class:`TradeoffStudy`; outputs are named after the
    study file's stem (see :func:`output_paths`).  ``progress`` is a callable taking one line
    of text (default: stderr) or None.  Returns ``(dataset, paths, rules)``: the dataset of
    :func:`build_dataset`, the dict of written files and the rules of :func:`derive_rules`.
    """
    study = load_tradeoff_study(study_path) if not isinstance(study_path, TradeoffStudy) else study_path
    start = time.perf_counter()
    previous = set_threads(study.mcs["threads"])
    try:
        warm_up(study)
        t_out = output_times(study.t_end, study.dt)
        points = build_points(study, progress)
        grid = measure_grid(study, points, t_out, progress)
        errors = grid_errors(grid, t_out)
        conv = measure_convergence(study, points, grid, t_out, progress)
        numerics = measure_sl_numerics(study, points, t_out)
    finally:
        set_threads(previous)
    ds = build_dataset(study, points, t_out, grid, errors, conv, numerics, time.perf_counter() - start)
    paths, rules = write_reports(study, ds, out_dir, _stem(study))
    return ds, paths, rules


def main(argv=None):
    """Command line: ``python -m screening.analysis.tradeoff STUDY.toml [--out-dir DIR] [--quiet] [--from-nc]``.

    ``--from-nc`` re-renders the tables, plots and rules from ``<out-dir>/<stem>.nc`` without
    recomputing (e.g. after changing ``[rule]``).  Exit status 0 on success, 2 for a bad
    study file.
    """
    parser = argparse.ArgumentParser(prog="screening tradeoff",
                                     description="Speed-accuracy trade study: SL vs condensed / coupled Monte Carlo")
    parser.add_argument("study", help="trade-study TOML file (e.g. studies/speed_accuracy.toml)")
    parser.add_argument("--out-dir", default="outputs", help="output directory (default: outputs)")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    parser.add_argument("--from-nc", action="store_true",
                        help="re-render reports from the saved netCDF instead of recomputing")
    args = parser.parse_args(argv)
    try:
        study = load_tradeoff_study(args.study)
    except OSError as err:
        print(f"screening: error: cannot read the study file {args.study}: {err.strerror or err}", file=sys.stderr)
        return 2
    except TradeoffStudyError as err:
        print(f"screening: error: {err}", file=sys.stderr)
        return 2
    if args.from_nc:
        nc = output_paths(args.out_dir, _stem(study))["nc"]
        if not nc.exists():
            print(f"screening: error: --from-nc: {nc} does not exist (run the study first)", file=sys.stderr)
            return 2
        with xr.open_dataset(nc) as saved:
            ds = from_file_layout(saved.load())
        paths, rules = write_reports(study, ds, args.out_dir, _stem(study), write_nc=False)
        del paths["nc"]
    else:
        ds, paths, rules = run_tradeoff(study, args.out_dir, progress=None if args.quiet else _stderr)
    print(summary_text(study, ds, rules))
    print("wrote " + ", ".join(str(p) for p in paths.values()))
    return 0


def summary_text(study, ds, rules):
    """Costs, cost ratios and the derived rules as printable text."""
    cs = cost_summary(ds)
    lines = [f"cost per point (median, one core): SL {1e3 * cs['sl'][0]:.2f} ms, condensed MCS "
             f"{cs['condensed_mcs'][0]:.2f} s, coupled MCS {cs['coupled_mcs'][0]:.2f} s "
             f"({study.mcs['samples']} samples) -> SL : condensed : coupled = 1 : "
             f"{cs['condensed_mcs'][0] / cs['sl'][0]:,.0f} : {cs['coupled_mcs'][0] / cs['sl'][0]:,.0f}",
             "Recommended: " + recommendation(rules),
             "Rules (from the data):"]
    lines += ["  - " + rule_text(r, study.rule["metric"], study.rule["quantity"]) for r in rules]
    lines.append(f"total run time of the study {float(ds.attrs.get('wall_time_s', float('nan'))):.0f} s")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
