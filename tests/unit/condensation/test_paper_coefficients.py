"""Closed-form c_eq, k_eq against an independent quadrature of their definition (eq. 31).

Independent route: Gaussian regression form E[grad g] = Cov^-1 E[g(y) y] (Stein's lemma),
which needs no derivative of the piecewise C, K.  With theta' | theta Gaussian, E[g y]
reduces to 1-d integrals over theta, done by adaptive quadrature split at +-theta_ul.
"""

import numpy as np
import pytest
from scipy import integrate, special

from functools import partial

from screening.condensation import api
from screening.condensation.paper import rocking_damping, restoring_moment, uplift_threshold

# the paper's condensation, pinned (the default is another)
equivalent_coefficients = partial(api.equivalent_coefficients, condensation="paper")
equivalent_coefficients_from_moments = partial(api.equivalent_coefficients_from_moments, condensation="paper")
uplift_probability = partial(api.uplift_probability, condensation="paper")
from screening.condensation.uplift_integrals import gaussian_uplift_integrals


def _regression_coefficients(s, sv, rho, block, foundation):
    tu = uplift_threshold(block, foundation)
    C = lambda th: float(rocking_damping(th, block, foundation))
    R = lambda th: float(restoring_moment(th, block, foundation))
    pdf = lambda th: np.exp(-0.5 * (th / s) ** 2) / (np.sqrt(2 * np.pi) * s)
    mean_v = lambda th: rho * sv * th / s
    mean_v2 = lambda th: sv**2 * (1 - rho**2) + mean_v(th) ** 2

    def expect(f):
        L = 40 * s
        edges = [-L] + [p for p in (-tu, 0.0, tu) if -L < p < L] + [L]
        return sum(integrate.quad(lambda th: f(th) * pdf(th), a, c, epsabs=0, epsrel=1e-13,
                                  limit=400)[0] for a, c in zip(edges[:-1], edges[1:]))

    e_g_theta = expect(lambda th: C(th) * mean_v(th) * th + R(th) * th)
    e_g_theta_dot = expect(lambda th: C(th) * mean_v2(th) + R(th) * mean_v(th))
    cov = rho * s * sv
    k_eq, c_eq = np.linalg.solve([[s * s, cov], [cov, sv * sv]], [e_g_theta, e_g_theta_dot])
    return c_eq, k_eq


@pytest.mark.parametrize("ratio", [1e-3, 0.1, 0.4, 1.0, 2.5, 30.0, 1e3])
@pytest.mark.parametrize("rho", [-0.95, -0.3, 0.0, 0.6, 0.95])
def test_closed_forms_match_quadrature_of_definition(paper_block, any_foundation, ratio, rho):
    tu = uplift_threshold(paper_block, any_foundation)
    s = ratio * tu
    sv = 42.0 * s
    c_ref, k_ref = _regression_coefficients(s, sv, rho, paper_block, any_foundation)
    c_eq, k_eq = equivalent_coefficients(s, sv, rho, paper_block, any_foundation)
    assert c_eq == pytest.approx(c_ref, rel=1e-6)
    assert k_eq == pytest.approx(k_ref, rel=1e-6)


def test_limits_at_zero_sigma_are_no_uplift_values(paper_block, any_foundation):
    c_eq, k_eq = equivalent_coefficients(0.0, 0.0, 0.0, paper_block, any_foundation)
    m, g, b, h, k, eps = 8.67, 9.81, 0.035, 0.21, any_foundation.k, any_foundation.eps
    c1 = rocking_damping(0.0, paper_block, any_foundation)
    assert np.isfinite(c_eq) and np.isfinite(k_eq)
    assert c_eq == pytest.approx(c1, rel=1e-14)
    assert k_eq == pytest.approx(2 / 3 * b**3 * k - m * g * h + eps * m**2 * g**2 * b / (2 * k), rel=1e-13)
    # the moment form starts the ODE from zero covariance
    c0, k0 = equivalent_coefficients_from_moments(0.0, 0.0, paper_block, any_foundation)
    assert (c0, k0) == (c_eq, k_eq)


