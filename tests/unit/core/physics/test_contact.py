"""Contact resultants (screening.core.physics.contact) against brute-force quadrature of the contact law."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from screening.core.physics.contact import (REGIME_FLIGHT, REGIME_FULL_CONTACT, REGIME_UPLIFT_NEGATIVE,
                                            REGIME_UPLIFT_POSITIVE, contact_length, contact_regime,
                                            contact_resultants, contact_resultants_jit, foundation_constants,
                                            rest_indentation)
from screening.core.model import Block, Foundation, contact_pressure

BLOCK = Block(m=8.67, b=0.035, h=0.21)
B = BLOCK.b
K = 2.89e7
Z_ST = BLOCK.m * BLOCK.g / (2.0 * B * K)          # ~4.2e-5 m

FOUNDATIONS = [Foundation(k=K, lam=8.95e8, eps=6e7), Foundation(k=K, lam=8.95e8, eps=-6e5),
               Foundation(k=K, lam=8.95e8, eps=0.0), Foundation(k=K, c=2.0e4, eps=6e7),
               Foundation(k=K, c=2.0e4, eps=-6e5)]
FOUNDATION_IDS = ["hc-eps+", "hc-eps-", "hc-eps0", "winkler-eps+", "winkler-eps-"]

# (theta [rad], theta_dot [rad/s], z_cb [m], z_cb_dot [m/s], expected regime)
STATES = [
    (2e-4, 0.05, Z_ST, 1e-3, REGIME_FULL_CONTACT),
    (-2e-4, -0.3, 2 * Z_ST, -2e-3, REGIME_FULL_CONTACT),
    (0.0, 0.4, Z_ST, 5e-4, REGIME_FULL_CONTACT),
    (0.15, 1.0, 0.02, 0.1, REGIME_FULL_CONTACT),          # large angle, deep: exact trig terms
    (5e-3, 0.2, -2e-5, 3e-3, REGIME_UPLIFT_POSITIVE),
    (0.05, -0.7, -1.2e-3, -1e-2, REGIME_UPLIFT_POSITIVE),
    (0.3, 2.0, -5e-3, 1e-2, REGIME_UPLIFT_POSITIVE),
    (-5e-3, 0.2, -2e-5, 3e-3, REGIME_UPLIFT_NEGATIVE),
    (-0.05, 0.7, -1.2e-3, -1e-2, REGIME_UPLIFT_NEGATIVE),
    (-0.3, -2.0, 1e-5, 1e-2, REGIME_UPLIFT_NEGATIVE),
    (0.01, 0.5, -4e-4, 1e-3, REGIME_FLIGHT),
    (-0.01, 0.5, -4e-4, 1e-3, REGIME_FLIGHT),
    (0.0, 0.0, -1e-6, 0.0, REGIME_FLIGHT),
]


def brute_force_resultants(theta, theta_dot, z_cb, z_cb_dot, foundation):
    """Eqs. (5)–(6) by adaptive quadrature of ``contact_pressure`` over ``eta in [0, 2b]`` (eqs. 1–4)."""
    s, c = math.sin(theta), math.cos(theta)
    z_b = z_cb + B * s
    z_b_dot = z_cb_dot + B * theta_dot * c

    def pressure(eta):
        return float(contact_pressure(z_b - eta * s, z_b_dot - eta * theta_dot * c, foundation))

    points = None
    if s != 0.0 and 0.0 < z_b / s < 2.0 * B:
        points = [z_b / s]                                 # where z changes sign
    opts = dict(points=points, epsabs=0.0, epsrel=1e-13, limit=200)
    force = quad(pressure, 0.0, 2.0 * B, **opts)[0]
    moment = quad(lambda eta: pressure(eta) * (B - eta) * c, 0.0, 2.0 * B, **opts)[0]
    return force, moment


def _scales(theta_dot, z_cb, z_cb_dot):
    """Absolute tolerances: rounding of the largest term in each integral."""
    big = abs(z_cb) + B
    return 1e-11 * (K * big * B * (1 + 6e7 * big**2) + 1e9 * big * (abs(z_cb_dot) + B * abs(theta_dot)) * B)


@pytest.mark.parametrize("foundation", FOUNDATIONS, ids=FOUNDATION_IDS)
@pytest.mark.parametrize("state", STATES, ids=[f"{s[4]}:{s[0]:+g}" for s in STATES])
def test_resultants_match_quadrature(state, foundation):
    theta, theta_dot, z_cb, z_cb_dot, regime = state
    assert int(contact_regime(theta, z_cb, B)) == regime
    f_ref, m_ref = brute_force_resultants(theta, theta_dot, z_cb, z_cb_dot, foundation)
    k, eps, damping, winkler = foundation_constants(foundation)
    f_vec, m_vec = contact_resultants(theta, theta_dot, z_cb, z_cb_dot, B, k, eps, damping, winkler)
    f_nb, m_nb = contact_resultants_jit(theta, theta_dot, z_cb, z_cb_dot, B, k, eps, damping, winkler)
    tol = _scales(theta_dot, z_cb, z_cb_dot)
    for f in (float(f_vec), f_nb):
        assert f == pytest.approx(f_ref, rel=1e-9, abs=tol)
    for m in (float(m_vec), m_nb):
        assert m == pytest.approx(m_ref, rel=1e-9, abs=tol * B)
    if regime == REGIME_FLIGHT:
        assert f_nb == 0.0 and m_nb == 0.0
    else:
        assert f_ref != 0.0  # the case is not trivially zero


def test_contact_length_by_regime():
    theta = np.array([1e-4, 0.01, -0.01, 0.01])
    z_cb = np.array([Z_ST, -1e-4, -1e-4, -1e-3])
    expected = np.array([2 * B, (-1e-4 + B * math.sin(0.01)) / math.sin(0.01),
                         (-1e-4 + B * math.sin(0.01)) / math.sin(0.01), 0.0])
    np.testing.assert_allclose(contact_length(theta, z_cb, B), expected, rtol=1e-14)


def test_vectorised_over_arrays_matches_scalar():
    rng = np.random.default_rng(3)
    n = 200
    theta = rng.uniform(-0.1, 0.1, n)
    theta_dot = rng.normal(0.0, 1.0, n)
    z_cb = rng.uniform(-3e-3, 3e-4, n)
    z_cb_dot = rng.normal(0.0, 1e-2, n)
    k, eps, lam, _ = foundation_constants(FOUNDATIONS[0])
    f, m = contact_resultants(theta, theta_dot, z_cb, z_cb_dot, B, k, eps, lam)
    assert f.shape == (n,) and m.shape == (n,)
    regimes = contact_regime(theta, z_cb, B)
    assert set(np.unique(regimes)) == {0, 1, 2, 3}       # all regimes exercised
    for i in range(n):
        fi, mi = contact_resultants_jit(theta[i], theta_dot[i], z_cb[i], z_cb_dot[i], B, k, eps, lam, False)
        assert fi == pytest.approx(f[i], rel=1e-12, abs=1e-9)
        assert mi == pytest.approx(m[i], rel=1e-12, abs=1e-11)


@settings(max_examples=200, deadline=None)
@given(theta=st.floats(-0.3, 0.3), theta_dot=st.floats(-3.0, 3.0), z_cb=st.floats(-1e-3, 1e-3),
       z_cb_dot=st.floats(-0.05, 0.05), winkler=st.booleans())
def test_mirror_symmetry(theta, theta_dot, z_cb, z_cb_dot, winkler):
    """F(theta, theta') = F(-theta, -theta') and M(theta, theta') = -M(-theta, -theta')."""
    damping = 2e4 if winkler else 8.95e8
    f1, m1 = contact_resultants_jit(theta, theta_dot, z_cb, z_cb_dot, B, K, 6e7, damping, winkler)
    f2, m2 = contact_resultants_jit(-theta, -theta_dot, z_cb, z_cb_dot, B, K, 6e7, damping, winkler)
    scale_f = abs(f1) + 1e-9
    assert abs(f1 - f2) <= 1e-12 * scale_f + 1e-12
    assert abs(m1 + m2) <= 1e-12 * (abs(m1) + 1e-9) + 1e-14


@pytest.mark.parametrize("theta", [0.02, -0.02])
def test_continuous_across_regime_boundaries(theta):
    """Force and moment are continuous where the far edge lifts and where the near edge lifts."""
    a = abs(math.sin(theta))
    k, eps, lam, _ = foundation_constants(FOUNDATIONS[0])
    for z_edge in (B * a, -B * a):                 # full<->uplift and uplift<->flight boundaries
        d = 1e-12
        below = contact_resultants_jit(theta, 0.3, z_edge - d, 1e-3, B, k, eps, lam, False)
        above = contact_resultants_jit(theta, 0.3, z_edge + d, 1e-3, B, k, eps, lam, False)
        at = contact_resultants_jit(theta, 0.3, z_edge, 1e-3, B, k, eps, lam, False)
        scale = abs(at[0]) + k * B * 1e-9
        assert abs(below[0] - above[0]) < 1e-6 * scale
        assert abs(below[1] - above[1]) < 1e-6 * scale * B


@pytest.mark.parametrize("eps", [6e7, 0.0, -6e5, -6e7])
def test_static_indentation_carries_the_weight(eps):
    foundation = Foundation(k=K, lam=8.95e8, eps=eps)
    z = rest_indentation(BLOCK, foundation)
    force, moment = contact_resultants_jit(0.0, 0.0, z, 0.0, B, K, eps, 8.95e8, False)
    assert force == pytest.approx(BLOCK.m * BLOCK.g, rel=1e-14)
    assert moment == 0.0
    assert 0.0 < z < 2 * Z_ST
    assert (z < Z_ST) == (eps > 0) or eps == 0.0        # hardening bed indents less
    if eps == 0.0:
        assert z == pytest.approx(Z_ST, rel=1e-15)


def test_static_indentation_rejects_a_bed_that_cannot_carry_the_block():
    with pytest.raises(ValueError, match="cannot carry"):
        rest_indentation(BLOCK, Foundation(k=K, lam=1.0, eps=-1e11))


# ---------------------------------------------------------------- the printed equations (errata)
def _state(theta, theta_dot=0.4, z_cb=None, z_cb_dot=2e-3):
    return theta, theta_dot, (Z_ST if z_cb is None else z_cb), z_cb_dot


def test_printed_eq9_is_exact_and_eq10_needs_two_fifths():
    theta, td, z, zd = _state(3e-4)
    lam, eps = 8.95e8, 6e7
    s, c = math.sin(theta), math.cos(theta)
    f_ref, m_ref = brute_force_resultants(theta, td, z, zd, Foundation(k=K, lam=lam, eps=eps))
    f9 = 2 * B * K * z + 2 * B * eps * K * z * (z**2 + B**2 * s**2) + B * lam * (B**2 * td * math.sin(2 * theta) / 3
                                                                                  + 2 * z * zd)

    def m10(coef):
        return (2 / 3 * B**3 * K * s * c + eps * K * c * (2 * z**2 * s * B**3 + coef * s**3 * B**5)
                + 2 / 3 * lam * B**3 * (z * td * c**2 + zd * s * c))

    assert f9 == pytest.approx(f_ref, rel=1e-10)
    assert m10(2 / 5) == pytest.approx(m_ref, rel=1e-10)
    # with a large angle the printed 2/3 is visibly wrong
    theta, td, z, zd = _state(0.1, z_cb=0.01)
    s, c = math.sin(theta), math.cos(theta)
    f_ref, m_ref = brute_force_resultants(theta, td, z, zd, Foundation(k=K, lam=lam, eps=eps))
    assert m10(2 / 5) == pytest.approx(m_ref, rel=1e-10)
    assert abs(m10(2 / 3) - m_ref) > 1e-3 * abs(m_ref)


def test_printed_eq11_damping_term_and_eq12_cosine_differ_from_the_integral():
    theta, td, z, zd = 0.05, -0.7, -1.2e-3, -1e-2
    lam = 8.95e8
    s, c = math.sin(theta), math.cos(theta)
    z_b = z + B * s
    f_ref, m_ref = brute_force_resultants(theta, td, z, zd, Foundation(k=K, lam=lam, eps=0.0))
    f_damp_ref = f_ref - K * z_b**2 / (2 * s)
    printed = lam / (6 * s**2) * z_b**2 * (B * td * math.sin(2 * theta) - zd * c + 3 * zd * s)
    derived = lam / (6 * s**2) * z_b**2 * (B * td * math.sin(2 * theta) - z * td * c + 3 * zd * s)
    assert derived == pytest.approx(f_damp_ref, rel=1e-9)
    assert abs(printed - f_damp_ref) > 0.01 * abs(f_damp_ref)
    m_damp_ref = m_ref - K * z_b**2 * (2 * B * s - z) * c / (6 * s**2)

    def m12_damping(theta_factor):
        return lam * c / (12 * s**3) * (td * theta_factor * (3 * B**4 * s**4 + 4 * B**3 * z * s**3 + z**4)
                                        + 2 * zd * z_b**2 * (2 * B * s - z) * s)

    assert m12_damping(c) == pytest.approx(m_damp_ref, rel=1e-9)     # one more cos(theta)
    assert abs(m12_damping(1.0) - m_damp_ref) > 1e-5 * abs(m_damp_ref)


def test_printed_eq11_eq12_cubic_terms_are_exact():
    theta, td, z, zd = -0.04, 0.9, -6e-4, 4e-3          # theta < 0: the mirror image of eqs. (11)–(12)
    eps = 6e7
    f_eps, m_eps = (np.subtract(brute_force_resultants(theta, td, z, zd, Foundation(k=K, lam=8.95e8, eps=eps)),
                                brute_force_resultants(theta, td, z, zd, Foundation(k=K, lam=8.95e8, eps=0.0))))
    s, c = math.sin(-theta), math.cos(theta)           # mirror: theta -> -theta, M -> -M
    z_b = z + B * s
    assert f_eps == pytest.approx(eps * K * z_b**4 / (4 * s), rel=1e-9)
    assert -m_eps == pytest.approx(eps * K * z_b**4 * (4 * B * s - z) * c / (20 * s**2), rel=1e-9)


def test_the_bed_rocking_stiffness_is_the_moment_of_the_linear_pressure_over_the_base():
    """``(2/3) b^3 k`` against a quadrature of the moment ``k (x theta) x`` over ``-b..b`` per unit rotation,
    for arrays of ``b`` and ``k``; the paper's ``K0`` and the linear rocking stiffness are built on it."""
    from screening.core.condensation.paper import coefficient_constants
    from screening.core.physics.contact import bed_rocking_stiffness, linear_rocking_stiffness

    b, k = np.array([0.02, 0.035, 0.3]), np.array([1e6, 2.89e7, 5e8])
    block, bed = Block(m=8.67, b=b, h=0.21), Foundation(k=k, lam=8.95e8)
    theta = 1e-4
    moment = [quad(lambda x, kk=kk: kk * (x * theta) * x, -bb, bb, epsabs=0, epsrel=1e-13)[0] / theta
              for bb, kk in zip(b, k)]
    np.testing.assert_allclose(bed_rocking_stiffness(block, bed), moment, rtol=1e-12)
    np.testing.assert_array_equal(coefficient_constants(block, bed)["K0"], bed_rocking_stiffness(block, bed))
    np.testing.assert_array_equal(linear_rocking_stiffness(block, bed),
                                  bed_rocking_stiffness(block, bed) - block.m * block.g * block.h)


