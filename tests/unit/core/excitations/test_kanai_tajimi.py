"""Kanai-Tajimi noise (screening.core.excitations.kanai_tajimi): filter, PSD (eq. 50) and stationary moments,
each against an independent computation."""

import numpy as np
import pytest
from scipy import integrate

from screening.core.excitations.base import stationary_covariance, transfer_psd
from screening.core.excitations.kanai_tajimi import (KanaiTajimi, kanai_tajimi_filter, kanai_tajimi_psd,
                                                     kanai_tajimi_stationary_moments, stationary_filter_moments_jit)

S0, WG, ZG = 3e-4, 12.0, 0.45


def test_the_closed_form_psd_is_the_filters_transfer_function():
    w = np.array([0.0, 1.0, WG, 30.0, 200.0])
    np.testing.assert_allclose(kanai_tajimi_psd(w, S0, WG, ZG), transfer_psd(kanai_tajimi_filter(WG, ZG), S0, w),
                               rtol=1e-12)
    assert kanai_tajimi_psd(0.0, S0, WG, ZG) == pytest.approx(S0)


def test_the_stationary_moments_are_the_lyapunov_covariance_and_the_output_variance_the_psd_integral():
    var_u, var_u_dot, var_z = kanai_tajimi_stationary_moments(S0, WG, ZG)
    p = stationary_covariance(kanai_tajimi_filter(WG, ZG), S0)
    np.testing.assert_allclose(np.diag(p), [var_u, var_u_dot], rtol=1e-12)
    assert abs(p[0, 1]) < 1e-12 * var_u_dot
    total = 2 * integrate.quad(lambda w: kanai_tajimi_psd(w, S0, WG, ZG), 0, np.inf, limit=400, epsabs=0)[0]
    assert var_z == pytest.approx(total, rel=1e-7)
    assert stationary_filter_moments_jit(S0, WG, ZG) == pytest.approx((var_u, var_u_dot), rel=1e-15)


def test_the_excitation_object_uses_its_closed_forms_and_refuses_bad_parameters():
    kt = KanaiTajimi(S0, WG, ZG, band_limit_hz=None)     # the closed forms are the idealized spectrum's
    assert kt.psd(5.0) == pytest.approx(kanai_tajimi_psd(5.0, S0, WG, ZG))
    np.testing.assert_allclose(np.diag(kt.stationary_covariance()), kanai_tajimi_stationary_moments(S0, WG, ZG)[:2])
    with pytest.raises(ValueError, match="^parameter 'zeta_g'"):
        KanaiTajimi(S0, WG, -0.1)