def test_small_sigma_limit_keeps_the_cubic_secant_term(paper_block, any_foundation):
    """Corrected eq. (36) (docs/method.md): k_eq -> K1 + eps (6/5) k b^5 s^2 (not 2/5) while uplift is negligible."""
    s = 0.02 * uplift_threshold(paper_block, any_foundation)
    _, k_eq = equivalent_coefficients(s, 40 * s, 0.3, paper_block, any_foundation)
    _, k0 = equivalent_coefficients(0.0, 0.0, 0.0, paper_block, any_foundation)
    k, eps = any_foundation.k, any_foundation.eps
    assert k_eq - k0 == pytest.approx(eps * 1.2 * k * 0.035**5 * s**2, rel=1e-9, abs=1e-12 * abs(k0))


def test_large_sigma_limits(paper_block, any_foundation):
    tu = uplift_threshold(paper_block, any_foundation)
    m, g, b, h, k, eps = 8.67, 9.81, 0.035, 0.21, any_foundation.k, any_foundation.eps
    s = np.array([1e6, 1e8]) * tu
    c_eq, k_eq = equivalent_coefficients(s, 40 * s, 0.0, paper_block, any_foundation)
    assert np.all(np.diff(c_eq) < 0) and np.all(c_eq > 0)
    limit = -m * g * h + eps * m**2 * g**2 * b / k
    assert k_eq[-1] == pytest.approx(limit, rel=1e-3, abs=1e-3 * abs(m * g * h))
    if not any_foundation.winkler:  # c_eq ~ s^-1/2 (Winkler: s^-3/2 tail, s^-1 overall)
        assert c_eq[0] / c_eq[1] == pytest.approx(10.0, rel=1e-3)


def test_vectorised_over_moments_and_parameters(paper_block):
    from screening.model import Foundation
    eps = np.array([-6e5, 0.0, 6e7])[:, None]
    s = np.array([0.0, 1e-4, 1e-3, 1e-2])[None, :]
    fnd = Foundation(k=2.89e7, lam=8.95e8, eps=eps)
    c_eq, k_eq = equivalent_coefficients(s, 40 * s, 0.2, paper_block, fnd)
    assert c_eq.shape == k_eq.shape == (3, 4)
    for i in range(3):
        for j in range(4):
            ci, ki = equivalent_coefficients(s[0, j], 40 * s[0, j], 0.2, paper_block,
                                             Foundation(k=2.89e7, lam=8.95e8, eps=eps[i, 0]))
            assert (c_eq[i, j], k_eq[i, j]) == (ci, ki)


def test_gaussian_integrals_against_direct_quadrature():
    for r in [0.05, 0.3, 1.0, 7.0, 300.0]:
        G = gaussian_uplift_integrals(np.array(r))
        pdf = lambda u: np.exp(-0.5 * (u / r) ** 2) / (np.sqrt(2 * np.pi) * r)
        tail = lambda p: 2 * integrate.quad(lambda u: u**p * pdf(u), 1.0, np.inf, epsrel=1e-12)[0]
        assert G["tail_m12"] == pytest.approx(tail(-0.5), rel=1e-9)
        assert G["tail_m32"] == pytest.approx(tail(-1.5), rel=1e-9)
        inner = 2 * integrate.quad(lambda u: u**2 * pdf(u), 0, 1.0, epsrel=1e-12)[0]
        assert G["inner_m2"] == pytest.approx(inner, rel=1e-9)
        assert G["p_out"] == pytest.approx(tail(0.0), rel=1e-9)


def test_uplift_probability_eq58(paper_block, any_foundation):
    tu = uplift_threshold(paper_block, any_foundation)
    s = np.array([0.0, 0.5 * tu, tu, 10 * tu])
    p = uplift_probability(s, paper_block, any_foundation)
    assert p[0] == 0.0
    np.testing.assert_allclose(p[1:], special.erfc(tu / (np.sqrt(2) * s[1:])), rtol=1e-14)


# ---------------------------------------------------------------- cubic condensation
"""c_eq, k_eq of the "cubic" condensation (quadrature of eq. 31, tabulated per point) against
an independent quadrature of the regression form Cov^-1 E[g y] with scipy's adaptive quad
over theta (split at +-theta_ul and +-theta_cap), using the cubic C(theta), K(theta) that
tests/unit/condensation/test_paper.py checks against the distributed contact law."""

import math  # noqa: E402

from screening.condensation import api as linearization, cubic, quadrature as cl  # noqa: E402
from screening.condensation.paper import rocking_stiffness  # noqa: E402
from screening.model import Foundation  # noqa: E402

