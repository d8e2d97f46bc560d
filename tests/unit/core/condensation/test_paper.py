"""C(theta), K(theta) (eqs. 24-25 and the Winkler derivation) against quadrature of the law.

Independent route: small-angle kinematics, z(eta) = z_st(theta) + (b - eta) theta and
zdot(eta) = z_st'(theta) theta' + (b - eta) theta' over the actual contact zone z > 0,
with z_st from eqs. (17)-(18); the moment about the base centre minus m g h theta must
equal C(theta) theta' + K(theta) theta.
"""

from functools import partial

import numpy as np
import pytest
from scipy import integrate

from screening.core.condensation import api
from screening.core.condensation.paper import (restoring_moment, rocking_damping, rocking_stiffness,
                                               static_indentation, uplift_threshold)
from screening.core.model import contact_pressure

#: the paper's condensation, pinned (the default is another); a ``condensation=`` argument overrides it
rocking_acceleration = partial(api.rocking_acceleration, condensation="paper")


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
                - restoring_moment(th, paper_block, any_foundation)) / paper_block.m_sdof
    assert rocking_acceleration(th, thd, ag, paper_block, any_foundation) == pytest.approx(expected)


# ---------------------------------------------------------------- cubic condensation
"""The "cubic" condensation against an independent route: the quasi-static z_cb is the
smallest root of the vertical force balance F(theta, z) = m g, with F integrated by
quadrature of the contact law over the actual contact zone (brentq, no closed form), its
slope by central differences of that root, and the moment by quadrature as above."""

from scipy import optimize  # noqa: E402

from screening.core.condensation import cubic, paper as condensed  # noqa: E402
from screening.core.physics.contact import rest_indentation  # noqa: E402
from screening.core.model import Foundation  # noqa: E402

from conftest import CUBIC_BEDS  # noqa: E402

def _contact_interval(theta, z, b):
    """Part of u in [-b, b] where z + u theta > 0 (small-angle kinematics, eqs. 1-2)."""
    if theta == 0:
        return (-b, b) if z > 0 else (0.0, 0.0)
    edge = -z / theta
    lo, hi = (max(edge, -b), b) if theta > 0 else (-b, min(edge, b))
    return (lo, hi) if hi > lo else (0.0, 0.0)


def _vertical_force(theta, z, block, foundation):
    """Stiffness part of F_cb [N] by quadrature of k z + eps k z^3 over the contact zone."""
    law = lambda u: foundation.k * (z + u * theta) * (1 + foundation.eps * (z + u * theta) ** 2)
    lo, hi = _contact_interval(theta, z, block.b)
    return integrate.quad(law, lo, hi, epsabs=0, epsrel=1e-13, limit=200)[0]


def _quasi_static_root(theta, block, foundation):
    """Smallest z with F(theta, z) = m g: first sign change on a scan, then brentq."""
    mg, a = block.m * block.g, abs(theta)
    f = lambda z: _vertical_force(theta, z, block, foundation) - mg
    lo = -block.b * a
    zs = lo + np.linspace(0.0, 1.0, 201)[1:] * (3 * mg / (2 * block.b * foundation.k) + 3 * block.b * a)
    for z in zs:
        if f(z) > 0:
            return optimize.brentq(f, lo, z, xtol=1e-22, rtol=1e-15, maxiter=500)
        lo = z
    raise AssertionError("no quasi-static root")


def _moment_by_quadrature(theta, theta_dot, z, z_dot, block, foundation):
    """Moment about the base centre of the law over the contact zone, minus m g h theta [N m]."""
    integrand = lambda u: float(contact_pressure(z + u * theta, z_dot + u * theta_dot, foundation)) * u
    lo, hi = _contact_interval(theta, z, block.b)
    total = integrate.quad(integrand, lo, hi, epsabs=0, epsrel=1e-13, limit=200)[0]
    return total - block.m * block.g * block.h * theta


