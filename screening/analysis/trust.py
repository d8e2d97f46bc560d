"""How far to trust a linearized point, calibrated on Monte Carlo.

Every linearized point gets ``sl_trust`` (:class:`screening.core.status.Trust`: ``trusted``, ``check``,
``untrusted``) and a predicted band ``sl_error_low``, ``sl_error_high`` of SL's relative error on peak
``var_theta``, ``SL / MCS - 1`` [1].  :func:`add_trust` (the product's rule) takes them from the error
atlas model's 90 % interval (:mod:`screening.analysis.error_model`): ``trusted`` within +-25 %,
``untrusted`` wholly beyond +-50 %, open (a factor 4) or where SL stopped, ``check`` otherwise and at best
``check`` outside what the atlas samples.  The former *cell rule* (:func:`sl_trust`,
:func:`add_cell_trust`, cells of condensation, bed law and ``peak_p_uplift`` bin calibrated on
``screening/data/trust_calibration.nc``) labels no point; it is kept for comparison and still decides
where ``[accuracy]`` may run condensed Monte Carlo.  The indicators, both rules and their calibration:
``docs/trust.md`` and ``docs/method.md#trusting-a-point``.
"""

from __future__ import annotations

import functools
import json
from importlib import resources

import numpy as np
import xarray as xr

from screening.analysis import error_model as em
from screening.analysis.error_model import shipped_model
from screening.analysis.indicators import envelope_fraction, indicators_from_dataset, trust_indicators
from screening.core.status import PointStatus, Trust
from screening.solvers import schema

__all__ = ["bed_law", "envelope_fraction", "trust_indicators", "indicators_from_dataset", "error_of", "p_bin",
           "regime", "calibration_rows", "trust_table", "shipped_table", "shipped_calibration", "sl_trust",
           "trust_attributes", "add_trust", "trust_models", "error_model_trust"]

#: Edges of the peak p_uplift bins of the cells.
P_EDGES = (0.0, 0.007, 0.08, 0.2, 0.45, 0.9, np.inf)
#: decay_excess above this: SL holds the response after the shaking (lock-in).
DECAY_LIMIT = 10.0
#: sigma_ratio above / k_eq_margin below these: near toppling.
SIGMA_LIMIT = 0.25
MARGIN_LIMIT = 0.25
#: Error thresholds: trusted cells have every observed |error| within TRUSTED_ERROR and the band within
#: TRUSTED_BAND; cells with an observed |error| beyond UNTRUSTED_ERROR are untrusted.
TRUSTED_ERROR = 0.10
TRUSTED_BAND = 0.25
UNTRUSTED_ERROR = 0.50
#: Band width in Monte Carlo standard errors.
N_SE = 2.0
#: A trusted cell needs at least this many calibration rows.
MIN_ROWS = 2
#: Fraction of overturned coupled samples above which SL (which never overturns a sample) has missed toppling.
OVERTURN_LIMIT = 0.01

BED_LAWS = ("hardening", "linear", "softening")
CONDENSATIONS = ("paper", "cubic")
INDICATORS = ("peak_p_uplift", "k_eq_margin", "sigma_ratio", "decay_excess")
#: The regimes decided before the cells (step 1 has no band).
OVERRIDES = ("lock_in", "near_toppling")

CALIBRATION_FILE = "trust_calibration.nc"


# ----------------------------------------------------------------------------- indicators
def bed_law(eps):
    """The bed law of a bed from the sign of its cubic coefficient, elementwise.

    Parameters
    ----------
    eps : array_like
        The cubic coefficient of the bed's contact law [m-2].

    Returns
    -------
    numpy.ndarray of str
        ``"hardening"`` (eps > 0), ``"linear"`` (eps == 0) or ``"softening"`` (eps < 0).

    Notes
    -----
    The bed's restoring force per unit base length is ``k z + eps k z^3`` (eq. (3) in [1]): ``eps > 0``
    stiffens with the indentation, ``eps < 0`` softens.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> bed_law([6e7, 0.0, -6e5]).tolist()
    ['hardening', 'linear', 'softening']
    """
    eps = np.asarray(eps, dtype=float)
    return np.where(eps > 0, "hardening", np.where(eps < 0, "softening", "linear"))


