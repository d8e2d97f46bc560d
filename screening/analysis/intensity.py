"""Intensity measures of the stochastic inputs by random-vibration theory (RVT).

A study point's ground acceleration is ``a(t) = q(t) f(t)``: the envelope ``q`` times a zero-mean
stationary Gaussian process of two-sided PSD ``S(omega)`` over ``|omega| <= omega_c``, the excitation's
band (:meth:`~screening.core.excitations.Excitation.reference_cutoff`), so the same nominal PGA is the
same ground motion whatever the block.  The measures: ``rms_acceleration`` [m s-2], ``arias_intensity``
[m s-1] (expected values), ``pga_median`` and ``pgv_median`` (medians of :data:`PGV_RECORDS` records
synthesised per excitation shape; ``method="rvt"``: first passage), ``sa_median`` [m s-2] (first passage
of the oscillator's Lyapunov covariance with Vanmarcke's clumping [vanmarcke1975]) and ``avgsa_median``.
Every measure goes as ``sqrt(S0)`` (Arias: ``S0``), so :func:`s0_for_pga` inverts a PGA exactly.  The
peak factors are in :mod:`screening.analysis.intensity_rvt`, the measures of records in
:mod:`screening.analysis.intensity_records`.  Definitions, limits and measured accuracy:
``docs/intensity_measures.md``.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import xarray as xr

from screening.analysis import intensity_rvt
from screening.analysis._excitation_shape import (distinct_points as _distinct_points,
                                                  scalar_excitation as _scalar_excitation, shape_key as _shape_key,
                                                  shape_names as _shape_names, times as _times)
from screening.analysis.fragility import parameter
from screening.analysis.intensity_records import (AVGSA_N_PERIODS, avgsa_periods, AVGSA_RANGE, continuous_peak, G,
                                                  highpass_gain, median_standard_error, OMEGA_LOW, oscillator_peak,
                                                  PGV_CHUNK, PGV_RECORDS, PGV_SEED, record_avgsa, RECORD_MEASURES,
                                                  record_measures, record_velocity, synthesised_peaks, synthesised_pgv)
from screening.analysis.intensity_rvt import (CHUNK_POINTS, CROSSING_EXTENT, CROSSING_STEP, envelope_exponentials,
                                              input_moments, median_peak, N_TIMES, oscillator_covariance,
                                              oscillator_response_bandwidth, rocking_start_probability, sa_median,
                                              spectral_moments, velocity_covariance, velocity_spectral_moments)
from screening.core import excitations
from screening.core.excitations.base import band_top, GROUND_BAND_LIMIT_HZ, ground_cutoff
from screening.core.validation import checked
from screening.solvers import schema

__all__ = ["MEASURES", "RECORD_MEASURES", "PERIOD_MEASURES", "ground_cutoff", "spectral_moments",
           "rms_acceleration", "arias_intensity", "median_peak", "input_moments", "pga_median",
           "rocking_start_probability", "oscillator_covariance", "sa_median", "s0_for_pga", "input_measures",
           "intensity_measures", "oscillator_peak", "record_measures", "highpass_gain", "velocity_spectral_moments",
           "envelope_exponentials", "velocity_covariance", "pgv_median", "median_standard_error", "synthesised_pgv",
           "simulated_pgv", "synthesised_peaks", "continuous_peak", "simulated_pga", "avgsa_periods",
           "avgsa_median", "record_velocity", "record_avgsa", "oscillator_response_bandwidth"]

#: Names of the measures (data variables of :func:`intensity_measures`) and their units.
MEASURES = {"pga_median": "m s-2", "rms_acceleration": "m s-2", "arias_intensity": "m s-1", "sa_median": "m s-2",
            "pgv_median": "m s-1", "avgsa_median": "m s-2"}


#: The measures that need an oscillator period (input and record names).
PERIOD_MEASURES = ("sa_median", "avgsa_median", "sa", "avgsa")


def rms_acceleration(excitation, t_end, cutoff):
    """Root mean square of the modulated, band-limited ground acceleration over ``[0, t_end]``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope.
    t_end, cutoff : float
        Record length [s] and band limit of the ground motion [rad s-1].

    Returns
    -------
    float
        ``a_rms`` [m s-2] (ensemble mean of the time average of ``a^2``, square-rooted).

    Notes
    -----
    ``a_rms = sqrt(lambda_0 int_0^T q^2 dt / T)`` with the spectral moment ``lambda_0`` of
    :func:`spectral_moments` and the envelope ``q`` of eq. (57) in [1]; the ground acceleration of
    eq. (56) in [1], band-limited as in [2].

    References
    ----------
    [1] [mitseas2026]; [2] D. M. Boore, "Simulation of ground motion using the stochastic method", Pure Appl.
    Geophys. 160 (2003) 635-676.

    Examples
    --------
    Stationary white noise band-limited to 50 rad/s: ``sqrt(2 S0 omega_c)``.

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> rms_acceleration(white, 10.0, 50.0), (2 * 0.01 * 50.0) ** 0.5
    (1.0, 1.0)
    """
    lam0 = spectral_moments(excitation, cutoff)[0]
    t = _times(t_end)
    return math.sqrt(lam0 * np.trapezoid(excitation.envelope(t) ** 2, t) / float(t_end))


def arias_intensity(excitation, t_end, cutoff, g=G):
    """Expected Arias intensity ``pi/(2 g) E[int_0^T a^2 dt]`` of the modulated, band-limited input.

    Parameters
    ----------
    excitation, t_end, cutoff
        As in :func:`rms_acceleration`.
    g : float, default G
        Standard gravity [m s-2].

    Returns
    -------
    float
        ``E[I_A]`` [m s-1].

    Notes
    -----
    ``E[I_A] = pi lambda_0 int_0^T q^2 dt / (2 g)`` [1] with the spectral moment ``lambda_0`` of
    :func:`spectral_moments` and the envelope ``q`` of eq. (57) in [2].

    References
    ----------
    [1] [arias1970]; [2] [mitseas2026].

    Examples
    --------
    The same noise over 10 s, against ``pi / (2 g) lambda_0 T``:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> import math
    >>> f"{arias_intensity(white, 10.0, 50.0):.6f}", f"{math.pi / (2 * G) * 1.0 * 10.0:.6f}"
    ('1.601766', '1.601766')
    """
    lam0 = spectral_moments(excitation, cutoff)[0]
    t = _times(t_end)
    return math.pi / (2.0 * g) * lam0 * np.trapezoid(excitation.envelope(t) ** 2, t)


def s0_for_pga(excitation, target_pga, t_end, cutoff):
    """The intensity ``S0`` that gives a target median PGA for the shape of an excitation.

    The shape is the excitation's filter and envelope; its own ``S0`` is irrelevant.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation with its envelope (filter fields may be arrays).
    target_pga : float or array_like
        The median PGA [m s-2].
    t_end, cutoff
        As in :func:`rms_acceleration`.

    Returns
    -------
    float or numpy.ndarray
        ``S0`` [m2 s-3] (NaN where the measures are beyond float64).

    Notes
    -----

    PGA is proportional to ``sqrt(S0)``: ``S0 = (target_pga / pga_1)^2`` with ``pga_1`` the median PGA
    at ``S0 = 1`` of :func:`pga_median` (simulated: the median of the :data:`PGV_RECORDS` records of
    :func:`simulated_pga`, which scale exactly as ``sqrt(S0)``), so a point built from ``target_pga`` has
    ``pga_median`` equal to it to rounding.  ``target_pga``, ``cutoff`` and the excitation's ``omega_g``,
    ``zeta_g`` may be arrays (broadcast together); :func:`pga_median` runs once per distinct filter and band limit.
    ``S0`` is the level of the input's PSD, eq. (56) in [1].

    References
    ----------
    [1] [mitseas2026]; [2] [shinozuka1991].

    Examples
    --------
    The ``S0`` found gives back the target PGA of 1 m s-2:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> s0 = s0_for_pga(white, 1.0, 2.0, 20.0)
    >>> f"{s0:.6f}", f"{pga_median(WhiteNoise(s0, white.envelope, band_limit_hz=None), 2.0, 20.0):.6f}"
    ('0.004518', '1.000000')
    """
    target, unit = _per_unit_s0(excitation, target_pga, t_end, cutoff)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):     # NaN / inf: not derivable
        out = (target / unit[..., 0]) ** 2
    return float(out) if out.ndim == 0 else out


def input_measures(excitation, t_end, cutoff):
    """The PGA, RMS acceleration and Arias intensity of every point of an excitation.

    Computed once per distinct filter and band limit at ``S0 = 1`` and scaled: the first two are
    proportional to ``sqrt(S0)``, the Arias intensity to ``S0``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation with its envelope; ``S0`` and filter fields may be arrays.
    t_end : float
        Record length [s].
    cutoff : float or array_like
        Band limit of the ground motion [rad s-1] (broadcast with the fields).

    Returns
    -------
    dict of str to numpy.ndarray
        ``pga_median`` [m s-2] (:func:`pga_median`), ``rms_acceleration`` [m s-2]
        (:func:`rms_acceleration`) and ``arias_intensity`` [m s-1] (:func:`arias_intensity`).

    References
    ----------
    [1] [arias1970]; [2] [shinozuka1991].

    Examples
    --------
    All three at once:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> m = input_measures(white, 2.0, 20.0)
    >>> f"{m['rms_acceleration']:.6f}", f"{(2 * 0.01 * 20.0) ** 0.5:.6f}", bool(m["pga_median"] == pga_median(white, 2.0, 20.0))
    ('0.632456', '0.632456', True)
    """
    s0, unit = _per_unit_s0(excitation, excitation.S0, t_end, cutoff)
    root = np.sqrt(s0)
    return {"pga_median": root * unit[..., 0], "rms_acceleration": root * unit[..., 1],
            "arias_intensity": s0 * unit[..., 2]}


def _per_unit_s0(excitation, values, t_end, cutoff):
    """``values`` broadcast with the filter and ``cutoff``, and the measures at ``S0 = 1`` (last axis:
    pga, rms, arias) of every point."""
    names = _shape_names(excitation)
    values, cut, *filt = np.broadcast_arrays(np.asarray(values, dtype=float), np.asarray(cutoff, dtype=float),
                                             *(np.asarray(getattr(excitation, n), dtype=float) for n in names))
    env = excitation.envelope
    shape = (excitation.kind, env.kind, names, *(np.atleast_1d(env.params[1:]).astype(float).tolist()
                                                 if env.kind == "exponential" else ()), float(t_end))
    unit = np.empty(values.shape + (3,))
    flat = unit.reshape(-1, 3)
    for (*point, wc), rows in _distinct_points([*filt, cut], values.shape):
        try:
            flat[rows] = _unit_measures(*shape, tuple(point), wc)
        except (ArithmeticError, ValueError):          # scales beyond float64 (see PointStatus.beyond_float_range)
            flat[rows] = np.nan
    return values, unit


@functools.lru_cache(maxsize=4096)
def _unit_measures(kind, envelope_kind, names, *args):
    """``(pga_median, rms_acceleration, arias_intensity)`` at ``S0 = 1`` of one filter (parameters
    ``names`` with ``values``), envelope, ``t_end`` and band limit."""
    *envelope, t_end, values, cutoff = args
    p = {**dict(zip(names, values)), **dict(zip(("T1", "T2"), envelope))}
    exc = _scalar_excitation(kind, envelope_kind, p)
    return (pga_median(exc, t_end, cutoff), rms_acceleration(exc, t_end, cutoff),
            arias_intensity(exc, t_end, cutoff))


def intensity_measures(ds, period=None, damping=0.05, cutoff=None):
    """RVT intensity measures of the input of every point of a result dataset (sweep or linearize).

    The band limit: ``cutoff`` [rad/s], else the dataset's ``cutoff_rad_s`` attribute, else its
    ``band_limit_hz`` coordinate (NaN or absent: the idealized spectrum to :data:`GROUND_BAND_LIMIT_HZ`):
    never the block's or bed's.

    Parameters
    ----------
    ds : xarray.Dataset
        A result dataset (sweep or :func:`screening.linearize`) with the coordinates ``S0`` [m2 s-3],
        the filter's parameters, ``T1``, ``T2`` [s] (exponential envelope), ``t`` [s] and the attributes
        ``excitation`` and ``envelope``; a sweep whose cases differ in excitation is measured case by case.
    period : float, optional
        Oscillator period of ``sa_median`` and ``avgsa_median`` [s] (``None``: neither).
    damping : float, default 0.05
        Oscillator damping ratio [1].
    cutoff : float, optional
        Band limit [rad s-1] (see above).

    Returns
    -------
    xarray.Dataset
        ``pga_median`` [m s-2], ``rms_acceleration`` [m s-2], ``arias_intensity`` [m s-1],
        ``pgv_median`` [m s-1] and, with ``period``, ``sa_median`` and ``avgsa_median`` [m s-2].

    Notes
    -----
    Every measure is proportional to ``sqrt(S0)`` (Arias: to ``S0``): each distinct filter, envelope
    and band limit is measured once.  The measures and their accuracy: the module docstring and
    ``docs/intensity_measures.md``.

    References
    ----------
    [1] [arias1970]; [2] [vanmarcke1975]; [3] [shinozuka1991].

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> ds = xr.Dataset(coords={"S0": [0.01, 0.04], "t": np.linspace(0.0, 2.0, 5)},
    ...                 attrs={"excitation": "white", "envelope": "constant", "cutoff_rad_s": 20.0})
    >>> im = intensity_measures(ds)
    >>> sorted(im.data_vars), im["pga_median"].attrs["units"]
    (['arias_intensity', 'pga_median', 'pgv_median', 'rms_acceleration'], 'm s-2')
    >>> (im["pga_median"][1] / im["pga_median"][0]).item(), (im["arias_intensity"][1] / im["arias_intensity"][0]).item()
    (2.0, 4.0)
    """
    if "excitation" not in ds.attrs and "excitation" in ds.coords and ds["excitation"].dims == ("case",):
        parts = []                                     # sweep whose cases differ in excitation or envelope
        for i in range(ds.sizes["case"]):
            one = ds.isel(case=i)
            labels = {n: str(one[n].values) for n in ("excitation", "envelope") if n in one.coords}
            parts.append(intensity_measures(one.drop_vars(list(labels)).assign_attrs(**{**ds.attrs, **labels}),
                                            period, damping, cutoff).expand_dims("case"))
        out = xr.concat(parts, "case", coords="different", compat="equals", join="outer", combine_attrs="override")
        return out.assign_coords(case=ds["case"])

    kind = ds.attrs.get("excitation")
    envelope_kind = ds.attrs.get("envelope", "exponential")
    if kind not in excitations.names():
        raise ValueError(f"dataset attribute 'excitation' must be one of {excitations.names()} (got {kind!r})")
    t_end = float(ds["t"].values[-1])
    names = ["S0"] + list(excitations.get(kind).parameters) + \
        (["T1", "T2"] if envelope_kind == "exponential" else [])
    banded = "band_limit_hz" in ds.coords              # the excitation's band (NaN in a case without one)
    if banded:
        names.append("band_limit_hz")
    fields = {n: parameter(ds, n) for n in names}
    cutoff_source = "given"
    if cutoff is None and "cutoff_rad_s" in ds.attrs:
        cutoff = float(ds.attrs["cutoff_rad_s"])
    if cutoff is None:
        hz = float(ds.attrs.get("band_limit_hz", GROUND_BAND_LIMIT_HZ))      # files written before the band
        cutoff = ground_cutoff(hz)
        cutoff_source = (f"the excitation's band_limit_hz (its low-pass, to {band_top(1.0):.3g} x the corner); "
                         f"without one, {hz:g} Hz" if banded else
                         f"the ground motion's, {hz:g} Hz" + ("" if "band_limit_hz" in ds.attrs else " (default)"))
    cut = xr.DataArray(float(cutoff))
    shape_fields = {n: v for n, v in fields.items() if n != "S0"}
    args = xr.broadcast(*(list(shape_fields.values()) + [cut])) if shape_fields else [cut]
    keys = list(shape_fields)
    cache = {}
    given = cutoff_source == "given" or "cutoff_rad_s" in ds.attrs

    def unit(*vals):
        p = dict(zip(keys, vals[:-1]))
        wc = vals[-1]
        band = p.get("band_limit_hz", math.nan)
        if math.isfinite(band) and not given:          # a band-limited input: its spectrum to the band's top
            wc = band_top(band)
        key = tuple(float(v) for v in vals)
        if key not in cache:
            exc = _scalar_excitation(kind, envelope_kind, p)
            out = [pga_median(exc, t_end, wc), rms_acceleration(exc, t_end, wc), arias_intensity(exc, t_end, wc)]
            if period is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    out.append(sa_median(exc, period, t_end, damping, wc))
                    out.append(avgsa_median(exc, period, t_end, damping, wc))
            out.append(pgv_median(exc, t_end, wc))
            cache[key] = out
        return cache[key]

    arrays = [np.asarray(a.values, dtype=float) for a in args]
    flat = np.broadcast_arrays(*arrays)
    res = np.array([unit(*vals) for vals in zip(*(f.ravel() for f in flat))]).reshape(flat[0].shape + (-1,))
    dims = args[0].dims
    s0 = fields["S0"]
    out = xr.Dataset()
    scale = {name: s0 if name == "arias_intensity" else np.sqrt(s0) for name in MEASURES}
    order = ["pga_median", "rms_acceleration", "arias_intensity"] + \
        (["sa_median", "avgsa_median"] if period is not None else []) + ["pgv_median"]
    for i, name in enumerate(order):
        out[name] = xr.DataArray(res[..., i], dims=dims) * scale[name]
    out.attrs.update(cutoff_rad_s_source=cutoff_source, t_end=t_end,
                     method="random-vibration theory: Rice rate over the modulated record "
                            "(Vanmarcke clumping for Sa); PGA and PGV: medians of synthesised records")
    if period is not None:
        out["sa_median"].attrs.update(period=float(period), damping_ratio=float(damping))
        out["avgsa_median"].attrs.update(period=float(period), damping_ratio=float(damping),
                                         periods=avgsa_periods(period))
    out["pga_median"].attrs.update(method=f"median of {PGV_RECORDS} synthesised records per excitation shape, "
                                   f"seed {PGV_SEED} (simulated_pga)")
    out["pgv_median"].attrs.update(omega_low=OMEGA_LOW, method=f"median of {PGV_RECORDS} synthesised records per "
                                   f"excitation shape, seed {PGV_SEED} (simulated_pgv)")
    for name in MEASURES:
        if name in out:
            out[name].attrs.update(schema.attributes(name, schema.INTENSITY))
    return out


def simulated_pgv(excitation, t_end, cutoff, omega_low=OMEGA_LOW, n_records=PGV_RECORDS, seed=PGV_SEED):
    """Median peak ground velocity [m s-1] of the excitation's records and its standard error [m s-1].

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields; envelope exponential or constant).
    t_end : float
        Record length [s].
    cutoff : float
        Band limit of the ground motion [rad s-1].
    omega_low : float
        Corner of the 2nd-order Butterworth high-pass [rad s-1] (default :data:`OMEGA_LOW`, 0.1 Hz).
    n_records : int
        Records synthesised per excitation shape (default :data:`PGV_RECORDS`).
    seed : int
        Seed of the synthesis (default :data:`PGV_SEED`).

    Returns
    -------
    (float, float)
        Sample median of :func:`synthesised_pgv` and its :func:`median_standard_error` [m s-1].

    Notes
    -----
    The velocity, like every measure of a Gaussian input, is proportional to ``sqrt(S0)``: the records
    are synthesised once per shape (filter parameters, envelope, ``t_end``, band limit, ``omega_low``,
    ``n_records``, ``seed``) at ``S0 = 1``, cached, and scaled.  A fixed seed makes the result
    reproducible; with 2,000 records its standard error is ~0.6 % of the median.  Records by spectral
    representation [1], high-passed as in record processing [2].

    References
    ----------
    [1] [shinozuka1991]; [2] [boore2005].

    Examples
    --------
    The median scales as ``sqrt(S0)`` (100 records, for speed):

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> pgv, se = simulated_pgv(white, 2.0, 20.0, n_records=100)
    >>> pgv4, _ = simulated_pgv(WhiteNoise(0.04, white.envelope, band_limit_hz=None), 2.0, 20.0, n_records=100)
    >>> f"{pgv4 / pgv:.6f}", bool(0 < se < 0.1 * pgv)
    ('2.000000', True)
    """
    return _simulated(excitation, t_end, cutoff, omega_low, n_records, seed)[2:]


def simulated_pga(excitation, t_end, cutoff, n_records=PGV_RECORDS, seed=PGV_SEED):
    """Median peak ground acceleration [m s-2] of the excitation's records and its standard error [m s-2].

    Parameters
    ----------
    excitation, t_end, cutoff, n_records, seed
        As in :func:`simulated_pgv`; the acceleration is not high-passed.

    Returns
    -------
    (float, float)
        Sample median of the continuous peaks ``max_t |a(t)|`` of :func:`synthesised_peaks` and its
        :func:`median_standard_error` [m s-2].

    Notes
    -----
    The same records as :func:`simulated_pgv` (without their velocities): synthesised once per shape
    at ``S0 = 1`` and scaled by ``sqrt(S0)``.  The peak is that of the continuous record (cubic Hermite
    interpolant of the synthesised values and rates, :func:`continuous_peak`).  With 2,000 records the
    standard error is ~0.5 % of the median.  Records by spectral representation [1].

    References
    ----------
    [1] [shinozuka1991].

    Examples
    --------
    So does the PGA's, and so does its standard error:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> pga, se = simulated_pga(white, 2.0, 20.0, n_records=100)
    >>> pga4, se4 = simulated_pga(WhiteNoise(0.04, white.envelope, band_limit_hz=None), 2.0, 20.0, n_records=100)
    >>> f"{pga4 / pga:.6f}", f"{se4 / se:.6f}"
    ('2.000000', '2.000000')
    """
    return _simulated(excitation, t_end, cutoff, None, n_records, seed)[:2]       # no velocity needed


def _simulated(excitation, t_end, cutoff, omega_low, n_records, seed):
    """``(pga median, its standard error, pgv median, its standard error)`` of the shape of ``excitation``
    scaled to its ``S0``; ``omega_low = None``: the PGA alone (the PGV NaN)."""
    if omega_low is not None:
        omega_low = float(checked("omega_low", omega_low, lower=0.0, upper=float(cutoff)))
    checked("n_records", n_records, lower=10.0, upper=1e7, lower_inclusive=True)
    names = _shape_names(excitation)
    key = (*_shape_key(excitation, t_end), names, tuple(float(getattr(excitation, k)) for k in names),
           float(cutoff), omega_low, int(n_records), int(seed))
    root = math.sqrt(float(excitation.S0))
    return tuple(root * v for v in _unit_simulated(*key))


@functools.lru_cache(maxsize=256)
def _unit_simulated(kind, envelope_kind, *args):
    """``(pga median, standard error, pgv median, standard error)`` at ``S0 = 1`` of one shape (one synthesis)."""
    *envelope, t_end, names, values, cutoff, omega_low, n_records, seed = args
    p = {**dict(zip(names, values)), **dict(zip(("T1", "T2"), envelope))}
    pga, pgv = synthesised_peaks(_scalar_excitation(kind, envelope_kind, p), t_end, cutoff, n_records, seed,
                                 omega_low)
    if pgv is None:
        return float(np.median(pga)), median_standard_error(pga), math.nan, math.nan
    return (float(np.median(pga)), median_standard_error(pga), float(np.median(pgv)), median_standard_error(pgv))


def pga_median(excitation, t_end, cutoff, method="simulated"):
    """Median peak ground acceleration [m s-2] of the modulated, band-limited input.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        The study's excitation (scalar fields; envelope exponential or constant).
    t_end : float
        Record length [s].
    cutoff : float
        Band limit of the input [rad/s].
    method : str
        ``"simulated"`` (default): the median of the :data:`PGV_RECORDS` records per excitation shape of
        :func:`simulated_pga` (the records of :func:`simulated_pgv`); ``"rvt"``: the first-passage
        median of :func:`screening.analysis.intensity_rvt.pga_median` (Rice's rate, crossings
        independent; kept for comparison).

    Returns
    -------
    float
        Median of ``max_t |a(t)|`` [m s-2], by ``method``.

    Notes
    -----
    Simulated because the RVT median is +3 % high on soft soil, where crossings clump
    (``docs/intensity_measures.md``); the simulated one is exact to its sampling error (~0.5 %).  A
    study's ``pga`` label (:func:`s0_for_pga`) inverts this same median.

    References
    ----------
    [1] [shinozuka1991]; [2] [vanmarcke1975].

    Examples
    --------
    The default method is the simulated median:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> pga = pga_median(white, 2.0, 20.0)
    >>> f"{pga:.4f}", pga == simulated_pga(white, 2.0, 20.0)[0]
    ('1.4877', True)
    """
    if method not in ("simulated", "rvt"):
        raise ValueError(f"parameter 'method' must be 'simulated' or 'rvt' (got {method!r})")
    if method == "simulated":
        return simulated_pga(excitation, t_end, cutoff)[0]
    return intensity_rvt.pga_median(excitation, t_end, cutoff)


def pgv_median(excitation, t_end, cutoff, omega_low=OMEGA_LOW, method="simulated"):
    """Median peak ground velocity [m s-1] of the modulated input, high-passed at ``omega_low``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        The study's excitation (``psd(omega)`` [m2 s-3], any spectrum; ``envelope`` exponential or
        constant).
    t_end : float
        Record length [s].
    cutoff : float
        Band limit of the input [rad/s].
    omega_low : float
        High-pass corner [rad/s] (default :data:`OMEGA_LOW`, 2 pi 0.1 Hz).
    method : str
        ``"simulated"`` (default): the median of :data:`PGV_RECORDS` synthesised records per excitation
        shape (:func:`simulated_pgv`); ``"rvt"``: the first-passage estimate below (biased, kept for
        comparison).

    Returns
    -------
    float
        Median of ``max_t |v(t)|`` [m s-1].

    Notes
    -----
    Simulated because no peak-factor model of the velocity's spectral moments holds (its period is about
    the strong-motion duration, and its ``1/omega^2`` tail makes crossings clump): the RVT median
    (``"rvt"``: :func:`velocity_covariance`, Rice's rate with Vanmarcke's clumping) was 4-11 % off.  The
    high-pass is stated, not optional: the velocity of white or Kanai-Tajimi acceleration has unbounded
    variance at low frequency; the same causal 2nd-order Butterworth filter is applied to records by
    :func:`record_velocity`, so the two PGVs compare.  ``docs/intensity_measures.md``.

    References
    ----------
    [1] [vanmarcke1975]; [2] [priestley1965]; [3] [boore2005]; [4] [shinozuka1991].

    Examples
    --------
    The default, simulated median of the high-passed velocity, against :func:`simulated_pgv`:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> pgv = pgv_median(white, 2.0, 20.0)
    >>> round(pgv, 4), pgv == simulated_pgv(white, 2.0, 20.0)[0]
    (0.2809, True)
    """
    if method not in ("simulated", "rvt"):
        raise ValueError(f"parameter 'method' must be 'simulated' or 'rvt' (got {method!r})")
    checked("omega_low", omega_low, lower=0.0, upper=float(cutoff))
    if method == "simulated":
        return simulated_pgv(excitation, t_end, cutoff, omega_low)[0]
    mu0, mu1, mu2 = velocity_spectral_moments(excitation, cutoff, omega_low)
    t, var_v, var_a, cov = velocity_covariance(excitation, t_end, cutoff, omega_low)
    delta = math.sqrt(max(1.0 - mu1**2 / (mu0 * mu2), 0.0))
    return median_peak(t, var_v, var_a, cov, delta)


def avgsa_median(excitation, period, t_end, damping=0.05, cutoff=None):
    """Median average spectral acceleration [m s-2] at ``period`` [s].

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        The study's excitation.
    period : float
        Central period ``T`` [s].
    t_end : float
        Record length [s].
    damping : float
        Oscillator damping ratio [1] (default 0.05).
    cutoff : float, optional
        Band limit [rad/s] of the input (the bandwidth of the oscillator responses and the warning of
        :func:`sa_median`; ``None``: unbounded).

    Returns
    -------
    float
        ``(prod_i Sa_med(T_i))^(1/n)`` [m s-2] over :func:`avgsa_periods`.

    Notes
    -----
    ``AvgSA = (prod_{i=1}^{n} Sa(T_i))^(1/n)``, ``T_i`` log-spaced in ``[0.2 T, 1.5 T]``, ``n = 10``
    (Eads et al. 2015; OpenQuake's ``AvgSA``).  Its median is taken as the geometric mean of the
    medians of :func:`sa_median`.  This is exact when the ``ln Sa(T_i)`` are jointly normal, whatever
    their correlation: ``ln AvgSA`` is then normal with mean = median = the mean of the
    ``ln Sa_med(T_i)``.  The peaks are not exactly lognormal (their logarithms are skewed, Gumbel-like),
    which is the only error of the approximation; it is checked against synthesised records.

    References
    ----------
    [1] [eads2015].

    Examples
    --------
    A short stationary record (ten Lyapunov integrations: about a second):

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> f"{avgsa_median(white, 2.0, 0.3, damping=0.2):.4f}"
    '0.2397'
    """
    logs = [math.log(sa_median(excitation, p, t_end, damping, cutoff)) for p in avgsa_periods(period)]
    return math.exp(sum(logs) / len(logs))