@pytest.mark.parametrize("ratio", [0.2, 0.9, 1.2, 3.0, 40.0, -0.5, -2.5, -40.0])
def test_cubic_condensed_moment_matches_distributed_law(paper_block, cubic_bed, ratio):
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    theta, theta_dot = ratio * tu, 0.05
    cap = cubic.capacity_angle(paper_block, cubic_bed)
    if abs(theta) >= cap:                  # softening bed: test close below the capacity angle instead
        theta = np.sign(ratio) * 0.9 * cap
    z = _quasi_static_root(theta, paper_block, cubic_bed)
    dth = 1e-6 * abs(theta)
    z_dot = (_quasi_static_root(theta + dth, paper_block, cubic_bed)
             - _quasi_static_root(theta - dth, paper_block, cubic_bed)) / (2 * dth) * theta_dot
    z_got, dz_got = cubic.quasi_static_indentation(theta, paper_block, cubic_bed)
    assert z_got == pytest.approx(z, rel=1e-10)
    assert dz_got * np.sign(theta) * theta_dot == pytest.approx(z_dot, rel=1e-5, abs=1e-9 * abs(z) * 20)
    restoring = _moment_by_quadrature(theta, 0.0, z, 0.0, paper_block, cubic_bed)
    assert cubic.restoring_moment(theta, paper_block, cubic_bed) == pytest.approx(restoring, rel=1e-9)
    damping = _moment_by_quadrature(theta, theta_dot, z, z_dot, paper_block, cubic_bed) - restoring
    assert cubic.rocking_damping(theta, paper_block, cubic_bed) * theta_dot == pytest.approx(damping, rel=1e-5)


def test_cubic_threshold_is_where_the_quasi_static_root_reaches_b_theta(paper_block, cubic_bed):
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    for sign in (1.0, -1.0):
        z = _quasi_static_root(sign * tu, paper_block, cubic_bed)
        assert z == pytest.approx(paper_block.b * tu, rel=1e-10)
    z_lo, _ = cubic.quasi_static_indentation(0.99 * tu, paper_block, cubic_bed)
    z_hi, _ = cubic.quasi_static_indentation(1.01 * tu, paper_block, cubic_bed)
    assert z_lo > 0.99 * paper_block.b * tu and z_hi < 1.01 * paper_block.b * tu   # full contact / uplift


def test_cubic_rest_indentation_is_the_exact_static_indentation(paper_block, cubic_bed):
    z0 = cubic.rest_indentation(paper_block, cubic_bed)
    z_lin = paper_block.m * paper_block.g / (2 * paper_block.b * cubic_bed.k)
    roots = np.roots([cubic_bed.eps, 0.0, 1.0, -z_lin]) if cubic_bed.eps else np.array([z_lin])
    independent = min(r.real for r in roots if abs(r.imag) <= 1e-9 * abs(r) and r.real > 0)
    assert z0 == pytest.approx(independent, rel=1e-12)          # eigenvalue root, not Newton
    assert z0 == rest_indentation(paper_block, cubic_bed)
    z, dz = cubic.quasi_static_indentation(0.0, paper_block, cubic_bed)
    assert z == pytest.approx(z0, rel=1e-14) and dz == 0.0
    k0 = cubic.rocking_stiffness(0.0, paper_block, cubic_bed)
    assert k0 == pytest.approx(cubic.stiffness_at_rest(paper_block, cubic_bed), rel=1e-13)
    assert cubic.rocking_damping(0.0, paper_block, cubic_bed) == pytest.approx(
        cubic.damping_at_rest(paper_block, cubic_bed), rel=1e-13)


def test_cubic_z_c_and_moment_are_continuous_at_the_threshold(paper_block, cubic_bed):
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    below, above = tu * (1 - 1e-11), tu * (1 + 1e-11)
    for f in (lambda t: cubic.quasi_static_indentation(t, paper_block, cubic_bed)[0],
              lambda t: cubic.quasi_static_indentation(t, paper_block, cubic_bed)[1],
              lambda t: cubic.rocking_damping(t, paper_block, cubic_bed),
              lambda t: cubic.restoring_moment(t, paper_block, cubic_bed)):
        assert f(above) == pytest.approx(f(below), rel=1e-8)
        assert f(-above) == pytest.approx(f(-below), rel=1e-8)


