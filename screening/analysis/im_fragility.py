"""Fragility over an engineering intensity measure, and its export (CSV, OpenQuake NRML).

:func:`fragility_over_im` takes the exceedance probability of a result dataset
(:func:`screening.analysis.fragility.exceedance_probability`) along a swept dimension of the
excitation (usually ``S0``) and fits the lognormal curve ``P = Phi(ln(IM / median) / beta)``
over the intensity measure of each point (:mod:`screening.analysis.intensity`): ``pga``
(median PGA), ``sa`` (median Sa(T, 5 %), needs a period), ``rms``, ``arias`` or ``s0``.

Refusals and flags (a fit others will load must mean what it says):

* the dimension must carry intensity: the IM must change along it at every point, strictly
  increasing (``ValueError`` otherwise: a bed parameter such as ``eps`` is not an intensity,
  and a fit over a non-monotone IM has no meaning);
* a fitted ``beta <= 0`` (probability falling with intensity) is flagged in ``fit_flag`` and
  reported in the returned warnings; such fits are not exported;
* a threshold at or beyond the slenderness angle is reported: beyond it the rigid block has
  overturned and the Gaussian exceedance is not a rocking measure.

Exports: :func:`write_csv` (one row per fitted curve: the other dimensions' values, the IM
name and units, median, beta) and :func:`write_nrml` (OpenQuake NRML 0.5 ``fragilityModel``
with continuous ``logncdf`` functions; OpenQuake parametrises them by the *mean* and *standard
deviation* of the lognormal capacity, ``mean = median exp(beta^2/2)``,
``stddev = mean sqrt(exp(beta^2) - 1)``, and reads PGA and SA in g, Arias intensity ``IA`` in m/s).
"""

from __future__ import annotations

import csv
import math
from xml.sax.saxutils import quoteattr

import numpy as np
import xarray as xr

from screening.analysis.fragility import (exceedance_probability, fit_lognormal_fragility, model_quantity,
                                          parameter, threshold_angle)

#: ``--im`` names -> (variable, units, OpenQuake IMT or None, factor from the units to the OpenQuake units).
IMS = {
    "pga": ("pga_median", "m s-2", "PGA", 1.0 / 9.80665),
    "sa": ("sa_median", "m s-2", "SA", 1.0 / 9.80665),
    "rms": ("rms_acceleration", "m s-2", None, None),
    "arias": ("arias_intensity", "m s-1", "IA", 1.0),
    "s0": ("S0", "m2 s-3", None, None),
}

FIT_OK, FIT_NEGATIVE_BETA, FIT_NONE = 0, 1, 2
#: Limit states of a fragility: name -> the limit state's label in the exports (NRML ``limitStates``).
LIMIT_STATES = {"exceed": "theta_exceeds_threshold", "overturn": "overturn"}


def _im_values(ds, im, period, cutoff):
    from screening.analysis.intensity import intensity_measures
    if im == "s0":
        return parameter(ds, "S0"), None
    if im == "sa" and period is None:
        raise ValueError("--im sa needs the oscillator period (--period SECONDS)")
    measures = intensity_measures(ds, period=period if im == "sa" else None, cutoff=cutoff)
    return measures[IMS[im][0]], measures