# ----------------------------------------------------------------------------- calibration -> table
def error_of(sl_peak, mcs_peak, mcs_se):
    """The relative error of the linearization's peak against Monte Carlo, and its standard error.

    Parameters
    ----------
    sl_peak : array_like
        The linearization's peak var_theta [rad2].
    mcs_peak, mcs_se : array_like
        Monte Carlo's peak var_theta and its standard error [rad2].

    Returns
    -------
    tuple of numpy.ndarray
        ``(SL / MCS - 1, (SL / MCS) x SE / MCS)`` [1].

    Notes
    -----
    The standard error is the first-order (delta-method) propagation of the Monte Carlo one [1].

    References
    ----------
    [1] [rubinstein2017].

    Examples
    --------
    >>> e, se = error_of([1.1, 0.5], [1.0, 1.0], [0.02, 0.02])
    >>> e.round(6).tolist(), se.round(6).tolist()
    ([0.1, -0.5], [0.022, 0.01])
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.asarray(sl_peak, dtype=float) / np.asarray(mcs_peak, dtype=float)
        return ratio - 1.0, ratio * np.asarray(mcs_se, dtype=float) / np.asarray(mcs_peak, dtype=float)


def p_bin(p):
    """Index of the ``peak_p_uplift`` bin of the cell rule (:data:`P_EDGES`), elementwise; -1 for NaN.

    Parameters
    ----------
    p : array_like
        Peak uplift probability [1].

    Returns
    -------
    numpy.ndarray of int
        The bin, ``0 .. len(P_EDGES) - 2``, or -1.

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    >>> p_bin([0.0, 0.01, 0.5, 0.95, np.nan]).tolist()
    [0, 1, 4, 5, -1]
    """
    p = np.asarray(p, dtype=float)
    idx = np.searchsorted(np.asarray(P_EDGES), p, side="right") - 1
    return np.where(np.isfinite(p), np.clip(idx, 0, len(P_EDGES) - 2), -1)


def regime(ind):
    """The regime of each point: ``"lock_in"``, ``"near_toppling"`` or ``"cell"``.

    The solver status is handled by the caller.

    Parameters
    ----------
    ind : dict
        ``decay_excess``, ``sigma_ratio`` and ``k_eq_margin`` [1] (:func:`trust_indicators`).

    Returns
    -------
    numpy.ndarray of str

    Notes
    -----
    ``lock_in`` where ``decay_excess > DECAY_LIMIT``, else ``near_toppling`` where ``sigma_ratio >
    SIGMA_LIMIT`` or ``k_eq_margin < MARGIN_LIMIT``, else ``cell``.

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    >>> regime({"decay_excess": [1.0, 20.0, 1.0], "sigma_ratio": [0.1, 0.1, 0.3],
    ...         "k_eq_margin": [0.9, 0.9, 0.9]}).tolist()
    ['cell', 'lock_in', 'near_toppling']
    """
    decay = np.asarray(ind["decay_excess"], dtype=float)
    lock = np.isfinite(decay) & (decay > DECAY_LIMIT)
    near = (np.asarray(ind["sigma_ratio"], dtype=float) > SIGMA_LIMIT) | \
        (np.asarray(ind["k_eq_margin"], dtype=float) < MARGIN_LIMIT)
    return np.where(lock, "lock_in", np.where(near, "near_toppling", "cell"))


def calibration_rows(ds):
    """Flat numpy columns of the calibration dataset, one row per (point, condensation) with SL status ok.

    Parameters
    ----------
    ds : xarray.Dataset
        The calibration dataset (:func:`shipped_calibration`).

    Returns
    -------
    dict of str to numpy.ndarray
        The indicators (:data:`INDICATORS`) [1], ``error`` and ``error_se`` [1],
        ``overturned_fraction`` [1], ``condensation``, ``bed_law`` and ``point`` (str).

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    >>> rows = calibration_rows(shipped_calibration())
    >>> len(rows["error"]), sorted(set(rows["condensation"].tolist()))
    (112, ['cubic', 'paper'])
    """
    stacked = ds.stack(row=("point", "condensation"))
    ok = (stacked["sl_status"].values == int(PointStatus.ok)) & np.isfinite(stacked["sl_error"].values)
    eps = np.broadcast_to(stacked["eps"].values, ok.shape)
    over = stacked["coupled_n_overturned"].values / stacked["coupled_n_samples"].values
    rows = {name: stacked[f"sl_{name}"].values[ok] for name in INDICATORS}
    rows.update(error=stacked["sl_error"].values[ok], error_se=stacked["sl_error_se"].values[ok],
                overturned_fraction=over[ok], condensation=np.asarray(stacked["condensation"].values[ok], dtype=str),
                bed_law=bed_law(eps[ok]), point=np.asarray(stacked["point"].values[ok], dtype=str))
    return rows


def _band(err, se):
    if err.size == 0:
        return [float("nan"), float("nan")]
    # SL / MCS - 1 >= -1: the lower end is clipped there
    return [float(max(np.min(err - N_SE * se), -1.0)), float(np.max(err + N_SE * se))]


def _cell_flag(err, se, over, band):
    if err.size == 0:
        return int(Trust.check)
    if np.any(np.abs(err) > UNTRUSTED_ERROR) or np.any(over > OVERTURN_LIMIT):
        return int(Trust.untrusted)
    if (err.size >= MIN_ROWS and np.all(np.abs(err) <= TRUSTED_ERROR)
            and band[0] >= -TRUSTED_BAND and band[1] <= TRUSTED_BAND):
        return int(Trust.trusted)
    return int(Trust.check)


def trust_table(calibration, rows=None):
    """The rule's cells derived from a calibration dataset (or from ``rows`` of :func:`calibration_rows`).

    Parameters
    ----------
    calibration : xarray.Dataset
        The calibration dataset (:func:`shipped_calibration`); not read when ``rows`` is given.
    rows : dict, optional
        :func:`calibration_rows`.

    Returns
    -------
    dict
        JSON-serialisable: ``{"cells": {"<condensation>|<bed law>|<bin>": {"flag", "band", "n",
        "points"}}, "overrides": {"lock_in"|"near_toppling": {"band", "n"}}, "pooled": {"<bin>": band},
        "p_edges", "limits"}``; bands of ``SL / MCS - 1`` [1].

    Notes
    -----
    A cell's band is ``[max(min(e - 2 se), -1), max(e + 2 se)]`` over its rows; its flag follows the
    steps of the module docstring.

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    The table recomputed from the shipped file is the one shipped with it:

    >>> table = trust_table(shipped_calibration())
    >>> table == shipped_table(), table["cells"]["paper|linear|0"]["flag"]
    (True, 0)
    """
    rows = calibration_rows(calibration) if rows is None else rows
    reg = regime(rows)
    bins = p_bin(rows["peak_p_uplift"])
    table = {"p_edges": [float(e) for e in P_EDGES],
             "limits": {"decay_excess": DECAY_LIMIT, "sigma_ratio": SIGMA_LIMIT, "k_eq_margin": MARGIN_LIMIT,
                        "trusted_error": TRUSTED_ERROR, "trusted_band": TRUSTED_BAND,
                        "untrusted_error": UNTRUSTED_ERROR, "n_se": N_SE, "min_rows": MIN_ROWS,
                        "overturn_limit": OVERTURN_LIMIT},
             "overrides": {}, "pooled": {}, "cells": {}}
    for name in OVERRIDES:
        sel = reg == name
        table["overrides"][name] = {"band": _band(rows["error"][sel], rows["error_se"][sel]), "n": int(sel.sum())}
    cell = reg == "cell"
    for b in range(len(P_EDGES) - 1):
        sel = cell & (bins == b)
        table["pooled"][str(b)] = _band(rows["error"][sel], rows["error_se"][sel])
    for cond in CONDENSATIONS:
        for law in BED_LAWS:
            worst = int(Trust.trusted)
            for b in range(len(P_EDGES) - 1):
                sel = cell & (bins == b) & (rows["condensation"] == cond) & (rows["bed_law"] == law)
                err, se = rows["error"][sel], rows["error_se"][sel]
                band = _band(err, se) if sel.any() else table["pooled"][str(b)]
                flag = max(_cell_flag(err, se, rows["overturned_fraction"][sel], band), worst)
                worst = flag
                table["cells"][f"{cond}|{law}|{b}"] = {"flag": flag, "band": band, "n": int(sel.sum()),
                                                       "points": sorted(set(rows["point"][sel].tolist()))}
    return table


@functools.lru_cache(maxsize=1)
def shipped_table():
    """The table stored with the shipped calibration file (``attrs["trust_table"]``), read alone: a
    sweep's client needs it before its first task, the dataset not at all."""
    import netCDF4

    path = resources.files("screening.data").joinpath(CALIBRATION_FILE)
    with resources.as_file(path) as p, netCDF4.Dataset(p) as ds:
        return json.loads(ds.getncattr("trust_table"))


