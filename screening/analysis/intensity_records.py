"""Intensity measures of records: PGA, PGV, Sa, AvgSA, RMS and Arias of accelerograms, and the PGVs of
synthesised records.

:func:`record_measures` reads one :class:`~screening.records.Record`; :func:`oscillator_peak` (exact
recurrence for piecewise-linear input), :func:`record_velocity` (the 0.1 Hz Butterworth high-pass of
record processing, then integration) and :func:`record_avgsa` work on rows of accelerations.
:func:`synthesised_pgv` draws records of a stochastic input exactly as the Monte Carlo does and returns
their PGVs (the median of which is :func:`screening.analysis.intensity.pgv_median`), and
:func:`median_standard_error` the distribution-free standard error of a sample median.

References: Nigam, N. C. & Jennings, P. C. (1969) Calculation of response spectra from strong-motion
earthquake records, Bull. Seismol. Soc. Am. 59(2), 909-922.  Boore, D. M. & Bommer, J. J. (2005)
Processing of strong-motion accelerograms: needs, options and consequences, Soil Dyn. Earthq. Eng. 25,
93-115.  Eads, L., Miranda, E. & Lignos, D. G. (2015) Earthq. Eng. Struct. Dyn. 44, 2057-2073.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan
from screening.validation import checked

__all__ = ["RECORD_MEASURES", "G", "oscillator_peak", "record_measures", "OMEGA_LOW", "AVGSA_N_PERIODS",
           "AVGSA_RANGE", "highpass_gain", "PGV_RECORDS", "PGV_SEED", "PGV_CHUNK", "median_standard_error",
           "synthesised_pgv", "synthesised_peaks", "continuous_peak", "avgsa_periods", "record_velocity",
           "record_avgsa"]


#: Names of the measures of one record (:func:`record_measures`; those of PERIOD_MEASURES only with a period).
RECORD_MEASURES = ("pga", "rms_acceleration", "arias_intensity", "sa", "pgv", "avgsa")


#: Standard gravity used by the Arias intensity [m s-2].
G = 9.80665


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
    [m s-2], ``arias_intensity`` [m s-1], ``pgv`` [m s-1] (:func:`record_velocity`, high-passed at
    :data:`OMEGA_LOW`) and with ``period`` [s] ``sa`` = ``w^2 max|u|`` [m s-2] and ``avgsa`` [m s-2]
    (:func:`record_avgsa`)."""
    a = record.acceleration
    energy = float(np.trapezoid(a * a, dx=record.dt))
    out = {"pga": float(np.max(np.abs(a))), "rms_acceleration": math.sqrt(energy / record.duration),
           "arias_intensity": math.pi / (2.0 * g) * energy}
    if period is not None:
        out["sa"] = (2.0 * math.pi / period) ** 2 * float(oscillator_peak(a, record.dt, period, damping)[0])
        out["avgsa"] = float(record_avgsa(a, record.dt, period, damping)[0])
    out["pgv"] = float(np.max(np.abs(record_velocity(a, record.dt))))
    return out


#: Default low-frequency corner of the velocity [rad/s]: 0.1 Hz, the usual high-pass corner of record processing.
OMEGA_LOW = 2.0 * math.pi * 0.1
#: Number of periods of the average spectral acceleration, and their range as multiples of ``T``.
AVGSA_N_PERIODS = 10
AVGSA_RANGE = (0.2, 1.5)


def highpass_gain(omega, omega_low=OMEGA_LOW):
    """Squared gain ``|H(omega)|^2 = omega^4 / (omega^4 + omega_low^4)`` [1] of the 2nd-order Butterworth
    high-pass with corner ``omega_low`` [rad/s] at ``omega`` [rad/s].

    Notes
    -----
    ``H(s) = s^2 / (s^2 + sqrt(2) omega_low s + omega_low^2)``: the filter applied to the records by
    :func:`record_velocity` and to the spectra by :func:`velocity_spectral_moments`.
    """
    w4 = np.asarray(omega, dtype=float) ** 4
    return w4 / (w4 + float(omega_low) ** 4)


#: Records per excitation shape of the simulated PGA and PGV medians (:func:`simulated_pga`,
#: :func:`simulated_pgv`), and their seed
#: (a fixed run, independent of the Monte Carlo's default seed 0).
PGV_RECORDS = 2000
PGV_SEED = 104_729
#: Records synthesised at a time by :func:`synthesised_pgv` (bounded memory).
PGV_CHUNK = 250


def median_standard_error(x):
    """Distribution-free standard error [units of ``x``] of the sample median of ``x``.

    Notes
    -----
    Half the width of the 95 % order-statistic interval of the median, ``x_(n/2 -+ 1.96 sqrt(n) / 2)``
    (the count of the sample below the true median is binomial(n, 1/2)), divided by 1.96.  For normal
    data it tends to ``sqrt(pi / 2) sigma / sqrt(n)`` = ``1.2533 sigma / sqrt(n)``.

    References
    ----------
    David, H. A. & Nagaraja, H. N. (2003) Order Statistics, 3rd ed., Wiley, section 7.1.
    """
    x = np.sort(np.asarray(x, dtype=float).ravel())
    n = x.size
    half = 1.96 * math.sqrt(n) / 2.0
    lo, hi = int(math.floor(n / 2 - half)), int(math.ceil(n / 2 + half))
    return float(x[min(hi, n - 1)] - x[max(lo, 0)]) / (2.0 * 1.96)


