"""The Gaussian-quadrature tables of a condensation without closed forms (screening.core.condensation.quadrature).

The nodes against scipy's adaptive quadrature of the half-Gaussian moments, with and without a capacity angle
(whose square-root substitution must still integrate smooth functions); the expectations of eq. (31) against
their closed forms for quadratic ``C`` and ``K`` (``E[x^2] = 1``, ``E[x^4] = 3``, ``E[x^6] = 15`` of a standard
Gaussian ``x = theta / sigma``), values and slopes in ``ln(sigma)`` over five decades of ``sigma``.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from screening.core.condensation import quadrature as quad

THETA_UL = 1.0372e-3


def _half_gaussian(sigma, theta):
    return 2.0 * np.exp(-0.5 * (theta / sigma) ** 2) / (sigma * math.sqrt(2.0 * math.pi))


@pytest.mark.parametrize("theta_cap", [math.inf, 5.0 * THETA_UL])
@pytest.mark.parametrize("sigma", [1e-6, 3e-5, 1e-3, 8e-3])
@pytest.mark.parametrize("power", [0, 2, 3, 4])
def test_the_nodes_integrate_half_gaussian_moments_as_scipy_does(theta_cap, sigma, power):
    theta, weight = quad.theta_quadrature(THETA_UL, theta_cap, quad.SIGMA_SPAN * 8e-3)
    assert np.all(theta > 0) and np.all(weight > 0)
    expected = integrate.quad(lambda t: t ** power * _half_gaussian(sigma, t), 0.0, quad.SIGMA_SPAN * sigma,
                              points=[THETA_UL] if THETA_UL < quad.SIGMA_SPAN * sigma else None,
                              epsabs=0.0, epsrel=1e-12, limit=200)[0]
    assert float(weight @ (theta ** power * _half_gaussian(sigma, theta))) == pytest.approx(expected, rel=1e-9)


def test_the_expectations_of_quadratic_coefficients_are_their_gaussian_moments():
    c0, a, k0, b = 2.0, 5e4, 1e3, -3e7            # C = c0 + a theta^2, K = k0 + b theta^2
    theta, weight = quad.theta_quadrature(THETA_UL, math.inf, quad.SIGMA_SPAN * 1e-2)
    sigma = np.geomspace(1e-6, 1e-2 / 1.01, 11)
    values, slopes = quad.gaussian_expectations(sigma, theta, weight, c0 + a * theta ** 2, k0 + b * theta ** 2,
                                                c0, k0)
    s2 = sigma ** 2
    np.testing.assert_allclose(values[:, 0], c0 + a * s2, rtol=1e-10)             # E[C]
    np.testing.assert_allclose(values[:, 1], k0 + 3 * b * s2, rtol=1e-10)         # E[K x^2]
    np.testing.assert_allclose(values[:, 2], 2 * a, rtol=1e-10)                   # E[(C - C0)(x^2 - 1)] / sigma^2
    np.testing.assert_allclose(slopes[:, 0], 2 * a * s2, rtol=1e-9)
    np.testing.assert_allclose(slopes[:, 1], 6 * b * s2, rtol=1e-9)
    np.testing.assert_allclose(slopes[:, 2], 0.0, atol=1e-8 * a)