def test_the_linear_rocking_stiffness_is_k_at_rest_of_every_condensation_without_the_cubic_term():
    """One home for ``(2/3) b^3 k - m g h``: each condensation's ``K(0)`` at ``eps = 0``, by its own
    function at ``theta = 0`` and by its ``stiffness_at_rest``; the rocking frequency squares to it."""
    from screening.core import condensation
    from screening.core.model import Block, Foundation
    from screening.core.physics.contact import linear_rocking_stiffness
    from screening.solvers.synthesis import rocking_frequency

    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    k0 = linear_rocking_stiffness(block, bed)
    assert k0 == pytest.approx(2 / 3 * 0.035**3 * 2.89e7 - 8.67 * block.g * 0.21, rel=1e-15) and k0 > 0
    for name in condensation.names():
        cond = condensation.get(name)
        assert float(cond.rocking_stiffness(0.0, block, bed)) == pytest.approx(k0, rel=1e-12), name
        assert float(cond.stiffness_at_rest(block, bed)) == pytest.approx(k0, rel=1e-12), name
    assert rocking_frequency(block, bed) ** 2 * block.m_sdof == pytest.approx(k0, rel=1e-14)


@pytest.mark.parametrize("eps", [6e7, 0.0, -6e5, -2e7])
def test_the_exact_uplift_angle_is_where_the_lifted_edge_leaves_the_bed_in_static_balance(eps):
    """An independent computation: the static base-centre indentation carrying the weight at each small
    rotation (quadrature of the contact pressure of eqs. 3-4 over the base, root in ``z``), and the rotation
    at which it equals ``b theta`` (the lifted edge at the surface), both by brentq.  ``eps = 0``: eq. 19."""
    from scipy.optimize import brentq

    from screening.core.physics.contact import exact_uplift_angle

    bed = Foundation(k=K, lam=8.95e8, eps=eps)

    def weight_carried(z_cb, theta):                        # small angles: z(u) = z_cb + u theta
        return quad(lambda u: float(contact_pressure(z_cb + u * theta, 0.0, bed)), -B, B, epsabs=0, epsrel=1e-13)[0]

    def resting_indentation(theta):
        return brentq(lambda z: weight_carried(z, theta) - BLOCK.m * BLOCK.g, -B * theta, 2 * Z_ST, xtol=1e-18,
                      rtol=1e-14)

    reference = brentq(lambda th: resting_indentation(th) - B * th, 1e-6, 3e-3, xtol=1e-16, rtol=1e-13)
    assert float(exact_uplift_angle(BLOCK, bed)) == pytest.approx(reference, rel=1e-9)
    if eps == 0.0:
        assert float(exact_uplift_angle(BLOCK, bed)) == pytest.approx(BLOCK.m * BLOCK.g / (2 * B**2 * K), rel=1e-15)


