"""The continuous peak searches only the steps that may pass the sampled peak, and the PGA median of the sweep
is synthesised without the velocity: both give the numbers of the full computation, bit for bit."""

import numpy as np

from screening.analysis import intensity as I
from screening.analysis.intensity_records import continuous_peak, synthesised_peaks
from screening.core.excitations.white import WhiteNoise


def _every_step(acc, rate, dt, refine=8):
    """The search over every step (the implementation before 2026-11-29)."""
    peak = np.max(np.abs(acc), axis=1)
    a0, a1, d0, d1 = acc[:, :-1], acc[:, 1:], rate[:, :-1] * dt, rate[:, 1:] * dt
    for u in np.linspace(0.0, 1.0, refine + 1)[1:-1]:
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        peak = np.maximum(peak, np.max(np.abs(h00 * a0 + h10 * d0 + h01 * a1 + h11 * d1), axis=1))
    return peak


def test_the_continuous_peak_is_that_of_the_search_over_every_step():
    rng = np.random.default_rng(11)
    t = np.arange(801) * 0.01
    w, phase, amp = rng.uniform(1.0, 300.0, (40, 1, 12)), rng.uniform(0, 6.3, (40, 1, 12)), rng.normal(size=(40, 1, 12))
    acc = (amp * np.sin(w * t[None, :, None] + phase)).sum(-1)            # steps up to 3 rad: peaks between samples
    rate = (amp * w * np.cos(w * t[None, :, None] + phase)).sum(-1)
    got = continuous_peak(acc, rate, 0.01)
    np.testing.assert_array_equal(got, _every_step(acc, rate, 0.01))
    assert np.mean(got > np.max(np.abs(acc), axis=1)) > 0.5             # the search between samples mattered


def test_the_pga_median_without_the_velocity_is_that_of_the_full_synthesis():
    white = WhiteNoise(0.04, band_limit_hz=None)
    pga, _ = synthesised_peaks(WhiteNoise(1.0, white.envelope, band_limit_hz=None), 4.0, 60.0, n_records=50, seed=3)
    median, se = I.simulated_pga(white, 4.0, 60.0, n_records=50, seed=3)
    assert median == 0.2 * float(np.median(pga)) and se > 0