CUBIC = cubic.CUBIC


def _cubic_regression_coefficients(s, sv, rhos, block, foundation):
    tu = cubic.uplift_threshold(block, foundation)
    cap = cubic.capacity_angle(block, foundation)
    # the compiled scalar C, K of the Monte Carlo kernel (tested equal to the numpy ones in
    # tests/unit/solvers/test_montecarlo.py): same functions, ~50x faster callbacks for quad
    p = cubic.sdof_record(block, foundation)[0]
    C = lambda th: cubic.damping_stiffness_jit(p, th)[0]
    R = lambda th: cubic.damping_stiffness_jit(p, th)[1] * th
    pdf = lambda th: np.exp(-0.5 * (th / s) ** 2) / (np.sqrt(2 * np.pi) * s)

    def expect(f):
        L = 40 * s
        cuts = [p for p in (-cap, -tu, 0.0, tu, cap) if -L < p < L]
        edges = [-L] + cuts + [L]
        return sum(integrate.quad(lambda th: f(th) * pdf(th), a, c, epsabs=0, epsrel=1e-10, limit=400)[0]
                   for a, c in zip(edges[:-1], edges[1:]))

    e_c, e_ct2, e_rt = expect(C), expect(lambda th: C(th) * th * th), expect(lambda th: R(th) * th)
    out = []
    for rho in rhos:                       # E[theta' | theta] = rho sv theta / s
        q = rho * sv / s
        e_g_theta = q * e_ct2 + e_rt
        e_g_theta_dot = sv**2 * (1 - rho**2) * e_c + q * q * e_ct2 + q * e_rt
        cov = rho * s * sv
        k_eq, c_eq = np.linalg.solve([[s * s, cov], [cov, sv * sv]], [e_g_theta, e_g_theta_dot])
        out.append((c_eq, k_eq))
    return out


@pytest.mark.parametrize("ratio", [1e-3, 0.1, 0.4, 1.0, 2.5, 30.0, 1e3])
def test_cubic_coefficients_match_quadrature_of_definition(paper_block, cubic_bed, ratio):
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    s = ratio * tu
    sv = 42.0 * s
    rhos = [-0.95, 0.0, 0.6]
    refs = _cubic_regression_coefficients(s, sv, rhos, paper_block, cubic_bed)
    for rho, (c_ref, k_ref) in zip(rhos, refs):
        c_eq, k_eq = linearization.equivalent_coefficients(s, sv, rho, paper_block, cubic_bed, condensation="cubic")
        assert c_eq == pytest.approx(c_ref, rel=1e-6)
        assert k_eq == pytest.approx(k_ref, rel=1e-6)


def test_cubic_coefficients_at_zero_sigma_are_the_no_uplift_values(paper_block, cubic_bed):
    c_eq, k_eq = linearization.equivalent_coefficients(0.0, 0.0, 0.0, paper_block, cubic_bed, condensation="cubic")
    assert np.isfinite(c_eq) and np.isfinite(k_eq)
    assert c_eq == pytest.approx(float(cubic.rocking_damping(0.0, paper_block, cubic_bed)), rel=1e-13)
    assert k_eq == pytest.approx(float(cubic.rocking_stiffness(0.0, paper_block, cubic_bed)), rel=1e-13)
    c0, k0 = linearization.equivalent_coefficients_from_moments(0.0, 0.0, paper_block, cubic_bed,
                                                                condensation="cubic")
    assert (c0, k0) == (c_eq, k_eq)
    # continuous into sigma > 0, and the velocity-coupling term stays finite at small sigma
    s = 1e-7 * cubic.uplift_threshold(paper_block, cubic_bed)
    c1, k1 = linearization.equivalent_coefficients(s, 40 * s, 0.9, paper_block, cubic_bed, condensation="cubic")
    assert c1 == pytest.approx(c_eq, rel=1e-9) and k1 == pytest.approx(k_eq, rel=1e-9)


