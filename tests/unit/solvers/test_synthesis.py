"""Spectral-representation synthesis (screening.solvers.synthesis): variance, spectrum, reproducibility.

Statistical tolerances: for ``n`` independent Gaussian samples the sample variance has
relative standard error ``sqrt(2/(n-1))`` and the sample covariance ``E[f(t) f(t+tau)]``
has standard error ``sqrt((var^2 + R(tau)^2)/n)``.  Every check below uses a fixed seed
and allows 4 standard errors for a single estimate (3 for a pooled one).
"""

import math

import numpy as np
import pytest

from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi, kanai_tajimi_stationary_moments
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation
from screening.solvers.synthesis import (band_limited_variance, default_cutoff, envelope_rate, ground_acceleration,
                                 ground_acceleration_samples, rocking_frequency, sample_phases, spectral_plan,
                                 stationary_samples, validate_seed, vertical_frequency)

BLOCK = Block(m=8.67, b=0.035, h=0.21)
FOUNDATION = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
# the idealized spectra: their closed forms (the band's low-pass: tests/unit/core/excitations/test_band.py)
WHITE = WhiteNoise(S0=2.4e-5, envelope=ConstantEnvelope(), band_limit_hz=None)
KT = KanaiTajimi(S0=2.5e-4, omega_g=10.0, zeta_g=0.4, envelope=ConstantEnvelope(), band_limit_hz=None)
N_SAMPLES = 1000
T_END = 4.0
CUTOFF = 300.0          # small grids keep the tests fast; the code paths are the same


def direct_sum(plan, seed, index, t):
    """The SRM sum ``sqrt(2) sum A_k cos(omega_k t + phi_k)`` and its rate, evaluated term by term."""
    phi = sample_phases(seed, index, plan.n_frequencies)
    w = plan.omega
    arg = np.outer(t, w) + phi
    a = math.sqrt(2.0) * plan.amplitudes
    return np.cos(arg) @ a, -(np.sin(arg) * w) @ a


def test_frequencies_and_default_cutoff_of_the_paper_block():
    assert rocking_frequency(BLOCK, FOUNDATION) == pytest.approx(39.68, rel=1e-3)
    assert vertical_frequency(BLOCK, FOUNDATION) == pytest.approx(math.sqrt(2 * 0.035 * 2.89e7 / 8.67))
    assert default_cutoff(BLOCK, FOUNDATION) == pytest.approx(3.0 * vertical_frequency(BLOCK, FOUNDATION))
    assert default_cutoff(BLOCK, Foundation(k=2.89e7, c=1.0), factor=2.0) == pytest.approx(
        2.0 * vertical_frequency(BLOCK, FOUNDATION))


@pytest.mark.parametrize("excitation", [WHITE, KT], ids=["white", "kanai-tajimi"])
def test_plan_variance_matches_the_band_limited_spectrum(excitation):
    plan = spectral_plan(excitation, T_END, CUTOFF)
    assert plan.n_fft * plan.dt >= T_END                    # no repetition within the record
    assert plan.times[-1] >= T_END
    assert plan.cutoff == pytest.approx(CUTOFF, abs=plan.d_omega / 2)      # whole bins
    assert plan.omega[-1] + plan.d_omega / 2 == pytest.approx(plan.cutoff, rel=1e-14)
    # midpoint rule for int S over |omega| < cutoff: exact for white noise, O(d_omega^2) otherwise
    assert plan.stationary_variance == pytest.approx(band_limited_variance(excitation, plan.cutoff),
                                                     rel=1e-5 if excitation.kind != "white" else 1e-13)


def test_kanai_tajimi_band_limit_keeps_nearly_all_the_variance():
    var_z = kanai_tajimi_stationary_moments(KT.S0, KT.omega_g, KT.zeta_g)[2]
    lost = 1.0 - band_limited_variance(KT, 1449.0) / var_z
    tail = 8.0 * KT.S0 * KT.zeta_g**2 * KT.omega_g**2 / 1449.0 / var_z   # int 2 S over |w| > w_c, leading term
    assert 0.0 < lost == pytest.approx(tail, rel=0.02)


def test_fft_samples_equal_the_direct_sum_with_exact_rates():
    plan = spectral_plan(KT, T_END, CUTOFF)
    values, rates = stationary_samples(plan, seed=7, sample_indices=[3])
    j = np.array([0, 1, 17, 400, plan.n_times - 1])
    f, f_dot = direct_sum(plan, 7, 3, plan.times[j])
    np.testing.assert_allclose(values[0, j], f, rtol=0, atol=1e-10 * np.std(values))
    np.testing.assert_allclose(rates[0, j], f_dot, rtol=0, atol=1e-10 * np.std(rates))


def test_hermite_interpolation_between_grid_points_is_accurate():
    """The integrator reads the input between grid points by cubic Hermite interpolation."""
    plan = spectral_plan(WHITE, T_END, CUTOFF)
    values, rates = stationary_samples(plan, seed=1, sample_indices=[0])
    j = np.arange(10, 200)
    mid = plan.times[j] + 0.5 * plan.dt
    f_mid, _ = direct_sum(plan, 1, 0, mid)
    hermite = (0.5 * (values[0, j] + values[0, j + 1]) + plan.dt / 8.0 * (rates[0, j] - rates[0, j + 1]))
    # worst case (omega dt)^4/384 at the cutoff, (pi/4)^4/384 = 1e-3 of the signal level
    assert np.max(np.abs(hermite - f_mid)) < 2e-3 * np.std(values)


