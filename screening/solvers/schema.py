"""The CF metadata of everything the package returns or writes, declared once.

Every variable and coordinate name the package produces is declared here with its ``units``
and ``long_name`` (CF-1.8 / UDUNITS spelling; ``"1"`` is dimensionless), status variables with
their flag attributes (:mod:`screening.core.status`), and :func:`apply_schema` applies them, with the
global attributes, to a dataset in one place.  Producers (solvers, sweep, trade study,
fragility) build plain datasets and call :func:`apply_schema`; none writes its own units.
"""

from __future__ import annotations

import numpy as np

from screening._version import __version__
from screening.core import excitations, laws
from screening.core.registry import Live
from screening.core.status import (AnswerQuantity, BestMethod, EscalationEstimator,
                                   FitFlag, flag_attributes, PointStatus, probability_sources, SampleState,
                                   TargetMet)
from screening.solvers import mc_registry
from screening.solvers.outputs import of_stage, OUTPUTS

__all__ = []

CONVENTIONS = "CF-1.8"
INTENSITY_CONVENTION = "E[xi(t) xi(s)] = 2 pi S0 delta(t - s), S0 two-sided PSD"
REFERENCE = ("Nonlinear dynamics of rocking rigid blocks under stochastic base excitation: stochastic "
             "linearization with Lyapunov moment equations (method and corrections: docs/method.md)")

#: Time coordinate: named ``t``; no ``axis = "T"`` in files (CF would then want "units since epoch").
TIME = {"units": "s", "long_name": "time since the start of the excitation"}

#: Time coordinate of the CDO form of a result (:mod:`screening.io.cdofile`): the same seconds from a
#: placeholder reference date (CDO keeps sub-second output times only with one; xarray decodes it to datetimes).
CDO_TIME = {"units": "seconds since 1970-01-01 00:00:00", "calendar": "standard", "standard_name": "time",
            "axis": "T", "long_name": TIME["long_name"],
            "comment": "seconds since the start of the excitation; the reference date is a placeholder (CDO needs "
                       "one), the record has no calendar date"}
#: Global attribute ``layout`` of the CDO form.
CDO_LAYOUT = ("CDO: t first and unlimited (seconds since a placeholder reference date), no coordinates "
              "attributes, string variables as attributes, p_exceed one variable per threshold "
              "(screening export --layout cdo)")


def cf(units, long_name, **extra):
    """CF attributes ``units`` [UDUNITS], ``long_name`` and ``extra``."""
    return {"units": units, "long_name": long_name, **extra}


def _declared(*names):
    """The attributes of the sweep-grid variables ``names`` as :mod:`screening.solvers.outputs` declares them."""
    return {name: dict(OUTPUTS[name].attrs) for name in names}


def _plain(attrs):
    """Declared attributes without the sweep's ``note``."""
    return {k: v for k, v in attrs.items() if k != "note"}


#: The tables the producing modules declare beside their code (:func:`declare`): name -> ``(table, prefix)``.
DECLARED = {}


def __getattr__(name):
    """A declared table by its name in capitals (``MONTE_CARLO``, ``SIMULATION``, ``TRADEOFF``, ...), as its producer
    declares it."""
    if name.lower() in DECLARED:
        return DECLARED[name.lower()][0]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def declare(name, table, prefix=""):
    """Declare a producer's variables (``{variable: attributes}``) as ``name``, in the module that makes them;
    :func:`attributes` finds them with ``prefix`` (``mcs_`` in sweeps; None: by name), or as its ``table``."""
    DECLARED[name] = (table, prefix)
    return table


def _parameters():
    """:data:`PARAMETERS`, read now (the contact laws' and excitations' parameters from their registries)."""
    return {
        "m": cf("kg", "block mass"),
        "b": cf("m", "half-width of the block base"),
        "h": cf("m", "height of the centre of mass above the base"),
        "I_cm": cf("kg m2", "moment of inertia about the centre of mass"),
        "g": cf("m s-2", "gravitational acceleration"),
        "k": cf("N m-2", "distributed foundation stiffness"),
        **{name: cf(a["units"], a["long_name"]) for name, a in laws.parameters().items()},   # the contact laws'
        "eps": cf("m-2", "cubic stiffness parameter of the contact law"),
        "S0": _plain(OUTPUTS["S0"].attrs),
        "pga": cf("m s-2", "target median peak ground acceleration of the input (S0 follows from it, band-limited "
                           "as the Monte Carlo synthesis)"),
        **{name: cf(p.units, p.long_name) for name, p in excitations.parameters().items()},   # the excitations'
        "T1": cf("s", "envelope decay time T1"),
        "T2": cf("s", "envelope rise time T2"),
        "band_limit_hz": cf("Hz", "corner of the ground motion's band: order-4 Butterworth low-pass of the "
                                  "excitation's spectrum (screening.core.excitations.base.band_gain)",
                            note="absent, or NaN in a case: no band, the idealized spectrum (band_limit_hz = "
                                 "\"none\"); the intensity measures then refer to a sharp 25 Hz"),
    }