def test_the_exact_uplift_angle_is_nan_where_a_softening_bed_cannot_carry_the_block_through_uplift():
    """Per point: NaN beyond the bearing limit |eps| z_lin^2 = 2/27, finite just below it; the cubic
    condensation's threshold is this angle and refuses the bed instead."""
    from screening.core.condensation import cubic
    from screening.core.physics.contact import UPLIFT_BEARING_LIMIT, bearing_load, exact_uplift_angle

    limit_eps = -UPLIFT_BEARING_LIMIT / Z_ST**2
    bed = Foundation(k=K, lam=8.95e8, eps=np.array([0.999 * limit_eps, 1.001 * limit_eps]))
    angle = exact_uplift_angle(BLOCK, bed)
    assert np.isfinite(angle[0]) and np.isnan(angle[1])
    np.testing.assert_allclose(bearing_load(BLOCK, bed), [0.999 * UPLIFT_BEARING_LIMIT, 1.001 * UPLIFT_BEARING_LIMIT],
                               rtol=1e-12)
    ok = Foundation(k=K, lam=8.95e8, eps=0.999 * limit_eps)
    assert cubic.uplift_threshold(BLOCK, ok) == exact_uplift_angle(BLOCK, ok)
    with pytest.raises(ValueError, match="cannot carry"):
        cubic.uplift_threshold(BLOCK, Foundation(k=K, lam=8.95e8, eps=1.001 * limit_eps))