def test_cubic_is_even_and_vectorised(paper_block, cubic_bed):
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    theta = np.array([0.3, 1.0, 2.0, 3.2]) * tu
    for f in (cubic.rocking_damping, cubic.rocking_stiffness):
        np.testing.assert_array_equal(f(theta, paper_block, cubic_bed), f(-theta, paper_block, cubic_bed))
        np.testing.assert_array_equal(f(theta, paper_block, cubic_bed),
                                      [f(t, paper_block, cubic_bed) for t in theta])
    beds = Foundation(k=2.89e7, lam=8.95e8, eps=np.array([-6e5, 6e7])[:, None])
    grid = cubic.rocking_stiffness(theta[None, :], paper_block, beds)
    assert grid.shape == (2, 4)
    for i, eps in enumerate([-6e5, 6e7]):
        np.testing.assert_array_equal(grid[i], cubic.rocking_stiffness(theta, paper_block,
                                                                       Foundation(k=2.89e7, lam=8.95e8, eps=eps)))


@pytest.mark.parametrize("bed", [Foundation(k=2.89e7, lam=8.95e8, eps=0.0), Foundation(k=2.89e7, c=2e3)])
def test_cubic_with_eps_zero_is_the_paper_condensation(paper_block, bed):
    tu = condensed.uplift_threshold(paper_block, bed)
    assert cubic.uplift_threshold(paper_block, bed) == pytest.approx(tu, rel=1e-15)
    theta = np.concatenate([np.linspace(-50, 50, 401), [1.0, -1.0, 1 + 1e-9]]) * tu
    for name in ("rocking_damping", "rocking_stiffness", "restoring_moment"):
        paper = getattr(condensed, name)(theta, paper_block, bed)
        np.testing.assert_allclose(getattr(cubic, name)(theta, paper_block, bed), paper, rtol=1e-12, atol=0)
        np.testing.assert_allclose(getattr(api, name)(theta, paper_block, bed, condensation="cubic"),
                                   paper, rtol=1e-12, atol=0)


def test_cubic_capacity_angle_of_a_softening_bed(paper_block):
    bed = CUBIC_BEDS["hc_capacity"]
    cap = cubic.capacity_angle(paper_block, bed)
    assert cap == pytest.approx(bed.k / (4 * 2e7 * paper_block.m * paper_block.g), rel=1e-14)
    # the largest force the uplifting contact can give (v^2 = 1/|eps|) straddles m g at theta_cap
    v_peak = 1 / np.sqrt(2e7)
    for factor, carries in ((0.99, True), (1.01, False)):
        theta = factor * cap
        f_peak = _vertical_force(theta, v_peak - paper_block.b * theta, paper_block, bed)
        assert (f_peak > paper_block.m * paper_block.g) == carries
    assert cubic.in_equilibrium([0.99 * cap, -1.01 * cap], paper_block, bed).tolist() == [True, False]
    assert cubic.capacity_angle(paper_block, CUBIC_BEDS["hc_hardening"]) == np.inf


@pytest.mark.parametrize("name", ["hc_capacity", "winkler_softening"])
def test_cubic_beyond_capacity_holds_the_peak_load_without_rate(paper_block, name):
    bed = CUBIC_BEDS[name]
    cap = cubic.capacity_angle(paper_block, bed)
    for theta in (1.2 * cap, -3.0 * cap):
        z = 1 / np.sqrt(2e7) - paper_block.b * abs(theta)
        z_got, dz = cubic.quasi_static_indentation(theta, paper_block, bed)
        assert z_got == pytest.approx(z, rel=1e-12) and dz == 0.0
        restoring = _moment_by_quadrature(theta, 0.0, z, 0.0, paper_block, bed)
        damping = _moment_by_quadrature(theta, 0.1, z, 0.0, paper_block, bed) - restoring
        assert cubic.restoring_moment(theta, paper_block, bed) == pytest.approx(restoring, rel=1e-9)
        c = cubic.rocking_damping(theta, paper_block, bed)
        assert c > 0 and c * 0.1 == pytest.approx(damping, rel=1e-9)
    # K theta is continuous at the capacity angle (with a sqrt(cap - theta) approach), C grows
    # without bound just below it
    jumps = [abs(cubic.restoring_moment(cap * (1 + d), paper_block, bed)
                 / cubic.restoring_moment(cap * (1 - d), paper_block, bed) - 1) for d in (1e-8, 1e-12)]
    assert jumps[1] < 1e-5 and jumps[1] < 0.03 * jumps[0]
    below = cap * (1 - 1e-10)
    if not bed.winkler:
        assert cubic.rocking_damping(below, paper_block, bed) > 10 * cubic.rocking_damping(0.5 * cap, paper_block, bed)


