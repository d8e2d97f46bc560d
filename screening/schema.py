"""The CF metadata of everything the package returns or writes, declared once.

Every variable and coordinate name the package produces is declared here with its ``units``
and ``long_name`` (CF-1.8 / UDUNITS spelling; ``"1"`` is dimensionless), status variables with
their flag attributes (:mod:`screening.status`), and :func:`apply_schema` applies them, with the
global attributes, to a dataset in one place.  Producers (solvers, sweep, trade study,
fragility) build plain datasets and call :func:`apply_schema`; none writes its own units.
"""

from __future__ import annotations

import numpy as np

from screening.status import PointStatus, SampleState, SpotStatus, flag_attributes

CONVENTIONS = "CF-1.8"
INTENSITY_CONVENTION = "E[xi(t) xi(s)] = 2 pi S0 delta(t - s), S0 two-sided PSD"
REFERENCE = ("Nonlinear dynamics of rocking rigid blocks under stochastic base excitation: stochastic "
             "linearization with Lyapunov moment equations (method and corrections: docs/method.md)")

#: Time coordinate: named ``t``; no ``axis = "T"`` in files (CF would then want "units since epoch").
TIME = {"units": "s", "long_name": "time since the start of the excitation"}


def _v(units, long_name, **extra):
    return {"units": units, "long_name": long_name, **extra}


#: Model parameters (coordinates, swept or scalar).
PARAMETERS = {
    "m": _v("kg", "block mass"),
    "b": _v("m", "half-width of the block base"),
    "h": _v("m", "height of the centre of mass above the base"),
    "I_cm": _v("kg m2", "moment of inertia about the centre of mass"),
    "g": _v("m s-2", "gravitational acceleration"),
    "k": _v("N m-2", "distributed foundation stiffness"),
    "lam": _v("N s m-4", "Hunt-Crossley distributed damping"),
    "c": _v("N s m-2", "Winkler distributed viscous damping"),
    "eps": _v("m-2", "cubic stiffness parameter of the contact law"),
    "S0": _v("m2 s-3", "two-sided PSD level of the driving white noise, E[xi xi] = 2 pi S0 delta"),
    "omega_g": _v("rad s-1", "Kanai-Tajimi filter frequency"),
    "zeta_g": _v("1", "Kanai-Tajimi filter damping ratio"),
    "T1": _v("s", "envelope decay time T1"),
    "T2": _v("s", "envelope rise time T2"),
}

#: Quantities derived from the model (stored beside the parameters, never re-derived downstream).
DERIVED = {
    "theta_ul": _v("rad", "static uplift threshold angle of the condensation"),
    "slenderness": _v("rad", "slenderness angle atan(b/h), the rigid-block overturning angle"),
    "m_sdof": _v("kg m2", "rotational inertia about the rocking edge, I_cm + m h2"),
    "theta_capacity": _v("rad", "capacity angle of the condensation (no quasi-static equilibrium beyond; "
                                "inf if none)"),
}

#: Linearization (stochastic linearization + Lyapunov moments).
LINEARIZATION = {
    "var_theta": _v("rad2", "variance of the rocking rotation"),
    "var_theta_dot": _v("rad2 s-2", "variance of the rocking angular velocity"),
    "cov_theta_theta_dot": _v("rad2 s-1", "covariance of rocking rotation and angular velocity"),
    "c_eq": _v("N m s rad-1", "equivalent linear rocking damping"),
    "k_eq": _v("N m rad-1", "equivalent linear rocking stiffness"),
    "p_uplift": _v("1", "probability of uplift (|theta| > theta_ul)"),
    "t_stop": _v("s", "time at which the integration of the point stopped"),
    "n_steps": _v("1", "number of solver steps (accepted and rejected)"),
    "n_rejected": _v("1", "number of rejected solver steps"),
    "peak_var_theta": _v("rad2", "peak variance of the rocking rotation"),
    "t_peak_var_theta": _v("s", "time of the peak rotation variance"),
    "peak_p_uplift": _v("1", "peak probability of uplift"),
    "min_k_eq": _v("N m rad-1", "minimum equivalent linear rocking stiffness"),
    "peak_p_beyond_capacity": _v("1", "Gaussian probability that |theta| exceeds theta_capacity at the peak "
                                      "var_theta"),
    "status": flag_attributes(PointStatus, "solver status of the point"),
}

