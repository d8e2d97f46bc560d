"""Sample intensity measures of synthesised records (the reference of the RVT predictions)."""

import math

import numpy as np

from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan


def hermite_peaks(acc, rate, dt, refine=8):
    """``max_t |a(t)|`` per row of the cubic Hermite interpolant (values and exact rates on the grid)."""
    peak = np.max(np.abs(acc), axis=1)
    a0, a1, d0, d1 = acc[:, :-1], acc[:, 1:], rate[:, :-1] * dt, rate[:, 1:] * dt
    for u in np.linspace(0.0, 1.0, refine + 1)[1:-1]:
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        peak = np.maximum(peak, np.max(np.abs(h00 * a0 + h10 * d0 + h01 * a1 + h11 * d1), axis=1))
    return peak


def oscillator_peaks(acc, dt, period, damping=0.05):
    """``max_t |u|`` per row of ``u'' + 2 zeta w u' + w^2 u = -a`` from rest: the exact recurrence for
    piecewise-linear input (Nigam & Jennings 1969)."""
    w = 2 * math.pi / period
    z = damping
    wd = w * math.sqrt(1 - z * z)
    e = math.exp(-z * w * dt)
    s, c = math.sin(wd * dt), math.cos(wd * dt)
    r = z / math.sqrt(1 - z * z)
    a11 = e * (r * s + c)
    a12 = e * s / wd
    a21 = -w / math.sqrt(1 - z * z) * e * s
    a22 = e * (c - r * s)
    t1 = (2 * z * z - 1) / (w * w * dt)
    t2 = 2 * z / (w**3 * dt)
    b11 = e * ((t1 + z / w) * s / wd + (t2 + 1 / w**2) * c) - t2
    b12 = -e * (t1 * s / wd + t2 * c) - 1 / w**2 + t2
    b21 = e * ((t1 + z / w) * (c - r * s) - (t2 + 1 / w**2) * (wd * s + z * w * c)) + 1 / (w * w * dt)
    b22 = -e * (t1 * (c - r * s) - t2 * (wd * s + z * w * c)) - 1 / (w * w * dt)
    u = np.zeros(acc.shape[0])
    v = np.zeros(acc.shape[0])
    peak = np.zeros(acc.shape[0])
    for j in range(acc.shape[1] - 1):
        p0, p1 = acc[:, j], acc[:, j + 1]
        u, v = a11 * u + a12 * v + b11 * p0 + b12 * p1, a21 * u + a22 * v + b21 * p0 + b22 * p1
        np.maximum(peak, np.abs(u), out=peak)
    return peak


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