#: Model parameters (coordinates, swept or scalar), read when used.
PARAMETERS = Live(_parameters)

#: Quantities derived from the model (stored beside the parameters, never re-derived downstream).
DERIVED = {
    **_declared(*(o.name for o in of_stage("model"))),           # theta_ul, slenderness
    "m_sdof": cf("kg m2", "rotational inertia about the rocking edge, I_cm + m h2"),
    "theta_capacity": cf("rad", "capacity angle of the condensation (no quasi-static equilibrium beyond; "
                                "inf if none)"),
}

#: Linearization (stochastic linearization + Lyapunov moments).
LINEARIZATION = {
    **_declared(*(o.name for o in of_stage("linearize"))),        # the moment solver's outputs
    "peak_p_beyond_capacity": cf("1", "Gaussian probability that |theta| exceeds theta_capacity at the peak "
                                      "var_theta"),
    # a linearize() result: the statuses the solver gives (a sweep's status also says when its task failed)
    "status": flag_attributes([s for s in PointStatus if s >= PointStatus.ok], "solver status of the point"),
    # trust of the point (screening.analysis.trust.add_trust; k_eq_rest and var_theta_end stand in for the
    # histories in files that do not store them)
    "k_eq_rest": cf("N m rad-1", "equivalent linear rocking stiffness at rest (t = 0)"),
    "var_theta_end": cf("rad2", "variance of the rocking rotation at the end of the record"),
    **_declared(*(o.name for o in of_stage("trust"))),           # the trust rule's flag and band
}

#: Best estimates of a sweep with ``[accuracy]`` (:mod:`screening.analysis.correction`) and its escalated Monte
#: Carlo points (dimension ``escalation``).
ACCURACY = {
    "best_peak_var_theta": cf("rad2", "best estimate of the coupled model's peak variance of the rocking rotation"),
    "best_peak_var_theta_se": cf("rad2", "standard error of best_peak_var_theta"),
    "best_peak_var_theta_dot": cf("rad2 s-2", "best estimate of the coupled model's peak variance of the rocking "
                                              "angular velocity"),
    "best_peak_var_theta_dot_se": cf("rad2 s-2", "standard error of best_peak_var_theta_dot"),
    "best_method": flag_attributes(BestMethod, "source of the best estimate of peak var_theta at the point "
                                               "(best_peak_var_theta_dot follows its own ratio; its standard error "
                                               "is NaN where that cannot be vouched for)"),
    "escalation": cf("1", "escalated Monte Carlo point index"),
    "esc_sample": cf("1", "Monte Carlo sample index of an escalated point (input seeded with "
                          "default_rng([seed, sample]))"),
    "esc_case": cf("1", "case index of the escalated point"),
    "esc_samples": cf("1", "Monte Carlo samples run at the escalated point"),
    "esc_estimator": flag_attributes(EscalationEstimator, "estimator of esc_peak_var_theta and of the point's "
                                                          "p_overturn and p_exceed"),
    "esc_cheap_samples": cf("1", "samples of the cheaper paired model at the escalated point (0: plain Monte Carlo)"),
    "esc_correlation": cf("1", "correlation of the paired models' influence values of var_theta at its peak time "
                               "(NaN without a paired model)"),
    "esc_cpu_time": cf("s", "CPU time of the Monte Carlo runs at the escalated point (pilot and top-up "
                            "included), measured"),
    "esc_cost": cf("s", "CPU time of the Monte Carlo runs at the escalated point estimated by the cost model "
                        "from their integration steps (the wall budget's projections scale it by the measured rate)"),
    "esc_transition": cf("1", "1: the escalated point lies in the transition of a fragility curve (it went first and "
                              "ran to a standard error of PROBABILITY_SE of every probability); 0: a covering point "
                              "(run to target / 2 of peak var_theta)"),
    "esc_target_met": flag_attributes(TargetMet, "whether the point's Monte Carlo reached its standard error: "
                                                 "PROBABILITY_SE of every probability where they answer the point "
                                                 "(a transition point, or a sample reached a level), else target / 2 "
                                                 "of peak var_theta"),
    "esc_sl_peak_var_theta": cf("rad2", "linearization peak var_theta at the escalated point"),
    "esc_sl_peak_var_theta_dot": cf("rad2 s-2", "linearization peak var_theta_dot at the escalated point"),
    "esc_peak_var_theta": cf("rad2", "Monte Carlo peak var_theta at the escalated point"),
    "esc_peak_var_theta_se": cf("rad2", "standard error of esc_peak_var_theta (at the peak time)"),
    "esc_peak_var_theta_dot": cf("rad2 s-2", "Monte Carlo peak var_theta_dot at the escalated point"),
    "esc_peak_var_theta_dot_se": cf("rad2 s-2", "standard error of esc_peak_var_theta_dot (at the peak time)"),
    "esc_n_overturned": cf("1", "overturned Monte Carlo samples at the escalated point"),
    "esc_n_diverged": cf("1", "diverged Monte Carlo samples at the escalated point"),
    "esc_n_used": cf("1", "Monte Carlo samples in the statistics at the escalated point"),
    "esc_peak_abs_theta": cf("rad", "peak |theta| of each Monte Carlo sample at the escalated point (NaN beyond "
                                    "esc_samples)"),
    "esc_sample_state": flag_attributes(SampleState, "state of each Monte Carlo sample of the escalated point"),
    "esc_grid_index": cf("1", "flat C-order grid index of the escalated point"),
}

