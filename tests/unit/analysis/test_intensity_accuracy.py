"""Accuracy of the peak measures: the simulated PGA median, the RVT PGA as the median of the
rocking-start distribution (Poisson crossings), Sa and AvgSA with the bandwidth of the oscillator's
response to the actual input, on every stochastic input (white, Kanai-Tajimi firm and soft soil, Clough-Penzien).

The slow tests draw 1,000 records per point (seed 0) exactly as the Monte Carlo draws them; the
standard error of a sample median (order statistics, ``median_standard_error``) is 0.4-1.3 % and is
asserted below 1.5 %.  Tolerance: 3 standard errors, plus the model error named in the test where the
RVT approximation is known to exceed the sampling error (docs/intensity_measures.md).
"""

import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from screening.core import excitations
from screening.analysis import intensity as I
from screening.analysis.fragility import oscillator_bandwidth
from screening.core.model.excitation import Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise

sys.path.insert(0, str(Path(__file__).parent))
from intensity_reference import sample_all_measures, sample_measures  # noqa: E402

T_END, CUTOFF, N = 20.0, 100.0, 1000
CP = excitations.build("clough_penzien", 1e-3, {"omega_g": 15.6, "zeta_g": 0.6, "omega_f": 1.56, "zeta_f": 0.6},
                       Envelope())
#: name: (excitation, period [s] of Sa and AvgSA)
POINTS = {"white": (WhiteNoise(1e-3), 0.5), "kanai_tajimi": (KanaiTajimi(1e-3, 15.6, 0.6), 0.3),
          "soft_soil": (KanaiTajimi(1e-3, 5.0, 0.3), 1.0), "clough_penzien": (CP, 0.3)}


def _response_bandwidth_by_trapezoid(excitation, period, damping, cutoff, n=400_001):
    """The bandwidth of the oscillator response by the trapezoidal rule on a dense grid (independent
    of the adaptive quadrature of the function under test)."""
    wn = 2 * math.pi / period
    w = np.linspace(0.0, cutoff, n)
    s = np.asarray(excitation.psd(w), dtype=float) / ((wn**2 - w**2) ** 2 + (2 * damping * wn * w) ** 2)
    lam = [np.trapezoid(w**i * s, w) for i in range(3)]
    return math.sqrt(1 - lam[1] ** 2 / (lam[0] * lam[2]))


def test_response_bandwidth_under_white_noise_is_the_closed_form():
    """Unbounded white noise: the integral equals the closed form of the white-noise oscillator
    bandwidth (1 - 2/pi atan(z / sqrt(1 - z^2)))^2 / (1 - z^2) = 1 - delta^2."""
    for zeta in (0.02, 0.05, 0.2):
        assert I.oscillator_response_bandwidth(WhiteNoise(1.0, band_limit_hz=None), 0.5, zeta) == pytest.approx(
            float(oscillator_bandwidth(zeta)), rel=1e-6)


@pytest.mark.parametrize("period", [0.2, 1.0, 1.5])
def test_response_bandwidth_under_a_narrow_band_input_against_a_dense_trapezoid(period):
    soft = POINTS["soft_soil"][0]
    delta = I.oscillator_response_bandwidth(soft, period, 0.05, CUTOFF)
    assert delta == pytest.approx(_response_bandwidth_by_trapezoid(soft, period, 0.05, CUTOFF), rel=1e-4)
    if period == 0.2:      # a stiff oscillator under a 5 rad/s input: two spectral peaks, a broad response
        assert delta > 2 * float(oscillator_bandwidth(0.05))


@pytest.mark.parametrize("name", list(POINTS))
def test_pga_median_is_the_median_of_the_rocking_start_distribution(name):
    """The RVT median PGA and the probability that the block starts to rock describe the same peak
    distribution: P(PGA > RVT pga_median) = 1/2 (to the 5e-5 interpolation of the crossings table)."""
    exc = POINTS[name][0]
    pga = I.pga_median(exc, T_END, CUTOFF, method="rvt")
    assert I.rocking_start_probability(exc, T_END, CUTOFF, pga) == pytest.approx(0.5, abs=1e-3)


@pytest.fixture(scope="module")
def samples():
    return {name: sample_all_measures(exc, T_END, CUTOFF, N, period, seed=0) for name, (exc, period) in POINTS.items()}


def _assert_within(pred, sample, model_error=0.0):
    med, se = float(np.median(sample)), I.median_standard_error(sample)
    assert se < 0.015 * med
    assert abs(pred - med) <= 3 * se + model_error * med, (pred, med, se, (pred / med - 1))


@pytest.mark.slow
@pytest.mark.parametrize("name", list(POINTS))
def test_pga_median_against_1000_records(name, samples):
    """The simulated median (2,000 records, seed PGV_SEED) against 1,000 other records (seed 0): both are
    sample medians, so the tolerance is 3 standard errors of their difference, with no model error."""
    exc = POINTS[name][0]
    pga, pga_se = I.simulated_pga(exc, T_END, CUTOFF)
    assert I.pga_median(exc, T_END, CUTOFF) == pga
    med, se = float(np.median(samples[name]["pga"])), I.median_standard_error(samples[name]["pga"])
    assert abs(pga - med) <= 3 * math.hypot(se, pga_se), (pga, med, se, pga_se)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(POINTS))
def test_rvt_pga_median_against_1000_records(name, samples):
    """The RVT median (the one of rocking_start_probability): within 3 standard errors on the broadband
    inputs (Vanmarcke's clumping left white noise 2.5 %, about 5 standard errors, low); on soft soil
    (zeta_g 0.3, narrow-band: Poisson crossings clump) a measured +3 % model error is allowed."""
    exc = POINTS[name][0]
    _assert_within(I.pga_median(exc, T_END, CUTOFF, method="rvt"), samples[name]["pga"],
                   0.03 if name == "soft_soil" else 0.0)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(POINTS))
def test_sa_and_avgsa_medians_against_1000_records(name, samples):
    """Sa(T) within 3 standard errors plus 2.5 % (measured -1 to -2.3 %: the transient of an oscillator
    started at rest), AvgSA(T) within 3 standard errors plus 1 % (measured within 0.5 %); the soft-soil
    AvgSA was 7 % low with the white-noise oscillator bandwidth (its stiff oscillators respond at the
    input's 5 rad/s, a broad response), and 2 % high on the broadband inputs with the band-limited
    bandwidth above half the band limit."""
    exc, period = POINTS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sa = I.sa_median(exc, period, T_END, cutoff=CUTOFF)
        avgsa = I.avgsa_median(exc, period, T_END, cutoff=CUTOFF)
    _assert_within(sa, samples[name]["sa"], 0.025)
    _assert_within(avgsa, samples[name]["avgsa"], 0.01)


@pytest.mark.slow
def test_sa_of_a_stiff_oscillator_on_soft_soil_against_1000_records():
    """T = 0.2 s under the 5 rad/s input: 10 % low with the white-noise oscillator bandwidth; now within
    3 standard errors plus 1 %."""
    exc = POINTS["soft_soil"][0]
    _, sample = sample_measures(exc, T_END, CUTOFF, N, 0.2, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _assert_within(I.sa_median(exc, 0.2, T_END, cutoff=CUTOFF), sample, 0.01)