def shipped_calibration():
    """The shipped calibration dataset (``screening/data/trust_calibration.nc``), loaded into memory.

    Returns
    -------
    xarray.Dataset
        59 points (``point``) under two condensations (``condensation``): the linearization's
        indicators and peak var_theta [rad2], the coupled (and condensed) Monte Carlo's, ``sl_error``
        [1].

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    >>> cal = shipped_calibration()
    >>> cal.sizes["point"], cal["condensation"].values.tolist()
    (59, ['paper', 'cubic'])
    """
    path = resources.files("screening.data").joinpath(CALIBRATION_FILE)
    with resources.as_file(path) as p, xr.open_dataset(p) as ds:
        return ds.load()


# ----------------------------------------------------------------------------- the rule
def sl_trust(indicators, calibration=None, status=None, condensation="paper", eps=0.0):
    """``(flag, error_low, error_high)`` numpy arrays of the trust rule (see the module docstring).

    Parameters
    ----------
    indicators : dict
        Arrays from :func:`trust_indicators` [1] (broadcast against each other).
    calibration : dict or xarray.Dataset, optional
        A table from :func:`trust_table`, a calibration dataset, or None (the shipped table).
    status : array_like of int, optional
        SL status codes (:class:`screening.core.status.PointStatus`), broadcastable; None: all ok.
    condensation : str or array_like of str, default "paper"
        ``"paper"`` or ``"cubic"`` (another is at best ``check``, with no band).
    eps : array_like, default 0.0
        Cubic parameter of the bed [m-2] (its sign is the bed law), broadcastable.

    Returns
    -------
    tuple of numpy.ndarray
        ``(flag, error_low, error_high)``: :class:`screening.core.status.Trust` codes [int8] and the band of
        ``SL / MCS - 1`` [1] (NaN where there is none).

    References
    ----------
    [1] ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    A point at low uplift on a linear bed, one at higher uplift, one whose linearization stopped:

    >>> ind = trust_indicators([0.001, 0.3, 0.3], 95.0, 100.0, [1e-6, 1e-4, 1e-4], 0.165, [1e-7, 1e-5, 1e-5], 0.1)
    >>> flag, low, high = sl_trust(ind, status=[0, 0, 2])
    >>> flag.tolist(), np.isnan(high).tolist()
    ([0, 1, 2], [False, False, True])
    """
    if calibration is None:
        table = shipped_table()
    elif isinstance(calibration, xr.Dataset):
        table = trust_table(calibration)
    else:
        table = calibration
    ind = {k: np.asarray(indicators[k], dtype=float) for k in INDICATORS}
    shape = np.broadcast_shapes(*(v.shape for v in ind.values()), np.shape(status if status is not None else 0),
                                np.shape(condensation), np.shape(eps))
    ind = {k: np.broadcast_to(v, shape) for k, v in ind.items()}
    st = np.broadcast_to(np.asarray(int(PointStatus.ok) if status is None else status), shape)
    cond = np.broadcast_to(np.asarray(condensation, dtype=str), shape)
    law = np.broadcast_to(bed_law(eps), shape)
    reg = regime(ind)
    bins = p_bin(ind["peak_p_uplift"])
    n_bins = len(table["p_edges"]) - 1
    # the cells as arrays [condensation, bed law, bin]; index len(CONDENSATIONS): unknown condensation
    tab_flag = np.full((len(CONDENSATIONS) + 1, len(BED_LAWS), n_bins), int(Trust.check), dtype=np.int8)
    tab_band = np.full(tab_flag.shape + (2,), np.nan)
    for b in range(n_bins):
        for ci, c in enumerate(CONDENSATIONS):
            for li, law_name in enumerate(BED_LAWS):
                entry = table["cells"][f"{c}|{law_name}|{b}"]
                tab_flag[ci, li, b] = entry["flag"]
                tab_band[ci, li, b] = entry["band"]
    ci = np.full(shape, len(CONDENSATIONS))
    for k, c in enumerate(CONDENSATIONS):
        ci[cond == c] = k
    li = np.zeros(shape, dtype=int)
    for k, law_name in enumerate(BED_LAWS):
        li[law == law_name] = k
    bi = np.clip(bins, 0, n_bins - 1)
    flag = np.array(tab_flag[ci, li, bi], dtype=np.int8, ndmin=1).reshape(shape)
    band = np.array(tab_band[ci, li, bi], ndmin=2).reshape(shape + (2,))
    for name in OVERRIDES:
        sel = reg == name
        flag[sel] = int(Trust.untrusted)
        band[sel] = table["overrides"][name]["band"]
    band[ci == len(CONDENSATIONS)] = np.nan             # not calibrated: no band

    # an indicator that could not be computed (e.g. a file without the histories) cannot clear the point
    unknown = ~np.isfinite(ind["decay_excess"]) | ~np.isfinite(ind["k_eq_margin"]) | ~np.isfinite(ind["sigma_ratio"])
    flag[unknown & (flag == int(Trust.trusted))] = int(Trust.check)
    stopped = (st != int(PointStatus.ok)) | (bins < 0)
    flag[stopped] = int(Trust.untrusted)
    band[stopped] = np.nan
    low, high = band[..., 0], band[..., 1]
    return flag, low, high


