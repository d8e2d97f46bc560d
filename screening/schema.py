"""CF-style metadata (units, long_name) of every variable the package writes."""

from __future__ import annotations

from screening.solvers.moments import STATUS_MEANINGS

#: Time coordinate: named ``t`` (a coordinate named ``time`` with units ``s`` trips CF checkers).
TIME = {"units": "s", "long_name": "time since the start of the excitation", "axis": "T"}

VARIABLES = {
    "var_theta": {"units": "rad2", "long_name": "variance of the rocking rotation"},
    "var_theta_dot": {"units": "rad2 s-2", "long_name": "variance of the rocking angular velocity"},
    "cov_theta_theta_dot": {"units": "rad2 s-1",
                            "long_name": "covariance of rocking rotation and angular velocity"},
    "c_eq": {"units": "N m s rad-1", "long_name": "equivalent linear rocking damping"},
    "k_eq": {"units": "N m rad-1", "long_name": "equivalent linear rocking stiffness"},
    "p_uplift": {"units": "1", "long_name": "probability of uplift (|theta| > theta_ul)"},
    "t_stop": {"units": "s", "long_name": "time at which the integration of the point stopped"},
    "n_steps": {"units": "1", "long_name": "number of solver steps (accepted and rejected)"},
    "n_rejected": {"units": "1", "long_name": "number of rejected solver steps"},
    "peak_var_theta": {"units": "rad2", "long_name": "peak variance of the rocking rotation"},
    "t_peak_var_theta": {"units": "s", "long_name": "time of the peak rotation variance"},
    "peak_p_uplift": {"units": "1", "long_name": "peak probability of uplift"},
    "min_k_eq": {"units": "N m rad-1", "long_name": "minimum equivalent linear rocking stiffness"},
    "theta_ul": {"units": "rad", "long_name": "static uplift threshold angle m g / (2 b^2 k)"},
}

STATUS = {
    "long_name": "solver status of the point",
    "flag_values": sorted(STATUS_MEANINGS),
    "flag_meanings": " ".join(STATUS_MEANINGS[k] for k in sorted(STATUS_MEANINGS)),
}

#: Units and long names of the model parameters, for coordinates and attributes.
PARAMETERS = {
    "m": {"units": "kg", "long_name": "block mass"},
    "b": {"units": "m", "long_name": "half-width of the block base"},
    "h": {"units": "m", "long_name": "height of the centre of mass above the base"},
    "I_cm": {"units": "kg m2", "long_name": "moment of inertia about the centre of mass"},
    "g": {"units": "m s-2", "long_name": "gravitational acceleration"},
    "k": {"units": "N m-2", "long_name": "distributed foundation stiffness"},
    "lam": {"units": "N s m-4", "long_name": "Hunt-Crossley distributed damping"},
    "c": {"units": "N s m-2", "long_name": "Winkler distributed viscous damping"},
    "eps": {"units": "m-2", "long_name": "cubic stiffness parameter of the contact law"},
    "S0": {"units": "m2 s-3",
           "long_name": "two-sided PSD level of the driving white noise, E[xi xi] = 2 pi S0 delta"},
    "omega_g": {"units": "rad s-1", "long_name": "Kanai-Tajimi filter frequency"},
    "zeta_g": {"units": "1", "long_name": "Kanai-Tajimi filter damping ratio"},
    "T1": {"units": "s", "long_name": "envelope decay time T1"},
    "T2": {"units": "s", "long_name": "envelope rise time T2"},
}
