"""An error model of the linearization learnt from the error atlas, with predictive intervals.

For one condensation, the error of a linearized point (:func:`targets`: ``log(SL / MC)`` of peak
``var_theta`` and ``SL - MC`` of ``p_exceed``) is predicted from its trust indicators and dimensionless
inputs (:func:`features`), with a feature set per regime of peak uplift probability
(:data:`REGIME_FEATURES`), by a local linear regression over the :data:`NEIGHBOURS` nearest atlas points
[cleveland1988] and a normalised Mondrian conformal interval ``estimate +- q s(x)`` [vovk2005] calibrated
on out-of-family residuals: the interval holds for a *new* system, not a point next to one the atlas
measured.  How it is fitted, checked and what it costs: ``docs/error_atlas.md#the-error-model``.
"""

from __future__ import annotations

import functools
import math
from types import SimpleNamespace
from typing import NamedTuple

import numpy as np

from screening.analysis.indicators import indicators_from_dataset
from screening.core.physics.contact import REST_BEARING_LIMIT, rising_root, vertical_damping_ratio
from screening.core.status import PointStatus, Trust
from screening.solvers.datasets import model_fields, model_labels

__all__ = []

#: The features, in order: the linearization's indicators and the point's dimensionless inputs.
FEATURES = ("logit_p_uplift", "log_sigma_ratio", "log_margin_loss", "log_decay_excess", "alpha", "log_r_ul",
            "log_zeta_v", "asinh_e", "kanai_tajimi", "log_omega_g_p", "log_tau", "log_I_S", "log_w_v_p")
#: The features of the model at little uplift: the four indicators and the bed's hardening ``e``.  Below a peak
#: ``p_uplift`` of 0.2 the block barely rocks: the error is how the condensation carries the bed's nonlinearity,
#: and the other input groups only take the neighbours of a new family away (docs/error_atlas.md).
LOW_UPLIFT_FEATURES = ("logit_p_uplift", "log_sigma_ratio", "log_margin_loss", "log_decay_excess", "asinh_e")
#: Candidate bandwidths (in standardised feature units, times sqrt(number of features)).
BANDWIDTHS = (0.15, 0.25, 0.4, 0.6, 1.0)
#: Edges of the peak uplift probability between the regimes whose conformal factors are calibrated apart
#: (Mondrian conformal prediction: the coverage holds in each regime, not only on average), and the fewest
#: atlas points a regime needs for its own factor (else the pooled one).
P_REGIMES = (0.2, 0.7)
MIN_REGIME = 20
#: Regimes of peak uplift probability of the conformal factors (dimension ``regime`` of the stored model).
N_REGIMES = len(P_REGIMES) + 1
#: The features of the model of each regime of :data:`P_REGIMES` (:class:`RegimeModel`): at little uplift
#: :data:`LOW_UPLIFT_FEATURES`, elsewhere every feature.
REGIME_FEATURES = (LOW_UPLIFT_FEATURES, FEATURES, FEATURES)
#: Clip of ``log(SL / MC)`` [1] in the fit (a factor of 4 either way).
LOG_CLIP = math.log(4.0)
#: Out-of-family residuals the local scale s(x) is the RMS of (the nearest ones).
SCALE_NEIGHBOURS = 12
#: Ridge on the slopes of the local fit (in standardised units).
RIDGE = 1e-2
#: Weight (in atlas points) of the pooled residual scale in the local one: far from the atlas the scale
#: tends to the pooled scale instead of to the nearest few residuals.
PRIOR_WEIGHT = 1.0
#: Floor of the residual scale s(x) [1] (the Monte Carlo noise never vanishes).
SCALE_FLOOR = 1e-3
#: Atlas points the local fit at a query uses (its nearest ones).
NEIGHBOURS = 64


