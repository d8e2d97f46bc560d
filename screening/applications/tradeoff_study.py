"""The speed-accuracy trade-study file (TOML): schema, validation and the vocabulary of the study.

A trade study shares ``[block]``, ``[foundation]``, ``[excitation]`` (the envelope) and ``[time]``
with sweep studies and reads them with the same code (:mod:`screening.sweep.config`); its own
tables are ``[[family]]``, ``[sl]``, ``[mcs]``, ``[convergence]`` and ``[rule]``.  Every problem
raises :class:`~screening.sweep.config.StudyError` with a one-line message naming the key
(``family[0].eps: empty list ...``), prefixed with the file name.  See
``studies/speed_accuracy.toml`` and :func:`parse_tradeoff_study` for the keys and units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.core import condensation as condensations
from screening.applications.metrics import RULE_METRICS
from screening.solvers.montecarlo import DEFAULT_RTOL as MCS_DEFAULT_RTOL
from screening.sweep.config import (EXCITATIONS, NUMERIC, TABLE_KEYS, Case, StudyError, check_choice,
                                    check_integer, check_keys, check_value, choice, integer, integer_list,
                                    model_tables, name_string, number_list, numeric_table, parse_toml,
                                    read_study_text, required, resolve_case, table, time_table,
                                    title_and_description, type_name)

__all__ = []

#: The methods compared: stochastic linearization and Monte Carlo on the condensed / coupled model.
METHODS = ("sl", "condensed_mcs", "coupled_mcs")
MCS_MODELS = ("condensed", "coupled")
#: (estimate, reference) method of each comparison.
COMPARISONS = {
    "sl_vs_coupled": ("sl", "coupled_mcs"),
    "sl_vs_condensed": ("sl", "condensed_mcs"),
    "condensed_vs_coupled": ("condensed_mcs", "coupled_mcs"),
}
QUANTITIES = ("var_theta", "var_theta_dot")

#: A trade study of one family of two points (one representative point), for examples and tests.
EXAMPLE_TRADEOFF_STUDY = """title = "example trade study"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[time]
t_end = 2.0
dt = 0.05
[[family]]
name = "w"
kind = "white"
eps = [6e7]
S0 = [1e-5, 2e-5]
[mcs]
samples = 50
[convergence]
points = [{family = "w", eps = 6e7, index = 1}]
samples = [20, 50]
rtol_samples = 20
rtol_factors = [1.0, 32.0]
"""

#: Model-table keys of a trade study: ``eps`` and the excitation kind and intensity are per family.
MODEL_KEYS = {"block": TABLE_KEYS["block"], "foundation": ("contact", "condensation", "k", "lam", "c"),
              "excitation": ("envelope", "T1", "T2", "band_limit_hz")}
_TOP_KEYS = ("title", "description", "block", "foundation", "excitation", "time", "family", "sl", "mcs",
             "convergence", "rule")
_FAMILY_KEYS = ("name", "kind", "omega_g", "zeta_g", "eps", "S0", "target_peak_p_uplift")
_SL_KEYS = ("rtol", "rtol_sweep", "h_max_sweep", "reference_rtol", "timing_repeats", "calibration_rtol")
_MCS_KEYS = ("samples", "seed", "threads", "rtol_coupled", "rtol_condensed", "h_max", "chunk_size")
_CONVERGENCE_KEYS = ("points", "samples", "rtol_factors", "rtol_samples", "models")
_POINT_KEYS = ("family", "eps", "index")
_RULE_KEYS = ("thresholds", "metric", "quantity")
_RTOL = {"lower": 0.0, "upper": 1e-2}            # bounds of every tolerance


@dataclass(frozen=True)
class Family:
    """An excitation family of the grid: points = ``eps`` x intensities.

    ``kind`` "white" or "kanai_tajimi" (``omega_g`` [rad/s], ``zeta_g`` [1]); intensities as
    ``S0`` [m2 s-3] values or as ``target_peak_p_uplift`` [1] values (the S0 at which SL's
    peak uplift probability equals the target, rounded to 3 significant digits).  ``case``
    holds the block, bed and excitation of the family without ``eps`` and ``S0``
    (:func:`screening.sweep.config.build_models` adds them per point).
    """

    name: str
    kind: str
    eps: tuple
    case: Case
    omega_g: float = float("nan")
    zeta_g: float = float("nan")
    S0: tuple | None = None
    target_peak_p_uplift: tuple | None = None

    @property
    def n_intensities(self):
        return len(self.S0 if self.S0 is not None else self.target_peak_p_uplift)


@dataclass(frozen=True)
class TradeoffStudy:
    """A validated trade study (see :func:`parse_tradeoff_study` for the keys and units).

    ``condensation`` is the :class:`~screening.core.condensation.Condensation` of ``foundation.condensation``.
    """

    title: str
    t_end: float
    dt: float
    families: tuple
    sl: dict
    mcs: dict
    convergence: dict
    rule: dict
    condensation: object
    source: str = "<string>"
    text: str = ""

    def family(self, name):
        """The :class:`Family` called ``name``."""
        return next(f for f in self.families if f.name == name)


def load_tradeoff_study(path):
    """Read and validate a trade-study file (see :func:`parse_tradeoff_study`).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (SI units throughout).

    Returns
    -------
    TradeoffStudy
        The validated study; :class:`StudyError` names any bad key.

    """
    return parse_tradeoff_study(read_study_text(path), source=str(path))


def parse_tradeoff_study(text, source="<string>"):
    """Parse and validate a trade-study TOML text; :class:`StudyError` names any bad key.

    Keys (SI units):

    * ``title``; ``[block]`` ``m`` [kg], ``b`` [m] (half-width), ``h`` [m] (centre-of-mass
      height), optional ``I_cm`` [kg m2], ``g`` [m s-2];
    * ``[foundation]`` ``contact`` ("hunt_crossley" with ``lam`` [N s m-3] or "winkler" with
      ``c`` [N s m-2]), ``k`` [N m-2], optional ``condensation`` ("paper" or "cubic");
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


    Parameters
    ----------
    text : str
        The TOML text.
    source : str
        Where it came from (in error messages).

    Returns
    -------
    TradeoffStudy
        The validated study.

    """
    return parse_toml(text, source, lambda raw: _build(raw, text, source))


def _build(raw, text, source):
    check_keys(raw, _TOP_KEYS, "")
    title, _ = title_and_description(raw, "speed-accuracy trade study")
    tables = model_tables(raw, MODEL_KEYS)
    for tname, tbl in tables.items():
        numeric_table(tbl, tname, {}, "", sweepable=())      # scalars only
    choice(tables["excitation"], "envelope", ("exponential",), "excitation.", "exponential")
    t_end, dt = time_table(raw)
    families = _families(raw, tables)
    mcs = _mcs(raw)
    return TradeoffStudy(title=title, t_end=t_end, dt=dt, families=families, sl=_sl(raw), mcs=mcs,
                         convergence=_convergence(raw, families, mcs), rule=_rule(raw),
                         condensation=condensations.get(families[0].case.condensation), source=source, text=text)


def _families(raw, tables):
    entries = raw.get("family")
    if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
        raise StudyError("family: at least one [[family]] table is required")
    families = []
    for i, entry in enumerate(entries):
        family = _family(entry, f"family[{i}].", tables)
        if family.name in (f.name for f in families):
            raise StudyError(f"family[{i}].name: duplicate family name {family.name!r}")
        families.append(family)
    return tuple(families)


def _family(entry, where, tables):
    check_keys(entry, _FAMILY_KEYS, where)
    name = name_string(f"{where}name", entry.get("name"))
    kind = choice(entry, "kind", EXCITATIONS, where)
    excitation = {**tables["excitation"], "kind": kind}
    if kind == "kanai_tajimi":
        for key in ("omega_g", "zeta_g"):
            value = required(entry, key, where, " for kind = 'kanai_tajimi'")
            excitation[key] = check_value(f"{where}{key}", value, *NUMERIC[key][1:])
    else:
        for key in ("omega_g", "zeta_g"):
            if key in entry:
                raise StudyError(f"{where}{key}: does not apply to kind = {kind!r}")
    eps = number_list(f"{where}eps", required(entry, "eps", where))
    if ("S0" in entry) == ("target_peak_p_uplift" in entry):
        raise StudyError(f"{where}S0: give exactly one of 'S0' and 'target_peak_p_uplift'")
    S0 = number_list(f"{where}S0", entry["S0"], lower=0.0) if "S0" in entry else None
    target = (number_list(f"{where}target_peak_p_uplift", entry["target_peak_p_uplift"], lower=0.0, upper=0.99)
              if S0 is None else None)
    # eps and S0 are given per point (S0 possibly calibrated later)
    case = resolve_case(name, {**tables, "excitation": excitation}, {"eps": np.asarray(eps), "S0": None}, "")
    return Family(name=name, kind=kind, eps=eps, case=case, omega_g=excitation.get("omega_g", float("nan")),
                  zeta_g=excitation.get("zeta_g", float("nan")), S0=S0, target_peak_p_uplift=target)


def _sl(raw):
    tbl = table(raw, "sl")
    check_keys(tbl, _SL_KEYS, "sl.")
    return {
        "rtol": check_value("sl.rtol", tbl.get("rtol", 1e-7), **_RTOL),
        "rtol_sweep": number_list("sl.rtol_sweep", tbl.get("rtol_sweep", [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9]),
                                  **_RTOL),
        "h_max_sweep": number_list("sl.h_max_sweep", tbl.get("h_max_sweep", [1.0, 0.1, 0.02]), lower=0.0),
        "reference_rtol": check_value("sl.reference_rtol", tbl.get("reference_rtol", 1e-11), **_RTOL),
        "timing_repeats": integer(tbl, "timing_repeats", 10, 1, "sl."),
        "calibration_rtol": check_value("sl.calibration_rtol", tbl.get("calibration_rtol", 1e-7), **_RTOL),
    }


def _mcs(raw):
    tbl = table(raw, "mcs")
    check_keys(tbl, _MCS_KEYS, "mcs.")
    mcs = {"samples": integer(tbl, "samples", 1000, 2, "mcs."), "seed": integer(tbl, "seed", 0, 0, "mcs."),
           "threads": integer(tbl, "threads", 1, 1, "mcs.")}
    for model in ("coupled", "condensed"):
        key = f"rtol_{model}"
        mcs[key] = check_value(f"mcs.{key}", tbl.get(key, MCS_DEFAULT_RTOL[model]), **_RTOL)
    if "h_max" in tbl:
        mcs["h_max"] = check_value("mcs.h_max", tbl["h_max"], lower=0.0)
    if "chunk_size" in tbl:
        mcs["chunk_size"] = integer(tbl, "chunk_size", None, 1, "mcs.")
    return mcs


def _convergence(raw, families, mcs):
    tbl = table(raw, "convergence")
    check_keys(tbl, _CONVERGENCE_KEYS, "convergence.")
    entries = tbl.get("points", [])
    if not isinstance(entries, list):
        raise StudyError(f"convergence.points: must be a list of {{family, eps, index}} tables "
                         f"(got {type_name(entries)})")
    points = tuple(_point(entry, f"convergence.points[{i}]", families) for i, entry in enumerate(entries))
    if len(set(points)) != len(points):
        raise StudyError("convergence.points: points must be distinct")
    samples = tuple(sorted(set(integer_list("convergence.samples", tbl.get("samples", [100, 300, 1000, 3000]), 2))))
    factors = tuple(sorted(set(number_list("convergence.rtol_factors", tbl.get("rtol_factors", [1.0 / 32.0, 1.0, 32.0]),
                                           lower=0.0))))
    if 1.0 not in factors:
        raise StudyError("convergence.rtol_factors: must include 1 (the default tolerance)")
    rtol_samples = integer(tbl, "rtol_samples", samples[0], 2, "convergence.")
    if rtol_samples not in samples:
        raise StudyError(f"convergence.rtol_samples: must be one of convergence.samples {list(samples)} "
                         f"(got {rtol_samples})")
    models = tbl.get("models", list(MCS_MODELS))
    if not isinstance(models, list) or not models:
        raise StudyError(f"convergence.models: must be a non-empty list (got {models!r})")
    models = tuple(check_choice(f"convergence.models[{i}]", m, MCS_MODELS) for i, m in enumerate(models))
    for model in models:
        if max(factors) * mcs[f"rtol_{model}"] > 1e-2:
            raise StudyError(f"convergence.rtol_factors: largest factor x mcs.rtol_{model} exceeds 1e-2")
    return {"points": points, "samples": samples, "rtol_factors": factors, "rtol_samples": rtol_samples,
            "models": models}


def _point(entry, key, families):
    """``(family name, eps, intensity index)`` of one representative point."""
    if not isinstance(entry, dict):
        raise StudyError(f"{key}: must be a table {{family, eps, index}} (got {type_name(entry)})")
    where = f"{key}."
    check_keys(entry, _POINT_KEYS, where)
    fam_name = choice(entry, "family", [f.name for f in families], where)
    fam = next(f for f in families if f.name == fam_name)
    eps = check_value(f"{where}eps", required(entry, "eps", where))
    if eps not in fam.eps:
        raise StudyError(f"{where}eps: must be one of the eps of family '{fam_name}' {list(fam.eps)} (got {eps!r})")
    index = check_integer(f"{where}index", required(entry, "index", where), 0)
    if index >= fam.n_intensities:
        raise StudyError(f"{where}index: must be < {fam.n_intensities}, the number of intensities of family "
                         f"'{fam_name}' (got {index})")
    return (fam_name, eps, index)


def _rule(raw):
    tbl = table(raw, "rule")
    check_keys(tbl, _RULE_KEYS, "rule.")
    return {"thresholds": tuple(sorted(number_list("rule.thresholds", tbl.get("thresholds", [0.10, 0.25]),
                                                   lower=0.0))),
            "metric": choice(tbl, "metric", RULE_METRICS, "rule.", "peak"),
            "quantity": choice(tbl, "quantity", QUANTITIES, "rule.", "var_theta")}


def example_tradeoff():
    """The study :data:`EXAMPLE_TRADEOFF_STUDY` and a made-up dataset of its layout (nothing is solved).

    Every variable the trade study's reports read (:func:`screening.report.tradeoff_files.write_reports`),
    with round numbers: SL's variances 0.95 of condensed Monte Carlo's and 0.91 of coupled Monte Carlo's,
    Monte Carlo standard errors of 2 %, costs of 0.01 s (SL), 1 s (condensed) and 5 s (coupled) per point.

    Returns
    -------
    study : TradeoffStudy
        The parsed example study (two points: ``S0`` = 1e-5, 2e-5 m2 s-3 at ``eps`` = 6e7 m-2).
    ds : xarray.Dataset
        Histories ``var_theta`` [rad2], ``var_theta_dot`` [rad2 s-2] (with ``*_se``), ``p_uplift`` [1] on
        ``(approach, point, t)``; peaks, relative errors [1] and their significance over ``comparison`` and
        ``quantity``; costs [s]; the sample-count (``cv_*``), tolerance (``tol_*``) and SL-numerics
        (``sl_*`` over ``sl_setting``) sub-studies at the representative point.

    """
    import xarray as xr

    study = parse_tradeoff_study(EXAMPLE_TRADEOFF_STUDY, source="example.toml")
    t = np.arange(round(study.t_end / study.dt) + 1) * study.dt
    ramp = t / study.t_end
    family = study.families[0]
    n = len(family.eps) * len(family.S0)
    factor = np.array([1.0, 1.05, 1.1])                      # sl, condensed, coupled: variance over SL's
    base = 1e-6 * np.arange(1, n + 1)                       # SL's peak var_theta [rad2] per point
    var = factor[:, None, None] * base[None, :, None] * ramp
    mcs_se = np.array([0.0, 0.02, 0.02])[:, None, None]
    peak = factor[:, None] * base
    ratios = {c: factor[METHODS.index(a)] / factor[METHODS.index(b)] - 1.0 for c, (a, b) in COMPARISONS.items()}
    err = np.array([[[ratios[c]] * n] * len(QUANTITIES) for c in COMPARISONS])
    rel_se = np.full(err.shape, 0.03)
    rep = [index for _, _, index in study.convergence["points"]]         # one eps: the point is the S0 index
    n_samples, factors = study.convergence["samples"], study.convergence["rtol_factors"]
    cv = peak[1:, rep].T[:, :, None] * np.array([1.03, 1.0])           # (rep_point, cv_model, n_samples)
    tol = cv[:, :, :1] * np.array([1.0, 1.001])                          # (rep_point, cv_model, rtol_factor)
    none_over = np.zeros((len(rep), 2, 2), dtype=np.int32)                # overturned samples
    per_point = ("point",)
    data = {
        "var_theta": (("approach", "point", "t"), var), "var_theta_se": (("approach", "point", "t"), mcs_se * var),
        "var_theta_dot": (("approach", "point", "t"), 100.0 * var),
        "var_theta_dot_se": (("approach", "point", "t"), 100.0 * mcs_se * var),
        "p_uplift": (("approach", "point", "t"), 0.2 * np.arange(1, n + 1)[None, :, None] * ramp * np.ones((3, 1, 1))),
        "peak_var_theta": (("approach", "point"), peak),
        "peak_var_theta_se": (("approach", "point"), mcs_se[..., 0] * peak),
        "n_overturned": (("mcs_model", "point"), np.zeros((2, n), dtype=np.int32)),
        "n_used": (("mcs_model", "point"), np.full((2, n), study.mcs["samples"], dtype=np.int32)),
        "overturned_fraction": (("mcs_model", "point"), np.zeros((2, n))),
        "sl_status": (per_point, np.zeros(n, dtype=np.int8)),
        "sl_peak_p_uplift": (per_point, 0.2 * np.arange(1, n + 1)),
        "k_eq_margin": (per_point, 1.0 - 0.2 * np.arange(1, n + 1)),
        "point_name": (per_point, [f"{family.name}_{i}" for i in range(n)]),
        "family": (per_point, [family.name] * n),
        "peak_rel_error": (("comparison", "quantity", "point"), err),
        "peak_rel_se": (("comparison", "quantity", "point"), rel_se),
        "peak_significant": (("comparison", "quantity", "point"), np.abs(err) > 2 * rel_se),
        "time_avg_rel_error": (("comparison", "quantity", "point"), np.abs(err)),
        "time_avg_significant": (("comparison", "quantity", "point"), np.abs(err) > 2 * rel_se),
        "cost": (("approach", "point"), np.array([0.01, 1.0, 5.0])[:, None] * np.ones(n)),
        "sl_batched_cost": ((), 0.001),
        "rep_point_name": (("rep_point",), [f"{family.name}_{i}" for i in rep]),
        "cv_peak_var_theta": (("rep_point", "cv_model", "n_samples"), cv),
        "cv_peak_var_theta_se": (("rep_point", "cv_model", "n_samples"), cv * np.array([0.05, 0.03])),
        "cv_n_overturned": (("rep_point", "cv_model", "n_samples"), none_over),
        "cv_deviation_vs_reference": (("rep_point", "cv_model", "n_samples"), cv / cv[..., -1:] - 1.0),
        "cv_cost": (("rep_point", "cv_model", "n_samples"), np.array([[[0.4, 1.0], [2.0, 5.0]]])),
        "cv_sl_peak_var_theta": (("rep_point",), peak[0, rep]),
        "tol_peak_var_theta": (("rep_point", "cv_model", "rtol_factor"), tol),
        "tol_peak_var_theta_se": (("rep_point", "cv_model", "rtol_factor"), 0.05 * tol),
        "tol_n_overturned": (("rep_point", "cv_model", "rtol_factor"), none_over),
        "tol_change_vs_tightest": (("rep_point", "cv_model", "rtol_factor"), tol / tol[..., :1] - 1.0),
        "tol_cost": (("rep_point", "cv_model", "rtol_factor"), np.array([[[0.4, 0.2], [2.0, 1.0]]])),
        "sl_setting_kind": (("sl_setting",), ["rtol", "h_max"]),
        "sl_rtol": (("sl_setting",), [study.sl["rtol"]] * 2),
        "sl_h_max": (("sl_setting",), [np.nan, 0.01]),
        "sl_cost": (("sl_setting", "point"), np.array([0.01, 0.02])[:, None] * np.ones(n)),
        "sl_n_steps": (("sl_setting", "point"), np.array([120.0, 200.0])[:, None] * np.ones(n)),
        "sl_numerical_peak_error": (("sl_setting", "point"), np.array([1e-5, 1e-4])[:, None] * np.ones(n)),
        "sl_numerical_time_avg_error": (("sl_setting", "point"), np.array([1e-5, 1e-4])[:, None] * np.ones(n)),
    }
    coords = {"approach": list(METHODS), "point": np.arange(n), "t": t, "mcs_model": ["coupled", "condensed"],
              "comparison": list(COMPARISONS), "quantity": list(QUANTITIES), "cv_model": list(MCS_MODELS),
              "n_samples": list(n_samples), "rtol_factor": list(factors), "sl_setting": [0, 1],
              "eps": ("point", np.repeat(family.eps, len(family.S0))),
              "S0": ("point", np.tile(family.S0, len(family.eps)))}
    attrs = {"wall_time_s": 42.0, "tol_samples": study.convergence["rtol_samples"]}
    return study, xr.Dataset(data, coords=coords, attrs=attrs)