@pytest.mark.parametrize("bed", [Foundation(k=2.89e7, lam=8.95e8), Foundation(k=2.89e7, lam=8.95e8, eps=6e7),
                                 Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), Foundation(k=1e9, c=3e4),
                                 Foundation(k=1e5, lam=1e9, eps=2e3)])
def test_the_vertical_damping_ratio_is_that_of_the_linearised_vertical_oscillator(bed):
    """zeta_v from the eigenvalues of the block's vertical oscillator about its rest indentation: the rest
    position a root of the static balance (numpy's polynomial roots), the dashpot the rate derivative of the
    contact pressure integrated over the base, the linear bed's spring 2 b k (the last bed is overdamped)."""
    from screening.core.physics.contact import vertical_damping_ratio

    block = Block(m=8.67, b=0.035, h=0.21)
    m, b, k, eps = block.m, block.b, bed.k, bed.eps
    roots = np.roots([eps * k, 0.0, k, -m * block.g / (2 * b)]) if eps else np.array([m * block.g / (2 * b * k)])
    z0 = min(r.real for r in roots if abs(r.imag) < 1e-12 * abs(r) and r.real > 0 and 1 + 3 * eps * r.real**2 > 0)
    dv = 1e-3
    c_v = 2 * b * (contact_pressure(z0, dv, bed) - contact_pressure(z0, -dv, bed)) / (2 * dv)
    lam = np.linalg.eigvals(np.array([[0.0, 1.0], [-2 * b * k / m, -c_v / m]]))
    zeta = -np.sum(lam).real / (2 * math.sqrt(np.prod(lam).real))
    assert float(vertical_damping_ratio(block, bed)) == pytest.approx(zeta, rel=1e-9)