def features(peak_p_uplift, sigma_ratio, k_eq_margin, decay_excess, alpha, r_ul, zeta_v, e, kind, omega_g_p, tau,
             I_S, w_v_p):
    """The ``(n, len(FEATURES))`` feature matrix [1] of points (array-likes broadcast to ``n``).

    Parameters
    ----------
    peak_p_uplift, sigma_ratio, k_eq_margin, decay_excess : array_like
        The linearization's indicators (:func:`screening.analysis.indicators.trust_indicators`) [1].
    alpha : array_like
        Slenderness [rad].
    r_ul, zeta_v, e, omega_g_p, tau, I_S, w_v_p : array_like
        The dimensionless groups of :func:`parameter_groups` [1] (``omega_g_p`` ignored for white noise).
    kind : array_like of str
        ``"white"`` or ``"kanai_tajimi"``.

    Returns
    -------
    numpy.ndarray
        ``(n, len(FEATURES))`` [1].

    Notes
    -----
    ``logit(p)`` with ``p`` clipped to ``[1e-4, 1 - 1e-4]``; ``log(1 - k_eq_margin)`` clipped below at
    ``log 1e-4``; ``log decay_excess`` clipped to ``[-5, 10]``; ``asinh(e / 1e-3)``; for white noise
    ``log_omega_g_p = 0``; ``log I_S``, ``log w_v_p``; ``zeta_v = 0`` gives ``log_zeta_v = -inf`` and a bed
    without a rest indentation a NaN one (:func:`interval_trust`: at best ``check``).
    """
    p = np.clip(np.asarray(peak_p_uplift, dtype=float), 1e-4, 1 - 1e-4)
    kt = (np.asarray(kind) == "kanai_tajimi").astype(float)
    with np.errstate(divide="ignore"):          # an undamped bed: log zeta_v = -inf, a point at best check
        log_zeta_v = np.log(np.asarray(zeta_v, dtype=float))
    cols = [np.log(p / (1 - p)),
            np.log(np.maximum(np.asarray(sigma_ratio, dtype=float), 1e-6)),
            np.log(np.maximum(1.0 - np.asarray(k_eq_margin, dtype=float), 1e-4)),
            np.clip(np.log(np.maximum(np.asarray(decay_excess, dtype=float), 1e-300)), -5.0, 10.0),
            np.asarray(alpha, dtype=float), np.log(np.asarray(r_ul, dtype=float)),
            log_zeta_v, np.arcsinh(np.asarray(e, dtype=float) / 1e-3), kt,
            np.where(kt > 0, np.log(np.where(kt > 0, np.asarray(omega_g_p, dtype=float), 1.0)), 0.0),
            np.log(np.asarray(tau, dtype=float)), np.log(np.asarray(I_S, dtype=float)),
            np.log(np.asarray(w_v_p, dtype=float))]
    cols = np.broadcast_arrays(*cols)
    return np.stack([np.asarray(c, dtype=float).ravel() for c in cols], axis=1)


def atlas_features(ds, condensation):
    """:func:`features` ``(points, len(FEATURES))`` of every point of an atlas dataset under one condensation."""
    s = ds.sel(condensation=condensation)
    return features(s["sl_peak_p_uplift"].values, s["sl_sigma_ratio"].values, s["sl_k_eq_margin"].values,
                    s["sl_decay_excess"].values, ds["alpha"].values, ds["r_ul"].values, ds["zeta_v"].values,
                    ds["e"].values, ds["kind"].values.astype(str), ds["omega_g_p"].values, ds["tau"].values,
                    ds["I_S"].values, ds["w_v_p"].values)


def targets(ds, condensation):
    """The errors the model learns of an atlas under one condensation, with their standard errors (dict [1]).

    Notes
    -----
    ``log_var_ratio`` ``(n,)`` = ``log(SL / MC)`` of peak var_theta, ``p_exceed_diff`` ``(n, n_levels)`` =
    ``SL p_exceed - MC p_exceed`` and their Monte Carlo standard errors ``*_se``; NaN where a side is
    missing or the reference may not judge the point (:func:`valid_reference`).
    """
    s = ds.sel(condensation=condensation)
    ok = (s["sl_status"].values == 0) & valid_reference(ds)
    sl, mc = s["sl_peak_var_theta"].values, ds["mc_peak_var_theta"].values
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(ok & (sl > 0) & (mc > 0), np.log(sl / mc), np.nan)
        y_se = ds["mc_peak_var_theta_se"].values / mc
    d = np.where(ok[:, None], s["sl_p_exceed"].values - ds["mc_p_exceed"].values, np.nan)
    return {"log_var_ratio": y, "log_var_ratio_se": np.where(np.isfinite(y), y_se, np.nan),
            "p_exceed_diff": d, "p_exceed_diff_se": ds["mc_p_exceed_se"].values}


def valid_reference(ds):
    """Boolean: the atlas points whose reference Monte Carlo may judge the linearization (``mc_reference_valid``; every point where not recorded)."""
    if "mc_reference_valid" not in ds.variables:
        return np.ones(ds.sizes["point"], dtype=bool)
    return ds["mc_reference_valid"].values == 1


class ErrorModel(NamedTuple):
    """A fitted error model (:func:`fit_error_model`): standardised training features ``x`` and errors ``y``,
    the standardisation (``center``, ``width``), the bandwidth ``h``, the out-of-family residuals ``r``, the
    conformal factor ``q`` and the interval's ``coverage``."""

    x: np.ndarray
    y: np.ndarray
    center: np.ndarray
    width: np.ndarray
    h: float
    r: np.ndarray
    q: np.ndarray
    coverage: float


class RegimeModel(NamedTuple):
    """A fitted error model with a feature set per uplift regime (:func:`fit_error_model`): ``parts`` (one
    :class:`ErrorModel` per distinct feature set, fitted on every atlas point), ``columns`` (the columns of
    :data:`FEATURES` each part reads) and ``part_of_regime`` (the part that predicts each regime of
    :data:`P_REGIMES`, with that part's conformal factor of the regime)."""

    parts: tuple
    columns: tuple
    part_of_regime: tuple