def fragility_over_im(ds, threshold, im="pga", dim=None, relative_to=None, method="vanmarcke", period=None,
                      cutoff=None, limit_state="exceed"):
    """Exceedance probability along ``dim`` fitted over the intensity measure ``im``.

    Returns ``(fragility dataset, warnings)``: ``p_exceed`` and the IM (``pga_median``, ...) over
    the dataset's dimensions, ``median`` [IM units] (``attrs["intensity"]``), ``beta`` [1] and
    ``fit_flag`` (0 ok, 1 beta <= 0, 2 no fit) over the other dimensions, ``threshold_rad``.
    Raises ``ValueError`` for an unknown ``im``, a ``dim`` that is not swept or not an intensity
    dimension, or an IM that is not strictly increasing along ``dim``.

    ``limit_state="overturn"``: the probability of overturning instead
    (:func:`screening.analysis.probabilities.overturning_probability`; ``threshold`` and ``relative_to``
    are not used, ``threshold_rad`` is ``atan(b/h)``), stored as ``p_exceed`` with the attribute
    ``limit_state`` and exported with that limit state.
    """
    if im not in IMS:
        raise ValueError(f"--im must be one of {', '.join(IMS)} (got {im!r})")
    if limit_state not in LIMIT_STATES:
        raise ValueError(f"--limit-state must be one of {', '.join(LIMIT_STATES)} (got {limit_state!r})")
    warnings = []
    if limit_state == "overturn":
        from screening.analysis.probabilities import overturning_probability

        p, note = overturning_probability(ds, method)
        p = p.rename("p_exceed")
        if note:
            warnings.append(f"overturning: {note}")
        threshold, relative_to = 1.0, "slenderness"
    else:
        p = exceedance_probability(ds, threshold, relative_to, method)
    grid = list(ds["status"].dims) if "status" in ds else list(p.dims)
    if dim is None:
        dim = next((d for d in ("S0", "pga") if d in grid), None)
    if dim is None or dim not in p.dims:
        raise ValueError(f"--dim {dim!r} is not a swept dimension (swept: {', '.join(grid) or 'none'})")
    if p.sizes[dim] < 2:
        raise ValueError(f"--dim {dim!r} has one value: nothing to fit")
    values, _ = _im_values(ds, im, period, cutoff)
    name = IMS[im][0]
    values = values.broadcast_like(p.isel({d: 0 for d in p.dims if d != dim}, drop=True)) \
        if dim not in values.dims else values
    if dim not in values.dims:
        raise ValueError(f"--dim {dim!r} is not an intensity dimension: {name} does not vary along it")
    step = values.diff(dim)
    if bool((step == 0).all()):
        raise ValueError(f"--dim {dim!r} is not an intensity dimension: {name} does not vary along it")
    if not bool((step > 0).all()):
        raise ValueError(f"{name} is not strictly increasing along --dim {dim!r}: a lognormal fit over it "
                         f"has no meaning")
    im_b, p_b = xr.broadcast(values, p)
    im_b = im_b.transpose(*p.dims)

    def _fit(x, prob):
        try:
            return np.array(fit_lognormal_fragility(x, prob))
        except ValueError:
            return np.array([np.nan, np.nan])

    fit = xr.apply_ufunc(_fit, im_b, p_b, input_core_dims=[[dim], [dim]], output_core_dims=[["fit"]],
                         vectorize=True)
    median, beta = fit.isel(fit=0, drop=True), fit.isel(fit=1, drop=True)
    flag = xr.where(np.isnan(beta), FIT_NONE, xr.where(beta <= 0, FIT_NEGATIVE_BETA, FIT_OK)).astype(np.int8)
    units = IMS[im][1]
    out = xr.Dataset({"p_exceed": p, name: im_b.assign_attrs(units=units),
                      "median": median.where(flag == FIT_OK).assign_attrs(units=units, intensity=name),
                      "beta": beta.where(flag == FIT_OK).assign_attrs(units="1"),
                      "fit_flag": flag.assign_attrs(flag_values=np.array([0, 1, 2], dtype=np.int8),
                                                    flag_meanings="ok non_positive_beta no_fit"),
                      "threshold_rad": _per_curve(threshold_angle(ds, threshold, relative_to), dim)})
    if period is not None and im == "sa":
        out[name].attrs.update(period=float(period), damping_ratio=0.05)
    out.attrs.update(intensity_measure=im, intensity_variable=name, intensity_dim=dim, threshold=float(threshold),
                     relative_to=str(relative_to), method=method, limit_state=limit_state,
                     title="Probability that |theta| exceeds a rotation, fitted over an intensity measure"
                     if limit_state == "exceed" else "Probability of overturning, fitted over an intensity measure")
    if limit_state == "overturn":
        out["p_exceed"].attrs.update(long_name="probability that the block overturns during the record")
    n_neg = int((flag == FIT_NEGATIVE_BETA).sum())
    if n_neg:
        warnings.append(f"{n_neg} fit(s) have beta <= 0 (probability falling with {name}); flagged in fit_flag "
                        "and left out of the exports")
    try:
        slender = model_quantity(ds, "slenderness")
        if limit_state == "exceed" and bool((out["threshold_rad"] >= slender).any()):
            warnings.append("the threshold is at or beyond the slenderness angle atan(b/h): the rigid block "
                            "overturns there; P(exceed) is then not a rocking measure")
    except KeyError:
        pass
    return out, warnings


