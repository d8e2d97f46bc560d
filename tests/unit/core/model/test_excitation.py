import numpy as np
import pytest
from scipy import integrate

from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi, kanai_tajimi_stationary_moments
from screening.core.excitations.white import WhiteNoise


def test_envelope_peaks_at_one_at_4_ln2():
    q = Envelope(4.0, 2.0)
    t = np.linspace(0, 20, 200001)
    assert q(0.0) == 0.0
    assert t[np.argmax(q(t))] == pytest.approx(4 * np.log(2), abs=1e-4)
    assert q(t).max() == pytest.approx(1.0, rel=1e-9)


@pytest.mark.parametrize("T1, T2", [(2.0, 2.0), (2.0, 3.0), (0.0, -1.0), (np.nan, 1.0)])
def test_envelope_rejects_bad_times(T1, T2):
    with pytest.raises(ValueError, match="T1|T2"):
        Envelope(T1, T2)


def test_constant_envelope_is_one():
    assert np.all(ConstantEnvelope()(np.linspace(0, 5, 7)) == 1.0)


@pytest.mark.parametrize("make, name", [
    (lambda: WhiteNoise(0.0), "'S0'"),
    (lambda: WhiteNoise(-1e-3), "'S0'"),
    (lambda: KanaiTajimi(1e-3, 10.0, 0.0), "'zeta_g'"),
    (lambda: KanaiTajimi(1e-3, -1.0, 0.4), "'omega_g'"),
    (lambda: KanaiTajimi(np.inf, 10.0, 0.4), "'S0'"),
])
def test_excitation_rejects_bad_values(make, name):
    with pytest.raises(ValueError, match=name):
        make()


@pytest.mark.parametrize("wg, zg", [(10.0, 0.4), (15.6, 0.6), (3.0, 0.05)])
def test_kanai_tajimi_output_variance_matches_integral_of_psd(wg, zg):
    kt = KanaiTajimi(2.0e-4, wg, zg, band_limit_hz=None)   # the closed form is the idealized spectrum's
    total = integrate.quad(kt.psd, -np.inf, np.inf, epsabs=0, epsrel=1e-11, limit=500)[0]
    assert kanai_tajimi_stationary_moments(2.0e-4, wg, zg)[2] == pytest.approx(total, rel=1e-8)


def test_kanai_tajimi_filter_moments_match_frequency_domain():
    S0, wg, zg = 3.0e-4, 12.0, 0.3
    H2 = lambda w: 1.0 / ((wg**2 - w**2) ** 2 + (2 * zg * wg * w) ** 2)
    var_u = integrate.quad(lambda w: S0 * H2(w), -np.inf, np.inf, epsrel=1e-11)[0]
    var_ud = integrate.quad(lambda w: S0 * w**2 * H2(w), -np.inf, np.inf, epsrel=1e-11)[0]
    vu, vud, _ = kanai_tajimi_stationary_moments(S0, wg, zg)
    assert vu == pytest.approx(var_u, rel=1e-8)
    assert vud == pytest.approx(var_ud, rel=1e-8)


def test_compiled_filter_moments_are_the_closed_form():
    from screening.core.excitations.kanai_tajimi import stationary_filter_moments_jit

    for S0, wg, zg in ((2e-4, 10.0, 0.4), (1e-12, 200.0, 0.01), (3.0, 0.5, 2.0)):
        var_u, var_ud, _ = kanai_tajimi_stationary_moments(S0, wg, zg)
        assert stationary_filter_moments_jit(S0, wg, zg) == (var_u, var_ud)