@pytest.mark.parametrize("ratio", [1e-3, 0.3, 1.0, 3.0, 100.0])
def test_cubic_with_eps_zero_reproduces_the_paper_closed_forms(paper_block, ratio):
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
    s = ratio * cubic.uplift_threshold(paper_block, bed)
    for rho in (-0.5, 0.0, 0.8):
        ref = linearization.equivalent_coefficients(s, 40 * s, rho, paper_block, bed, condensation="paper")
        got = linearization.equivalent_coefficients(s, 40 * s, rho, paper_block, bed, condensation="cubic")
        np.testing.assert_allclose(got, ref, rtol=1e-10)


def test_quadrature_engine_reproduces_the_paper_closed_forms(paper_block, any_foundation):
    """gaussian_expectations applied to the paper's C, K: exact closed forms (a check of the engine)."""
    tu = uplift_threshold(paper_block, any_foundation)
    theta, weight = cl.theta_quadrature(tu, np.inf, 12 * 500 * tu)
    C = rocking_damping(theta, paper_block, any_foundation)
    K = rocking_stiffness(theta, paper_block, any_foundation)
    c0 = float(rocking_damping(0.0, paper_block, any_foundation))
    k0 = float(rocking_stiffness(0.0, paper_block, any_foundation))
    s = tu * np.logspace(-4, np.log10(500), 60)
    values, _ = cl.gaussian_expectations(s, theta, weight, C, K, c0, k0)
    for rho in (-0.7, 0.0, 0.9):
        c_ref, k_ref = equivalent_coefficients(s, 40 * s, rho, paper_block, any_foundation)
        np.testing.assert_allclose(values[:, 0], c_ref, rtol=1e-11)
        np.testing.assert_allclose(values[:, 1] + rho * 40 * s * s * values[:, 2], k_ref, rtol=1e-10)


def test_cubic_table_matches_direct_quadrature_between_nodes(paper_block, cubic_bed):
    values, slopes = cl.node_values(paper_block, cubic_bed, CUBIC)
    table = cl.coefficient_table(paper_block, cubic_bed, CUBIC)
    assert table.shape == (values.shape[0], 12)
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    c0 = float(cubic.damping_at_rest(paper_block, cubic_bed))
    k0 = float(cubic.stiffness_at_rest(paper_block, cubic_bed))
    n = values.shape[0]
    assert n == cl.table_size(paper_block, cubic_bed, CUBIC)
    assert cl.T_LO + (n - 1) / cl.STEPS_PER_UNIT >= math.log(4 * paper_block.slenderness / tu)
    t = np.concatenate([cl.T_LO + (np.arange(0, n - 1, 3) + 0.5) / cl.STEPS_PER_UNIT, [-20.0, -13.0]])
    s = tu * np.exp(t)
    e_c, e_k, d_c = cl.expectations(s, paper_block, cubic_bed, CUBIC)
    cov = 0.9 * s * s * math.sqrt(k0 / paper_block.m_sdof)     # a strongly correlated state
    for i, ti in enumerate(t):
        got_c, got_k, got_d = cl.table_lookup(ti, table, c0, k0)
        assert got_c == pytest.approx(e_c[i], rel=1e-6)
        # k_eq = e_k + cov d_c crosses zero at large sigma: absolute floor 1e-9 K(0)
        assert got_k + cov[i] * got_d == pytest.approx(e_k[i] + cov[i] * d_c[i], rel=1e-6, abs=1e-9 * k0)
    assert cl.table_lookup(-np.inf, table, c0, k0)[:2] == (c0, k0)
    # nodes carry the exact d/d(ln sigma): check against central differences of the values
    h = 1.0 / cl.STEPS_PER_UNIT
    fd = (values[2:] - values[:-2]) / (2 * h)
    mid = slice(1, -1)
    scale = np.abs(values).max(axis=0)
    smooth = np.arange(1, n - 1) * h + cl.T_LO > 1.0      # well above the onset of uplift
    np.testing.assert_allclose(fd[smooth], slopes[mid][smooth], rtol=0, atol=2e-3 * scale.max())


@pytest.mark.parametrize("bad", ["exact", "", None])
def test_linearization_rejects_unknown_condensation(paper_block, bad):
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    with pytest.raises(ValueError, match=r"'condensation'.*\('paper', 'cubic', 'virtual_work'\)"):
        equivalent_coefficients(1e-3, 0.04, 0.0, paper_block, bed, condensation=bad)
    with pytest.raises(ValueError, match="'condensation'"):
        equivalent_coefficients_from_moments(1e-6, 0.0, paper_block, bed, condensation=bad)