def _per_curve(angle, dim):
    """A threshold angle read from the grid (``slenderness``, ``theta_ul``) once per curve: dropped along the
    intensity ``dim`` where it does not change along it (a block's angles do not depend on the shaking)."""
    if dim in angle.dims and bool((angle.diff(dim) == 0).all()):
        return angle.isel({dim: 0}, drop=True)
    return angle


# ----------------------------------------------------------------------------- export
def _curves(frag):
    """``[(labels dict, median, beta)]`` of the fits flagged ok."""
    median, beta = frag["median"], frag["beta"]
    flag = frag["fit_flag"] if "fit_flag" in frag else xr.zeros_like(median, dtype=np.int8)
    rows = []
    dims = list(median.dims)
    for index in np.ndindex(*median.shape) if dims else [()]:
        sel = dict(zip(dims, index))
        if int(flag[sel]) != FIT_OK or not np.isfinite(float(median[sel])):
            continue
        labels = {d: frag[d].values[i].item() if d in frag.coords else i for d, i in sel.items()}
        rows.append((labels, float(median[sel]), float(beta[sel])))
    return rows


def write_csv(frag, path):
    """One row per fitted curve: other dimensions, ``im``, ``units``, ``median``, ``beta``, threshold."""
    rows = _curves(frag)
    name = frag["median"].attrs.get("intensity", "intensity")
    units = frag["median"].attrs.get("units", "")
    dims = list(frag["median"].dims)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(dims + ["intensity_measure", "units", "median", "beta", "threshold_rad", "period_s"])
        period = frag[name].attrs.get("period", "") if name in frag else ""
        th = frag["threshold_rad"]
        for labels, median, beta in rows:
            t = float(th.sel({d: v for d, v in labels.items() if d in th.dims}) if th.ndim else th)
            w.writerow([labels[d] for d in dims] + [name, units, f"{median:.8g}", f"{beta:.6g}", f"{t:.8g}",
                        period])
    return path


def nrml_parameters(median, beta):
    """OpenQuake ``logncdf`` ``(mean, stddev)`` of a lognormal capacity with ``median`` and ``beta``."""
    mean = median * math.exp(0.5 * beta * beta)
    return mean, mean * math.sqrt(math.expm1(beta * beta))


def write_nrml(frag, path, model_id="screening_rocking", description="rocking blocks on flexible beds"):
    """OpenQuake NRML 0.5 fragility model: one continuous ``logncdf`` function per fitted curve,
    limit state ``theta_exceeds_threshold``.  Raises ``ValueError`` for an IM OpenQuake does not know."""
    name = frag["median"].attrs.get("intensity", "")
    key = next((k for k, v in IMS.items() if v[0] == name), {"pga": "pga", "sa": "sa"}.get(name))
    if key is None or IMS[key][2] is None:
        raise ValueError(f"OpenQuake has no intensity measure type for {name!r}; export CSV instead")
    imt = IMS[key][2]
    limit_state = LIMIT_STATES[frag.attrs.get("limit_state", "exceed")]
    if imt == "SA":
        imt = f"SA({float(frag[name].attrs['period']):g})"
    factor = IMS[key][3]
    values = frag[name].values[np.isfinite(frag[name].values)] * factor
    lo, hi = float(values.min()), float(values.max())
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             '<nrml xmlns="http://openquake.org/xmlns/nrml/0.5">',
             f'  <fragilityModel id={quoteattr(model_id)} assetCategory="buildings" lossCategory="contents">',
             f"    <description>{description}: P(max |theta| &gt; threshold) fitted by screening over "
             f"{name}</description>",
             f"    <limitStates>{limit_state}</limitStates>"]
    for labels, median, beta in _curves(frag):
        fid = "screening" + "".join(f"_{d}={v:g}" if isinstance(v, float) else f"_{d}={v}" for d, v in labels.items())
        mean, std = nrml_parameters(median * factor, beta)
        lines += [f'    <fragilityFunction id={quoteattr(fid)} format="continuous" shape="logncdf">',
                  f'      <imls imt="{imt}" minIML="{lo:.6g}" maxIML="{hi:.6g}"/>',
                  f'      <params ls="{limit_state}" mean="{mean:.8g}" stddev="{std:.8g}"/>',
                  "    </fragilityFunction>"]
    lines += ["  </fragilityModel>", "</nrml>", ""]
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines))
    return path
