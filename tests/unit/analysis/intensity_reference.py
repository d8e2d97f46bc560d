"""Sample intensity measures of synthesised records (the reference of the RVT predictions)."""

import math

import numpy as np

from screening.analysis.intensity import continuous_peak as hermite_peaks
from screening.analysis.intensity import oscillator_peak as oscillator_peaks  # validated against an ODE
from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan


def sample_measures(excitation, t_end, cutoff, n_samples, period, seed=0):
    """``(pga, sa)`` arrays of ``n_samples`` synthesised records (continuous peaks; Sa = w^2 max|u|)."""
    plan = spectral_plan(excitation, t_end, cutoff)
    pga, sa = [], []
    for lo in range(0, n_samples, 100):
        idx = np.arange(lo, min(lo + 100, n_samples))
        acc, rate = ground_acceleration_samples(excitation, plan, seed, idx)
        n = int(round(t_end / plan.dt)) + 1
        acc, rate = acc[:, :n], rate[:, :n]
        pga.append(hermite_peaks(acc, rate, plan.dt))
        sa.append((2 * math.pi / period) ** 2 * oscillator_peaks(acc, plan.dt, period))
    return np.concatenate(pga), np.concatenate(sa)


def sample_all_measures(excitation, t_end, cutoff, n_samples, period, seed=0, chunk=100):
    """Every intensity measure of ``n_samples`` synthesised records, as a dict of arrays: ``pga``
    (continuous peak), ``pgv`` (:func:`~screening.analysis.intensity.record_velocity`), ``sa`` and
    ``avgsa`` at ``period``, ``rms_acceleration`` and ``arias_intensity`` (record by record)."""
    from screening.analysis.intensity import G, record_avgsa, record_velocity

    plan = spectral_plan(excitation, t_end, cutoff)
    n = int(round(t_end / plan.dt)) + 1
    out = {k: [] for k in ("pga", "pgv", "sa", "avgsa", "rms_acceleration", "arias_intensity")}
    for lo in range(0, n_samples, chunk):
        acc, rate = ground_acceleration_samples(excitation, plan, seed, np.arange(lo, min(lo + chunk, n_samples)))
        acc, rate = acc[:, :n], rate[:, :n]
        energy = np.trapezoid(acc * acc, dx=plan.dt, axis=1)
        out["pga"].append(hermite_peaks(acc, rate, plan.dt))
        out["pgv"].append(np.max(np.abs(record_velocity(acc, plan.dt)), axis=1))
        out["sa"].append((2 * math.pi / period) ** 2 * oscillator_peaks(acc, plan.dt, period))
        out["avgsa"].append(record_avgsa(acc, plan.dt, period))
        out["rms_acceleration"].append(np.sqrt(energy / t_end))
        out["arias_intensity"].append(math.pi / (2 * G) * energy)
    return {k: np.concatenate(v) for k, v in out.items()}