@pytest.mark.parametrize("excitation", [WHITE, KT], ids=["white", "kanai-tajimi"])
def test_ensemble_variance_and_covariance_match_theory(excitation):
    plan = spectral_plan(excitation, T_END, CUTOFF)
    values, _ = stationary_samples(plan, seed=2024, sample_indices=np.arange(N_SAMPLES))
    var = plan.stationary_variance
    rel_se = math.sqrt(2.0 / (N_SAMPLES - 1))
    # single instants, well apart (correlation time << 0.5 s)
    idx = np.searchsorted(plan.times, [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5])
    ratios = values[:, idx].var(axis=0, ddof=1) / var
    assert np.all(np.abs(ratios - 1.0) < 4.0 * rel_se), ratios
    # pooled over the 8 (nearly independent) instants
    assert abs(ratios.mean() - 1.0) < 3.0 * rel_se / math.sqrt(idx.size)
    # spectrum: E[f(t) f(t + tau)] = sum A_k^2 cos(omega_k tau)
    for tau in (0.02, 0.1, 0.3):
        lag = int(round(tau / plan.dt))
        r_theory = float(np.sum(plan.amplitudes**2 * np.cos(plan.omega * lag * plan.dt)))
        r_hat = np.mean(values[:, idx[:4]] * values[:, idx[:4] + lag], axis=0)
        se = math.sqrt((var**2 + r_theory**2) / N_SAMPLES)
        assert np.all(np.abs(r_hat - r_theory) < 4.0 * se), (tau, r_hat, r_theory, se)


def test_modulated_variance_follows_the_envelope():
    excitation = WhiteNoise(S0=2.4e-5, envelope=Envelope(T1=4.0, T2=2.0), band_limit_hz=None)
    plan = spectral_plan(excitation, 8.0, CUTOFF)
    acc, acc_rate = ground_acceleration_samples(excitation, plan, 11, np.arange(N_SAMPLES))
    idx = np.searchsorted(plan.times, [1.0, 2.77, 4.0, 6.0, 7.5])
    q = excitation.envelope(plan.times[idx])
    ratios = acc[:, idx].var(axis=0, ddof=1) / (q**2 * plan.stationary_variance)
    assert np.all(np.abs(ratios - 1.0) < 4.0 * math.sqrt(2.0 / (N_SAMPLES - 1))), ratios
    # the rate is d(q f)/dt (check against centred differences of a direct evaluation)
    t = plan.times[idx]
    d = 1e-6
    f_p, _ = direct_sum(plan, 11, 5, t + d)
    f_m, _ = direct_sum(plan, 11, 5, t - d)
    numeric = (excitation.envelope(t + d) * f_p - excitation.envelope(t - d) * f_m) / (2 * d)
    np.testing.assert_allclose(acc_rate[5, idx], numeric, rtol=1e-6, atol=1e-6 * np.std(acc_rate))


def test_envelope_rate_is_the_derivative():
    env = Envelope(T1=4.0, T2=2.0)
    t = np.linspace(0.0, 20.0, 41)
    d = 1e-6
    np.testing.assert_allclose(envelope_rate(env, t), (env(t + d) - env(t - d)) / (2 * d), atol=1e-8)
    assert np.all(envelope_rate(ConstantEnvelope(), t) == 0.0)


def test_reproducible_and_independent_of_the_split():
    plan = spectral_plan(KT, T_END, CUTOFF)
    whole, whole_rate = stationary_samples(plan, 5, np.arange(10))
    first, _ = stationary_samples(plan, 5, np.arange(4))
    second, second_rate = stationary_samples(plan, 5, np.arange(4, 10))
    alone, _ = stationary_samples(plan, 5, [7])
    again, _ = stationary_samples(plan, 5, np.arange(10))
    np.testing.assert_array_equal(whole, again)
    np.testing.assert_array_equal(whole, np.vstack([first, second]))
    np.testing.assert_array_equal(whole_rate[4:], second_rate)
    np.testing.assert_array_equal(whole[7], alone[0])
    other_seed, _ = stationary_samples(plan, 6, np.arange(10))
    assert not np.allclose(whole, other_seed)
    assert np.corrcoef(whole[0], whole[1])[0, 1] < 0.2          # distinct samples are not copies


def test_convenience_wrapper_and_seed_validation():
    t, acc, plan = ground_acceleration(WHITE, 1.0, CUTOFF, n_samples=3, seed=0)
    assert acc.shape == (3, t.size) and t[-1] >= 1.0
    for bad in (-1, 1.5, "1", None, True):
        with pytest.raises(ValueError, match="'seed'"):
            validate_seed(bad)
    with pytest.raises(ValueError, match="'cutoff'"):
        spectral_plan(WHITE, 1.0, 0.0)
    with pytest.raises(ValueError, match="'t_end'"):
        spectral_plan(WHITE, -1.0, 10.0)
