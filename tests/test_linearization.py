"""Closed-form c_eq, k_eq against an independent quadrature of their definition (eq. 31).

Independent route: Gaussian regression form E[grad g] = Cov^-1 E[g(y) y] (Stein's lemma),
which needs no derivative of the piecewise C, K.  With theta' | theta Gaussian, E[g y]
reduces to 1-d integrals over theta, done by adaptive quadrature split at +-theta_ul.
"""

import numpy as np
import pytest
from scipy import integrate, special

from screening.condensed import rocking_damping, restoring_moment, uplift_threshold
from screening.linearization import (equivalent_coefficients, equivalent_coefficients_from_moments,
                                     gaussian_uplift_integrals, uplift_probability)


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
    """ERRATA: k_eq -> K1 + eps (6/5) k b^5 s^2 (not 2/5) while uplift is negligible."""
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
    if any_foundation.contact == "hunt_crossley":  # c_eq ~ s^-1/2 (Winkler: s^-3/2 tail, s^-1 overall)
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
