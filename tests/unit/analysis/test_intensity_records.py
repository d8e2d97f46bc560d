"""Measures of records (screening.analysis.intensity_records) against independent computations: an ODE
solution (scipy RK45) and the closed-form steady state for the high-passed velocity, a frequency-domain
(FFT) oscillator for Sa and AvgSA, the normal closed form and the scatter of sample medians for the
order-statistic standard error."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from screening.analysis import intensity_records as I
from screening.core.records import Record

WL = I.OMEGA_LOW


@pytest.mark.parametrize("freq", [0.1, 1.0])
def test_record_velocity_against_an_ode_and_the_steady_state(freq):
    """Ramped sine at the corner (0.1 Hz) and above it: the filtered, integrated record against
    x'' + sqrt(2) wl x' + wl^2 x = a, v = x' (RK45, rtol 1e-10) within 2e-3 (bilinear transform and
    trapezoid at dt = 5 ms), and its late amplitude against A w / sqrt(w^4 + wl^4)."""
    w, amp, dt = 2 * math.pi * freq, 3.0, 0.005
    t_end = 120.0 if freq < 0.5 else 40.0
    t = np.arange(0.0, t_end, dt)

    def acc(s):
        return amp * np.sin(w * s) * np.minimum(s / (0.25 * t_end), 1.0) ** 2

    ref = solve_ivp(lambda s, y: [y[1], acc(s) - math.sqrt(2) * WL * y[1] - WL * WL * y[0]], (0.0, t[-1]),
                    [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=0.02).y[1]
    v = I.record_velocity(acc(t), dt)[0]
    assert np.max(np.abs(v - ref)) < 2e-3 * np.max(np.abs(ref))
    late = t > 0.75 * t_end
    assert np.max(np.abs(ref[late])) == pytest.approx(amp * w / math.sqrt(w**4 + WL**4), rel=2e-3)
    assert I.record_measures(Record(acc(t), dt))["pgv"] == pytest.approx(np.max(np.abs(v)))


def _fft_oscillator_peak(a, dt, period, zeta=0.05):
    """max |u| of u'' + 2 zeta wn u' + wn^2 u = -a by the frequency response (zero-padded FFT)."""
    n = 1 << int(math.ceil(math.log2(4 * a.size)))
    w = 2 * math.pi * np.fft.rfftfreq(n, dt)
    wn = 2 * math.pi / period
    u = np.fft.irfft(-np.fft.rfft(a, n) / (wn * wn - w * w + 2j * zeta * wn * w), n)[:a.size]
    return np.max(np.abs(u))


@pytest.mark.parametrize("period", [0.5, 0.8])
def test_sa_and_avgsa_against_a_frequency_domain_oscillator(period):
    """Sine at 2 Hz (resonant for T = 0.5 s, off resonance for 0.8 s) ramped up and down over 20 s
    (sin^2 ramps, no transient to speak of), then 10 s of rest: Sa and AvgSA of record_measures against
    the FFT oscillator (1e-3), and the steady-state amplitude A / sqrt((wn^2 - w^2)^2 + (2 zeta wn w)^2)
    against the closed form (2e-3)."""
    dt, wf, amp = 0.002, 2 * math.pi * 2.0, 1.5
    t = np.arange(0.0, 80.0, dt)
    a = amp * np.sin(wf * t) * np.sin(0.5 * np.pi * np.clip(np.minimum(t, 70.0 - t) / 20.0, 0.0, 1.0)) ** 2
    m = I.record_measures(Record(a, dt), period=period)
    wn = 2 * math.pi / period
    assert m["sa"] == pytest.approx(wn * wn * _fft_oscillator_peak(a, dt, period), rel=1e-3)
    ref = [(2 * math.pi / p) ** 2 * _fft_oscillator_peak(a, dt, p) for p in I.avgsa_periods(period)]
    assert m["avgsa"] == pytest.approx(math.exp(np.mean(np.log(ref))), rel=1e-3)
    steady = amp / math.sqrt((wn * wn - wf * wf) ** 2 + (2 * 0.05 * wn * wf) ** 2)
    assert m["sa"] == pytest.approx(wn * wn * steady, rel=2e-3)
    periods = I.avgsa_periods(period)
    assert periods.size == 10 and periods[0] == pytest.approx(0.2 * period) and periods[-1] == pytest.approx(
        1.5 * period)


def test_median_standard_error_against_the_normal_closed_form_and_the_scatter_of_medians():
    """For normal data the order-statistic standard error tends to sqrt(pi/2) sigma / sqrt(n); checked on
    one sample of 20,000 (its own sampling error ~3 %: tolerance 10 %) and against the standard
    deviation of the medians of 400 independent samples of 1,000 (that spread is itself known to
    ~1 / sqrt(2 x 400) = 3.5 %: tolerance 12 %)."""
    rng = np.random.default_rng(7)
    assert I.median_standard_error(rng.normal(0.0, 2.0, 20_000)) == pytest.approx(
        math.sqrt(math.pi / 2) * 2.0 / math.sqrt(20_000), rel=0.10)
    draws = rng.gumbel(1.0, 0.3, (400, 1000))                 # skewed, like peaks
    spread = np.std(np.median(draws, axis=1), ddof=1)
    assert np.mean([I.median_standard_error(d) for d in draws]) == pytest.approx(spread, rel=0.12)
