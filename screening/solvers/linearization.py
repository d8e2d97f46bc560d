"""``linearize``: the stochastic-linearization response of one block as a labelled dataset."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import erfc

from screening import __version__
from screening.condensation import get as get_condensation
from screening.solvers.moments import DEFAULT_RTOL, HISTORY_VARIABLES, solve_moments
from screening.status import PointStatus
from screening.schema import STATUS, TIME, VARIABLES
from screening.solvers.timegrid import output_times


def model_attributes(block, foundation, excitation):
    """Flat dict of the (scalar) inputs, for dataset attributes."""
    attrs = {"m": block.m, "b": block.b, "h": block.h, "I_cm": block.I_cm, "g": block.g,
             "contact": foundation.contact, "k": foundation.k, "eps": foundation.eps,
             "excitation": excitation.kind, "S0": excitation.S0,
             "envelope": excitation.envelope.kind,
             "intensity_convention": "E[xi(t) xi(s)] = 2 pi S0 delta(t - s), S0 two-sided PSD"}
    if foundation.contact == "hunt_crossley":
        attrs["lam"] = foundation.lam
    else:
        attrs["c"] = foundation.c
    if excitation.kind == "kanai_tajimi":
        attrs.update(omega_g=excitation.omega_g, zeta_g=excitation.zeta_g)
    if excitation.envelope.kind == "exponential":
        attrs.update(T1=excitation.envelope.T1, T2=excitation.envelope.T2)
    return {k: (float(v) if isinstance(v, (int, float, np.floating)) else v) for k, v in attrs.items()}


def linearize(block, foundation, excitation, t_end=20.0, dt=0.05, rtol=DEFAULT_RTOL, condensation="paper"):
    """Time-varying second-order rocking statistics by stochastic linearization (sections 2.4–2.6).

    Parameters
    ----------
    block, foundation, excitation : scalar model objects (for batches of points use
        :func:`screening.solvers.moments.solve_moments`, which this wraps).
    t_end : record length [s]. dt : output step [s] (the solver is adaptive and finer).
    rtol : solver relative tolerance.
    condensation : ``"paper"`` (eqs. 17–25, default) or ``"cubic"`` (static balance with the
        cubic term, :mod:`screening.condensation.cubic`); recorded in ``attrs["condensation"]``.

    Returns
    -------
    xarray.Dataset on the coordinate ``t`` [s] with ``var_theta`` [rad2], ``var_theta_dot``
    [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1], ``c_eq`` [N m s rad-1], ``k_eq``
    [N m rad-1], ``p_uplift`` [1] (eq. 58), the scalar summaries ``peak_var_theta``,
    ``t_peak_var_theta``, ``peak_p_uplift``, ``min_k_eq``, ``status`` (CF flag variable)
    and ``t_stop``.  Inputs are stored as attributes.  Values after a point stopped
    (status != 0) are NaN.  With ``"cubic"`` the attributes also hold ``theta_capacity`` [rad]
    (softening beds: no quasi-static equilibrium beyond it; ``inf`` otherwise) and
    ``peak_p_beyond_capacity``, the Gaussian probability ``P(|theta| > theta_capacity)`` at the
    peak ``var_theta`` (where the cubic condensation leaves its validity).
    """
    cond = get_condensation(condensation)
    t = output_times(t_end, dt)
    res = solve_moments(block, foundation, excitation, t, rtol=rtol, condensation=cond)
    if res["status"].ndim != 0:
        raise ValueError("linearize() takes scalar model parameters; use "
                         "screening.solvers.moments.solve_moments for arrays of points")
    data = {name: (("t",), res[name], VARIABLES[name]) for name in HISTORY_VARIABLES}
    for name in ("peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq", "t_stop",
                 "n_steps"):
        data[name] = ((), res[name], VARIABLES[name])
    data["status"] = ((), res["status"], STATUS)
    theta_ul_meta = dict(VARIABLES["theta_ul"])
    if condensation == "cubic":
        theta_ul_meta["long_name"] = ("static uplift threshold angle, cubic static balance: "
                                      "b theta_ul (1 + 2 eps b^2 theta_ul^2) = m g / (2 b k)")
    data["theta_ul"] = ((), cond.uplift_threshold(block, foundation), theta_ul_meta)
    ds = xr.Dataset(data, coords={"t": ("t", t, TIME)})
    ds.attrs.update(model_attributes(block, foundation, excitation))
    ds.attrs.update(method="stochastic linearization + Lyapunov moment equations",
                    status_meaning=PointStatus(int(res["status"])).name, rtol=float(rtol),
                    condensation=cond.name, screening_version=__version__)
    if condensation == "cubic":
        cap = float(cond.capacity_angle(block, foundation))
        peak = float(res["peak_var_theta"])
        beyond = float(erfc(cap / np.sqrt(2.0 * peak))) if np.isfinite(cap) and peak > 0 else 0.0
        ds.attrs.update(theta_capacity=cap, peak_p_beyond_capacity=beyond,
                        condensation_note="quasi-static z_cb from the static vertical balance with the "
                                          "cubic term (eqs. 13, 15); C, K from eqs. 14, 16 with "
                                          "zdot_cb = z_cb'(theta) theta'")
    return ds
