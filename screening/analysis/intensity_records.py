"""Intensity measures of records (PGA, PGV, Sa, AvgSA, RMS, Arias) and the PGVs of synthesised records.

:func:`record_measures` reads one :class:`~screening.core.records.Record`; :func:`oscillator_peak` (exact
recurrence for piecewise-linear input [nigam1969]), :func:`record_velocity` (0.1 Hz Butterworth high-pass,
then integration [boore2005]) and :func:`record_avgsa` [eads2015] work on rows of accelerations;
:func:`synthesised_pgv` draws records exactly as the Monte Carlo does.  ``docs/intensity_measures.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan
from screening.core.validation import checked

__all__ = ["RECORD_MEASURES", "oscillator_peak", "record_measures", "highpass_gain", "median_standard_error",
           "synthesised_pgv", "synthesised_peaks", "continuous_peak", "avgsa_periods", "record_velocity",
           "record_avgsa"]


#: Names of the measures of one record (:func:`record_measures`; those of PERIOD_MEASURES only with a period).
RECORD_MEASURES = ("pga", "rms_acceleration", "arias_intensity", "sa", "pgv", "avgsa")


#: Standard gravity used by the Arias intensity [m s-2].
G = 9.80665


def oscillator_peak(acceleration, dt, period, damping=0.05):
    """Peak displacement of a linear oscillator driven by rows of sampled ground accelerations.

    Parameters
    ----------
    acceleration : array_like
        Ground accelerations [m s-2], one record per row (or one record).
    dt : float
        Time step [s].
    period : float
        Natural period ``2 pi / w`` [s].
    damping : float, default 0.05
        Damping ratio ``zeta`` [1], in ``[0, 1)``.

    Returns
    -------
    numpy.ndarray
        ``max_t |u|`` [m] per row.

    Notes
    -----
    ``u'' + 2 zeta w u' + w^2 u = -a`` from rest, stepped by the exact recurrence for piecewise-linear
    input [1]; the peak is taken on the samples.

    References
    ----------
    [1] [nigam1969].

    Examples
    --------
    An undamped oscillator under a constant unit acceleration peaks at ``2 / w^2``:

    >>> import math, numpy as np
    >>> t = np.arange(0.0, 10.0001, 0.01)
    >>> oscillator_peak(np.ones_like(t), 0.01, 2 * math.pi, damping=0.0).round(5)     # w = 1 rad/s
    array([2.])
    """
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
    """Intensity measures of one accelerogram.

    Parameters
    ----------
    record : screening.core.records.Record
        The record (``acceleration`` [m s-2], ``dt`` [s]).
    period : float, optional
        Oscillator period [s] of ``sa`` and ``avgsa`` (``None``: neither).
    damping : float, default 0.05
        Oscillator damping ratio [1].
    g : float, default G
        Standard gravity of the Arias intensity [m s-2].

    Returns
    -------
    dict of str to float
        ``pga`` [m s-2], ``rms_acceleration`` [m s-2], ``arias_intensity`` [m s-1], ``pgv`` [m s-1]
        (:func:`record_velocity`, high-passed at :data:`OMEGA_LOW`) and with ``period`` ``sa`` =
        ``w^2 max|u|`` [m s-2] and ``avgsa`` [m s-2] (:func:`record_avgsa`).

    Notes
    -----
    ``rms = sqrt(int a^2 dt / T)``, Arias ``I_A = pi / (2 g) int a^2 dt`` [1] (trapezoidal rule);
    ``sa`` by :func:`oscillator_peak` [2]; ``avgsa`` as in [3].

    References
    ----------
    [1] [arias1970]; [2] [nigam1969]; [3] [eads2015].

    Examples
    --------
    Ten seconds of a 1 Hz sine of unit amplitude:

    >>> import math, numpy as np
    >>> from screening.core.records import Record
    >>> t = np.arange(0.0, 10.0001, 0.01)
    >>> m = record_measures(Record(np.sin(2 * math.pi * t), 0.01, "sine"))
    >>> m["pga"], f"{m['rms_acceleration']:.6f}", f"{m['arias_intensity']:.6f}", f"{math.pi / (2 * G) * 5.0:.6f}"
    (1.0, '0.707107', '0.800883', '0.800883')
    """
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
    """Squared gain ``|H(omega)|^2 = omega^4 / (omega^4 + omega_low^4)`` of the 2nd-order Butterworth high-pass.

    Parameters
    ----------
    omega : array_like
        Angular frequencies [rad s-1].
    omega_low : float, default OMEGA_LOW
        Corner [rad s-1].

    Returns
    -------
    numpy.ndarray
        ``|H(omega)|^2`` [1].

    Notes
    -----
    ``H(s) = s^2 / (s^2 + sqrt(2) omega_low s + omega_low^2)``: the filter applied to the records by
    :func:`record_velocity` and to the spectra by :func:`velocity_spectral_moments`; the usual
    high-pass of record processing [1].

    References
    ----------
    [1] [boore2005].

    Examples
    --------
    >>> highpass_gain([OMEGA_LOW, 10 * OMEGA_LOW]).round(6).tolist()
    [0.5, 0.9999]
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

    Parameters
    ----------
    x : array_like
        The sample (flattened).

    Returns
    -------
    float
        The standard error [units of ``x``].

    Notes
    -----
    Half the width of the 95 % order-statistic interval of the median, ``x_(n/2 -+ 1.96 sqrt(n) / 2)``
    (the count of the sample below the true median is binomial(n, 1/2)), divided by 1.96.  For normal
    data it tends to ``sqrt(pi / 2) sigma / sqrt(n)`` = ``1.2533 sigma / sqrt(n)``.

    References
    ----------
    [1] H. A. David and H. N. Nagaraja, Order Statistics, 3rd ed., Wiley (2003), section 7.1.

    Examples
    --------
    The normal quantiles of 10,000 points: close to ``sqrt(pi / 2) / sqrt(n)``.

    >>> import math, numpy as np
    >>> from scipy.stats import norm
    >>> n = 10_000
    >>> f"{median_standard_error(norm.ppf((np.arange(n) + 0.5) / n)):.4f}", f"{math.sqrt(math.pi / 2 / n):.4f}"
    ('0.0125', '0.0125')
    """
    x = np.sort(np.asarray(x, dtype=float).ravel())
    n = x.size
    half = 1.96 * math.sqrt(n) / 2.0
    lo, hi = int(math.floor(n / 2 - half)), int(math.ceil(n / 2 + half))
    return float(x[min(hi, n - 1)] - x[max(lo, 0)]) / (2.0 * 1.96)


def continuous_peak(acceleration, rate, dt, refine=8):
    """Peak of the continuous record: ``max_t |a(t)|`` of the cubic Hermite interpolant of the samples.

    Parameters
    ----------
    acceleration : array_like
        Samples [m s-2], one record per row.
    rate : array_like
        Their exact rates ``a'`` [m s-3], same shape.
    dt : float
        Time step [s].
    refine : int, default 8
        The interpolant is searched at ``refine - 1`` points inside each step.

    Returns
    -------
    numpy.ndarray
        ``max_t |a(t)|`` [m s-2] per row.

    Notes
    -----
    ``a(t_k + u dt) = h00(u) a_k + h10(u) dt a'_k + h01(u) a_{k+1} + h11(u) dt a'_{k+1}`` with the Hermite
    basis ``h00 = 2u^3 - 3u^2 + 1``, ``h10 = u^3 - 2u^2 + u``, ``h01 = -2u^3 + 3u^2``, ``h11 = u^3 - u^2``:
    the peak of the continuous record, which the grid maximum underestimates by up to ``1 - cos(omega dt / 2)``
    [1].

    References
    ----------
    [1] [fritsch1980].

    Examples
    --------
    ``sin t`` sampled every second: the grid misses its peak of 1, the interpolant nearly finds it.

    >>> t = np.arange(0.0, 6.0, 1.0)
    >>> float(np.max(np.sin(t)).round(4)), continuous_peak(np.sin(t), np.cos(t), 1.0).round(4).tolist()
    (0.9093, [0.9979])
    """
    acc, rate = np.atleast_2d(np.asarray(acceleration, dtype=float)), np.atleast_2d(np.asarray(rate, dtype=float))
    peak = np.max(np.abs(acc), axis=1)
    a0, a1, d0, d1 = acc[:, :-1], acc[:, 1:], rate[:, :-1] * dt, rate[:, 1:] * dt
    # within a step |a(t)| <= max(|a0|, |a1|) + 4/27 (|d0| + |d1|) (h00, h01 >= 0 sum to 1, |h10|, |h11| <= 4/27):
    # only the steps that may pass the sampled peak are searched (the same values, fewer of them)
    bound = np.maximum(np.abs(a0), np.abs(a1)) + (4.0 / 27.0) * (np.abs(d0) + np.abs(d1))
    row, col = np.nonzero(bound * (1.0 + 1e-9) >= peak[:, None])
    a0, a1, d0, d1 = a0[row, col], a1[row, col], d0[row, col], d1[row, col]
    for u in np.linspace(0.0, 1.0, int(refine) + 1)[1:-1]:
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        np.maximum.at(peak, row, np.abs(h00 * a0 + h10 * d0 + h01 * a1 + h11 * d1))
    return peak


def synthesised_peaks(excitation, t_end, cutoff, n_records=PGV_RECORDS, seed=PGV_SEED, omega_low=OMEGA_LOW):
    """The peak ground accelerations and velocities of records synthesised as the Monte Carlo does.

    Records ``i = 0 .. n_records - 1`` of run ``seed`` (:mod:`screening.solvers.synthesis`), in one
    pass: the PGA is the continuous peak (:func:`continuous_peak`), the PGV ``max_t |v|`` on the
    synthesis grid of the velocity high-passed by :func:`record_velocity`.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope.
    t_end, cutoff : float
        Record length [s] and band limit [rad s-1].
    n_records : int, default PGV_RECORDS
        Number of records.
    seed : int, default PGV_SEED
        Seed of the run.
    omega_low : float or None, default OMEGA_LOW
        High-pass corner of the velocity [rad s-1]; None: the PGA alone (``pgv`` None, no filter).

    Returns
    -------
    tuple of numpy.ndarray
        ``(pga [m s-2], pgv [m s-1])``, one value per record.

    Notes
    -----
    Spectral-representation synthesis [1] of the modulated process; record ``i`` of a seed is the same
    whatever ``n_records``.

    References
    ----------
    [1] [shinozuka1991]; [2] [boore2005].

    Examples
    --------
    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope())          # S0 = 0.01 m2 s-3, stationary
    >>> pga, pgv = synthesised_peaks(white, 5.0, 50.0, n_records=20, seed=1)
    >>> pga.shape, bool(np.all(synthesised_peaks(white, 5.0, 50.0, n_records=3, seed=1)[0] == pga[:3]))
    ((20,), True)
    """
    plan = spectral_plan(excitation, float(t_end), float(cutoff))
    n = int(round(float(t_end) / plan.dt)) + 1
    pga, pgv = [], []
    for lo in range(0, int(n_records), PGV_CHUNK):
        acc, rate = ground_acceleration_samples(excitation, plan, seed, np.arange(lo, min(lo + PGV_CHUNK, n_records)))
        acc, rate = acc[:, :n], rate[:, :n]
        pga.append(continuous_peak(acc, rate, plan.dt))
        if omega_low is not None:
            pgv.append(np.max(np.abs(record_velocity(acc, plan.dt, omega_low)), axis=1))
    return np.concatenate(pga), (np.concatenate(pgv) if omega_low is not None else None)


def synthesised_pgv(excitation, t_end, cutoff, n_records=PGV_RECORDS, seed=PGV_SEED, omega_low=OMEGA_LOW):
    """Peak ground velocities of :func:`synthesised_peaks` (same arguments).

    Parameters
    ----------
    excitation, t_end, cutoff, n_records, seed, omega_low
        As in :func:`synthesised_peaks` (``omega_low`` not None).

    Returns
    -------
    numpy.ndarray
        The PGV of every record [m s-1].

    References
    ----------
    [1] [shinozuka1991]; [2] [boore2005].

    Examples
    --------
    The velocities of the same records:

    >>> from screening import ConstantEnvelope, WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope())          # S0 = 0.01 m2 s-3, stationary
    >>> pgv = synthesised_pgv(white, 5.0, 50.0, n_records=20, seed=1)
    >>> bool(np.all(pgv == synthesised_peaks(white, 5.0, 50.0, n_records=20, seed=1)[1])), pgv.shape
    (True, (20,))
    """
    return synthesised_peaks(excitation, t_end, cutoff, n_records, seed, omega_low)[1]


def avgsa_periods(period, n=AVGSA_N_PERIODS, span=AVGSA_RANGE):
    """The periods of the average spectral acceleration at ``period``: log-spaced over ``[0.2 T, 1.5 T]``.

    Parameters
    ----------
    period : float
        Central period ``T`` [s].
    n : int, default AVGSA_N_PERIODS
        Number of periods.
    span : tuple of float, default AVGSA_RANGE
        First and last period in units of ``T`` [1].

    Returns
    -------
    numpy.ndarray
        The ``n`` periods [s].

    References
    ----------
    [1] [eads2015].

    Examples
    --------
    >>> p = avgsa_periods(1.0)
    >>> p.size, float(p[0]), float(p[-1]), f"{p[1] / p[0]:.6f}", f"{7.5 ** (1 / 9):.6f}"
    (10, 0.2, 1.5, '1.250919', '1.250919')
    """
    return np.geomspace(span[0] * float(period), span[1] * float(period), int(n))


def record_velocity(acceleration, dt, omega_low=OMEGA_LOW):
    """Ground velocity of rows of sampled accelerations, high-passed as in record processing.

    A causal 2nd-order Butterworth high-pass at ``omega_low`` (bilinear transform with pre-warped
    corner), then trapezoidal integration from ``v(0) = 0``.

    Parameters
    ----------
    acceleration : array_like
        Ground accelerations [m s-2], one record per row.
    dt : float
        Time step [s].
    omega_low : float, default OMEGA_LOW
        High-pass corner [rad s-1], in ``(0, pi / dt]``.

    Returns
    -------
    numpy.ndarray
        Velocities [m s-1], ``(rows, samples)``.

    Notes
    -----
    ``v(t) = int_0^t a_hp dt'``, ``a_hp = H * a`` with ``H(s) = s^2 / (s^2 + sqrt(2) omega_low s +
    omega_low^2)`` (:func:`highpass_gain`), the filter of :func:`pgv_median` [1].

    References
    ----------
    [1] [boore2005].

    Examples
    --------
    A 2 Hz sine far above the corner: after the transient the velocity's amplitude is ``1 / w``.

    >>> import math, numpy as np
    >>> w = 2 * math.pi * 2.0
    >>> v = record_velocity(np.sin(w * np.arange(0.0, 20.0, 0.005)), 0.005)
    >>> f"{np.max(np.abs(v[0, -1000:])):.5f}", f"{1 / w:.5f}"
    ('0.07959', '0.07958')
    """
    from scipy import signal
    checked("omega_low", omega_low, lower=0.0, upper=math.pi / float(dt))
    acc = np.atleast_2d(np.asarray(acceleration, dtype=float))
    sos = signal.butter(2, float(omega_low) / (2.0 * math.pi), btype="highpass", fs=1.0 / float(dt), output="sos")
    return integrate.cumulative_trapezoid(signal.sosfilt(sos, acc, axis=-1), dx=float(dt), axis=-1, initial=0.0)


def record_avgsa(acceleration, dt, period, damping=0.05):
    """Average spectral acceleration of rows of sampled accelerations at one period.

    Parameters
    ----------
    acceleration, dt
        As in :func:`record_velocity`.
    period : float
        Central period [s].
    damping : float, default 0.05
        Damping ratio [1].

    Returns
    -------
    numpy.ndarray
        AvgSA [m s-2] per row.

    Notes
    -----
    ``AvgSA = (prod_i w_i^2 max|u_i|)^(1/n)`` over :func:`avgsa_periods` [1], the peaks by
    :func:`oscillator_peak` [2].

    References
    ----------
    [1] [eads2015]; [2] [nigam1969].

    Examples
    --------
    >>> import math, numpy as np
    >>> from scipy.stats import gmean
    >>> t = np.arange(0.0, 10.0001, 0.01)
    >>> a = np.sin(2 * math.pi * t)
    >>> sa = [(2 * math.pi / p) ** 2 * oscillator_peak(a, 0.01, p)[0] for p in avgsa_periods(1.0)]
    >>> f"{record_avgsa(a, 0.01, 1.0)[0]:.6f}", f"{gmean(sa):.6f}"
    ('2.072731', '2.072731')
    """
    logs = [np.log((2.0 * math.pi / p) ** 2 * oscillator_peak(acceleration, dt, p, damping))
            for p in avgsa_periods(period)]
    return np.exp(np.mean(logs, axis=0))