def trust_attributes():
    """CF attributes of ``sl_trust``, ``sl_error_low``, ``sl_error_high`` (from :mod:`screening.solvers.schema`).

    Returns
    -------
    dict of str to dict
        ``{name: attributes}``.

    References
    ----------
    [1] NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8, section 3.5 (flags); [2]
    ``docs/trust.md``, ``docs/method.md`` ("Trusting a point").

    Examples
    --------
    >>> attrs = trust_attributes()
    >>> attrs["sl_trust"]["flag_meanings"], attrs["sl_trust"]["flag_values"].tolist()
    ('trusted check untrusted', [0, 1, 2])
    """
    return {name: schema.attributes(name) for name in ("sl_trust", "sl_error_low", "sl_error_high")}


def add_trust(ds, models=None):
    """``ds`` (a :func:`screening.linearize` or sweep result) with ``sl_trust``, ``sl_error_low`` and
    ``sl_error_high`` on the dimensions of ``peak_var_theta``, by the error atlas model (module docstring).

    The condensation comes from ``attrs["condensation"]`` or a ``condensation`` coordinate.  Without the
    histories (nor ``k_eq_rest``, ``var_theta_end``) a point whose status is ok is ``check`` with a NaN band.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`screening.linearize` or sweep result (its indicators, ``status`` and parameter
        coordinates, :func:`screening.analysis.error_model.dataset_features`).
    models : dict, optional
        ``{condensation: ErrorModel}`` (None: the shipped models,
        :func:`screening.analysis.error_model.shipped_model`).

    Returns
    -------
    xarray.Dataset
        ``ds`` with ``sl_trust`` (:class:`screening.core.status.Trust` codes), ``sl_error_low`` and
        ``sl_error_high`` [1].

    Notes
    -----
    The interval is the error model's normalised conformal interval [2] of ``log(SL / MC)``, mapped
    to ``SL / MC - 1``.

    References
    ----------
    [1] ``docs/error_atlas.md``; [2] [vovk2005].

    Examples
    --------
    >>> ds = xr.Dataset(            # two points of the paper's block, as screening.linearize reports them
    ...     {"peak_p_uplift": ("S0", [0.2011, 0.7653]), "min_k_eq": ("S0", [1071.0, 780.7]), "k_eq_rest": 1071.0,
    ...      "peak_var_theta": ("S0", [8.829e-7, 1.619e-5]), "var_theta_end": ("S0", [8.490e-10, 8.480e-9]),
    ...      "slenderness": 0.16515, "status": ("S0", [0, 0])},
    ...     coords={"S0": [1e-4, 1e-3], "t": np.linspace(0.0, 20.0, 401), "m": 8.67, "b": 0.035, "h": 0.21,
    ...             "I_cm": 0.131, "g": 9.81, "k": 2.89e7, "lam": 8.95e8, "eps": 6e7, "T1": 4.0, "T2": 2.0},
    ...     attrs={"excitation": "white", "envelope": "exponential", "contact": "hunt_crossley",
    ...            "condensation": "paper"})
    >>> out = add_trust(ds)
    >>> out["sl_trust"].values.tolist(), out["sl_error_low"].values.round(2).tolist()
    ([1, 2], [-0.68, -1.0])
    """
    dims = ds["peak_var_theta"].dims
    peak = ds["peak_var_theta"]

    def on(x):
        return np.asarray(xr.DataArray(x).broadcast_like(peak).transpose(*dims).values)

    x, x_dims, shape = em.dataset_features(ds)
    x = xr.DataArray(x.reshape(shape + (x.shape[1],)), dims=x_dims + ("feature",)).broadcast_like(peak)
    x = x.transpose(*dims, "feature").values.reshape(-1, len(em.FEATURES))
    cond = ds["condensation"] if "condensation" in ds.variables else ds.attrs.get("condensation", "paper")
    cond = on(cond).astype(str).reshape(-1) if isinstance(cond, xr.DataArray) else np.full(len(x), str(cond))
    status = on(ds["status"]).reshape(-1)
    covered = ds.attrs.get("excitation", "white") in em.ATLAS_KINDS and \
        ds.attrs.get("contact", "hunt_crossley") in em.ATLAS_CONTACTS
    flag, low, high = error_model_trust(x, status, cond, covered, models)
    attrs = trust_attributes()
    shape = peak.shape
    return ds.assign(sl_trust=xr.DataArray(flag.reshape(shape), dims=dims, attrs=attrs["sl_trust"]),
                     sl_error_low=xr.DataArray(low.reshape(shape), dims=dims, attrs=attrs["sl_error_low"]),
                     sl_error_high=xr.DataArray(high.reshape(shape), dims=dims, attrs=attrs["sl_error_high"]))


