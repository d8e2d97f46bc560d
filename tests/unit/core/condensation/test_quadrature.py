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


def test_the_compiled_sums_equal_numpys_formulas_and_each_row_has_its_own_bits():
    c0, a, k0, b = 2.0, 5e4, 1e3, -3e7            # C = c0 + a theta^2, K = k0 + b theta^2
    theta, weight = quad.theta_quadrature(THETA_UL, 5.0 * THETA_UL, quad.SIGMA_SPAN * 1e-2)
    c, k = c0 + a * theta ** 2, k0 + b * theta ** 2
    sigma = np.geomspace(1e-8, 1e-2 / 1.01, 101)
    values, slopes = quad.gaussian_expectations(sigma, theta, weight, c, k, c0, k0)
    # the formulas on the whole (sigma, node) array at once (numpy's pairwise sums: the tables' numbers until
    # 2026-11; the compiled loop sums in node order, so the two differ by the rounding of the sums only)
    s = sigma[:, None]
    x2 = (theta[None, :] / s) ** 2
    phi = (2.0 / math.sqrt(2.0 * math.pi)) * weight[None, :] * np.exp(-0.5 * x2) / s
    he2 = phi * (x2 - 1.0)
    inv_s2 = 1.0 / sigma ** 2
    ref_values = np.stack([np.sum(phi * c, axis=1), np.sum(phi * x2 * k, axis=1),
                           np.sum(he2 * (c - c0), axis=1) * inv_s2], axis=1)
    ref_slopes = np.stack([np.sum(he2 * (c - c0), axis=1), np.sum(phi * x2 * (x2 - 3.0) * (k - k0), axis=1),
                           np.sum(phi * (x2 * (x2 - 6.0) + 3.0) * (c - c0), axis=1) * inv_s2], axis=1)
    # rounding bound of a sum of n terms: n eps times the sum of the terms' magnitudes (the slopes cancel)
    eps = np.finfo(float).eps * theta.size
    bound_v = np.stack([np.sum(np.abs(phi * c), axis=1), np.sum(np.abs(phi * x2 * k), axis=1),
                        np.sum(np.abs(he2 * (c - c0)), axis=1) * inv_s2], axis=1) * eps
    bound_s = np.stack([np.sum(np.abs(he2 * (c - c0)), axis=1), np.sum(np.abs(phi * x2 * (x2 - 3.0) * (k - k0)), axis=1),
                        np.sum(np.abs(phi * (x2 * (x2 - 6.0) + 3.0) * (c - c0)), axis=1) * inv_s2], axis=1) * eps
    assert np.all(np.abs(values - ref_values) <= bound_v)
    assert np.all(np.abs(slopes - ref_slopes) <= bound_s)
    # a row's numbers do not depend on the other rows computed with it (a batch's table, any process)
    part_values, part_slopes = quad.gaussian_expectations(sigma[37:40], theta, weight, c, k, c0, k0)
    np.testing.assert_array_equal(part_values, values[37:40])
    np.testing.assert_array_equal(part_slopes, slopes[37:40])


def test_a_point_met_again_reuses_its_table_and_the_cache_is_bounded():
    from screening.core.condensation import get
    from screening.core.model import Block, Foundation
    from screening.core.model.points import flatten

    cond = get("virtual_work")
    quad._TABLES.clear()
    (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=0.21),
                              Foundation(k=2.89e7, lam=8.95e8, eps=np.linspace(0.0, 6e7, quad.TABLE_CACHE_SIZE + 3)))
    kernel = quad.moment_kernel(block, bed, cond)
    assert len(quad._TABLES) == quad.TABLE_CACHE_SIZE and kernel.table_index.tolist() == list(range(bed.eps.size))
    newest = next(reversed(quad._TABLES.values()))[0]
    again = quad.moment_kernel(*(flatten(Block(m=8.67, b=0.035, h=0.21),
                                         Foundation(k=2.89e7, lam=8.95e8, eps=6e7))[0]), cond)
    assert next(reversed(quad._TABLES.values()))[0] is newest and not newest.flags.writeable
    np.testing.assert_array_equal(again.tables[0], kernel.tables[-1][:again.tables.shape[1]])


