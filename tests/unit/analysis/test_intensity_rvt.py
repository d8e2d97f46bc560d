"""The random-vibration moments of the high-passed ground velocity (screening.analysis.intensity_rvt)
against independent computations: the closed-form white-noise moment, a time-domain convolution
integral (impulse response by scipy.signal), the stationary limit, and the variance of synthesised
records."""

import math

import numpy as np
import pytest
from scipy import integrate, signal

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


def _adaptive_oscillator_covariance(exc, period, t_end, damping, n_times):
    """The full Lyapunov equation ``P' = A(t) P + P A(t)^T + 2 pi S0 b(t) b(t)^T`` of (filter, u, u'),
    integrated by LSODA with its exact Jacobian (rtol 1e-11): the filter block is integrated, not assumed
    stationary, and the envelope is evaluated, not expanded in exponentials."""
    wn = 2.0 * math.pi / period
    A_f, B_f, C_f, D_f = (np.asarray(m, dtype=float) for m in exc.filter())
    nf = A_f.shape[0]
    n = nf + 2
    base = np.zeros((n, n))
    base[:nf, :nf] = A_f
    base[nf:, nf:] = [[0.0, 1.0], [-wn * wn, -2.0 * damping * wn]]

    def drift(t):
        a = base.copy()
        a[nf + 1, :nf] = -exc.envelope(t) * C_f
        return a

    def rhs(t, y):
        P, a = y.reshape(n, n), drift(t)
        b = np.concatenate([B_f, [0.0, -exc.envelope(t) * float(D_f)]])
        return (a @ P + P @ a.T + 2.0 * math.pi * exc.S0 * np.outer(b, b)).ravel()

    def jac(t, y):
        a, one = drift(t), np.eye(n)
        return np.kron(a, one) + np.kron(one, a)

    P0 = np.zeros((n, n))
    if nf:
        P0[:nf, :nf] = exc.stationary_covariance()
    t = np.linspace(0.0, t_end, n_times)
    sol = integrate.solve_ivp(rhs, (0.0, t_end), P0.ravel(), method="LSODA", t_eval=t, jac=jac, rtol=1e-11,
                              atol=1e-20 * exc.S0)
    P = sol.y.reshape(n, n, -1)
    return P[nf, nf], P[nf + 1, nf + 1], P[nf, nf + 1]


@pytest.mark.parametrize("exc", [WhiteNoise(1e-3), KanaiTajimi(1e-3, 15.6, 0.6),
                                 WhiteNoise(1e-3, ConstantEnvelope(), band_limit_hz=None),
                                 KanaiTajimi(1e-3, 15.6, 0.6, band_limit_hz=None)],
                         ids=["white-band", "kt-band", "white-stationary", "kt-unbounded"])
def test_oscillator_covariance_against_an_adaptive_lyapunov_integration(exc):
    """The exact propagation of :func:`oscillator_covariance` against the adaptive integration of the whole
    Lyapunov equation on a 1 s record: agreement 1e-8 of each moment's peak (measured 2e-13 to 2e-9, the
    reference's own tolerance; band-limited inputs: filter states of order 4 and 6)."""
    got = I.oscillator_covariance(exc, 0.3, 1.0, 0.05, n_times=201)
    for g, r in zip(got[1:], _adaptive_oscillator_covariance(exc, 0.3, 1.0, 0.05, 201)):
        assert np.max(np.abs(g - r)) < 1e-8 * np.max(np.abs(r))