def trust_models(*condensations):
    """The shipped error models of the given condensations.

    Those the atlas does not hold are left out: their points are at best ``check``.

    Parameters
    ----------
    *condensations : str
        Condensation names.

    Returns
    -------
    dict
        ``{condensation: ErrorModel}`` (:func:`screening.analysis.error_model.shipped_model`).

    References
    ----------
    [1] ``docs/error_atlas.md``.

    Examples
    --------
    >>> sorted(trust_models("paper", "no_such_condensation"))
    ['paper']
    """
    out = {}
    for name in condensations:
        try:
            out[name] = shipped_model(name)
        except ValueError:
            pass
    return out


def error_model_trust(x, status, condensation, covered=True, models=None):
    """The trust flag and predicted error band of flat points from their error-model features.

    Each condensation's points are judged by its model; a condensation without a model is ``check``
    at best, with a NaN band.

    Parameters
    ----------
    x : array_like
        ``(n, len(FEATURES))`` features (:func:`screening.analysis.error_model.features`).
    status : array_like of int
        :class:`screening.core.status.PointStatus` codes, ``(n,)`` or scalar.
    condensation : str or array_like of str
        A name or ``(n,)`` names.
    covered : bool or array_like of bool, default True
        False where the point's model lies outside what the atlas samples.
    models : dict, optional
        As in :func:`add_trust` (None: the shipped ones).

    Returns
    -------
    tuple of numpy.ndarray
        ``(flag, low, high)``: :class:`screening.core.status.Trust` codes [int8] and the interval of
        ``SL / MC - 1`` [1].

    References
    ----------
    [1] ``docs/error_atlas.md``; [2] [vovk2005].

    Examples
    --------
    Two points of the paper's block (their features from the model objects and the indicators):

    >>> from screening import Block, Foundation, WhiteNoise
    >>> from screening.analysis.error_model import model_features
    >>> ind = {"peak_p_uplift": np.array([0.2011, 0.7653]), "k_eq_margin": np.array([1.0, 0.729]),
    ...        "sigma_ratio": np.array([0.00569, 0.02437]), "decay_excess": np.array([1.342, 0.731])}
    >>> x = model_features(ind, Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7),
    ...                    WhiteNoise(np.array([1e-4, 1e-3])))
    >>> error_model_trust(x, [0, 0], "paper")[0].tolist(), error_model_trust(x, [0, 2], "paper")[0].tolist()
    ([1, 2], [1, 2])
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    n = len(x)
    cond = np.broadcast_to(np.asarray(condensation, dtype=str), (n,))
    status = np.broadcast_to(np.asarray(status), (n,))
    covered = np.broadcast_to(np.asarray(covered, dtype=bool), (n,))
    flag = np.where(status != int(PointStatus.ok), int(Trust.untrusted), int(Trust.check)).astype(np.int8)
    low, high = np.full(n, np.nan), np.full(n, np.nan)
    for name in np.unique(cond):
        sel = cond == name
        try:
            model = em.shipped_model(str(name)) if models is None else models[str(name)]
        except (KeyError, ValueError):
            continue
        flag[sel], _, low[sel], high[sel] = em.interval_trust(model, x[sel], status[sel], covered[sel])
    return flag, low, high


def add_cell_trust(ds, calibration=None):
    """``ds`` (a :func:`screening.linearize` or sweep result) with ``sl_trust``, ``sl_error_low`` and
    ``sl_error_high`` on the dimensions of ``peak_var_theta`` by the *cell rule* (:func:`sl_trust`, the
    59-point calibration): kept for the calibration benchmark and comparisons; the product's rule is
    :func:`add_trust` (the error atlas model).

    Reads ``peak_p_uplift``, ``min_k_eq``, ``k_eq`` (at ``t = 0``; or a per-point ``k_eq_rest``),
    ``peak_var_theta``, ``var_theta`` (at ``t_end``; or a per-point ``var_theta_end``),
    ``slenderness``, ``status``, ``eps`` and the envelope (``T1``, ``T2``, ``attrs["envelope"]``);
    the condensation from ``attrs["condensation"]`` or a ``condensation`` coordinate (sweeps whose
    cases differ in it).  Without the histories (nor the per-point values) the lock-in and margin
    indicators are NaN and no point is labelled trusted (at best ``check``).

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`screening.linearize` or sweep result.
    calibration : dict or xarray.Dataset, optional
        As in :func:`sl_trust` (None: the shipped table).

    Returns
    -------
    xarray.Dataset
        ``ds`` with ``sl_trust``, ``sl_error_low`` and ``sl_error_high`` [1].
    """
    dims = ds["peak_var_theta"].dims
    peak = ds["peak_var_theta"]

    def on(x):
        return xr.DataArray(x).broadcast_like(peak).transpose(*dims).values

    ind = {k: v.values for k, v in indicators_from_dataset(ds).items()}
    cond = ds["condensation"] if "condensation" in ds.variables else ds.attrs.get("condensation", "paper")
    cond = on(cond) if isinstance(cond, xr.DataArray) else cond
    eps = on(ds["eps"]) if "eps" in ds.variables else 0.0
    flag, low, high = sl_trust(ind, calibration, status=on(ds["status"]), condensation=cond, eps=eps)
    attrs = trust_attributes()
    return ds.assign(sl_trust=xr.DataArray(flag, dims=dims, attrs=attrs["sl_trust"]),
                     sl_error_low=xr.DataArray(low, dims=dims, attrs=attrs["sl_error_low"]),
                     sl_error_high=xr.DataArray(high, dims=dims, attrs=attrs["sl_error_high"]))