def test_the_solver_reads_the_interpolant_of_the_table_without_a_logarithm(paper_block, cubic_bed):
    from screening.core.condensation import get

    cond = get("virtual_work")
    table = quad.coefficient_table(paper_block, cubic_bed, cond)
    c0, k0 = float(cond.damping_at_rest(paper_block, cubic_bed)), float(cond.stiffness_at_rest(paper_block, cubic_bed))
    solver_table = quad.octave_table(table, c0, k0)
    n_buckets = solver_table.shape[0] // 2
    ends = (*table[0, 0::4][:3], *table[-1, 0::4][:3])
    rng = np.random.default_rng(5)
    t = np.concatenate([rng.uniform(quad.T_LO - 3, quad.T_LO + (table.shape[0] + 60) / quad.STEPS_PER_UNIT, 3000),
                        quad.T_LO + np.arange(table.shape[0]) / quad.STEPS_PER_UNIT])     # and every node
    got = np.array([quad.octave_lookup_jit(math.exp(2 * x), solver_table, c0, k0, *ends, n_buckets) for x in t])
    ref = np.array([quad.table_lookup(x, table, c0, k0) for x in t])
    # within the rounding of the logarithm that table_lookup takes (its t carries ~1e-13 absolute): measured
    # 1e-13 K(0) in e_k and up to 4e-12 relative in e_c and d_c on the softening beds, where they are steepest
    np.testing.assert_allclose(got[:, 0], ref[:, 0], rtol=1e-11)
    np.testing.assert_allclose(got[:, 1], ref[:, 1], rtol=0, atol=1e-12 * abs(k0))
    np.testing.assert_allclose(got[:, 2], ref[:, 2], rtol=0, atol=1e-11 * np.abs(ref[:, 2]).max())
    assert quad.octave_lookup_jit(0.0, solver_table, c0, k0, *ends, n_buckets) == (c0, k0, table[0, 8])


def test_distinct_points_are_found_as_point_key_finds_them():
    from screening.core.model import Block, Foundation
    from screening.core.model.points import flatten, point_key, select

    rng = np.random.default_rng(3)
    (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=rng.choice([0.21, 0.3], 40)),
                              Foundation(k=2.89e7, lam=8.95e8, eps=rng.choice([0.0, -0.0, 6e7, -6e5], 40)))
    first, index = quad._distinct_points(block, bed)
    keys = [point_key(select(block, i), select(bed, i)) for i in range(40)]
    order = list(dict.fromkeys(keys))                       # distinct keys in order of appearance
    assert [keys[i] for i in first] == order
    assert [order.index(key) for key in keys] == index.tolist()


#: (eps [m-2], S0 [m2 s-3], peak var_theta [rad2] of virtual_work, of cubic), 20 s of the paper block's white
#: noise, solved 2026-11-29 before the tables were built faster (issue 38: results within 1e-6 relative).
PEAKS_BEFORE = [
    (-6e5, 1e-05, 1.1626353530696153e-07, 1.1628040935959838e-07),
    (-6e5, 0.00015491933384829674, 2.7363182166009012e-06, 2.4767384243862114e-06),
    (-6e5, 0.00096274077986829, 0.00019250205797083242, 7.78540636532256e-05),
    (-6e5, 0.0024, 0.0036869009057764134, 0.0009326106157440177),
    (2.97e7, 1e-05, 1.0676494233032789e-07, 1.0627960497090722e-07),
    (2.97e7, 0.00015491933384829674, 3.0754715620297885e-06, 2.663141065789832e-06),
    (2.97e7, 0.00096274077986829, 0.0003621231962031293, 0.00023281976502764417),
    (6e7, 1e-05, 1.0042889309058819e-07, 9.981783153840936e-08),
    (6e7, 0.00015491933384829674, 3.326430222980717e-06, 2.861944464681202e-06),
    (6e7, 0.00096274077986829, 0.000445742006764719, 0.0003559072424586905),
]


def test_the_peak_variances_are_those_of_the_tables_before_they_were_built_faster():
    from screening.core.condensation import get
    from screening.core.excitations.white import WhiteNoise
    from screening.core.model import Block, Foundation
    from screening.solvers.moments import solve_moments
    from screening.solvers.timegrid import output_times

    eps, s0, *before = (np.array(column) for column in zip(*PEAKS_BEFORE))
    for name, peak in zip(("virtual_work", "cubic"), before):
        quad._TABLES.clear()
        res = solve_moments(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, eps), WhiteNoise(s0, band_limit_hz=None),
                            output_times(20.0, 0.05), condensation=get(name), histories=False)
        assert np.all(res["status"] == 0)
        np.testing.assert_allclose(res["peak_var_theta"], peak, rtol=1e-6)