def local_linear(xq, x, y, h, ridge=RIDGE, neighbours=NEIGHBOURS):
    """Local linear estimates ``(m,)`` [units of ``y``] at standardised queries ``xq`` ``(m, d)`` from ``(x, y)``.

    Notes
    -----
    At a query, the intercept ``beta_0`` of ``min sum_i w_i (y_i - beta_0 - beta^T (x_i - x_q))^2 +
    ridge sum_i w_i |beta|^2`` over its ``neighbours`` nearest training points, ``w_i =
    exp(-|x_i - x_q|^2 / (2 h^2))`` scaled so the nearest weighs 1 [cleveland1988]; the weighted mean where
    the normal equations are singular.  Without the ridge it reproduces a linear function exactly.
    """
    from scipy.spatial import cKDTree

    xq = np.atleast_2d(np.asarray(xq, dtype=float))
    m, d = xq.shape
    k = int(min(neighbours, len(x)))
    dist, idx = cKDTree(x).query(xq, k)
    dist, idx = dist.reshape(m, k), idx.reshape(m, k)
    d2 = dist * dist
    w = np.exp(-0.5 * (d2 - d2[:, :1]) / (h * h))                           # (m, k)
    z = x[idx] - xq[:, None, :]                                             # (m, k, d)
    zz = np.concatenate([np.ones((m, k, 1)), z], axis=-1)                   # (m, k, d+1)
    zw = zz * w[..., None]
    reg = ridge * np.eye(d + 1)
    reg[0, 0] = 0.0
    sw = w.sum(axis=1)
    a = np.swapaxes(zw, 1, 2) @ zz + reg * sw[:, None, None]
    rhs = np.swapaxes(zw, 1, 2) @ y[idx][..., None]
    mean = np.sum(w * y[idx], axis=1) / sw
    try:
        est = np.linalg.solve(a, rhs)[:, 0, 0]
    except np.linalg.LinAlgError:                     # a degenerate neighbourhood somewhere: one at a time
        est = np.array([np.linalg.lstsq(a[i], rhs[i], rcond=None)[0][0, 0] for i in range(m)])
    return np.where(np.isfinite(est), est, mean)


def _sq_distances(xq, x):
    d2 = np.sum(xq * xq, axis=1)[:, None] + np.sum(x * x, axis=1)[None, :] - 2.0 * xq @ x.T
    return np.maximum(d2, 0.0)


def _local_scale(xq, x, r, mask=None, neighbours=None):
    """RMS [units of ``r``] of the residuals ``r`` of the ``neighbours`` training points nearest each query
    (where ``mask`` allows), shrunk towards the pooled (median) mean square with the weight of :data:`PRIOR_WEIGHT` points."""
    k = int(min(neighbours or SCALE_NEIGHBOURS, len(x)))
    pooled2 = float(np.median(r * r))
    out = np.empty(len(xq))
    for lo in range(0, len(xq), 1024):
        d2 = _sq_distances(xq[lo:lo + 1024], x)
        if mask is not None:
            d2 = np.where(mask[lo:lo + 1024], d2, np.inf)
        idx = np.argpartition(d2, k - 1, axis=1)[:, :k]
        usable = np.isfinite(np.take_along_axis(d2, idx, axis=1))
        r2 = np.where(usable, (r * r)[idx], 0.0)
        out[lo:lo + 1024] = np.sqrt((r2.sum(axis=1) + PRIOR_WEIGHT * pooled2) / (usable.sum(axis=1) + PRIOR_WEIGHT))
    return np.maximum(out, SCALE_FLOOR)


def uplift_regime(x):
    """Regime index ``0 .. len(P_REGIMES)`` of feature rows: the bin of their first column, ``logit_p_uplift``."""
    p = 1.0 / (1.0 + np.exp(-np.asarray(x, dtype=float)[:, FEATURES.index("logit_p_uplift")]))
    return np.searchsorted(np.asarray(P_REGIMES), p, side="right")


def _out_of_family(x, y, groups, h):
    r = np.empty_like(y)
    for g in np.unique(groups):
        held = groups == g
        r[held] = y[held] - local_linear(x[held], x[~held], y[~held], h)
    return r


def _standardised(x):
    center = np.median(x, axis=0)
    width = np.std(x, axis=0)
    width = np.where(width > 0, width, 1.0)
    return (x - center) / width, center, width


def _regime_columns(x, regimes):
    """``(columns, part_of_regime)`` of the feature sets ``regimes`` (None: :data:`REGIME_FEATURES` where ``x``
    holds every feature, else one model on every column: None)."""
    if regimes is None:
        if x.shape[1] != len(FEATURES):
            return None
        regimes = REGIME_FEATURES
    if len(regimes) != N_REGIMES or x.shape[1] != len(FEATURES) or \
            any(not names or names[0] != FEATURES[0] or not set(names) <= set(FEATURES) for names in regimes):
        raise ValueError(f"parameter 'regimes' must give {N_REGIMES} feature sets of FEATURES, each starting with "
                         f"{FEATURES[0]!r}, for a feature matrix of {len(FEATURES)} columns")
    columns = list(dict.fromkeys(tuple(FEATURES.index(n) for n in names) for names in regimes))
    return tuple(columns), tuple(columns.index(tuple(FEATURES.index(n) for n in names)) for names in regimes)