def test_cubic_rejects_a_bed_that_cannot_carry_the_block_through_uplift(paper_block):
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=-3e8)     # |eps| z_lin^2 = 0.53 > 2/27
    for f in (cubic.uplift_threshold, cubic.rest_indentation, cubic.damping_at_rest):
        with pytest.raises(ValueError, match="'foundation.eps'.*2/27"):
            f(paper_block, bed)
    with pytest.raises(ValueError, match="'foundation.eps'"):
        api.rocking_stiffness(0.001, paper_block, bed, condensation="cubic")
    # the limit is sharp: 2/27 (1 - 1e-6) still has a threshold, on the rising branch
    z_lin = cubic.linear_indentation(paper_block, bed)
    edge = Foundation(k=2.89e7, lam=8.95e8, eps=-2 / 27 * (1 - 1e-6) / z_lin**2)
    y = paper_block.b * cubic.uplift_threshold(paper_block, edge)
    assert y + 2 * edge.eps * y**3 == pytest.approx(z_lin, rel=1e-12)
    assert 1 + 6 * edge.eps * y * y > 0


@pytest.mark.parametrize("bad", ["exact", "Paper", None, 1])
def test_unknown_condensation_is_rejected(paper_block, bad):
    bed = CUBIC_BEDS["hc_hardening"]
    for f in (lambda: api.uplift_threshold(paper_block, bed, bad),
              lambda: api.rocking_damping(0.001, paper_block, bed, condensation=bad),
              lambda: api.rocking_acceleration(0.001, 0.1, 0.2, paper_block, bed, condensation=bad)):
        with pytest.raises(ValueError, match=r"'condensation'.*\('paper', 'cubic', 'virtual_work'\)"):
            f()


def test_condensed_equation_of_motion_with_cubic_condensation(paper_block):
    bed = CUBIC_BEDS["hc_hardening"]
    th, thd, ag = 2e-3, 0.1, 0.7
    expected = (8.67 * 0.21 * ag - cubic.rocking_damping(th, paper_block, bed) * thd
                - cubic.restoring_moment(th, paper_block, bed)) / paper_block.m_sdof
    got = rocking_acceleration(th, thd, ag, paper_block, bed, condensation="cubic")
    assert got == pytest.approx(expected, rel=1e-14)
    assert got != pytest.approx(rocking_acceleration(th, thd, ag, paper_block, bed), rel=1e-3)


@pytest.mark.parametrize("bed", [Foundation(k=2.89e7, lam=8.95e8, eps=6e7), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5),
                                 Foundation(k=1e9, c=3e4, eps=2e9)])
def test_the_compiled_record_takes_c_and_k_at_rest_from_their_one_home(paper_block, bed):
    """sdof_record's C1 and K1_0 are the condensation's damping and stiffness at rest (bit for bit), and those
    are the rate and rotation derivatives at rest of the moment of the contact pressure about the base
    centre at the static indentation m g / (2 b k) (eqs. (24)-(25) at theta = 0), by quadrature, less m g h."""
    b, z = paper_block.b, paper_block.m * paper_block.g / (2 * paper_block.b * bed.k)

    def central_difference(pressure):          # of the moment, the quadrature of the difference of the pressures
        return integrate.quad(lambda x: pressure(x) * x, -b, b, epsabs=0.0, epsrel=1e-12)[0]

    d = 1e-9
    k_rest = central_difference(lambda x: (contact_pressure(z + x * d, 0.0, bed)
                                           - contact_pressure(z - x * d, 0.0, bed)) / (2 * d))
    k_rest -= paper_block.m * paper_block.g * paper_block.h
    c_rest = central_difference(lambda x: (contact_pressure(z, x, bed) - contact_pressure(z, -x, bed)) / 2.0)
    rec = condensed.sdof_record(paper_block, bed)
    assert rec["C1"][0] == condensed.PAPER.damping_at_rest(paper_block, bed)
    assert rec["K1_0"][0] == condensed.PAPER.stiffness_at_rest(paper_block, bed)
    assert rec["C1"][0] == pytest.approx(c_rest, rel=1e-9)
    assert rec["K1_0"][0] == pytest.approx(k_rest, rel=1e-8)      # the difference quotient: ~1e-10
