"""The indicators the linearization computes for every point, read by the trust rules
(:mod:`screening.analysis.trust`) and the error atlas model (:mod:`screening.analysis.error_model`).

* ``peak_p_uplift`` — the linearization's peak uplift probability;
* ``k_eq_margin = min k_eq / k_eq(0)`` — how far the equivalent stiffness dropped;
* ``sigma_ratio = sqrt(peak var_theta) / atan(b/h)`` — closeness to the rigid-block toppling angle;
* ``decay_excess = (var_theta(t_end) / peak var_theta) / (q(t_end)^2 / max q^2)`` — the variance retained
  at the end of the record over the envelope's retained power (>> 1: the stiff-bed lock-in).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from screening.model.excitation import Envelope

__all__ = ["ENVELOPE_FLOOR", "envelope_fraction", "trust_indicators", "indicators_from_dataset"]

#: Floor of the envelope's late fraction q(t_end)^2 / max q^2 (avoids dividing by ~0).
ENVELOPE_FLOOR = 1e-12


def envelope_fraction(ds):
    """``q(t_end)^2 / max_t q(t)^2`` of a dataset's envelope on its output times (1 for a constant one)."""
    kind = ds.attrs.get("envelope", "exponential")
    if kind == "constant":
        return xr.DataArray(1.0)
    q2 = Envelope(ds["T1"], ds["T2"])(ds["t"]) ** 2       # eq. (57), the model's own envelope
    return q2.isel(t=-1) / q2.max("t")


def trust_indicators(peak_p_uplift, min_k_eq, k_eq_rest, peak_var_theta, slenderness, var_theta_end,
                     envelope_end_fraction):
    """The numeric indicators of the rule (numpy arrays, broadcast against each other).

    Parameters
    ----------
    peak_p_uplift : SL peak uplift probability [1].
    min_k_eq, k_eq_rest : minimum and at-rest equivalent stiffness [N m rad-1].
    peak_var_theta : SL peak var_theta [rad2].
    slenderness : atan(b/h) [rad].
    var_theta_end : SL var_theta at the end of the record [rad2].
    envelope_end_fraction : ``q(t_end)^2 / max q^2`` [1] (1 for stationary input).

    Returns
    -------
    dict
        ``{"peak_p_uplift", "k_eq_margin", "sigma_ratio", "decay_excess"}`` (see the module docstring),
        arrays broadcast to one shape.
    """
    peak = np.asarray(peak_var_theta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        margin = np.asarray(min_k_eq, dtype=float) / np.asarray(k_eq_rest, dtype=float)
        sigma_ratio = np.sqrt(peak) / np.asarray(slenderness, dtype=float)
        retained = np.asarray(var_theta_end, dtype=float) / peak
        decay = retained / np.maximum(np.asarray(envelope_end_fraction, dtype=float), ENVELOPE_FLOOR)
    out = {"peak_p_uplift": np.asarray(peak_p_uplift, dtype=float), "k_eq_margin": margin,
           "sigma_ratio": sigma_ratio, "decay_excess": decay}
    shape = np.broadcast_shapes(*(v.shape for v in out.values()))
    return {k: np.broadcast_to(v, shape) for k, v in out.items()}


def indicators_from_dataset(ds):
    """:func:`trust_indicators` of a :func:`screening.linearize` (or sweep) dataset, as DataArrays on the
    dimensions of ``peak_var_theta``."""
    dims = ds["peak_var_theta"].dims
    peak = ds["peak_var_theta"]

    def on(x):
        return xr.DataArray(x).broadcast_like(peak).transpose(*dims).values

    nan = xr.DataArray(np.nan)
    k_rest = ds["k_eq"].isel(t=0) if "k_eq" in ds.variables else ds.get("k_eq_rest", nan)
    var_end = ds["var_theta"].isel(t=-1) if "var_theta" in ds.variables else ds.get("var_theta_end", nan)
    ind = trust_indicators(on(ds["peak_p_uplift"]), on(ds["min_k_eq"]), on(k_rest), on(peak),
                           on(ds["slenderness"]), on(var_end), on(envelope_fraction(ds)))
    return {name: xr.DataArray(np.array(v), dims=dims) for name, v in ind.items()}