#: Monte Carlo ensembles (``monte_carlo``); in sweeps the same names carry the prefix ``mcs_``.
MONTE_CARLO = {
    "var_theta": _v("rad2", "Monte Carlo ensemble variance of the rocking rotation"),
    "var_theta_dot": _v("rad2 s-2", "Monte Carlo ensemble variance of the rocking angular velocity"),
    "cov_theta_theta_dot": _v("rad2 s-1", "Monte Carlo ensemble covariance of theta and theta'"),
    "var_theta_se": _v("rad2", "standard error of the Monte Carlo rotation variance"),
    "var_theta_dot_se": _v("rad2 s-2", "standard error of the Monte Carlo angular-velocity variance"),
    "p_uplift": _v("1", "fraction of Monte Carlo samples in uplift"),
    "peak_abs_theta": _v("rad", "peak |theta| of each Monte Carlo sample over the record (up to overturning "
                                "or divergence)"),
    "overturned": _v("1", "Monte Carlo sample overturned (|theta| > atan(b/h))"),
    "diverged": _v("1", "Monte Carlo sample diverged (excluded from the statistics)"),
    "n_steps": _v("1", "integration steps of the sample (accepted + rejected)"),
    "n_overturned": _v("1", "number of overturned Monte Carlo samples"),
    "n_diverged": _v("1", "number of diverged Monte Carlo samples"),
    "n_used": _v("1", "number of Monte Carlo samples in the statistics"),
    "peak_var_theta": _v("rad2", "peak over the output times of the Monte Carlo rotation variance"),
    "peak_var_theta_dot": _v("rad2 s-2", "peak over the output times of the Monte Carlo angular-velocity "
                                         "variance"),
    "rel_error_peak_var_theta": _v("1", "relative error of the linearization's peak var_theta against Monte "
                                        "Carlo, (max_t lin - max_t mcs) / max_t mcs on the output times"),
    "rel_error_peak_var_theta_dot": _v("1", "relative error of the linearization's peak var_theta_dot "
                                            "against Monte Carlo, (max_t lin - max_t mcs) / max_t mcs"),
    "sample_state": flag_attributes(SampleState, "state of each Monte Carlo sample at the end of the record"),
    "status": flag_attributes(SpotStatus, "status of the Monte Carlo spot check"),
}

#: Fragility (exceedance of a rotation threshold).
FRAGILITY = {
    "p_exceed": _v("1", "probability that |theta| exceeds the threshold during the record"),
    "p_exceed_at_spot": _v("1", "Gaussian probability that |theta| exceeds the threshold, at the spot point"),
    "mcs_p_exceed": _v("1", "probability that |theta| exceeds the threshold, from the Monte Carlo peaks"),
    "mcs_p_exceed_se": _v("1", "standard error of mcs_p_exceed (binomial)"),
    "threshold_rad": _v("rad", "rotation threshold"),
    "beta": _v("1", "lognormal dispersion beta of the fragility curve"),
}

#: Index and label coordinates.
COORDINATES = {
    "t": TIME,
    "sample": _v("1", "Monte Carlo sample index (input seeded with default_rng([seed, sample]))"),
    "spot": _v("1", "Monte Carlo spot-check index"),
    "case": _v("1", "case index (names in case_name)"),
    "case_name": {"long_name": "case name (the [[case]] tables of the study file)"},
    # a swept k is stored in k_value on dimension k (screening.workflow.sweep.AUX_GRID_COORDINATES)
    "k_value": PARAMETERS["k"],
    # string choices that differ between the cases of a sweep (coordinates on case)
    "contact": {"long_name": "contact model of the case"},
    "condensation": {"long_name": "condensation model of the case"},
    "excitation": {"long_name": "excitation model of the case"},
    "envelope": {"long_name": "envelope model of the case"},
}


def attributes(name, table=None):
    """The declared attributes of ``name`` (``table``: one of the dicts above, tried first).

    Parameters and derived quantities are found by their own names and with the prefix
    ``spot_`` (their value at a Monte Carlo spot point); Monte Carlo names with the prefix
    ``mcs_``.  Raises ``KeyError`` for an undeclared name.
    """
    tables = ([table] if table is not None else []) + [LINEARIZATION, PARAMETERS, DERIVED, COORDINATES,
                                                       FRAGILITY]
    for t in tables:
        if name in t:
            return dict(t[name])
    if name.startswith("mcs_") and name[4:] in MONTE_CARLO:
        return dict(MONTE_CARLO[name[4:]])
    if name.startswith("spot_"):
        base = attributes(name[5:])
        return {**base, "long_name": f"{base['long_name']} at the spot point"}
    if name.startswith("median_") and name[7:] in PARAMETERS:
        base = PARAMETERS[name[7:]]
        return {"units": base["units"], "long_name": f"median {name[7:]} of the lognormal fragility curve"}
    raise KeyError(f"variable {name!r} is not declared in screening.schema")


def global_attributes(version, **extra):
    """Global attributes common to every dataset (``Conventions``, intensity convention, version)."""
    return {"Conventions": CONVENTIONS, "intensity_convention": INTENSITY_CONVENTION,
            "screening_version": version, "references": REFERENCE, **extra}


def apply_schema(ds, table=None, **global_attrs):
    """``ds`` with the declared attributes on every data variable and coordinate, and the global ones.

    ``table``: the producer's own table (e.g. :data:`MONTE_CARLO` for ``monte_carlo``) tried before the
    shared ones.  Existing attributes other than ``units``, ``long_name`` and flags are kept.
    Raises ``KeyError`` naming any variable that is not declared.
    """
    from screening import __version__

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


# names still used by modules being moved onto apply_schema (issue 11); removed when the last one is
VARIABLES = {**LINEARIZATION, "theta_ul": DERIVED["theta_ul"]}
STATUS = LINEARIZATION["status"]
