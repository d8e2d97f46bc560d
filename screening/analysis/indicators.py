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

from screening.core.model.excitation import Envelope

__all__ = []

#: Floor of the envelope's late fraction q(t_end)^2 / max q^2 (avoids dividing by ~0).
ENVELOPE_FLOOR = 1e-12


def envelope_fraction(ds):
    """The envelope's power left at the end of the record: ``q(t_end)^2 / max_t q(t)^2``.

    Evaluated on the dataset's output times ``t`` with its envelope parameters ``T1``, ``T2``; 1 for a
    stationary (``envelope = "constant"``) input.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization dataset with ``t`` [s], ``T1`` and ``T2`` [s] and the attribute ``envelope``
        (``"exponential"`` when absent).

    Returns
    -------
    xarray.DataArray
        The fraction [1], on the dimensions of ``T1`` and ``T2``.

    Notes
    -----
    The envelope is ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` (eq. (57) in [1]); its square scales the
    input's power spectral density (eq. (56) in [1]).

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> ds = xr.Dataset({"T1": 4.0, "T2": 2.0}, coords={"t": np.linspace(0.0, 20.0, 201)})
    >>> q = lambda t: 4 * (np.exp(-t / 4) - np.exp(-t / 2))
    >>> f"{float(envelope_fraction(ds)):.5f}", f"{q(20.0) ** 2 / q(4 * np.log(2)) ** 2:.5f}"
    ('0.00072', '0.00072')
    >>> float(envelope_fraction(ds.assign_attrs(envelope="constant")))
    1.0
    """
    kind = ds.attrs.get("envelope", "exponential")
    if kind == "constant":
        return xr.DataArray(1.0)
    q2 = Envelope(ds["T1"], ds["T2"])(ds["t"]) ** 2       # eq. (57), the model's own envelope
    return q2.isel(t=-1) / q2.max("t")


def trust_indicators(peak_p_uplift, min_k_eq, k_eq_rest, peak_var_theta, slenderness, var_theta_end,
                     envelope_end_fraction):
    """The numeric indicators the trust rules read, from the linearization's outputs.

    The four numbers the rules of :mod:`screening.analysis.trust` compare with their thresholds; the
    inputs are numpy arrays (or scalars) that broadcast against each other.

    Parameters
    ----------
    peak_p_uplift : array_like
        The linearization's peak uplift probability [1].
    min_k_eq, k_eq_rest : array_like
        The minimum and the at-rest equivalent stiffness [N m rad-1].
    peak_var_theta : array_like
        The linearization's peak variance of the rotation [rad2].
    slenderness : array_like
        ``atan(b/h)`` [rad].
    var_theta_end : array_like
        The variance of the rotation at the end of the record [rad2].
    envelope_end_fraction : array_like
        ``q(t_end)^2 / max q^2`` [1] (1 for a stationary input; :func:`envelope_fraction`).

    Returns
    -------
    dict of str to numpy.ndarray
        ``{"peak_p_uplift", "k_eq_margin", "sigma_ratio", "decay_excess"}`` [1], broadcast to one shape.

    Notes
    -----
    ``k_eq_margin = min k_eq / k_eq(0)``; ``sigma_ratio = sqrt(peak var_theta) / atan(b/h)``;
    ``decay_excess = (var_theta(t_end) / peak var_theta) / max(q(t_end)^2 / max q^2, 1e-12)``.  The
    equivalent stiffness is that of the stochastic linearization (section 2.4 in [1]); ``atan(b/h)`` is
    the rigid block's toppling angle [2].

    References
    ----------
    [1] [mitseas2026]; [2] [housner1963].

    Examples
    --------
    >>> out = trust_indicators(0.3, 50.0, 100.0, 0.01, 0.2, 0.002, [0.1, 1.0])
    >>> out["k_eq_margin"].tolist(), out["sigma_ratio"].round(6).tolist(), out["decay_excess"].tolist()
    ([0.5, 0.5], [0.5, 0.5], [2.0, 0.2])
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
    """:func:`trust_indicators` of a :func:`screening.linearize` (or sweep) dataset.

    Reads the at-rest stiffness and the final variance from the time histories ``k_eq`` and
    ``var_theta`` when the dataset has them, else from ``k_eq_rest`` and ``var_theta_end`` (NaN when
    neither is there).

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization dataset: ``peak_p_uplift`` [1], ``min_k_eq`` [N m rad-1], ``peak_var_theta``
        [rad2], ``slenderness`` [rad], ``t``, ``T1``, ``T2`` [s] and ``k_eq`` / ``k_eq_rest``
        [N m rad-1], ``var_theta`` / ``var_theta_end`` [rad2].

    Returns
    -------
    dict of str to xarray.DataArray
        The indicators of :func:`trust_indicators` [1], on the dimensions of ``peak_var_theta``.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> ds = xr.Dataset({"peak_p_uplift": ("S0", [0.1, 0.4]), "min_k_eq": ("S0", [90.0, 40.0]),
    ...                  "k_eq_rest": 100.0, "peak_var_theta": ("S0", [1e-4, 4e-4]), "slenderness": 0.1,
    ...                  "var_theta_end": ("S0", [1e-5, 4e-5])}, attrs={"envelope": "constant"})
    >>> ind = indicators_from_dataset(ds)
    >>> ind["k_eq_margin"].dims, ind["k_eq_margin"].values.tolist(), ind["sigma_ratio"].values.round(6).tolist()
    (('S0',), [0.9, 0.4], [0.1, 0.2])
    """
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