#: Sweep results: a point's status also says when its task failed.

#: Small probabilities by subset simulation (:func:`screening.solvers.tail.tail_probability`).
TAIL = {
    "p_overturn": cf("1", "probability that the block overturns (|theta| > atan(b/h)), by subset simulation"),
    "p_overturn_se": cf("1", "standard error of p_overturn: the larger of the spread of independent runs and Au & Beck's"),
    "p_overturn_cov": cf("1", "coefficient of variation of p_overturn (p_overturn_se / p_overturn)"),
    "p_exceed": cf("1", "probability that the peak |theta| exceeds the threshold (overturning counts), by subset "
                        "simulation"),
    "p_exceed_se": cf("1", "standard error of p_exceed: the larger of the spread of independent runs and Au & Beck's"),
    "p_exceed_cov": cf("1", "coefficient of variation of p_exceed (p_exceed_se / p_exceed)"),
    "threshold": cf("rad", "rotation threshold of p_exceed"),
    "level_threshold": cf("rad", "intermediate threshold of peak |theta| of each subset level of each run"),
    "level_gamma": cf("1", "correlation factor gamma of the Markov chains of each subset level of each run"),
}

#: The attributes of ``fit_flag``, the state of a fitted lognormal fragility curve.
FIT_FLAG = {**flag_attributes(FitFlag, "state of the lognormal fit"), "units": "1"}

#: Probabilities of overturning and of exceedance at every point of a sweep with ``[accuracy]`` or
#: ``[fragility]`` (:mod:`screening.sweep.probabilities`), and the closed-form probability that rocking
#: starts at all (every point; :func:`screening.analysis.intensity.rocking_start_probability`).
#: ``p_exceed`` is :mod:`screening.analysis.fragility`'s too, with the same declared attributes; ``p_source`` is
#: declared by :func:`probability_source_attributes`.
PROBABILITIES = {
    **_declared(*(o.name for o in of_stage("probabilities", "rocking"))),
    "answer_quantity": {**flag_attributes(AnswerQuantity, "which quantity answers the point: its peak variance, or "
                                                          "near toppling p_overturn and p_exceed (with p_source); "
                                                          "never read a variance where the probabilities answer"),
                        "units": "1"},
}


def probability_source_attributes():
    """CF flag attributes of ``p_source``: one value per source, a Monte Carlo model's from the models
    :func:`screening.monte_carlo` knows (the Monte Carlo registry and its compiled models are
    loaded when asked, not when the schema is).

    Returns
    -------
    dict
        ``units`` (``"1"``), ``long_name``, ``flag_values`` (int8 codes of
        :func:`screening.core.status.probability_sources`) and ``flag_meanings`` (the source names, in
        the order of the values).

    """
    codes = sorted(probability_sources(mc_registry.codes()).items(), key=lambda item: item[1])
    return {"units": "1", "long_name": "model that produced p_overturn and p_exceed at the point",
            "flag_values": np.array([c for _, c in codes], dtype=np.int8),
            "flag_meanings": " ".join(name for name, _ in codes)}


