"""The cubic condensation (screening.core.condensation.cubic) against the distributed contact law integrated numerically.

Independent route: the bed's pressure per unit length ``k (w + eps w^3)`` of the indentation ``w(x) = z + x theta``
along the base ``-b <= x <= b``, over the part in contact (``w > 0``), integrated by adaptive quadrature (scipy).
At the quasi-static indentation the vertical resultant carries the weight, and the moment about the base centre
less the overturning ``m g h theta`` is the restoring moment; the slope ``dz/d|theta|`` is the derivative of the
indentation (central differences).  Below and above the uplift angle, hardening and softening beds.
"""

import pytest
from scipy import integrate

from screening.core.condensation import cubic
from screening.core.model import Block, Foundation

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BEDS = {"hardening": Foundation(k=2.89e7, lam=8.95e8, eps=6e7), "softening": Foundation(k=2.89e7, lam=8.95e8, eps=-2e6),
        "linear": Foundation(k=2.89e7, lam=8.95e8)}


def _resultants(theta, z, block, bed):
    """``(vertical force [N], moment about the base centre [N m])`` of the pressure over the contact."""
    b, k, eps = float(block.b), float(bed.k), float(bed.eps)

    def pressure(x):
        w = z + x * theta
        return k * (w + eps * w ** 3) if w > 0.0 else 0.0

    low = max(-b, -z / theta) if theta > 0.0 else -b
    force = integrate.quad(pressure, low, b, epsabs=0.0, epsrel=1e-12)[0]
    moment = integrate.quad(lambda x: pressure(x) * x, low, b, epsabs=0.0, epsrel=1e-12)[0]
    return force, moment


@pytest.mark.parametrize("name", sorted(BEDS))
@pytest.mark.parametrize("ratio", [0.0, 0.3, 0.9, 1.5, 4.0])
def test_the_quasi_static_contact_carries_the_weight_and_gives_the_restoring_moment(name, ratio):
    bed = BEDS[name]
    theta = ratio * float(cubic.uplift_threshold(BLOCK, bed))
    if theta > 0.0 and not bool(cubic.in_equilibrium(theta, BLOCK, bed)):
        pytest.skip("beyond the softening bed's capacity")
    z = float(cubic.quasi_static_indentation(theta, BLOCK, bed)[0])
    force, moment = _resultants(theta, z, BLOCK, bed)
    weight = BLOCK.m * BLOCK.g
    assert force == pytest.approx(weight, rel=1e-9)
    if theta > 0.0:
        expected = moment - weight * BLOCK.h * theta
        assert float(cubic.restoring_moment(theta, BLOCK, bed)) == pytest.approx(expected, rel=1e-8, abs=1e-9 * weight
                                                                               * BLOCK.b * theta)
    state = cubic.indentation_state(theta, BLOCK, bed)
    assert bool(state[4]) == (ratio > 1.0)
    assert float(state[2]) == pytest.approx(BLOCK.b * theta + z, rel=1e-14)


@pytest.mark.parametrize("name", sorted(BEDS))
@pytest.mark.parametrize("ratio", [0.4, 0.95, 1.05, 2.5])
def test_the_slope_is_the_derivative_of_the_indentation(name, ratio):
    bed = BEDS[name]
    theta = ratio * float(cubic.uplift_threshold(BLOCK, bed))
    h = 1e-6 * theta
    z_plus, z_minus = (float(cubic.quasi_static_indentation(t, BLOCK, bed)[0]) for t in (theta + h, theta - h))
    slope = float(cubic.quasi_static_indentation(theta, BLOCK, bed)[1])
    assert slope == pytest.approx((z_plus - z_minus) / (2 * h), rel=1e-6)


def test_at_rest_the_stiffness_is_the_linear_bed_less_the_overturning_term():
    """``K(0) = (2/3) b^3 k - m g h + 2 eps k b^3 z0^2``: eq. (14) at ``theta = 0`` with the rest indentation."""
    for bed in BEDS.values():
        z0 = float(cubic.rest_indentation(BLOCK, bed))
        expected = (2 / 3 * BLOCK.b ** 3 * bed.k - BLOCK.m * BLOCK.g * BLOCK.h
                    + 2 * float(bed.eps) * float(bed.k) * BLOCK.b ** 3 * z0 ** 2)
        assert float(cubic.stiffness_at_rest(BLOCK, bed)) == pytest.approx(expected, rel=1e-12)
        assert float(cubic.rocking_stiffness(0.0, BLOCK, bed)) == pytest.approx(expected, rel=1e-12)
