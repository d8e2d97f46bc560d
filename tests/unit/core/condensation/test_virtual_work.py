"""The energy-consistent condensation: C(theta) theta'^2 against quadrature of the power the bed
dissipates along the quasi-static path; compiled twin; what it shares with "cubic" and "paper".

Independent route: small-angle kinematics z(u) = z_cb(theta) + u theta, zdot(u) = (z_cb'(theta) + u)
theta' with z_cb(theta) of the cubic condensation (its slope by central differences, not the closed
form), the damping part of the contact law F_n(z, zdot) - F_n(z, 0) integrated times zdot over the
part of the base in contact.
"""

import numpy as np
import pytest
from scipy import integrate

from screening.core import condensation
from screening.core.condensation import cubic, paper, virtual_work
from screening.core.model import Block, Foundation, contact_pressure

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BEDS = {
    "hc_linear": Foundation(k=2.89e7, lam=8.95e8, eps=0.0),
    "hc_hardening": Foundation(k=2.89e7, lam=8.95e8, eps=6e7),
    "hc_softening": Foundation(k=2.89e7, lam=8.95e8, eps=-6e5),
    "winkler_hardening": Foundation(k=2.89e7, c=2e4, eps=6e7),
}


def _dissipated_power(theta, theta_dot, block, foundation):
    """Power [W] dissipated by the damping part of the law, by quadrature over the contact zone."""
    b = block.b
    z = float(cubic.quasi_static_indentation(theta, block, foundation)[0])
    h = 1e-6 * max(abs(theta), 1e-6)
    dz = float((cubic.quasi_static_indentation(theta + h, block, foundation)[0]
                - cubic.quasi_static_indentation(theta - h, block, foundation)[0]) / (2 * h))

    def integrand(u):
        zu = z + u * theta
        zd = (dz + u) * theta_dot
        if zu <= 0.0:
            return 0.0
        damping = float(contact_pressure(zu, zd, foundation)) - float(contact_pressure(zu, 0.0, foundation))
        return damping * zd

    edges = [-b, b]
    if theta != 0.0 and -b < -z / theta < b:
        edges.insert(1, -z / theta)
    return sum(integrate.quad(integrand, lo, hi, epsabs=0, epsrel=1e-12, limit=200)[0]
               for lo, hi in zip(edges[:-1], edges[1:]))


@pytest.mark.parametrize("bed", sorted(BEDS))
@pytest.mark.parametrize("ratio", [0.0, 0.3, 0.99, 1.01, 2.0, 7.0, 30.0, -0.5, -4.0])
def test_damping_is_the_dissipated_power(bed, ratio):
    foundation = BEDS[bed]
    theta = ratio * float(cubic.uplift_threshold(BLOCK, foundation))
    theta_dot = 0.37                               # [rad/s]; C does not depend on it
    c = float(virtual_work.rocking_damping(theta, BLOCK, foundation))
    assert c > 0.0
    assert c * theta_dot**2 == pytest.approx(_dissipated_power(theta, theta_dot, BLOCK, foundation), rel=1e-7)


@pytest.mark.parametrize("bed", sorted(BEDS))
def test_compiled_twin_matches_numpy(bed):
    foundation = BEDS[bed]
    rec = cubic.sdof_record(BLOCK, foundation)[0]
    theta = np.concatenate([np.linspace(-40, 40, 161), [0.0, 1.0, -1.0]]) * float(
        cubic.uplift_threshold(BLOCK, foundation))
    c_np = virtual_work.rocking_damping(theta, BLOCK, foundation)
    k_np = cubic.rocking_stiffness(theta, BLOCK, foundation)
    for th, c, k in zip(theta, c_np, k_np):
        c_jit, k_jit = virtual_work.damping_stiffness_jit(rec, th)
        assert c_jit == pytest.approx(c, rel=1e-12, abs=1e-300)
        assert k_jit == pytest.approx(k, rel=1e-12, abs=1e-9)


def test_continuous_at_threshold_and_paper_limits():
    bed = BEDS["hc_linear"]
    tu = float(paper.uplift_threshold(BLOCK, bed))
    below = float(virtual_work.rocking_damping(tu * (1 - 1e-9), BLOCK, bed))
    above = float(virtual_work.rocking_damping(tu * (1 + 1e-9), BLOCK, bed))
    assert above == pytest.approx(below, rel=1e-6)
    # eps = 0: C = C1 min(1, theta_ul / |theta|), the paper's eq. (24) C1 (theta_ul / |theta|)^(1/2)
    c1 = float(paper.damping_inner(BLOCK, bed))
    assert below == pytest.approx(c1, rel=1e-12)
    for a in (2 * tu, 10 * tu, -30 * tu):
        c = float(virtual_work.rocking_damping(a, BLOCK, bed))
        assert c == pytest.approx(c1 * tu / abs(a), rel=1e-10)
        assert c == pytest.approx(float(paper.rocking_damping(a, BLOCK, bed)) * np.sqrt(tu / abs(a)), rel=1e-10)


def test_registered_with_cubic_stiffness():
    cond = condensation.get("virtual_work")
    assert cond is virtual_work.VIRTUAL_WORK
    bed = BEDS["hc_hardening"]
    theta = np.linspace(-0.02, 0.02, 41)
    np.testing.assert_array_equal(cond.rocking_stiffness(theta, BLOCK, bed), cubic.rocking_stiffness(theta, BLOCK, bed))
    assert cond.uplift_threshold(BLOCK, bed) == cubic.uplift_threshold(BLOCK, bed)
    with pytest.raises(ValueError, match="foundation.eps"):
        cond.check(BLOCK, Foundation(k=2.89e7, lam=8.95e8, eps=-5e7))


def test_linear_winkler_bed_is_already_energy_consistent():
    """With c zdot and eps = 0 the damping force vanishes along the quasi-static path (V = L/2), so the
    moment-based damping of the paper's condensation is the dissipation: the two coincide."""
    bed = Foundation(k=2.89e7, c=2e4, eps=0.0)
    theta = np.linspace(-30, 30, 121) * float(paper.uplift_threshold(BLOCK, bed))
    np.testing.assert_allclose(virtual_work.rocking_damping(theta, BLOCK, bed),
                               paper.rocking_damping(theta, BLOCK, bed), rtol=1e-10)