def _fit_part(x, y, groups, coverage, bandwidths):
    xs, center, width = _standardised(x)
    d = x.shape[1]
    best = None
    for b in bandwidths:
        h = b * math.sqrt(d)
        r = _out_of_family(xs, y, groups, h)
        mse = float(np.mean(r * r))
        if best is None or mse < best[0]:
            best = (mse, h, r)
    _, h, r = best
    other = groups[:, None] != groups[None, :]
    s = _local_scale(xs, xs, r, mask=other)
    ratio = np.abs(r) / s
    regime = uplift_regime(x)
    q = np.empty(N_REGIMES)
    for c in range(len(q)):
        mine = ratio[regime == c] if np.count_nonzero(regime == c) >= MIN_REGIME else ratio
        level = min(1.0, math.ceil((len(mine) + 1) * coverage) / len(mine))
        q[c] = float(np.quantile(mine, level))
    return ErrorModel(xs, y, center, width, h, r, q, float(coverage))


def fit_error_model(x, y, groups, coverage=0.9, bandwidths=BANDWIDTHS, clip=None, regimes=None):
    """Fit the error model of one method and one error (module docstring), with a feature set per uplift regime.

    Parameters
    ----------
    x : array_like
        ``(n, d)`` features (:func:`features`).
    y : array_like
        ``(n,)`` errors [1]; rows with a NaN are dropped.
    groups : array_like
        ``(n,)`` family ids (a family is held out whole).
    coverage : float, default 0.9
        Nominal coverage of the interval, in (0, 1).
    bandwidths : sequence of float, default BANDWIDTHS
        Candidate bandwidths (times ``sqrt(d)``, standardised features); the least out-of-family squared error wins.
    clip : float, optional
        Errors clipped to ``[-clip, clip]`` before the fit (:data:`LOG_CLIP` for ``log(SL / MC)``: beyond a
        factor of 4 a point is untrusted whatever the factor).
    regimes : sequence of sequence of str, optional
        The feature names of the model of each regime of :data:`P_REGIMES`; None: :data:`REGIME_FEATURES`
        where ``x`` has every feature, else one model on every column.

    Returns
    -------
    ErrorModel or RegimeModel
        One :class:`ErrorModel`, or a :class:`RegimeModel` of one per distinct feature set; a point of regime
        ``c`` is predicted by the part of ``regimes[c]`` with that part's factor of regime ``c``.
    """
    if not 0.0 < coverage < 1.0:
        raise ValueError(f"parameter 'coverage' must be in (0, 1) (got {coverage!r})")
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    groups = np.asarray(groups)
    split = _regime_columns(x, regimes)
    keep = np.isfinite(y) & np.all(np.isfinite(x), axis=1)
    x, y, groups = x[keep], y[keep], groups[keep]
    if clip is not None:
        y = np.clip(y, -clip, clip)
    if len(np.unique(groups)) < 2:
        raise ValueError("parameter 'groups' must hold at least two families with finite errors")
    if split is None:
        return _fit_part(x, y, groups, coverage, bandwidths)
    columns, part_of_regime = split
    return RegimeModel(tuple(_fit_part(x[:, list(c)], y, groups, coverage, bandwidths) for c in columns),
                       columns, part_of_regime)


def predict(model, x):
    """``(estimate, low, high)`` [units of the error] of the model at feature rows ``x``: ``estimate +- q s(x)``; NaN where a feature is not finite."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    ok = np.all(np.isfinite(x), axis=1)
    if isinstance(model, RegimeModel):
        part = np.full(len(x), -1)
        part[ok] = np.asarray(model.part_of_regime)[uplift_regime(x[ok])]
        out = np.full((3, len(x)), np.nan)
        for k, (one, cols) in enumerate(zip(model.parts, model.columns)):
            if np.any(part == k):
                out[:, part == k] = predict(one, x[part == k][:, list(cols)])
        return out[0], out[1], out[2]
    est = np.full(len(x), np.nan)
    half = np.full(len(x), np.nan)
    if ok.any():
        xs = (x[ok] - model.center) / model.width
        est[ok] = local_linear(xs, model.x, model.y, model.h)
        half[ok] = model.q[uplift_regime(x[ok])] * _local_scale(xs, model.x, model.r)
    return est, est - half, est + half


def grouped_cross_validation(x, y, groups, folds=0, coverage=0.9, clip=None, regimes=None):
    """``(estimate, low, high)`` of every point predicted by a model fitted without its fold of families [hastie2009].

    Notes
    -----
    ``folds = 0``: leave one family out; otherwise families dealt at random (seed 0) into ``folds`` folds.
    ``coverage``, ``clip``, ``regimes`` as in :func:`fit_error_model`.  The coverage it measures is that of a
    new system.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    groups = np.asarray(groups)
    fam = np.unique(groups[np.isfinite(y)])
    if folds and folds < len(fam):
        rng = np.random.default_rng(0)
        assign = dict(zip(rng.permutation(fam).tolist(), (np.arange(len(fam)) % folds).tolist()))
    else:
        assign = {f: i for i, f in enumerate(fam.tolist())}
    fold = np.array([assign.get(g, -1) for g in groups.tolist()])
    est, low, high = (np.full(len(y), np.nan) for _ in range(3))
    for k in np.unique(fold[fold >= 0]):
        test = fold == k
        if len(np.unique(groups[~test & np.isfinite(y)])) < 2:
            continue
        model = fit_error_model(x[~test], y[~test], groups[~test], coverage=coverage, clip=clip, regimes=regimes)
        est[test], low[test], high[test] = predict(model, x[test])
    return est, low, high


