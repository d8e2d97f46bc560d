"""Fragility post-processing: probability that |theta| exceeds a rotation during the record.

From the Gaussian second-order statistics of the linearization, by the up-crossing
approximation:

* Rice's rate for the non-stationary, correlated Gaussian pair ``(theta, theta')``: the
  mean rate of outward crossings of the double barrier ``|theta| = a`` is
  ``nu(a, t) = 2 p_theta(a) [s phi(mu/s) + mu Phi(mu/s)]`` with the conditional mean
  ``mu = a cov / var_theta`` and standard deviation ``s = sqrt(var_theta_dot - cov^2/var_theta)``
  of ``theta'`` given ``theta = a`` (``phi``, ``Phi``: standard normal pdf and cdf).  For a
  stationary process (``cov = 0``) it is ``(1/pi)(sigma_theta_dot/sigma_theta) exp(-a^2/(2 sigma_theta^2))``.
* Poisson: crossings independent, ``P = 1 - exp(-int_0^T nu dt)``.
* Vanmarcke (1975), double barrier: crossings come in clumps for narrow-band response;
  the hazard is ``nu (1 - exp(-sqrt(pi/2) delta^1.2 r)) / (1 - exp(-r^2/2))`` with
  ``r = a / sigma_theta`` and the bandwidth ``delta`` of the equivalent linear oscillator
  (damping ratio ``zeta = c_eq / (2 sqrt(k_eq M))``, white-noise input).

A fragility curve over a swept intensity (usually ``S0``) is fitted with the lognormal
model ``P(IM) = Phi(ln(IM / median) / beta)``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import optimize, special

_SQRT_2PI = np.sqrt(2.0 * np.pi)


def _phi(x):
    return np.exp(-0.5 * x * x) / _SQRT_2PI


def _Phi(x):
    return 0.5 * special.erfc(-x / np.sqrt(2.0))


def upcrossing_rate(var_theta, var_theta_dot, cov_theta_theta_dot, level):
    """Mean rate [1/s] of outward crossings of ``|theta| = level`` (Rice, both barriers).

    ``var_theta`` [rad2], ``var_theta_dot`` [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1],
    ``level`` [rad] > 0; arrays broadcast.  Zero where ``var_theta = 0``.
    """
    v = np.asarray(var_theta, dtype=float)
    vd = np.asarray(var_theta_dot, dtype=float)
    c = np.asarray(cov_theta_theta_dot, dtype=float)
    a = np.asarray(level, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        pos = v > 0
        vs = np.where(pos, v, 1.0)
        p_a = np.exp(-0.5 * a * a / vs) / (_SQRT_2PI * np.sqrt(vs))
        mu = a * c / vs
        s = np.sqrt(np.maximum(vd - c * c / vs, 0.0))
        ss = np.where(s > 0, s, 1.0)
        mean_outward = np.where(s > 0, s * _phi(mu / ss) + mu * _Phi(mu / ss), np.maximum(mu, 0.0))
        rate = 2.0 * p_a * mean_outward
    return np.where(pos, rate, 0.0) + 0.0 * a


def oscillator_bandwidth(zeta):
    """Spectral bandwidth ``delta`` [1] of a white-noise driven linear oscillator of damping ratio ``zeta`` (0 < zeta < 1)."""
    z = np.clip(np.asarray(zeta, dtype=float), 1e-12, 1 - 1e-12)
    q = np.sqrt(1.0 - z * z)
    ratio = (1.0 - 2.0 / np.pi * np.arctan(z / q)) ** 2 / (1.0 - z * z)
    return np.sqrt(np.clip(1.0 - ratio, 0.0, 1.0))


def vanmarcke_factor(var_theta, level, bandwidth):
    """Vanmarcke's clumping correction [1] to the double-barrier Poisson rate."""
    v = np.asarray(var_theta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.asarray(level, dtype=float) / np.sqrt(np.where(v > 0, v, np.nan))
        num = -np.expm1(-np.sqrt(np.pi / 2.0) * np.asarray(bandwidth, dtype=float) ** 1.2 * r)
        den = -np.expm1(-0.5 * r * r)
        factor = np.where(den > 0, num / den, 1.0)
    return np.where(v > 0, factor, 0.0)


def exceedance_probability_from_moments(t, var_theta, var_theta_dot, cov_theta_theta_dot, level,
                                        method="vanmarcke", bandwidth=None, axis=-1):
    """``P(max_t |theta| > level)`` [1] over the record sampled at times ``t`` [s].

    ``method``: ``"poisson"`` or ``"vanmarcke"`` (needs ``bandwidth``, same shape as the
    moments or broadcastable).  The hazard is integrated by the trapezoidal rule along
    ``axis``.
    """
    rate = upcrossing_rate(var_theta, var_theta_dot, cov_theta_theta_dot, level)
    if method == "vanmarcke":
        if bandwidth is None:
            raise ValueError("parameter 'bandwidth' is required with method='vanmarcke'")
        rate = rate * vanmarcke_factor(var_theta, level, bandwidth)
    elif method != "poisson":
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    return -np.expm1(-np.trapezoid(rate, np.asarray(t, dtype=float), axis=axis))


def mcs_exceedance_probability(peak_abs_theta, level, overturned=None):
    """Fraction of Monte Carlo samples whose peak ``|theta|`` [rad] exceeds ``level`` [rad].

    Overturned samples count as exceedances.  Returns ``(p, standard_error)``.
    """
    peaks = np.asarray(peak_abs_theta, dtype=float)
    hit = peaks > level
    if overturned is not None:
        hit = hit | np.asarray(overturned, dtype=bool)
    n = hit.size
    p = hit.mean()
    return float(p), float(np.sqrt(max(p * (1 - p), 0.0) / n))


def lognormal_fragility(intensity, median, beta):
    """``Phi(ln(intensity / median) / beta)`` [1]."""
    return _Phi(np.log(np.asarray(intensity, dtype=float) / median) / beta)


def fit_lognormal_fragility(intensity, probability=None, n_exceed=None, n_total=None):
    """Fit ``(median, beta)`` of a lognormal fragility curve.

    Either to probabilities (least squares on the probit scale where ``0 < p < 1``) or,
    with ``n_exceed`` of ``n_total`` samples per intensity, by binomial maximum likelihood.
    """
    im = np.asarray(intensity, dtype=float).ravel()
    if n_exceed is not None:
        k = np.asarray(n_exceed, dtype=float).ravel()
        n = np.asarray(n_total, dtype=float).ravel() * np.ones_like(k)

        def nll(x):
            p = np.clip(lognormal_fragility(im, np.exp(x[0]), np.exp(x[1])), 1e-15, 1 - 1e-15)
            return -np.sum(k * np.log(p) + (n - k) * np.log1p(-p))

        x0 = [np.log(np.median(im)), np.log(0.5)]
        x = optimize.minimize(nll, x0, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-12,
                                                                      "maxiter": 4000}).x
        return float(np.exp(x[0])), float(np.exp(x[1]))
    p = np.asarray(probability, dtype=float).ravel()
    use = np.isfinite(p) & (p > 1e-6) & (p < 1 - 1e-6) & (im > 0)
    if use.sum() < 2:
        raise ValueError("need at least two intensities with 0 < probability < 1 to fit a fragility curve")
    z = special.ndtri(p[use])
    slope, intercept = np.polyfit(np.log(im[use]), z, 1)
    beta = 1.0 / slope
    return float(np.exp(-intercept * beta)), float(beta)