def monte_carlo_model_attributes():
    """CF flag attributes of the per-spot ``mcs_model``: the Monte Carlo model that ran there (with ``model =
    "auto"`` the one chosen for the point), each registered model's flag code and -1 (``none``) where the spot
    check's task failed, an integer flag variable without a fill value (read when asked)."""
    codes = sorted(mc_registry.codes().items(), key=lambda item: item[1])
    return {"units": "1", "long_name": "Monte Carlo model that produced the spot point's statistics",
            "flag_values": np.array([-1, *(c for _, c in codes)], dtype=np.int8),
            "flag_meanings": " ".join(("none", *(name for name, _ in codes))),
            "comment": "none: the spot check's task failed (no model ran)"}


#: Intensity measures of the inputs (:mod:`screening.analysis.intensity`) and of records.
INTENSITY = {
    **{name: _plain(OUTPUTS[name].attrs) for name in ("pga_median", "rms_acceleration", "arias_intensity")},
    "sa_median": cf("m s-2", "median 5 %-damped pseudo-spectral acceleration at the stated period"),
    "pgv_median": cf("m s-1", "median peak ground velocity of the modulated input, 2nd-order Butterworth "
                              "high-pass at omega_low (random-vibration theory)"),
    "avgsa_median": cf("m s-2", "median average spectral acceleration: geometric mean of Sa(T_i, 5 %) over 10 "
                                "periods log-spaced in [0.2 T, 1.5 T]"),
    "pga": cf("m s-2", "peak ground acceleration of the record"),
    "pgv": cf("m s-1", "peak ground velocity of the record (2nd-order Butterworth high-pass at 0.1 Hz, "
                       "trapezoidal integration)"),
    "avgsa": cf("m s-2", "average spectral acceleration of the record: geometric mean of Sa(T_i, 5 %) over 10 "
                         "periods log-spaced in [0.2 T, 1.5 T]"),
    "sa": cf("m s-2", "5 %-damped pseudo-spectral acceleration of the record at the stated period"),
    "fit_flag": FIT_FLAG,
}

#: Per-point variables of a sweep that no other table declares: the status (with the failed tasks) and the
#: intensity measures of each point's excitation.
SWEEP = _declared("status", *(o.name for o in of_stage("intensity")))

#: Model inputs stored per point where the study derives them: ``S0`` from a target PGA (``excitation.pga``).
SWEEP_INPUTS = _declared(*(o.name for o in of_stage("inputs")))

#: Calibration of the trust rule (``benchmarks/trust_calibration.py`` -> ``screening/data/trust_calibration.nc``).
TRUST_CALIBRATION = {
    "point": {"long_name": "calibration point name"},
    "condensation": {"long_name": "condensation of the SL run"},
    "family": {"long_name": "block and bed family of the calibration point"},
    "excitation_kind": {"long_name": "excitation kind"},
    "contact": {"long_name": "contact law"},
    "target_peak_p_uplift": cf("1", "target SL peak uplift probability used to find S0 (paper condensation)"),
    "omega_g": {**PARAMETERS["omega_g"], "note": "NaN for white noise"},
    "zeta_g": {**PARAMETERS["zeta_g"], "note": "NaN for white noise"},
    "sl_peak_p_uplift": cf("1", "SL peak uplift probability"),
    "sl_k_eq_margin": cf("1", "SL min_k_eq / k_eq at rest"),
    "sl_sigma_ratio": cf("1", "SL sqrt(peak var_theta) / slenderness angle"),
    "sl_decay_excess": cf("1", "SL (var_theta(t_end) / peak var_theta) / (q(t_end)^2 / max q^2)"),
    "sl_peak_var_theta": cf("rad2", "SL peak var_theta"),
    "sl_status": flag_attributes([s for s in PointStatus if s >= PointStatus.ok], "SL solver status",
                                 ) | {"note": "-2: the condensation does not apply to the point (no SL run)"},
    "sl_error": cf("1", "relative error of SL's peak var_theta against coupled MCS, SL / MCS - 1"),
    "sl_error_se": cf("1", "Monte Carlo standard error of sl_error"),
    **{f"{model}_{name}": value for model in ("coupled", "condensed") for name, value in {
        "peak_var_theta": cf("rad2", f"{model} MCS peak var_theta over surviving samples"),
        "peak_var_theta_se": cf("rad2", f"standard error of the {model} MCS peak var_theta (at the peak time)"),
        "n_overturned": cf("1", f"overturned {model} MCS samples"),
        "n_diverged": cf("1", f"diverged {model} MCS samples"),
        "n_samples": cf("1", f"{model} MCS samples"),
        "peak_p_uplift": cf("1", f"{model} MCS peak uplift occupancy"),
        "var_theta_end": cf("rad2", f"{model} MCS var_theta at the end of the record"),
        "wall": cf("s", f"{model} MCS wall time"),
    }.items()},
}

