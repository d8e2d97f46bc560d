"""C(theta), K(theta) (eqs. 24-25 and the Winkler derivation) against quadrature of the law.

Independent route: small-angle kinematics, z(eta) = z_st(theta) + (b - eta) theta and
zdot(eta) = z_st'(theta) theta' + (b - eta) theta' over the actual contact zone z > 0,
with z_st from eqs. (17)-(18); the moment about the base centre minus m g h theta must
equal C(theta) theta' + K(theta) theta.
"""

import numpy as np
import pytest
from scipy import integrate

from screening.condensed import (m_sdof, restoring_moment, rocking_acceleration,
                                 rocking_damping, rocking_stiffness, static_indentation,
                                 uplift_threshold)
from screening.model import contact_pressure


def _quadrature_moment(theta, theta_dot, block, foundation):
    b = block.b
    z_st = float(static_indentation(theta, block, foundation))
    dth = 1e-7 * max(abs(theta), 1e-9)
    dz_dtheta = float((static_indentation(theta + dth, block, foundation)
                       - static_indentation(theta - dth, block, foundation)) / (2 * dth))
    zcb_dot = dz_dtheta * theta_dot

    def integrand(eta):
        u = b - eta
        z = z_st + u * theta
        zd = zcb_dot + u * theta_dot
        return float(contact_pressure(z, zd, foundation)) * u

    # contact edge where z = 0
    edges = [0.0, 2 * b]
    if theta != 0:
        e = b + z_st / theta
        if 0 < e < 2 * b:
            edges.insert(1, e)
    total = sum(integrate.quad(integrand, a, c, epsabs=0, epsrel=1e-12, limit=200)[0]
                for a, c in zip(edges[:-1], edges[1:]))
    return total - block.m * block.g * block.h * theta


@pytest.mark.parametrize("ratio", [0.2, 0.9, 1.2, 3.0, 40.0, -0.5, -2.5, -40.0])
def test_condensed_moment_matches_distributed_law(paper_block, any_foundation, ratio):
    tu = uplift_threshold(paper_block, any_foundation)
    theta, theta_dot = ratio * tu, 0.05
    expected = _quadrature_moment(theta, theta_dot, paper_block, any_foundation)
    # restoring part alone (theta_dot = 0) and damping part
    restoring = _quadrature_moment(theta, 0.0, paper_block, any_foundation)
    assert restoring_moment(theta, paper_block, any_foundation) == pytest.approx(restoring, rel=1e-7)
    got = restoring + rocking_damping(theta, paper_block, any_foundation) * theta_dot
    assert got == pytest.approx(expected, rel=1e-6)


def test_damping_and_restoring_moment_continuous_at_threshold(paper_block, any_foundation):
    tu = uplift_threshold(paper_block, any_foundation)
    below, above = tu * (1 - 1e-12), tu * (1 + 1e-12)
    for f in (rocking_damping, restoring_moment):
        lo, hi = f(below, paper_block, any_foundation), f(above, paper_block, any_foundation)
        assert hi == pytest.approx(lo, rel=1e-9)


def test_uplift_threshold_eq19(paper_block, any_foundation):
    tu = uplift_threshold(paper_block, any_foundation)
    assert tu == pytest.approx(8.67 * 9.81 / (2 * 0.035**2 * any_foundation.k), rel=1e-14)
    # eq. 19: theta_ul = z_st / b at the threshold, and both branches of z_st agree there
    assert static_indentation(tu, paper_block, any_foundation) == pytest.approx(tu * 0.035, rel=1e-12)
    z_out = np.sqrt(2 * 8.67 * 9.81 * tu / any_foundation.k) - 0.035 * tu
    assert z_out == pytest.approx(tu * 0.035, rel=1e-12)


def test_no_uplift_stiffness_eq25(paper_block, any_foundation):
    k, eps = any_foundation.k, any_foundation.eps
    m, g, b, h = 8.67, 9.81, 0.035, 0.21
    th = 0.3 * uplift_threshold(paper_block, any_foundation)
    expected = 2 / 3 * b**3 * k - m * g * h + eps * (m**2 * g**2 * b / (2 * k) + 0.4 * k * b**5 * th**2)
    assert rocking_stiffness(th, paper_block, any_foundation) == pytest.approx(expected, rel=1e-13)


def test_condensed_equation_of_motion(paper_block, any_foundation):
    th, thd, ag = 2e-3, 0.1, 0.7
    expected = (8.67 * 0.21 * ag - rocking_damping(th, paper_block, any_foundation) * thd
                - restoring_moment(th, paper_block, any_foundation)) / m_sdof(paper_block)
    assert rocking_acceleration(th, thd, ag, paper_block, any_foundation) == pytest.approx(expected)