# ------------------------------------------------------------------ xarray layer
def _parameter(ds, name):
    """A model parameter from the dataset: a coordinate/variable if swept, else an attribute."""
    for var in (name, f"{name}_value"):          # a swept k is stored as k_value (screening.workflow.sweep)
        if var in ds.variables:
            return ds[var]
    if name in ds.attrs:
        return xr.DataArray(float(ds.attrs[name]))
    raise KeyError(f"the dataset does not record the parameter '{name}'")


def threshold_angle(ds, threshold, relative_to=None):
    """The rotation [rad] meant by ``threshold``: absolute, or a fraction of the slenderness
    angle ``atan(b/h)`` (``relative_to="slenderness"``) or of ``theta_ul`` (``"theta_ul"``)."""
    if relative_to is None:
        return xr.DataArray(float(threshold))
    if relative_to == "slenderness":
        return threshold * np.arctan2(_parameter(ds, "b"), _parameter(ds, "h"))
    if relative_to == "theta_ul":
        m, g, b, k = (_parameter(ds, n) for n in ("m", "g", "b", "k"))
        return threshold * m * g / (2.0 * b**2 * k)
    raise ValueError(f"parameter 'relative_to' must be None, 'slenderness' or 'theta_ul' (got {relative_to!r})")


def equivalent_damping_ratio(ds):
    """``zeta_eq(t) = c_eq / (2 sqrt(k_eq M))`` [1] along the record."""
    m, h, b = (_parameter(ds, n) for n in ("m", "h", "b"))
    I_cm = _parameter(ds, "I_cm") if ("I_cm" in ds.variables or "I_cm" in ds.attrs) else m * (b**2 + h**2) / 3
    M = I_cm + m * h**2
    k_eq = ds["k_eq"].where(ds["k_eq"] > 0)
    return ds["c_eq"] / (2.0 * np.sqrt(k_eq * M))