#: Index and label coordinates.
COORDINATES = {
    "t": TIME,
    "sample": cf("1", "Monte Carlo sample index (input seeded with default_rng([seed, sample]))"),
    "spot": cf("1", "Monte Carlo spot-check index"),
    "case": cf("1", "case index (names in case_name)"),
    "case_name": {"long_name": "case name (the [[case]] tables of the study file)"},
    "spot_case": cf("1", "case index of the spot point"),
    "spot_case_name": {"long_name": "case name of the spot point"},
    # model labels of each case, on dimension case (sweeps whose cases differ in them)
    # a swept k: its values with units in the auxiliary coordinate k_value (grid_coordinate_attributes)
    "k_value": PARAMETERS["k"],
    # string choices that differ between the cases of a sweep (coordinates on case)
    "contact": {"long_name": "contact model of the case"},
    "condensation": {"long_name": "condensation model of the case"},
    "excitation": {"long_name": "excitation model of the case"},
    "envelope": {"long_name": "envelope model of the case"},
}


#: Parameters in units of pressure.  CF (section 4.3) reads a coordinate variable in pressure units as a
#: vertical axis, and a vertical axis must then be the rightmost dimension but for T, Y, X (section 2.4,
#: a strict-check failure for every ``(grid..., t)`` variable).  Swept, such a parameter gets a coordinate
#: variable without ``units`` (so that every tool can select on it by value) and its values with units in
#: the auxiliary coordinate ``<name>_value``.
PRESSURE_PARAMETERS = ("k",)


def grid_coordinate_attributes(name):
    """Attributes of the coordinate variable of swept parameter ``name`` in a sweep result
    (those of :func:`attributes`, without ``units`` for :data:`PRESSURE_PARAMETERS`).

    CF reads a coordinate variable in units of pressure (``k`` [N m-2]) as a vertical axis; such a
    swept parameter's coordinate variable gets a ``comment`` naming its units instead, and the
    units go on the auxiliary coordinate ``<name>_value``.

    Parameters
    ----------
    name : str
        A declared parameter (``"h"``, ``"k"``, ``"S0"``, ...).

    Returns
    -------
    dict
        ``long_name`` and ``units`` (or, for :data:`PRESSURE_PARAMETERS`, ``comment`` instead of
        ``units``).

    Raises
    ------
    KeyError
        ``name`` is not declared.

    """
    attrs = attributes(name)
    if name in PRESSURE_PARAMETERS:
        units = attrs.pop("units")
        attrs["comment"] = (f"values in {units}; the units are on the auxiliary coordinate {name}_value (CF reads "
                            "a coordinate variable in units of pressure as a vertical axis)")
    return attrs


def cdo_threshold_attributes(value, threshold_attrs):
    """Attributes that say which rotation threshold a per-threshold variable of the CDO form is at
    (``threshold_attrs``: those of the ``threshold`` coordinate).

    Parameters
    ----------
    value : float
        The threshold, in the units of the ``threshold`` coordinate ([rad], or [1] relative).
    threshold_attrs : dict
        The attributes of the ``threshold`` coordinate (``units``, ``long_name``).

    Returns
    -------
    dict
        ``threshold`` (float), ``threshold_units`` (default ``"1"``) and ``threshold_long_name``.

    """
    units = threshold_attrs.get("units", "1")
    return {"threshold": float(value), "threshold_units": units,
            "threshold_long_name": threshold_attrs.get("long_name", "rotation threshold")}