#: A point is trusted when its whole predicted interval of ``SL / MC - 1`` lies within +-TRUSTED_ERROR [1]
#: and untrusted when the whole interval lies beyond +-UNTRUSTED_ERROR [1].
TRUSTED_ERROR = 0.25
UNTRUSTED_ERROR = 0.5


def trust_from_interval(low, high, trusted_error=TRUSTED_ERROR, untrusted_error=UNTRUSTED_ERROR):
    """:class:`screening.core.status.Trust` codes (int8) from an interval ``[low, high]`` of ``log(SL / MC)``.

    Notes
    -----
    ``trusted`` where ``exp(low) - 1 >= -trusted_error`` and ``exp(high) - 1 <= trusted_error``; ``untrusted``
    where it lies wholly beyond ``+-untrusted_error`` or is NaN; ``check`` otherwise.
    """
    low = np.asarray(low, dtype=float)
    high = np.asarray(high, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        rel_lo, rel_hi = np.expm1(low), np.expm1(high)
        trusted = (rel_lo >= -trusted_error) & (rel_hi <= trusted_error)
        beyond = (rel_hi < -untrusted_error) | (rel_lo > untrusted_error)
    finite = ~np.isnan(low) & ~np.isnan(high)          # an open end (+-inf, :func:`open_ended`) is an answer
    return np.where(~finite | beyond, int(Trust.untrusted),
                    np.where(trusted, int(Trust.trusted), int(Trust.check))).astype(np.int8)


ATLAS_FILE = "error_atlas.nc"


def fitted_variables(ds):
    """The error model of ``log(SL / MC)`` of every condensation of an atlas, as DataArrays to store with it.

    Notes
    -----
    ``em_residual`` (point, condensation, em_part: out-of-family residuals, NaN where not fitted),
    ``em_bandwidth`` (condensation, em_part), ``em_q`` (condensation, em_part, regime) and
    ``em_part_of_regime`` (regime), coordinate ``em_part`` naming each part's features; all [1].
    :func:`model_from_atlas` rebuilds the model from them without refitting.
    """
    import xarray as xr

    conds = [str(c) for c in ds["condensation"].values]
    columns, part_of_regime = _regime_columns(np.empty((0, len(FEATURES))), REGIME_FEATURES)
    n_parts = len(columns)
    res = np.full((ds.sizes["point"], len(conds), n_parts), np.nan)
    h, q = np.full((len(conds), n_parts), np.nan), np.full((len(conds), n_parts, N_REGIMES), np.nan)
    for j, c in enumerate(conds):
        x, y, keep = _atlas_rows(ds, c)
        model = fit_error_model(x, y, ds["family"].values, clip=LOG_CLIP, regimes=REGIME_FEATURES)
        for k, part in enumerate(model.parts):
            res[np.flatnonzero(keep), j, k] = part.r
            h[j, k], q[j, k] = part.h, part.q
    part = {"em_part": ("em_part", np.array([" ".join(FEATURES[i] for i in cols) for cols in columns], dtype=object),
                        {"long_name": "features of each part of the error model"})}
    return {"em_residual": xr.DataArray(res, dims=("point", "condensation", "em_part"), coords=part, attrs={
                "units": "1", "long_name": "out-of-family residual of log(SL / MC) of the error model's part"}),
            "em_bandwidth": xr.DataArray(h, dims=("condensation", "em_part"), coords=part, attrs={
                "units": "1", "long_name": "bandwidth of the local linear fit of the error model's part "
                                           "(standardised features)"}),
            "em_q": xr.DataArray(q, dims=("condensation", "em_part", "regime"), coords=part, attrs={
                "units": "1", "long_name": "conformal factor of the error model's 90 % interval per part and "
                                           "uplift regime"}),
            "em_part_of_regime": xr.DataArray(np.asarray(part_of_regime, dtype=np.int8), dims="regime", attrs={
                "units": "1", "long_name": "index along em_part of the part that predicts each uplift regime "
                                           "(peak p_uplift below 0.2, 0.2 to 0.7, above)"})}


def _atlas_rows(ds, condensation):
    x = atlas_features(ds, condensation)
    y = targets(ds, condensation)["log_var_ratio"]
    keep = np.isfinite(y) & np.all(np.isfinite(x), axis=1)
    return x, y, keep


#: The variables of a stored error model fit (:func:`fitted_variables`).
STORED_FIT = ("em_residual", "em_bandwidth", "em_q", "em_part_of_regime", "em_part")


def model_from_atlas(ds, condensation):
    """The :class:`RegimeModel` of ``log(SL / MC)`` of one condensation of an atlas: from its stored fit, else fitted."""
    if condensation not in ds["condensation"].values:
        raise ValueError(f"parameter 'condensation' must be one of {[str(c) for c in ds['condensation'].values]} "
                         f"(got {condensation!r})")
    x, y, keep = _atlas_rows(ds, condensation)
    if "em_residual" not in ds.variables:
        return fit_error_model(x, y, ds["family"].values, clip=LOG_CLIP, regimes=REGIME_FEATURES)
    if "em_part" not in ds["em_residual"].dims:
        raise ValueError("the atlas's stored error model has no parts (an older layout): refit it (fitted_variables)")
    r = ds["em_residual"].sel(condensation=condensation).transpose("point", "em_part").values
    if not all(np.array_equal(np.isfinite(r[:, k]), keep) for k in range(r.shape[1])):
        raise ValueError("the atlas's stored error model does not match its points: refit it (fitted_variables)")
    x, y = x[keep], np.clip(y[keep], -LOG_CLIP, LOG_CLIP)
    columns = tuple(tuple(FEATURES.index(n) for n in str(names).split()) for names in ds["em_part"].values)
    h = ds["em_bandwidth"].sel(condensation=condensation).values
    q = ds["em_q"].sel(condensation=condensation).transpose("em_part", "regime").values.astype(float)
    parts = []
    for k, cols in enumerate(columns):
        xs, center, width = _standardised(x[:, list(cols)])
        parts.append(ErrorModel(xs, y, center, width, float(h[k]), r[keep, k], q[k], 0.9))
    return RegimeModel(tuple(parts), columns, tuple(int(i) for i in ds["em_part_of_regime"].values))


@functools.lru_cache(maxsize=None)
def shipped_model(condensation="paper"):
    """The error model of ``log(SL / MC)`` of one condensation from the shipped atlas
    (``screening/data/error_atlas.nc``, :func:`model_from_atlas`); cached per process."""
    from importlib import resources

    import xarray as xr

    names = ["u", "alpha", "r_ul", "zeta_v", "e", "kind", "omega_g_p", "tau", "I_S", "w_v_p", "family", "sl_status",
             "sl_peak_var_theta", "sl_peak_p_uplift", "sl_sigma_ratio", "sl_k_eq_margin", "sl_decay_excess",
             "sl_p_exceed", "mc_peak_var_theta", "mc_peak_var_theta_se", "mc_p_exceed", "mc_p_exceed_se",
             "mc_reference_valid", *STORED_FIT]
    with resources.as_file(resources.files("screening.data") / ATLAS_FILE) as path, xr.open_dataset(path) as ds:
        ds = ds[[n for n in names if n in ds.variables]].load()
    return model_from_atlas(ds, condensation)


def parameter_groups(fields, contact="hunt_crossley", excitation="white"):
    """The point's dimensionless inputs of :func:`features` from its model parameters (same types as ``fields``).

    Parameters
    ----------
    fields : mapping
        ``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2], ``k`` [N m-2], and where present ``eps`` [m-2], ``I_cm``
        [kg m2], ``lam`` [N s m-3] or ``c`` [N s m-2], ``omega_g`` [rad s-1], ``T1`` [s], ``S0`` [m2 s-3].
    contact : str, default "hunt_crossley"
        ``"hunt_crossley"`` or ``"winkler"``.
    excitation : str, default "white"
        The excitation kind.

    Returns
    -------
    dict
        ``alpha`` [rad], ``r_ul``, ``zeta_v``, ``e``, ``omega_g_p``, ``tau``, ``I_S``, ``w_v_p`` [1].

    Notes
    -----
    ``alpha = atan(b/h)``; ``r_ul = m g / (2 b^2 k alpha)`` (the uplift angle of [mitseas2026] over
    ``alpha``); ``e = eps z0^2``, ``z0 = m g / (2 b k)``; ``zeta_v`` of
    :func:`screening.core.physics.contact.vertical_damping_ratio` (NaN without damping or rest indentation);
    Housner's [housner1963] ``p = sqrt(m g R / (I_cm + m R^2))``; ``omega_g / p``; ``tau = T1 p`` (``1e6``
    without ``T1``); ``I_S = sqrt(2 pi S0 p) / (g tan(alpha))``; ``w_v_p = sqrt(2 b k / m) / p``.
    """
    like = None
    if any(hasattr(v, "dims") for v in fields.values()):         # xarray: broadcast once, compute on numpy
        import xarray as xr

        labelled = xr.broadcast(*(v if hasattr(v, "dims") else xr.DataArray(v) for v in fields.values()))
        like = labelled[0]
        fields = {name: np.asarray(v.values, dtype=float) for name, v in zip(fields, labelled)}
    m, b, h, g, k = (fields[name] for name in ("m", "b", "h", "g", "k"))
    eps = fields.get("eps", 0.0)
    i_cm = fields.get("I_cm", m * (b**2 + h**2) / 3.0)
    alpha = np.arctan2(b, h)
    z0 = m * g / (2.0 * b * k)
    eps_b, z0_b = np.broadcast_arrays(np.asarray(eps, dtype=float), np.asarray(z0, dtype=float))
    carried = -eps_b * z0_b**2 < REST_BEARING_LIMIT             # else the bed cannot carry the block at rest
    z_rest = np.full(z0_b.shape, np.nan)
    z_rest[carried] = rising_root(eps_b[carried], 1.0, z0_b[carried])
    damping = (fields.get("c", np.nan), 0.0) if contact == "winkler" else (0.0, fields.get("lam", np.nan))
    zeta_v = vertical_damping_ratio(SimpleNamespace(m=m, b=b), SimpleNamespace(k=k, damping_weights=damping),
                                    z_rest[()])
    R = np.hypot(b, h)
    p = np.sqrt(m * g * R / (i_cm + m * R**2))
    out = {"alpha": alpha, "r_ul": m * g / (2.0 * b**2 * k * alpha), "zeta_v": zeta_v,
           "e": eps * z0**2, "omega_g_p": fields["omega_g"] / p if "omega_g" in fields else np.nan + 0.0 * p,
           "tau": fields["T1"] * p if "T1" in fields else 1e6 + 0.0 * p,
           "I_S": np.sqrt(2.0 * np.pi * fields.get("S0", np.nan) * p) / (g * b / h),
           "w_v_p": np.sqrt(2.0 * b * k / m) / p}
    if like is None:
        return out
    return {name: xr.DataArray(np.broadcast_to(v, like.shape), dims=like.dims, coords=like.coords)
            for name, v in out.items()}


def dataset_features(ds):
    """``(features, dims, shape)`` of every point of a :func:`screening.linearize` (or sweep) dataset, from its indicators and parameter coordinates."""
    import xarray as xr

    ind = indicators_from_dataset(ds)
    fields = {name: ds[name] for name in ("m", "b", "h", "g", "k", "eps", "I_cm", "lam", "c", "omega_g", "T1", "S0")
              if name in ds.variables}
    kind = ds.attrs.get("excitation", "white")
    grp = parameter_groups(fields, ds.attrs.get("contact", "hunt_crossley"), kind)
    parts = [ind["peak_p_uplift"], ind["sigma_ratio"], ind["k_eq_margin"], ind["decay_excess"],
             *(grp[name] for name in ("alpha", "r_ul", "zeta_v", "e", "omega_g_p", "tau", "I_S", "w_v_p"))]
    parts = xr.broadcast(*[xr.DataArray(v) if not isinstance(v, xr.DataArray) else v for v in parts])
    dims = parts[0].dims
    vals = [np.asarray(v.transpose(*dims).values, dtype=float).ravel() for v in parts]
    x = features(*vals[:8], np.full(vals[0].size, kind), *vals[8:])
    return x, dims, parts[0].transpose(*dims).shape


def model_features(indicators, block, foundation, excitation):
    """:func:`features` of ``n`` points given as model objects and their :func:`screening.analysis.indicators.trust_indicators`."""
    labels = model_labels(foundation, excitation)
    grp = parameter_groups(model_fields(block, foundation, excitation), labels["contact"], labels["excitation"])
    n = np.size(indicators["peak_p_uplift"])
    col = {name: np.broadcast_to(np.asarray(v, dtype=float), (n,)) for name, v in grp.items()}
    return features(indicators["peak_p_uplift"], indicators["sigma_ratio"], indicators["k_eq_margin"],
                    indicators["decay_excess"], col["alpha"], col["r_ul"], col["zeta_v"], col["e"],
                    np.full(n, labels["excitation"]), col["omega_g_p"], col["tau"], col["I_S"], col["w_v_p"])


#: Features of the point's inputs that are the atlas's design groups: outside the atlas's range of any of
#: them a point is never ``trusted`` (the interval is calibrated for systems like the atlas's).  ``I_S`` and
#: ``w_v/p`` are no design axes (the atlas sets the intensity by a target uplift probability, and ``w_v/p``
#: follows from ``alpha`` and ``r_ul`` for a uniform block).
INPUT_FEATURES = FEATURES[4:11]
#: Excitation kinds and contact laws the atlas samples.
ATLAS_KINDS = ("white", "kanai_tajimi")
ATLAS_CONTACTS = ("hunt_crossley",)


def inside_atlas(model, x):
    """Boolean: where every feature of :data:`INPUT_FEATURES` of the rows lies within the model's atlas range."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    cols = [FEATURES.index(name) for name in INPUT_FEATURES]
    if isinstance(model, RegimeModel):          # the input groups of a part that reads them all
        model, part_cols = next((m, list(c)) for m, c in zip(model.parts, model.columns) if set(cols) <= set(c))
        cols_in = [part_cols.index(i) for i in cols]
    else:
        cols_in = cols
    train = model.x[:, cols_in] * model.width[cols_in] + model.center[cols_in]
    lo, hi = train.min(axis=0), train.max(axis=0)
    pad = 1e-9 * np.maximum(np.abs(lo), np.abs(hi)) + 1e-12
    with np.errstate(invalid="ignore"):
        return np.all((x[:, cols] >= lo - pad) & (x[:, cols] <= hi + pad), axis=1)


def open_ended(est, low, high, clip=LOG_CLIP):
    """``(est, low, high)`` of ``log(SL / MC)`` with an end that reaches the fit's clip ``+-clip`` made infinite.

    Notes
    -----
    The model is fitted on errors clipped there, so such an interval says "beyond a factor 4", not how far
    (on held-out families it covers the unclipped error at a third of such points, against 95 % elsewhere).
    """
    low = np.where(np.asarray(low, dtype=float) <= -clip, -np.inf, low)
    high = np.where(np.asarray(high, dtype=float) >= clip, np.inf, high)
    return est, low, high


def interval_trust(model, x, status=None, covered=True):
    """``(flag, estimate, low, high)``: the Trust code [int8] and the predicted ``SL / MC - 1`` of peak var_theta with its interval.

    Notes
    -----
    A point whose ``status`` (:class:`screening.core.status.PointStatus`, None: all ok) is not ok is
    ``untrusted`` with NaNs; an interval end at the clip is open (:func:`open_ended`: ``low = -1`` or
    ``high = inf``) and the point ``untrusted``.  Points not ``covered`` (another excitation kind or contact
    law than the atlas samples) or outside its range (:func:`inside_atlas`) are at best ``check``; a point
    with a feature not finite is ``check`` with a NaN band.  ``docs/error_atlas.md``.
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    est, low, high = open_ended(*predict(model, x))
    bad = np.zeros(len(x), dtype=bool) if status is None else \
        np.broadcast_to(np.asarray(status), (len(x),)) != int(PointStatus.ok)
    est, low, high = (np.where(bad, np.nan, a) for a in (est, low, high))
    flag = np.where(bad, int(Trust.untrusted), trust_from_interval(low, high)).astype(np.int8)
    flag[np.isinf(low) | np.isinf(high)] = int(Trust.untrusted)     # the atlas measured errors beyond a factor 4
    flag[~bad & ~np.all(np.isfinite(x), axis=1)] = int(Trust.check)
    outside = ~(inside_atlas(model, x) & np.broadcast_to(np.asarray(covered, dtype=bool), (len(x),)))
    flag[outside & (flag == int(Trust.trusted))] = int(Trust.check)
    with np.errstate(over="ignore"):
        return flag, np.expm1(est), np.expm1(low), np.expm1(high)


def with_error_model(ds, model):
    """``ds`` (a :func:`screening.linearize` dataset) with ``sl_trust``, ``sl_error`` (``SL / MC - 1``), ``sl_error_low``, ``sl_error_high`` (:func:`interval_trust`)."""
    import xarray as xr

    x, dims, shape = dataset_features(ds)
    status = np.broadcast_to(np.asarray(ds["status"].transpose(*[d for d in dims if d in ds["status"].dims]).values),
                             shape).ravel() if "status" in ds.variables else None
    covered = ds.attrs.get("excitation", "white") in ATLAS_KINDS and \
        ds.attrs.get("contact", "hunt_crossley") in ATLAS_CONTACTS
    flag, est, low, high = interval_trust(model, x, status, covered)

    def arr(values, units, long_name):
        return xr.DataArray(values.reshape(shape), dims=dims, attrs={"units": units, "long_name": long_name})

    return ds.assign(
        sl_trust=arr(flag, "1", "trust from the error atlas model (0 trusted, 1 check, 2 untrusted)"),
        sl_error=arr(est, "1", "predicted SL / MC - 1 of peak var_theta (error atlas model)"),
        sl_error_low=arr(low, "1", "lower end of the predicted interval of SL / MC - 1"),
        sl_error_high=arr(high, "1", "upper end of the predicted interval of SL / MC - 1"))
