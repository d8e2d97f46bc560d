"""The stiff-bed model's contact law (screening.solvers.stiff_bed_contact): the compiled acceleration and
indentation curvature against the numpy reference, the curvature against a finite difference of the
condensation's slope, Housner's restitution against the angular momentum balance."""

import pytest

from screening.condensation import cubic
from screening.solvers import stiff_bed_contact as sb
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


def test_housner_restitution_from_angular_momentum():
    """r = 1 - 1.5 sin^2 alpha equals (I_O - 2 m b^2) / I_O for the uniform block."""
    i_o = STATUE.I_cm + STATUE.m * (STATUE.b**2 + STATUE.h**2)
    assert sb.housner_restitution(STATUE) == pytest.approx((i_o - 2 * STATUE.m * STATUE.b**2) / i_o, rel=1e-14)
