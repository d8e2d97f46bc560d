"""The Gaussian-quadrature tables of a condensation without closed forms (screening.condensation.quadrature).

The nodes against scipy's adaptive quadrature of the half-Gaussian moments, with and without a capacity angle
(whose square-root substitution must still integrate smooth functions); the expectations of eq. (31) against
their closed forms for quadratic ``C`` and ``K`` (``E[x^2] = 1``, ``E[x^4] = 3``, ``E[x^6] = 15`` of a standard
Gaussian ``x = theta / sigma``), values and slopes in ``ln(sigma)`` over five decades of ``sigma``.
"""

import math

import numba
import numpy as np
import pytest
from scipy import integrate

from screening.condensation import quadrature as quad

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


def test_the_compiled_sums_are_numpys_and_their_second_derivatives_the_closed_forms():
    c0, a, k0, b = 2.0, 5e4, 1e3, -3e7            # C = c0 + a theta^2, K = k0 + b theta^2
    theta, weight = quad.theta_quadrature(THETA_UL, math.inf, quad.SIGMA_SPAN * 1e-2)
    c, k = c0 + a * theta ** 2, k0 + b * theta ** 2
    sigma = np.geomspace(1e-6, 1e-2 / 1.01, 11)
    values, slopes, curvatures = quad.gaussian_expectations_jit(sigma, theta, weight, c, k, c0, k0)
    ref_values, ref_slopes = quad.gaussian_expectations(sigma, theta, weight, c, k, c0, k0)
    np.testing.assert_allclose(values, ref_values, rtol=1e-12)
    np.testing.assert_allclose(slopes, ref_slopes, rtol=1e-12, atol=1e-12 * a)
    s2 = sigma ** 2                               # d2/d ln(sigma)2 of c0 + a s2, k0 + 3 b s2, 2 a
    np.testing.assert_allclose(curvatures[:, 0], 4 * a * s2, rtol=1e-9)
    np.testing.assert_allclose(curvatures[:, 1], 12 * b * s2, rtol=1e-9)
    np.testing.assert_allclose(curvatures[:, 2], 0.0, atol=1e-8 * a)


@numba.njit
def _exps(y):
    out = np.empty(y.size)
    for i in range(y.size):
        out[i] = quad._exp_nonpositive(y[i])
    return out


def test_the_vectorisable_exponential_is_within_a_rounding_of_libms():
    y = np.concatenate([-np.random.default_rng(0).uniform(0.0, 700.0, 20000), [0.0, -0.5 * quad.SIGMA_SPAN ** 2]])
    got = _exps(y)
    assert np.max(np.abs(got / np.exp(y) - 1)) <= 2.3e-16 * 1.5
    assert got[-2] == 1.0


def test_a_point_met_again_reuses_its_table_and_the_cache_is_bounded():
    from screening.condensation import get
    from screening.model import Block, Foundation
    from screening.model.points import flatten

    cond = get("virtual_work")
    quad._TABLES.clear()
    (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=0.21),
                              Foundation(k=2.89e7, lam=8.95e8, eps=np.linspace(0.0, 6e7, quad.TABLE_CACHE_SIZE + 3)))
    tables, index = quad.coefficient_tables(block, bed, cond)
    assert len(quad._TABLES) == quad.TABLE_CACHE_SIZE and index.tolist() == list(range(bed.eps.size))
    newest = next(reversed(quad._TABLES.values()))
    again, _ = quad.coefficient_tables(*(flatten(Block(m=8.67, b=0.035, h=0.21),
                                                 Foundation(k=2.89e7, lam=8.95e8, eps=6e7))[0]), cond)
    assert next(reversed(quad._TABLES.values())) is newest and not newest.flags.writeable
    np.testing.assert_array_equal(again[0], tables[-1])


def test_distinct_points_are_found_as_point_key_finds_them():
    from screening.model import Block, Foundation
    from screening.model.points import flatten, point_key, select

    rng = np.random.default_rng(3)
    (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=rng.choice([0.21, 0.3], 40)),
                              Foundation(k=2.89e7, lam=8.95e8, eps=rng.choice([0.0, -0.0, 6e7, -6e5], 40)))
    first, index = quad._distinct_points(block, bed)
    keys = [point_key(select(block, i), select(bed, i)) for i in range(40)]
    order = list(dict.fromkeys(keys))                       # distinct keys in order of appearance
    assert [keys[i] for i in first] == order
    assert [order.index(key) for key in keys] == index.tolist()
