"""Modulated white noise (screening.core.excitations.white): a flat PSD with closed-form spectral moments."""

import pytest
from scipy import integrate

from screening.core.excitations.white import WhiteNoise


def test_the_psd_is_flat_and_the_filter_has_no_state():
    wn = WhiteNoise(2e-4, band_limit_hz=None)          # the idealized spectrum (its closed forms)
    assert wn.psd(0.0) == wn.psd(123.0) == pytest.approx(2e-4)
    f = wn.filter()
    assert f.A.shape == (0, 0) and float(f.D) == 1.0


@pytest.mark.parametrize("order", [0, 1, 2, 4])
def test_the_spectral_moments_are_the_band_limited_integrals(order):
    wn, cutoff = WhiteNoise(2e-4, band_limit_hz=None), 60.0
    two_sided = 2 * integrate.quad(lambda w: w**order * 2e-4, 0.0, cutoff)[0]
    assert wn.spectral_moment(order, cutoff) == pytest.approx(two_sided, rel=1e-12)


def test_a_non_positive_intensity_is_refused():
    with pytest.raises(ValueError, match="^parameter 'S0'"):
        WhiteNoise(0.0)