def test_the_vertical_damping_ratio_has_one_home():
    """The Monte Carlo set-up, the bed summary and the error model's inputs use the physics layer's vertical
    damping ratio, over arrays as point by point; the automatic model choice takes it at the linear bed's
    static indentation (the rule's indicator as measured), the same where eps = 0."""
    from screening.analysis.error_model import parameter_groups
    from screening.analysis.beds import bed_summary
    from screening.core.physics.contact import vertical_damping_ratio
    from screening.solvers import model_choice, montecarlo

    assert montecarlo.vertical_damping_ratio is vertical_damping_ratio
    block, eps = Block(m=8.67, b=0.035, h=0.21), np.array([-6e5, 0.0, 6e7])
    zeta = vertical_damping_ratio(block, Foundation(k=2.89e7, lam=8.95e8, eps=eps))
    each = [float(vertical_damping_ratio(block, Foundation(k=2.89e7, lam=8.95e8, eps=e))) for e in eps]
    assert zeta.tolist() == each
    assert [bed_summary(block, Foundation(k=2.89e7, lam=8.95e8, eps=e))["vertical_damping_ratio"]
            for e in eps] == each
    groups = parameter_groups({"m": 8.67, "b": 0.035, "h": 0.21, "g": 9.81, "k": 2.89e7, "lam": 8.95e8, "eps": eps})
    np.testing.assert_allclose(groups["zeta_v"], each, rtol=1e-12, atol=0)
    z_st = 8.67 * 9.81 / (2 * 0.035 * 2.89e7)
    for e in eps:
        bed = Foundation(k=2.89e7, lam=8.95e8, eps=e)
        assert model_choice.vertical_damping_ratio(block, bed) == vertical_damping_ratio(block, bed, z_st)
    assert model_choice.vertical_damping_ratio(block, Foundation(k=2.89e7, lam=8.95e8)) == each[1]
