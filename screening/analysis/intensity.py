"""Intensity measures of the stochastic inputs by random-vibration theory (RVT).

The ground acceleration of a study point is ``a(t) = q(t) f(t)``: the envelope ``q``
(:mod:`screening.model.excitation`) times a zero-mean stationary Gaussian process ``f`` with
two-sided PSD ``S(omega)`` band-limited to ``|omega| <= omega_c``, exactly as the Monte Carlo
synthesis draws it (:mod:`screening.solvers.synthesis`; white noise has finite variance only
because of this band limit, so its PGA grows like ``sqrt(omega_c)``).  With the spectral
moments ``lambda_i = int_{-omega_c}^{omega_c} |omega|^i S(omega) d omega``:

* ``rms_acceleration`` [m s-2] = ``sqrt(lambda_0 int_0^T q^2 dt / T)``, the root mean square of
  ``a`` over the record ``[0, T]`` (ensemble mean of the time average);
* ``arias_intensity`` [m s-1] = ``E[pi/(2 g) int_0^T a^2 dt] = pi lambda_0 int_0^T q^2 dt / (2 g)``
  (its expected value; the sample-to-sample scatter is a few per cent for records of many cycles);
* ``pga_median`` [m s-2]: the median of ``max_t |a(t)|`` from the first-passage probability of
  the non-stationary Gaussian pair ``(a, a')`` with ``var a = q^2 lambda_0``,
  ``var a' = q^2 lambda_2 + q'^2 lambda_0``, ``cov(a, a') = q q' lambda_0``: Rice's rate of
  outward crossings of ``|a| = x`` (:func:`screening.analysis.fragility.upcrossing_rate`) with
  Vanmarcke's (1975) clumping correction for the bandwidth ``delta = sqrt(1 - lambda_1^2 /
  (lambda_0 lambda_2))`` of ``f``, and ``P(PGA <= x) = exp(-int_0^T nu(x, t) dt)``; the median solves
  ``int nu dt = ln 2``.  This is the peak-factor method of Der Kiureghian (1980) / Vanmarcke
  written over the whole modulated record instead of a stationary "strong-motion" duration;
* ``sa_median`` [m s-2]: median pseudo-spectral acceleration ``omega_n^2 max |u|`` of a linear
  oscillator (period ``T_n``, damping ratio ``zeta``, default 5 %) driven by ``-a(t)``, from the
  same first-passage formula applied to the oscillator's non-stationary covariance (Lyapunov
  equation of the oscillator, with the Kanai-Tajimi filter states for that input, started at rest
  with the filter in its stationary state as in the synthesis) and the white-noise bandwidth of
  the oscillator (:func:`~screening.analysis.fragility.oscillator_bandwidth`).  The Lyapunov
  equation does not see the band limit: valid for ``omega_n`` well below ``omega_c`` (a
  ``UserWarning`` is raised when ``omega_n > omega_c / 2``).

Every measure is proportional to ``sqrt(S0)`` (Arias: to ``S0``), so
:func:`s0_for_pga` inverts a target PGA exactly.

Validation (``tests/unit/analysis/test_intensity.py``, slow): 1,000 synthesised records of a
white-noise and a Kanai-Tajimi point; medians of the sampled peaks and of the oscillator peaks
against these predictions (measured accuracies in the test docstrings).

References: Vanmarcke, E. H. (1975) On the distribution of the first-passage time for normal
stationary random processes, J. Appl. Mech. 42, 215-220.  Der Kiureghian, A. (1980) Structural
response to stationary excitation, J. Eng. Mech. Div. 106(6), 1195-1213.  Boore, D. M. (2003)
Simulation of ground motion using the stochastic method, Pure Appl. Geophys. 160, 635-676.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import xarray as xr
from scipy import integrate, optimize

from screening.analysis.fragility import oscillator_bandwidth, upcrossing_rate, vanmarcke_factor
from screening.solvers.synthesis import envelope_rate

#: Names of the measures (data variables of :func:`intensity_measures`) and their units.
MEASURES = {"pga_median": "m s-2", "rms_acceleration": "m s-2", "arias_intensity": "m s-1", "sa_median": "m s-2"}
#: Names of the measures of one record (:func:`record_measures`; ``sa`` only with a period).
RECORD_MEASURES = ("pga", "rms_acceleration", "arias_intensity", "sa")
#: Standard gravity used by the Arias intensity [m s-2].
G = 9.80665
N_TIMES = 4001
#: Points evaluated together by :func:`rocking_start_probability`.
CHUNK_POINTS = 64


def spectral_moments(excitation, cutoff):
    """``(lambda_0, lambda_1, lambda_2)`` of the unmodulated input band-limited to ``cutoff`` [rad/s].

    ``lambda_i = int_{-omega_c}^{omega_c} |omega|^i S(omega) d omega``: [m2 s-4], [m2 s-5], [m2 s-6].
    """
    wc = float(cutoff)
    if excitation.kind == "white":
        s0 = float(excitation.S0)
        return 2.0 * s0 * wc, s0 * wc**2, 2.0 * s0 * wc**3 / 3.0
    out = []
    for i in range(3):
        val, _ = integrate.quad(lambda w: w**i * float(excitation.psd(w)), 0.0, wc, limit=400,
                                points=[float(excitation.omega_g)], epsrel=1e-11)
        out.append(2.0 * val)
    return tuple(out)


def _times(t_end, n=N_TIMES):
    return np.linspace(0.0, float(t_end), n)


def rms_acceleration(excitation, t_end, cutoff):
    """Root mean square of the modulated, band-limited ground acceleration over ``[0, t_end]`` [m s-2]."""
    lam0 = spectral_moments(excitation, cutoff)[0]
    t = _times(t_end)
    return math.sqrt(lam0 * np.trapezoid(excitation.envelope(t) ** 2, t) / float(t_end))


def arias_intensity(excitation, t_end, cutoff, g=G):
    """Expected Arias intensity ``pi/(2 g) E[int_0^T a^2 dt]`` [m s-1]."""
    lam0 = spectral_moments(excitation, cutoff)[0]
    t = _times(t_end)
    return math.pi / (2.0 * g) * lam0 * np.trapezoid(excitation.envelope(t) ** 2, t)


def median_peak(t, var, var_dot, cov, bandwidth, probability=0.5):
    """Level ``x`` with ``P(max_t |y| <= x) = probability`` for a non-stationary Gaussian ``y`` with the
    given moments on times ``t`` (Rice rate, Vanmarcke clumping with ``bandwidth``, Poisson in time)."""
    target = -math.log(probability)
    sigma = math.sqrt(float(np.max(var)))
    if not sigma > 0.0:
        return 0.0

    def excess(log_x):
        x = math.exp(log_x)
        rate = upcrossing_rate(var, var_dot, cov, x) * vanmarcke_factor(var, x, bandwidth)
        return float(np.trapezoid(rate, t)) - target

    lo, hi = math.log(0.05 * sigma), math.log(20.0 * sigma)
    while excess(lo) < 0.0:
        lo -= 1.0
    return math.exp(optimize.brentq(excess, lo, hi, xtol=1e-10))


def input_moments(excitation, t_end, cutoff):
    """``(t, var a, var a', cov(a, a'), delta)`` of the modulated, band-limited ground acceleration on
    :data:`N_TIMES` times over ``[0, t_end]`` [s, m2 s-4, m2 s-6, m2 s-5, 1] (see the module docstring)."""
    lam0, lam1, lam2 = spectral_moments(excitation, cutoff)
    t = _times(t_end)
    q = excitation.envelope(t)
    qd = envelope_rate(excitation.envelope, t)
    delta = math.sqrt(max(1.0 - lam1**2 / (lam0 * lam2), 0.0))
    return t, q * q * lam0, q * q * lam2 + qd * qd * lam0, q * qd * lam0, delta


def pga_median(excitation, t_end, cutoff):
    """Median peak ground acceleration [m s-2] of the modulated input (see the module docstring)."""
    return median_peak(*input_moments(excitation, t_end, cutoff))


def rocking_start_probability(excitation, t_end, cutoff, uplift_acceleration, method="poisson"):
    """Probability [1] that ``|a_g|`` exceeds ``uplift_acceleration`` [m s-2] at least once over ``[0, t_end]``.

    Parameters
    ----------
    excitation : white noise or Kanai-Tajimi input (array fields broadcast with the others).
    t_end : record length [s].
    cutoff : band limit of the input [rad s-1] (the Monte Carlo synthesis's).
    uplift_acceleration : ground acceleration at which the block starts to rock [m s-2]
        (:func:`screening.analysis.probabilities.uplift_acceleration`).
    method : ``"poisson"`` (default: independent crossings) or ``"vanmarcke"`` (clumped crossings, the
        assumption of :func:`pga_median`).

    Returns
    -------
    float or array over the broadcast points.

    Notes
    -----
    The distribution of the peak ground acceleration of which :func:`pga_median` is the median:
    ``P(max_t |a| > x) = 1 - exp(-int_0^T nu(x, t) dt)`` with Rice's double-barrier rate ``nu`` of the
    non-stationary pair ``(a, a')`` (:func:`screening.analysis.fragility.exceedance_probability_from_moments`).
    Ground acceleration is broad-band (bandwidth ``delta`` 0.5 for band-limited white noise, 0.65 for
    the Kanai-Tajimi point of the tests), so its crossings barely clump: against 2,000 synthesised
    records the Poisson form is within 2.5 binomial standard errors at probabilities 0.05-0.95, where
    Vanmarcke's correction is up to 0.08 (12 standard errors) low at the middle of the distribution
    (``tests/unit/analysis/test_intensity.py``).  The moments
    scale with ``S0``, so one evaluation per distinct filter, envelope and band limit at ``S0 = 1``
    serves every point, at the level ``x / sqrt(S0)``.

    References
    ----------
    Vanmarcke, E. H. (1975), see the module docstring.
    """
    if method not in ("poisson", "vanmarcke"):
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    s0 = np.asarray(excitation.S0, dtype=float)
    level, s0, cut = np.broadcast_arrays(np.asarray(uplift_acceleration, dtype=float), s0,
                                         np.asarray(cutoff, dtype=float))
    omega, zeta = (np.broadcast_to(np.asarray(getattr(excitation, n, np.nan), dtype=float), level.shape)
                   for n in ("omega_g", "zeta_g"))
    out = np.full(level.shape, np.nan)
    keys = {}
    for index in np.ndindex(level.shape):
        keys.setdefault((_key(omega[index]), _key(zeta[index]), float(cut[index])), []).append(index)
    for (om, ze, wc), points in keys.items():
        try:
            x_grid, log_crossings = _unit_crossings(*_shape_key(excitation, t_end), om, ze, wc, method)
        except (ArithmeticError, ValueError):          # scales beyond float64: NaN
            continue
        rows = tuple(np.array(i) for i in zip(*points)) if level.ndim else ()
        with np.errstate(divide="ignore", invalid="ignore"):
            x = level[rows] / np.sqrt(s0[rows])
            crossings = np.exp(np.interp(x, x_grid, log_crossings, right=-np.inf))
            out[rows] = np.where(np.isfinite(x), -np.expm1(-crossings), np.nan)
    return float(out) if out.ndim == 0 else out


#: Levels per unit peak standard deviation of the table of :func:`_unit_crossings`, and its extent.
CROSSING_STEP, CROSSING_EXTENT = 0.02, 12.0


@functools.lru_cache(maxsize=256)
def _unit_crossings(*args):
    """``(x, log int_0^T nu(x, t) dt)`` at ``S0 = 1`` of one filter, envelope, ``t_end``, band limit and method,
    tabulated at levels ``x`` every :data:`CROSSING_STEP` peak standard deviations (``log`` of the expected
    crossings is nearly quadratic in ``x``: linear interpolation errs by about ``step^2 / 8``, 5e-5 relative;
    beyond the table, 12 peak standard deviations, the probability is below 1e-28 and read as 0)."""
    from screening.analysis.fragility import exceedance_probability_from_moments

    *shape, method = args
    t, var, var_dot, cov, delta = _unit_input_moments(*shape)
    x = np.arange(0.0, CROSSING_EXTENT, CROSSING_STEP) * math.sqrt(float(np.max(var)))
    crossings = np.empty_like(x)
    for lo in range(0, x.size, CHUNK_POINTS):              # bounded memory: levels x N_TIMES at a time
        p = exceedance_probability_from_moments(t, var, var_dot, cov, x[lo:lo + CHUNK_POINTS, None], method=method,
                                                bandwidth=delta)
        crossings[lo:lo + CHUNK_POINTS] = -np.log1p(-np.minimum(p, 1.0 - 1e-16))    # certain beyond ~37
    with np.errstate(divide="ignore"):
        log_crossings = np.log(crossings)
    keep = np.isfinite(log_crossings)                     # the levels no record reaches are read as 0
    return x[keep], log_crossings[keep]


def _shape_key(excitation, t_end):
    """Cache key of the filter kind, envelope and record length of ``excitation``."""
    env = excitation.envelope
    return (excitation.kind, env.kind, *(np.atleast_1d(env.params[1:]).astype(float).tolist()
                                         if env.kind == "exponential" else ()), float(t_end))


@functools.lru_cache(maxsize=256)
def _unit_input_moments(kind, envelope_kind, *args):
    """:func:`input_moments` at ``S0 = 1`` of one filter, envelope, ``t_end`` and band limit."""
    *envelope, t_end, omega_g, zeta_g, cutoff = args
    p = {"omega_g": omega_g, "zeta_g": zeta_g, **dict(zip(("T1", "T2"), envelope))}
    return input_moments(_scalar_excitation(kind, envelope_kind, p), t_end, cutoff)


def oscillator_covariance(excitation, period, t_end, damping=0.05, n_times=N_TIMES):
    """``(t, var_u [m2], var_u_dot [m2 s-2], cov [m2 s-1])`` of a linear oscillator driven by ``-a(t)``
    (Lyapunov equation; Kanai-Tajimi filter states included and started stationary)."""
    wn = 2.0 * math.pi / float(period)
    z = float(damping)
    S0 = float(excitation.S0)
    env = excitation.envelope
    if excitation.kind == "white":
        def A(t):
            return np.array([[0.0, 1.0], [-wn * wn, -2.0 * z * wn]])
        B = np.array([0.0, 1.0])
        P0 = np.zeros((2, 2))
        iu = 0
    else:
        wg, zg = float(excitation.omega_g), float(excitation.zeta_g)

        def A(t):
            q = float(env(t))
            return np.array([[0.0, 1.0, 0.0, 0.0], [-wg * wg, -2.0 * zg * wg, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0],
                             [q * wg * wg, q * 2.0 * zg * wg, -wn * wn, -2.0 * z * wn]])
        B = np.array([0.0, -1.0, 0.0, 0.0])
        P0 = np.zeros((4, 4))
        P0[0, 0] = math.pi * S0 / (2.0 * zg * wg**3)
        P0[1, 1] = math.pi * S0 / (2.0 * zg * wg)
        iu = 2
    n = P0.shape[0]
    BB = 2.0 * math.pi * S0 * np.outer(B, B)

    def rhs(t, y):
        P = y.reshape(n, n)
        a = A(t)
        Q = BB * (float(env(t)) ** 2 if excitation.kind == "white" else 1.0)
        return (a @ P + P @ a.T + Q).ravel()

    t = _times(t_end, n_times)
    sol = integrate.solve_ivp(rhs, (0.0, float(t_end)), P0.ravel(), t_eval=t, rtol=1e-8,
                              atol=1e-14 * max(S0, 1e-300), max_step=min(0.05, float(period) / 10.0))
    P = sol.y.reshape(n, n, -1)
    return t, P[iu, iu], P[iu + 1, iu + 1], P[iu, iu + 1]


def sa_median(excitation, period, t_end, damping=0.05, cutoff=None):
    """Median pseudo-spectral acceleration ``omega_n^2 max|u|`` [m s-2] at ``period`` [s]."""
    wn = 2.0 * math.pi / float(period)
    if cutoff is not None and wn > 0.5 * float(cutoff):
        warnings.warn(f"Sa at T = {period:g} s: omega_n = {wn:.3g} rad/s is above half the input's band limit "
                      f"{float(cutoff):.3g} rad/s; the RVT estimate ignores the band limit", UserWarning,
                      stacklevel=2)
    t, v, vd, c = oscillator_covariance(excitation, period, t_end, damping)
    return wn * wn * median_peak(t, v, vd, c, float(oscillator_bandwidth(damping)))


def s0_for_pga(excitation, target_pga, t_end, cutoff):
    """``S0`` [m2 s-3] giving the median PGA ``target_pga`` [m s-2] for the shape of ``excitation``
    (its filter and envelope; its own ``S0`` is irrelevant), with band limit ``cutoff`` [rad/s] over a
    record of ``t_end`` [s].

    PGA is proportional to ``sqrt(S0)``: ``S0 = (target_pga / pga_1)^2`` with ``pga_1`` the median PGA
    at ``S0 = 1``.  ``target_pga``, ``cutoff`` and the excitation's ``omega_g``, ``zeta_g`` may be
    arrays (broadcast together); :func:`pga_median` runs once per distinct filter and band limit.
    """
    target, unit = _per_unit_s0(excitation, target_pga, t_end, cutoff)
    out = (target / unit[..., 0]) ** 2
    return float(out) if out.ndim == 0 else out


def input_measures(excitation, t_end, cutoff):
    """``pga_median`` [m s-2], ``rms_acceleration`` [m s-2] and ``arias_intensity`` [m s-1] of every
    point of ``excitation`` (array fields and ``cutoff`` [rad/s] broadcast together), as a dict.

    Computed once per distinct filter and band limit at ``S0 = 1`` and scaled: the first two are
    proportional to ``sqrt(S0)``, the Arias intensity to ``S0``."""
    s0, unit = _per_unit_s0(excitation, excitation.S0, t_end, cutoff)
    root = np.sqrt(s0)
    return {"pga_median": root * unit[..., 0], "rms_acceleration": root * unit[..., 1],
            "arias_intensity": s0 * unit[..., 2]}


def _per_unit_s0(excitation, values, t_end, cutoff):
    """``values`` broadcast with the filter and ``cutoff``, and the measures at ``S0 = 1`` (last axis:
    pga, rms, arias) of every point."""
    omega = np.asarray(getattr(excitation, "omega_g", np.nan), dtype=float)
    zeta = np.asarray(getattr(excitation, "zeta_g", np.nan), dtype=float)
    values, cut, omega, zeta = np.broadcast_arrays(np.asarray(values, dtype=float),
                                                   np.asarray(cutoff, dtype=float), omega, zeta)
    env = excitation.envelope
    shape = (excitation.kind, env.kind, *(np.atleast_1d(env.params[1:]).astype(float).tolist()
                                          if env.kind == "exponential" else ()), float(t_end))
    unit = np.empty(values.shape + (3,))
    for index in np.ndindex(values.shape):
        try:
            unit[index] = _unit_measures(*shape, _key(omega[index]), _key(zeta[index]), float(cut[index]))
        except (ArithmeticError, ValueError):          # scales beyond float64 (see PointStatus.beyond_float_range)
            unit[index] = np.nan
    return values, unit


def _key(value):
    """A cache key of a filter parameter: None for NaN (white noise), which never equals itself."""
    value = float(value)
    return None if math.isnan(value) else value


@functools.lru_cache(maxsize=4096)
def _unit_measures(kind, envelope_kind, *args):
    """``(pga_median, rms_acceleration, arias_intensity)`` at ``S0 = 1`` of one filter, envelope,
    ``t_end`` and band limit."""
    *envelope, t_end, omega_g, zeta_g, cutoff = args
    p = {"omega_g": omega_g, "zeta_g": zeta_g, **dict(zip(("T1", "T2"), envelope))}
    exc = _scalar_excitation(kind, envelope_kind, p)
    return (pga_median(exc, t_end, cutoff), rms_acceleration(exc, t_end, cutoff),
            arias_intensity(exc, t_end, cutoff))


# ----------------------------------------------------------------------------- datasets
def _scalar_excitation(kind, envelope_kind, p):
    from screening.model.excitation import ConstantEnvelope, Envelope, KanaiTajimi, WhiteNoise
    env = Envelope(p["T1"], p["T2"]) if envelope_kind == "exponential" else ConstantEnvelope()
    if kind == "white":
        return WhiteNoise(1.0, env)
    return KanaiTajimi(1.0, p["omega_g"], p["zeta_g"], env)


def intensity_measures(ds, period=None, damping=0.05, cutoff=None):
    """RVT intensity measures of the input of every point of a result dataset (sweep or linearize).

    Reads ``S0``, ``omega_g``, ``zeta_g``, ``T1``, ``T2`` (coordinates), the ``excitation`` and
    ``envelope`` attributes, ``t_end`` (last ``t``) and the band limit: ``cutoff`` [rad/s], else
    the dataset's ``cutoff_rad_s`` attribute, else the Monte Carlo default
    (:func:`screening.solvers.synthesis.default_cutoff` of each point's block and bed).  Returns a
    Dataset with ``pga_median``, ``rms_acceleration``, ``arias_intensity`` and, with ``period``
    [s], ``sa_median`` (attribute ``period``), on the dimensions of the parameters they depend on.
    """
    from screening.analysis.fragility import parameter
    from screening.model import Block, Foundation
    from screening.solvers.synthesis import default_cutoff

    if "excitation" not in ds.attrs and "excitation" in ds.coords and ds["excitation"].dims == ("case",):
        parts = []                                     # sweep whose cases differ in excitation or envelope
        for i in range(ds.sizes["case"]):
            one = ds.isel(case=i)
            labels = {n: str(one[n].values) for n in ("excitation", "envelope") if n in one.coords}
            parts.append(intensity_measures(one.drop_vars(list(labels)).assign_attrs(**{**ds.attrs, **labels}),
                                            period, damping, cutoff).expand_dims("case"))
        out = xr.concat(parts, "case", combine_attrs="override")
        return out.assign_coords(case=ds["case"])
    kind = ds.attrs.get("excitation")
    envelope_kind = ds.attrs.get("envelope", "exponential")
    if kind not in ("white", "kanai_tajimi"):
        raise ValueError(f"dataset attribute 'excitation' must be 'white' or 'kanai_tajimi' (got {kind!r})")
    t_end = float(ds["t"].values[-1])
    names = ["S0"] + (["omega_g", "zeta_g"] if kind == "kanai_tajimi" else []) + \
        (["T1", "T2"] if envelope_kind == "exponential" else [])
    fields = {n: parameter(ds, n) for n in names}
    if cutoff is None and "cutoff_rad_s" in ds.attrs:
        cutoff = float(ds.attrs["cutoff_rad_s"])
    if cutoff is None:
        bed = {n: parameter(ds, n) for n in ("m", "b", "h", "I_cm", "g", "k") if n in ds.variables}
        cut = xr.apply_ufunc(
            lambda m, b, h, I, g, k: np.vectorize(lambda *a: default_cutoff(
                Block(m=a[0], b=a[1], h=a[2], I_cm=a[3], g=a[4]), Foundation(k=a[5], lam=0.0)))(m, b, h, I, g, k),
            bed["m"], bed["b"], bed["h"], bed["I_cm"], bed["g"], bed["k"])
        cutoff_source = "Monte Carlo default: 3 x max(rocking, vertical frequency) of each point"
    else:
        cut = xr.DataArray(float(cutoff))
        cutoff_source = "given"
    shape_fields = {n: v for n, v in fields.items() if n != "S0"}
    args = xr.broadcast(*(list(shape_fields.values()) + [cut])) if shape_fields else [cut]
    keys = list(shape_fields)
    cache = {}

    def unit(*vals):
        p = dict(zip(keys, vals[:-1]))
        wc = vals[-1]
        key = tuple(float(v) for v in vals)
        if key not in cache:
            exc = _scalar_excitation(kind, envelope_kind, p)
            out = [pga_median(exc, t_end, wc), rms_acceleration(exc, t_end, wc), arias_intensity(exc, t_end, wc)]
            if period is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    out.append(sa_median(exc, period, t_end, damping, wc))
            cache[key] = out
        return cache[key]

    arrays = [np.asarray(a.values, dtype=float) for a in args]
    flat = np.broadcast_arrays(*arrays)
    res = np.array([unit(*vals) for vals in zip(*(f.ravel() for f in flat))]).reshape(flat[0].shape + (-1,))
    dims = args[0].dims
    s0 = fields["S0"]
    out = xr.Dataset()
    scale = {"pga_median": np.sqrt(s0), "rms_acceleration": np.sqrt(s0), "arias_intensity": s0,
             "sa_median": np.sqrt(s0)}
    for i, name in enumerate([n for n in MEASURES if n != "sa_median" or period is not None]):
        out[name] = xr.DataArray(res[..., i], dims=dims) * scale[name]
    out.attrs.update(cutoff_rad_s_source=cutoff_source, t_end=t_end,
                     method="random-vibration theory: Rice rate + Vanmarcke clumping over the modulated record")
    if period is not None:
        out["sa_median"].attrs.update(period=float(period), damping_ratio=float(damping))
    from screening import schema
    for name in MEASURES:
        if name in out:
            out[name].attrs.update(schema.attributes(name, schema.INTENSITY))
    return out


# ----------------------------------------------------------------------------- records
def oscillator_peak(acceleration, dt, period, damping=0.05):
    """``max_t |u|`` [m] of ``u'' + 2 zeta w u' + w^2 u = -a`` from rest, for rows of ``acceleration``
    [m s-2] sampled at ``dt`` [s]: the exact recurrence for piecewise-linear input (Nigam & Jennings 1969)."""
    acc = np.atleast_2d(np.asarray(acceleration, dtype=float))
    w = 2.0 * math.pi / float(period)
    z = float(damping)
    wd = w * math.sqrt(1.0 - z * z)
    e = math.exp(-z * w * dt)
    s, c = math.sin(wd * dt), math.cos(wd * dt)
    r = z / math.sqrt(1.0 - z * z)
    a11, a12 = e * (r * s + c), e * s / wd
    a21, a22 = -w / math.sqrt(1.0 - z * z) * e * s, e * (c - r * s)
    t1, t2 = (2.0 * z * z - 1.0) / (w * w * dt), 2.0 * z / (w**3 * dt)
    b11 = e * ((t1 + z / w) * s / wd + (t2 + 1.0 / w**2) * c) - t2
    b12 = -e * (t1 * s / wd + t2 * c) - 1.0 / w**2 + t2
    b21 = e * ((t1 + z / w) * (c - r * s) - (t2 + 1.0 / w**2) * (wd * s + z * w * c)) + 1.0 / (w * w * dt)
    b22 = -e * (t1 * (c - r * s) - t2 * (wd * s + z * w * c)) - 1.0 / (w * w * dt)
    u = np.zeros(acc.shape[0])
    v = np.zeros(acc.shape[0])
    peak = np.zeros(acc.shape[0])
    for j in range(acc.shape[1] - 1):
        p0, p1 = acc[:, j], acc[:, j + 1]
        u, v = a11 * u + a12 * v + b11 * p0 + b12 * p1, a21 * u + a22 * v + b21 * p0 + b22 * p1
        np.maximum(peak, np.abs(u), out=peak)
    return peak


def record_measures(record, period=None, damping=0.05, g=G):
    """Intensity measures of one :class:`~screening.records.Record`: ``pga`` [m s-2], ``rms_acceleration``
    [m s-2], ``arias_intensity`` [m s-1] and with ``period`` [s] ``sa`` = ``w^2 max|u|`` [m s-2]."""
    a = record.acceleration
    energy = float(np.trapezoid(a * a, dx=record.dt))
    out = {"pga": float(np.max(np.abs(a))), "rms_acceleration": math.sqrt(energy / record.duration),
           "arias_intensity": math.pi / (2.0 * g) * energy}
    if period is not None:
        out["sa"] = (2.0 * math.pi / period) ** 2 * float(oscillator_peak(a, record.dt, period, damping)[0])
    return out