def exceedance_probability(ds, threshold, relative_to=None, method="vanmarcke"):
    """Probability [1] that ``|theta|`` exceeds the threshold during the record, over all swept dims.

    Points whose linearized model became unstable (status 1: k_eq <= 0, or 2: sigma_theta
    beyond the slenderness angle) are given probability 1; points that failed numerically
    (status 3, 4) are NaN.
    """
    level = threshold_angle(ds, threshold, relative_to)
    bandwidth = None
    if method == "vanmarcke":
        bandwidth = xr.apply_ufunc(oscillator_bandwidth, equivalent_damping_ratio(ds).fillna(0.05))
    args = [ds["var_theta"], ds["var_theta_dot"], ds["cov_theta_theta_dot"], level]
    filled = [a.fillna(0.0) if "t" in a.dims else a for a in args]
    extra = [bandwidth] if bandwidth is not None else []

    def _prob(t, v, vd, c, a, *bw):
        return exceedance_probability_from_moments(t, v, vd, c, a, method=method,
                                                   bandwidth=bw[0] if bw else None)

    p = xr.apply_ufunc(_prob, ds["t"], *filled, *extra,
                       input_core_dims=[["t"]] * 4 + [[]] + ([["t"]] if extra else []),
                       output_core_dims=[[]])
    if "status" in ds:
        p = xr.where(ds["status"].isin([1, 2]), 1.0, xr.where(ds["status"] == 0, p, np.nan))
    p.attrs = {"units": "1", "long_name": f"probability that |theta| exceeds the threshold ({method})",
               "threshold_rad": float(level.max()) if level.size else float(level),
               "method": method}
    return p.rename("p_exceed")


def fragility_curve(ds, threshold, dim="S0", relative_to=None, method="vanmarcke"):
    """Exceedance probability along the intensity ``dim`` and its lognormal fit.

    Returns ``(p, median, beta)``: ``p`` over all swept dims; ``median`` and ``beta``
    DataArrays over the other dims.
    """
    p = exceedance_probability(ds, threshold, relative_to, method)
    if dim not in p.dims:
        raise ValueError(f"parameter 'dim' must be a swept dimension of the dataset (got {dim!r}; have {list(p.dims)})")
    im = p[dim]

    def _fit(prob):
        try:
            return np.array(fit_lognormal_fragility(im.values, prob))
        except ValueError:
            return np.array([np.nan, np.nan])

    fit = xr.apply_ufunc(_fit, p, input_core_dims=[[dim]], output_core_dims=[["fit"]], vectorize=True)
    median = fit.isel(fit=0, drop=True).assign_attrs(units=_parameter(ds, dim).attrs.get("units", ""),
                                                     long_name=f"median {dim} of the lognormal fragility")
    beta = fit.isel(fit=1, drop=True).assign_attrs(units="1", long_name="lognormal dispersion beta")
    return p, median, beta


