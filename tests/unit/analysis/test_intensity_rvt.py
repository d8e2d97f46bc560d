"""The random-vibration moments of the high-passed ground velocity (screening.analysis.intensity_rvt)
against independent computations: the closed-form white-noise moment, a time-domain convolution
integral (impulse response by scipy.signal), the stationary limit, and the variance of synthesised
records."""

import math

import numpy as np
import pytest
from scipy import signal

from screening.analysis import intensity_records as R
from screening.analysis import intensity_rvt as I
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise

WL = R.OMEGA_LOW
CUTOFF = 100.0


def test_white_noise_velocity_moment_closed_form():
    """mu_0 = pi S0 / (sqrt(2) omega_low) without band limit; the band limit removes ~2 S0 / omega_c."""
    mu0 = I.velocity_spectral_moments(WhiteNoise(2.0, band_limit_hz=None), 1e4)[0]
    assert mu0 == pytest.approx(math.pi * 2.0 / (math.sqrt(2.0) * WL) - 2 * 2.0 / 1e4, rel=1e-6)
    assert R.highpass_gain(WL) == pytest.approx(0.5) and R.highpass_gain(0.0) == 0.0


def test_velocity_variance_against_a_time_domain_convolution():
    """var v(t) = 2 pi S0 int_0^t h(t-s)^2 q(s)^2 ds for white noise (h: impulse response of
    s / (s^2 + sqrt(2) wl s + wl^2)); agreement 1e-3 (trapezoid on 2,000 points per second)."""
    exc = WhiteNoise(1.0, Envelope(4.0, 2.0), band_limit_hz=None)      # the closed form is unbounded white noise's
    t, var_v, _, cov = I.velocity_covariance(exc, 12.0, 1e4)
    tau = np.linspace(0.0, 12.0, 24001)
    _, h = signal.impulse(signal.lti([1.0, 0.0], [1.0, math.sqrt(2) * WL, WL * WL]), T=tau)
    for tk in (1.0, 3.0, 6.0, 12.0):
        s = tau[tau <= tk]
        ref = 2 * math.pi * np.trapezoid(h[:s.size][::-1] ** 2 * exc.envelope(s) ** 2, s)
        assert np.interp(tk, t, var_v) == pytest.approx(ref, rel=1e-3)
    # cov(v, v') = (1/2) d var_v / dt
    np.testing.assert_allclose(cov[1:-1], 0.5 * np.gradient(var_v, t)[1:-1], rtol=2e-2,
                               atol=2e-3 * np.max(np.abs(cov)))


def test_velocity_covariance_reaches_the_stationary_moments():
    """Constant envelope, 40 s >> 1/omega_low: var v -> mu_0, var v' -> mu_2 (quad), cov -> 0."""
    exc = KanaiTajimi(1.0, 15.6, 0.6, ConstantEnvelope())
    mu0, _, mu2 = I.velocity_spectral_moments(exc, CUTOFF)
    t, var_v, var_a, cov = I.velocity_covariance(exc, 40.0, CUTOFF)
    assert var_v[-1] == pytest.approx(mu0, rel=1e-4)
    assert var_a[-1] == pytest.approx(mu2, rel=1e-4)
    assert abs(cov[-1]) < 1e-4 * math.sqrt(mu0 * mu2)
    again = I.velocity_covariance(exc, 40.0, CUTOFF)                 # the cached low band is not altered
    np.testing.assert_array_equal(again[1], var_v)
    assert I.velocity_covariance(exc, 40.0, 2 * CUTOFF)[1][-1] > var_v[-1]


def test_synthesised_velocity_variance_against_the_evolutionary_spectrum():
    """The variance over 2,000 synthesised records of the high-passed velocity at 3, 6 and 12 s (sample
    variance: relative standard error sqrt(2 / n) = 3.2 %) against the exact non-stationary variance of
    velocity_covariance (evolutionary spectrum, closed form): within 3 standard errors.  The records
    of simulated_pgv are therefore the velocity whose variance the closed form gives."""
    from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan
    exc = KanaiTajimi(1.0, 15.6, 0.6, Envelope(4.0, 2.0))
    t_end, cutoff, n = 12.0, 60.0, 2000
    plan = spectral_plan(exc, t_end, cutoff)
    acc, _ = ground_acceleration_samples(exc, plan, 3, np.arange(n))
    v = R.record_velocity(acc, plan.dt)
    t, var_v, _, _ = I.velocity_covariance(exc, t_end, plan.cutoff)
    for tk in (3.0, 6.0, 12.0):
        ref = np.interp(tk, t, var_v)
        assert np.var(v[:, int(round(tk / plan.dt))]) == pytest.approx(ref, rel=3 * math.sqrt(2 / n))
