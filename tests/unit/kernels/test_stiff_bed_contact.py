"""The stiff-bed model's contact law (screening.kernels.stiff_bed_contact): the compiled acceleration and
indentation curvature against the numpy reference, the curvature against a finite difference of the
condensation's slope, the damping on the quasi-static contact against the coupled model's dissipation and a
quadrature, Housner's restitution against the angular momentum balance."""

import math

import numpy as np
import pytest

from screening.core.condensation import cubic
from screening.core.physics import contact
from screening.kernels import stiff_bed_contact as sb
from test_stiff_bed import BEDS, STATUE


@pytest.mark.parametrize("bed", BEDS, ids=["hc", "hardening", "winkler", "softening"])
def test_compiled_acceleration_equals_the_numpy_reference(bed):
    sp = sb.stiff_record(STATUE, bed)[0]
    cp = cubic.sdof_record(STATUE, bed)[0]
    tu = float(cubic.uplift_threshold(STATUE, bed))
    for theta in (0.0, 0.3 * tu, -tu, 1.5 * tu, -20 * tu, 1e-3, -0.05, 0.2):
        for theta_dot in (0.0, 0.4, -2.0):
            ref = float(sb.rocking_acceleration(theta, theta_dot, 1.7, STATUE, bed))
            jit = sb.rocking_acceleration_jit(sp, cp, theta, theta_dot, 1.7)
            assert jit == pytest.approx(ref, rel=1e-9, abs=1e-9)   # Q: bed moment minus gravity cancel


@pytest.mark.parametrize("bed", BEDS[:2] + BEDS[3:], ids=["hc", "hardening", "softening"])
def test_indentation_curvature_is_the_derivative_of_the_condensation_slope(bed):
    tu = float(cubic.uplift_threshold(STATUE, bed))
    for a in (0.2 * tu, 0.8 * tu, 1.3 * tu, 10 * tu, 1e-3, 0.1):
        d = 1e-6 * a
        slope = lambda x: float(cubic.quasi_static_indentation(x, STATUE, bed)[1])  # noqa: E731
        fd = (slope(a + d) - slope(a - d)) / (2 * d)
        assert float(sb.indentation_curvature(a, STATUE, bed)) == pytest.approx(fd, rel=1e-5, abs=1e-9 * abs(fd) + 1e-12)
        z, dz = cubic.quasi_static_indentation(a, STATUE, bed)
        jit = sb.indentation_curvature_jit(cubic.sdof_record(STATUE, bed)[0], a, float(z), float(dz),
                                           float(z) + STATUE.b * a)
        assert jit == pytest.approx(float(sb.indentation_curvature(a, STATUE, bed)), rel=1e-12)


@pytest.mark.parametrize("bed", BEDS, ids=["hc", "hardening", "winkler", "softening"])
def test_constraint_damping_is_the_coupled_contact_dissipation_on_the_quasi_static_contact(bed):
    """With z_cb = Z(|sin theta|) and its rate, the coupled model's contact law (screening.core.physics.contact,
    exact resultants) dissipates (M_d theta' + F_d z_cb') = cos^2(theta) C_D theta'^2 (1e-9, both signs, full
    contact and uplift); C_D against a trapezoid quadrature over the contact of int (w_rate + w_ind z(u)) (Z' + u)^2 du (1e-6)
    and its compiled twin (1e-12)."""
    tu = float(cubic.uplift_threshold(STATUE, bed))
    cp = cubic.sdof_record(STATUE, bed)[0]
    w_rate, w_ind = bed.damping_weights
    for theta in (0.3 * tu, -0.9 * tu, 1.2 * tu, -10 * tu, 300 * tu, -0.05):
        for theta_dot in (0.7, -2.0):
            a = abs(math.sin(theta))
            z, dz = (float(x) for x in cubic.quasi_static_indentation(a, STATUE, bed))
            z_dot = dz * math.copysign(1.0, theta) * math.cos(theta) * theta_dot
            f1, m1 = contact.law_resultants(theta, theta_dot, z, z_dot, STATUE.b, bed.k, bed.eps, w_rate, w_ind)
            f0, m0 = contact.law_resultants(theta, 0.0, z, 0.0, STATUE.b, bed.k, bed.eps, w_rate, w_ind)
            power = float((m1 - m0) * theta_dot + (f1 - f0) * z_dot)
            c_d = float(sb.constraint_damping(a, STATUE, bed))
            assert power == pytest.approx(math.cos(theta) ** 2 * c_d * theta_dot ** 2, rel=1e-9)
            u = np.linspace(max(-STATUE.b, -z / a) if a > 0 else -STATUE.b, STATUE.b, 200_001)   # the contact
            quad = np.trapezoid((w_rate + w_ind * (z + a * u)) * (dz + u) ** 2, u)
            assert c_d == pytest.approx(quad, rel=1e-6)
            v = z + STATUE.b * a
            assert sb.constraint_damping_jit(cp, a, z, dz, v) == pytest.approx(c_d, rel=1e-12)


def test_condensation_damping_moment_overstates_the_uplift_dissipation_by_the_base_over_the_contact():
    """The condensation's damping moment coefficient counts the moment's work only; on the Hunt-Crossley bed
    in uplift it exceeds the dissipation C_D by 2 b / L (L the contact length), equal at the threshold."""
    bed = BEDS[0]
    tu = float(cubic.uplift_threshold(STATUE, bed))
    for a in (tu, 3 * tu, 100 * tu, 0.01):
        z, _ = cubic.quasi_static_indentation(a, STATUE, bed)
        length = min((float(z) + STATUE.b * a) / a, 2 * STATUE.b)
        ratio = float(cubic.rocking_damping(a, STATUE, bed)) / float(sb.constraint_damping(a, STATUE, bed))
        assert ratio == pytest.approx(2 * STATUE.b / length, rel=1e-6)


def test_housner_restitution_from_angular_momentum():
    """r = 1 - 1.5 sin^2 alpha equals (I_O - 2 m b^2) / I_O for the uniform block."""
    i_o = STATUE.I_cm + STATUE.m * (STATUE.b**2 + STATUE.h**2)
    assert sb.housner_restitution(STATUE) == pytest.approx((i_o - 2 * STATUE.m * STATUE.b**2) / i_o, rel=1e-14)