@xr.register_dataset_accessor("rocking")
class RockingAccessor:
    """``ds.rocking.exceedance_probability(...)`` and ``ds.rocking.fragility_curve(...)``."""

    def __init__(self, ds):
        self._ds = ds

    def exceedance_probability(self, threshold, relative_to=None, method="vanmarcke"):
        return exceedance_probability(self._ds, threshold, relative_to, method)

    def fragility_curve(self, threshold, dim="S0", relative_to=None, method="vanmarcke"):
        return fragility_curve(self._ds, threshold, dim, relative_to, method)


def spot_positions(ds):
    """Integer positions of the Monte Carlo spot points along each grid dimension.

    Returns a dict ``{dim: DataArray over spot}`` for ``ds.isel(...)`` (pointwise), from the
    ``spot_<dim>`` coordinates of a sweep result (``spot_case`` holds the case index; a swept
    ``k`` is matched against ``k_value``).
    """
    positions = {}
    for dim in ds["status"].dims:
        spot = ds[f"spot_{dim}"].values
        if dim == "case":
            idx = spot.astype(int)
        else:
            grid = _parameter(ds, dim).values
            idx = np.abs(grid[None, :] - spot[:, None]).argmin(axis=1)
        positions[dim] = xr.DataArray(idx, dims="spot")
    return positions


def mcs_exceedance_at_spots(ds, level):
    """Probability [1] that ``|theta|`` exceeds ``level`` [rad] from the per-sample peaks of the
    Monte Carlo spot checks (``mcs_peak_abs_theta``, ``mcs_sample_state`` of a sweep result).

    Overturned samples count as exceedances; diverged or failed samples are left out.
    ``level`` may vary over the grid (it is taken at each spot point).  Returns
    ``(p, standard_error)`` over ``spot``.
    """
    if level.ndim:
        level = level.isel({d: i for d, i in spot_positions(ds).items() if d in level.dims})
    peaks = ds["mcs_peak_abs_theta"]
    state = ds["mcs_sample_state"] if "mcs_sample_state" in ds else xr.zeros_like(peaks, dtype=np.int8)
    over = state == 1
    valid = (state == 0) | over
    n = valid.sum("sample")
    p = (((peaks > level) | over) & valid).sum("sample") / n.where(n > 0)
    se = np.sqrt(p * (1 - p) / n.where(n > 0))
    p.attrs = {"units": "1", "long_name": "probability that |theta| exceeds the threshold, from the Monte Carlo "
                                          "sample peaks"}
    se.attrs = {"units": "1", "long_name": "standard error of mcs_p_exceed (binomial)"}
    return p, se


def fragility_dataset(ds, threshold, relative_to=None, method="vanmarcke", dim="S0"):
    """The fragility result of a sweep: a Dataset with ``p_exceed`` over the swept dims and,
    when ``dim`` is swept with at least two points, the lognormal ``median`` and ``beta``.

    At Monte Carlo spot points (``spot`` dimension with per-sample ``mcs_peak_abs_theta``),
    the same probability from the sample peaks (``mcs_p_exceed`` and its standard error)
    is put beside the Gaussian one (``p_exceed_at_spot``).
    """
    level = threshold_angle(ds, threshold, relative_to)
    p = exceedance_probability(ds, threshold, relative_to, method)
    out = xr.Dataset({"p_exceed": p})
    if dim in p.dims and p.sizes[dim] >= 2:
        _, median, beta = fragility_curve(ds, threshold, dim, relative_to, method)
        out["median"] = median
        out["beta"] = beta
    if "mcs_peak_abs_theta" in ds and "spot" in ds.dims:
        out["mcs_p_exceed"], out["mcs_p_exceed_se"] = mcs_exceedance_at_spots(ds, level)
        at_spot = p.isel(spot_positions(ds)) if p.ndim else p.expand_dims(spot=ds.sizes["spot"])
        out["p_exceed_at_spot"] = at_spot.assign_attrs(
            units="1", long_name=f"{p.attrs['long_name']} at the spot point")
    out["threshold_rad"] = level.assign_attrs(units="rad", long_name="rotation threshold")
    out = out.assign_coords({c: ds[c] for c in out.coords if c in ds.variables})     # units, long_name
    out.attrs.update(threshold=float(threshold), relative_to=str(relative_to), method=method,
                     Conventions="CF-1.8",
                     title="Probability that |theta| exceeds a rotation during the record")
    return out