def attributes(name, table=None):
    """The declared attributes of ``name`` (``table``: one of the dicts above, tried first).

    Parameters and derived quantities are found by their own names and with the prefix
    ``spot_`` (their value at a Monte Carlo spot point); Monte Carlo names with the prefix
    ``mcs_``.  Raises ``KeyError`` for an undeclared name.

    Parameters
    ----------
    name : str
        A variable or coordinate name.
    table : dict, optional
        A producer's own table (``TRADEOFF``, :data:`screening.solvers.datasets.MONTE_CARLO`, ...), tried first.

    Returns
    -------
    dict
        A copy of its attributes: ``units`` (UDUNITS spelling, ``"1"`` dimensionless), ``long_name``,
        and the flag attributes of a status variable.

    Raises
    ------
    KeyError
        ``name`` is not declared.

    """
    if table is not None and name in table:         # the table asked for first (the trade study's
        return dict(table[name])                    # ``mcs_model`` is a label dimension, not the flag)
    if name == "p_source":
        return probability_source_attributes()
    if name == "mcs_model":
        return monte_carlo_model_attributes()
    if name == "esc_model":                         # the registered models' escalation codes, read now
        return flag_attributes(mc_registry.escalation_models(), "Monte Carlo model of the escalated point")
    tables = ([table] if table is not None else []) + [LINEARIZATION, PARAMETERS, DERIVED, COORDINATES,
                                                       ACCURACY, PROBABILITIES]
    tables += [t for t, prefix in DECLARED.values() if prefix is None]     # the shared declared ones
    for t in tables:
        if name in t:
            return dict(t[name])
    for declared, prefix in DECLARED.values():
        if prefix and name.startswith(prefix) and name[len(prefix):] in declared:
            return dict(declared[name[len(prefix):]])
    if name.startswith("spot_"):
        base = attributes(name[5:])
        return {**base, "long_name": f"{base['long_name']} at the spot point"}
    if name.startswith("esc_"):
        base = attributes(name[4:])
        return {**base, "long_name": f"{base['long_name']} at the escalated point"}
    if name in OUTPUTS:                             # a sweep-grid variable no table lists
        return dict(OUTPUTS[name].attrs)
    if name.startswith("median_") and name[7:] in PARAMETERS:
        base = PARAMETERS[name[7:]]
        return {"units": base["units"], "long_name": f"median {name[7:]} of the lognormal fragility curve"}
    raise KeyError(f"variable {name!r} is not declared in screening.solvers.schema")


def global_attributes(version, **extra):
    """Global attributes common to every dataset (``Conventions``, intensity convention, version).

    Parameters
    ----------
    version : str
        The package version that made the dataset.
    **extra
        More global attributes (``title``, ``source``, ...).

    Returns
    -------
    dict
        ``Conventions`` (``"CF-1.8"``), ``intensity_convention`` (how ``S0`` is defined: two-sided
        PSD, ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``), ``screening_version``, ``references``
        and ``extra``.

    """
    return {"Conventions": CONVENTIONS, "intensity_convention": INTENSITY_CONVENTION,
            "screening_version": version, "references": REFERENCE, **extra}


def apply_schema(ds, table=None, **global_attrs):
    """``ds`` with the declared attributes on every data variable and coordinate, and the global ones.

    ``table``: the producer's own table (e.g. ``datasets.MONTE_CARLO`` for ``monte_carlo``) tried before the
    shared ones.  Existing attributes other than ``units``, ``long_name`` and flags are kept.
    Raises ``KeyError`` naming any variable that is not declared.

    Parameters
    ----------
    ds : xarray.Dataset
        A producer's dataset.
    table : dict, optional
        The producer's own table, tried before the shared ones (:func:`attributes`).
    **global_attrs
        Global attributes beside those of :func:`global_attributes`.

    Returns
    -------
    xarray.Dataset
        A copy of ``ds`` with ``units``/``long_name`` (and flags, their values in the variable's
        dtype) on every variable and coordinate, and the global attributes.

    Raises
    ------
    KeyError
        A variable or coordinate that is not declared.

    """
    ds = ds.copy()
    for name in list(ds.variables):
        declared = attributes(name, table)
        var = ds[name]
        flags = {k: v for k, v in declared.items() if k.startswith("flag_")}
        if flags:
            declared["flag_values"] = np.asarray(flags["flag_values"], dtype=var.dtype)
        var.attrs.update(declared)
    ds.attrs.update(global_attributes(__version__, **global_attrs))
    return ds

