"""The ground motion's band (``band_limit_hz``): one Butterworth low-pass, the same in every model.

* the appended filter states have the PSD ``|H|^2`` times the idealized one (every kind);
* ``band_limit_hz=None`` is today's excitation bit for bit (the numbers frozen from the code before the band);
* the linearization with the band equals the linear oscillator's variance under the banded spectrum, and
  Monte Carlo at the same band agrees with it within 2.5 standard errors at soft-bed points where the band
  changes the variance by many standard errors (fixed seed; the tolerance from the sampling error);
* a band the synthesis cannot carry is refused, one line naming the parameter and its range.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from screening import Block, Foundation
from screening.core import condensation
from screening.core.excitations import CloughPenzien, KanaiTajimi, WhiteNoise, transfer_psd
from screening.core.excitations.base import BAND_ORDER, band_filter, band_gain, band_top, stationary_covariance
from screening.core.model.excitation import ConstantEnvelope
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.synthesis import check_band, default_cutoff, max_band_limit_hz, synthesis_cutoff
from screening.solvers.timegrid import output_times

OMEGA = np.array([0.5, 10.0, 60.0, 157.0, 300.0, 900.0])
KINDS = [lambda band: WhiteNoise(1e-3, band_limit_hz=band),
         lambda band: KanaiTajimi(1e-3, 15.6, 0.6, band_limit_hz=band),
         lambda band: CloughPenzien(1e-3, 15.6, 0.6, 1.5, 0.8, band_limit_hz=band)]
BLOCK = Block(m=8.67, b=0.035, h=0.21)
#: A soft bed whose rocking frequency (156 rad/s) sits at the 25 Hz corner: the band halves the variance there.
#: The damping is raised so the oscillator is stationary within the record (damping ratio 0.049).
CORNER_BED = Foundation(k=4.4e8, lam=1e11)


@pytest.mark.parametrize("make", KINDS, ids=["white", "kanai_tajimi", "clough_penzien"])
def test_the_appended_filter_has_the_butterworth_gain_times_the_idealized_psd(make):
    banded, ideal = make(25.0), make(None)
    wc = 2.0 * math.pi * 25.0
    gain = 1.0 / (1.0 + (OMEGA / wc) ** (2 * BAND_ORDER))            # |H|^2 written out
    np.testing.assert_allclose(band_gain(OMEGA, 25.0), gain, rtol=1e-14)
    expected = ideal.psd(OMEGA) * gain
    np.testing.assert_allclose(transfer_psd(banded.filter(), banded.S0, OMEGA), expected, rtol=1e-10)
    np.testing.assert_allclose(banded.psd(OMEGA), expected, rtol=1e-12)
    assert banded.filter().A.shape[-1] == ideal.filter().A.shape[-1] + BAND_ORDER
    assert float(banded.filter().D) == 0.0                            # the band makes even white noise finite


def test_the_banded_white_noise_has_the_butterworth_variance():
    # int |H|^2 d omega over the real line = 2 omega_c (pi / (2 n)) / sin(pi / (2 n)): the filter's last state
    s0, n, wc = 2e-3, BAND_ORDER, 2.0 * math.pi * 25.0
    expected = 2.0 * s0 * wc * (math.pi / (2 * n)) / math.sin(math.pi / (2 * n))
    P = stationary_covariance(band_filter(25.0), s0)
    assert P[-2, -2] == pytest.approx(expected, rel=1e-10)
    white = WhiteNoise(s0, band_limit_hz=25.0)
    assert white.spectral_moment(0, white.reference_cutoff()) == pytest.approx(expected, rel=2e-6)   # BAND_TAIL
    assert white.reference_cutoff() == pytest.approx(band_top(25.0)) and band_top(25.0) > 5.6 * wc


#: peak var_theta and var_theta at 10 s of the paper block on its bed, S0 = 1e-4 and 1e-3, computed by the
#: code before the band existed (float.hex): band_limit_hz=None must reproduce them exactly
FROZEN = {
    "white": (["0x1.705821467f799p-20", "0x1.7624a9c245b0ap-14"], ["0x1.2977621d6682dp-23", "0x1.5bff2c99d75b6p-19"]),
    "kanai_tajimi": (["0x1.61ed3dad5de1fp-22", "0x1.2bbf156236a59p-14"],
                     ["0x1.42862b519768ap-25", "0x1.b7968f689f656p-21"]),
    "clough_penzien": (["0x1.5ed92db8e966bp-22", "0x1.17baf0f097bafp-14"],
                       ["0x1.40539d8c26580p-25", "0x1.9675a5d6cc6e7p-21"]),
}


@pytest.mark.parametrize("kind", list(FROZEN))
def test_none_is_the_idealized_excitation_bit_for_bit(kind):
    s0 = np.array([1e-4, 1e-3])
    exc = {"white": WhiteNoise(s0, band_limit_hz=None), "kanai_tajimi": KanaiTajimi(s0, 15.0, 0.6, band_limit_hz=None),
           "clough_penzien": CloughPenzien(s0, 15.0, 0.6, 1.5, 0.8, band_limit_hz=None)}[kind]
    for a, b in zip(exc.filter(), exc.shaping_filter()):
        np.testing.assert_array_equal(a, b)
    res = solve_moments(BLOCK, Foundation(k=2.89e7, lam=8.95e8), exc, output_times(10.0, 0.5), condensation="paper")
    peak, end = FROZEN[kind]
    assert [float(v).hex() for v in res["peak_var_theta"]] == peak
    assert [float(v).hex() for v in res["var_theta"][:, -1]] == end
    bed = Foundation(k=2.89e7, lam=8.95e8)
    assert synthesis_cutoff(exc, BLOCK, bed) == default_cutoff(BLOCK, bed)     # the synthesis as before


def _linear_oscillator(bed):
    cond = condensation.get("paper")
    w = math.sqrt(cond.stiffness_at_rest(BLOCK, bed) / BLOCK.m_sdof)
    zeta = cond.damping_at_rest(BLOCK, bed) / (2.0 * BLOCK.m_sdof * w)
    return w, zeta, BLOCK.m * BLOCK.h / BLOCK.m_sdof


def test_the_banded_linearization_is_the_oscillator_under_the_banded_spectrum():
    w, zeta, a = _linear_oscillator(CORNER_BED)
    exc = WhiteNoise(2e-8, ConstantEnvelope())
    h2 = lambda om: a**2 / ((w**2 - om**2) ** 2 + (2.0 * zeta * w * om) ** 2) * band_gain(om, 25.0)
    expected = 2.0 * exc.S0 * integrate.quad(h2, 0.0, band_top(25.0), points=[w, 157.08], limit=400,
                                             epsrel=1e-10)[0]
    res = solve_moments(BLOCK, CORNER_BED, exc, output_times(4.0, 0.5), condensation="paper")
    assert float(res["peak_p_uplift"]) < 1e-12                       # linear: k_eq, c_eq at rest
    assert float(res["var_theta"][-1]) == pytest.approx(expected, rel=1e-4)
    ideal = solve_moments(BLOCK, CORNER_BED, WhiteNoise(2e-8, ConstantEnvelope(), band_limit_hz=None),
                          output_times(4.0, 0.5), condensation="paper")
    assert float(ideal["var_theta"][-1]) > 1.7 * expected            # the corner at the rocking frequency


@pytest.mark.parametrize("make", [lambda b: WhiteNoise(2e-8, ConstantEnvelope(), band_limit_hz=b),
                                  lambda b: KanaiTajimi(2e-8, 100.0, 0.3, ConstantEnvelope(), band_limit_hz=b)],
                         ids=["white", "kanai_tajimi"])
def test_monte_carlo_at_the_band_agrees_with_the_banded_linearization(make):
    """1,000 condensed samples (seed 5), linear regime: the stationary variance, averaged over the record's second
    half, within 2.5 of its per-instant standard errors (the average's own is smaller: conservative), while the
    idealized spectrum's linearization lies more than 5 standard errors away (the check sees the band)."""
    t = output_times(6.0, 0.25)
    late = t >= 3.0                                              # > 20 decay times of the oscillator
    banded = float(solve_moments(BLOCK, CORNER_BED, make(25.0), t, condensation="paper")["var_theta"][late].mean())
    ideal = float(solve_moments(BLOCK, CORNER_BED, make(None), t, condensation="paper")["var_theta"][late].mean())
    ds = monte_carlo(BLOCK, CORNER_BED, make(25.0), n_samples=1000, model="condensed", t_end=6.0, dt=0.25,
                     seed=5, condensation="paper")
    assert int(ds.n_used) == 1000
    assert float(ds.attrs["cutoff_rad_s"]) == pytest.approx(band_top(25.0), rel=1e-2)   # synthesized to the top
    var = float(ds.var_theta.values[late].mean())
    se = float(ds.var_theta_se.values[late].mean())
    assert abs(var - banded) < 2.5 * se, (var, banded, se)
    assert abs(ideal - banded) > 5.0 * se, (ideal, banded, se)


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf, "25"])
def test_a_bad_band_is_refused_by_every_excitation(value):
    for make in KINDS:
        with pytest.raises(ValueError, match="band_limit_hz") as info:
            make(value)
        assert "\n" not in str(info.value)


def test_a_band_the_synthesis_cannot_carry_is_refused_before_any_work():
    assert max_band_limit_hz(20.0) == pytest.approx(2**23 * math.pi / (4 * 20.0) / band_top(1.0), rel=1e-6)
    with pytest.raises(ValueError, match=r"band_limit_hz' must be in \(0, 9323\] Hz for a 20 s record"):
        check_band(WhiteNoise(1e-4, band_limit_hz=1e4), 20.0)
    with pytest.raises(ValueError, match=r"band_limit_hz' must be in \(0, 15.92\] Hz for the synthesis' cutoff"):
        monte_carlo(BLOCK, Foundation(k=2.89e7, lam=8.95e8), WhiteNoise(1e-4), n_samples=2, model="condensed",
                    t_end=1.0, dt=0.5, cutoff=100.0)
    check_band(WhiteNoise(1e-4, band_limit_hz=None), 20.0, cutoff=1.0)      # no band: nothing to carry