def continuous_peak(acceleration, rate, dt, refine=8):
    """``max_t |a(t)|`` [m s-2] per row of the cubic Hermite interpolant of ``acceleration`` [m s-2] with its
    exact ``rate`` [m s-3] on the grid of step ``dt`` [s], searched at ``refine - 1`` points inside each step.

    Notes
    -----
    ``a(t_k + u dt) = h00(u) a_k + h10(u) dt a'_k + h01(u) a_{k+1} + h11(u) dt a'_{k+1}`` with the Hermite
    basis ``h00 = 2u^3 - 3u^2 + 1``, ``h10 = u^3 - 2u^2 + u``, ``h01 = -2u^3 + 3u^2``, ``h11 = u^3 - u^2``:
    the peak of the continuous record, which the grid maximum underestimates by up to ``1 - cos(omega dt / 2)``.
    """
    acc, rate = np.atleast_2d(np.asarray(acceleration, dtype=float)), np.atleast_2d(np.asarray(rate, dtype=float))
    peak = np.max(np.abs(acc), axis=1)
    a0, a1, d0, d1 = acc[:, :-1], acc[:, 1:], rate[:, :-1] * dt, rate[:, 1:] * dt
    for u in np.linspace(0.0, 1.0, int(refine) + 1)[1:-1]:
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        peak = np.maximum(peak, np.max(np.abs(h00 * a0 + h10 * d0 + h01 * a1 + h11 * d1), axis=1))
    return peak


def synthesised_peaks(excitation, t_end, cutoff, n_records=PGV_RECORDS, seed=PGV_SEED, omega_low=OMEGA_LOW):
    """``(pga [m s-2], pgv [m s-1])``: the peak ground accelerations and velocities of ``n_records`` records of
    the excitation, synthesised exactly as the Monte Carlo synthesises them
    (:mod:`screening.solvers.synthesis`, band limit ``cutoff`` [rad/s], records ``i = 0 .. n_records - 1`` of
    run ``seed``, ``t_end`` [s]), in one pass: the PGA is the continuous peak (:func:`continuous_peak`), the
    PGV ``max_t |v|`` on the synthesis grid of the velocity high-passed at ``omega_low`` [rad/s] by
    :func:`record_velocity`."""
    plan = spectral_plan(excitation, float(t_end), float(cutoff))
    n = int(round(float(t_end) / plan.dt)) + 1
    pga, pgv = [], []
    for lo in range(0, int(n_records), PGV_CHUNK):
        acc, rate = ground_acceleration_samples(excitation, plan, seed, np.arange(lo, min(lo + PGV_CHUNK, n_records)))
        acc, rate = acc[:, :n], rate[:, :n]
        pga.append(continuous_peak(acc, rate, plan.dt))
        pgv.append(np.max(np.abs(record_velocity(acc, plan.dt, omega_low)), axis=1))
    return np.concatenate(pga), np.concatenate(pgv)


def synthesised_pgv(excitation, t_end, cutoff, n_records=PGV_RECORDS, seed=PGV_SEED, omega_low=OMEGA_LOW):
    """Peak ground velocities [m s-1] of :func:`synthesised_peaks` (same arguments)."""
    return synthesised_peaks(excitation, t_end, cutoff, n_records, seed, omega_low)[1]


def avgsa_periods(period, n=AVGSA_N_PERIODS, span=AVGSA_RANGE):
    """The ``n`` periods [s] of the average spectral acceleration at ``period`` [s]: log-spaced over
    ``[0.2 period, 1.5 period]`` (OpenQuake's ``AvgSA``)."""
    return np.geomspace(span[0] * float(period), span[1] * float(period), int(n))


def record_velocity(acceleration, dt, omega_low=OMEGA_LOW):
    """Ground velocity [m s-1] of rows of ``acceleration`` [m s-2] sampled at ``dt`` [s]: causal 2nd-order
    Butterworth high-pass at ``omega_low`` [rad/s] (bilinear transform with pre-warped corner), then
    trapezoidal integration from ``v(0) = 0``.

    Notes
    -----
    ``v(t) = int_0^t a_hp dt'``, ``a_hp = H * a`` with ``H(s) = s^2 / (s^2 + sqrt(2) omega_low s +
    omega_low^2)`` (:func:`highpass_gain`), the filter of :func:`pgv_median`.
    """
    from scipy import signal
    checked("omega_low", omega_low, lower=0.0, upper=math.pi / float(dt))
    acc = np.atleast_2d(np.asarray(acceleration, dtype=float))
    sos = signal.butter(2, float(omega_low) / (2.0 * math.pi), btype="highpass", fs=1.0 / float(dt), output="sos")
    return integrate.cumulative_trapezoid(signal.sosfilt(sos, acc, axis=-1), dx=float(dt), axis=-1, initial=0.0)


def record_avgsa(acceleration, dt, period, damping=0.05):
    """Average spectral acceleration [m s-2] of rows of ``acceleration`` [m s-2] at ``period`` [s]: the
    geometric mean of ``w_i^2 max|u_i|`` (:func:`oscillator_peak`) over :func:`avgsa_periods`."""
    logs = [np.log((2.0 * math.pi / p) ** 2 * oscillator_peak(acceleration, dt, p, damping))
            for p in avgsa_periods(period)]
    return np.exp(np.mean(logs, axis=0))
