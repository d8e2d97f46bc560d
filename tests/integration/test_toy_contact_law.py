"""A contact law registered from outside the package runs through the contact resultants, the
condensation and the linearization without any change to them (the plug-in interface of screening.core.laws).

The toy is a dashpot that stiffens with the indentation, ``F_d = c zdot (1 + z / Z_REF)``: it has both
basis pressures (``zdot`` and ``z zdot``) at once, which neither built-in law has.  Every check is
against an independent numerical computation from the toy's own ``damping_pressure``: adaptive
quadrature over the contact zone (resultants, condensed damping) and a Gaussian expectation by
quadrature (the equivalent damping of the linearization, eq. 31).
"""

import math

import numpy as np
import pytest
from scipy import integrate

from screening.core import condensation, laws
from screening.core.model import Block, ConstantEnvelope, Foundation
from screening.core.excitations import WhiteNoise
from screening.core.physics.contact import law_constants, law_resultants, law_resultants_jit
from screening.solvers.moments import solve_moments
from screening.solvers.timegrid import output_times
from screening.sweep.study import StudyError, build_models, parse_study

BLOCK = Block(m=8.67, b=0.035, h=0.21)
B = BLOCK.b
K = 2.89e7
C = 2.0e4                 # [N s m-2]
Z_REF = 2.0e-5            # [m]: comparable to the static indentation (4.2e-5 m), so both terms count
MG = BLOCK.m * BLOCK.g


class StiffeningDashpot(laws.ContactLaw):
    """Test law: ``c zdot (1 + z / Z_REF)``."""

    name = "stiffening_dashpot"
    description = "test: c zdot (1 + z / z_ref)"
    parameter = "c"
    attributes = {"units": "N s m-2", "long_name": "dashpot of the stiffening-dashpot test law"}

    def damping_pressure(self, z, z_dot, coefficient):
        return coefficient * np.asarray(z_dot, dtype=float) * (1.0 + np.asarray(z, dtype=float) / Z_REF)

    def damping_weights(self, coefficient):
        return coefficient, coefficient / Z_REF


class Wrong(StiffeningDashpot):
    name = "wrong"

    def damping_pressure(self, z, z_dot, coefficient):
        return coefficient * np.asarray(z_dot, dtype=float) * (1.0 + (np.asarray(z, dtype=float) / Z_REF) ** 2)


@pytest.fixture(scope="module")
def toy():
    law = laws.register(StiffeningDashpot())
    yield law
    laws.unregister(law.name)


@pytest.fixture(scope="module")
def bed(toy):
    return Foundation(k=K, c=C, eps=0.0, law=toy.name)


def pressure(z, z_dot, bed):
    """The toy's full pressure (stiffness + damping), zero out of contact."""
    return np.where(z > 0.0, K * z + bed.contact_law.damping_pressure(z, z_dot, C), 0.0)


# ----------------------------------------------------------------------------- registry
def test_registered_by_name_refused_once_removed_and_unknown_names_list_the_laws(toy, bed):
    assert laws.get(toy.name) is toy and toy.name in laws.names()
    assert bed.damping == C and bed.damping_weights == (C, C / Z_REF)
    laws.unregister(toy.name)
    with pytest.raises(ValueError, match=r"parameter 'law' must be one of \('hunt_crossley', 'winkler'"):
        Foundation(k=K, c=C, law=toy.name)
    laws.register(toy)
    with pytest.raises(ValueError, match="'lam' does not apply"):
        Foundation(k=K, c=C, lam=1.0, law=toy.name)


def test_a_law_whose_pressure_is_not_its_weights_is_refused_at_registration():
    with pytest.raises(ValueError, match="damping_pressure is not"):
        laws.register(Wrong())
    assert "wrong" not in laws.names()


def test_studies_take_the_registered_law_and_refuse_unknown_ones_with_the_list(toy):
    text = f"""
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
contact = "{toy.name}"
k = 2.89e7
c = 2e4
[excitation]
kind = "white"
S0 = 1e-4
[time]
t_end = 1.0
dt = 0.5
"""
    study = parse_study(text)
    _, foundation, _ = build_models(study.cases[0], {})
    assert foundation.law == toy.name and foundation.c == C
    with pytest.raises(StudyError, match=r"foundation\.contact: .*'hunt_crossley'.*'winkler'.*'stiffening_dashpot'"):
        parse_study(text.replace(f'"{toy.name}"', '"hertz"'))
    with pytest.raises(StudyError, match=r"foundation\.lam: does not apply"):
        parse_study(text.replace("c = 2e4", "lam = 1e8"))


# ----------------------------------------------------------------------------- resultants
@pytest.mark.parametrize("theta, theta_dot, z_cb, z_cb_dot", [
    (2e-4, 0.05, 4e-5, 1e-3),          # full contact
    (-1e-4, -0.3, 6e-5, -2e-3),        # full contact
    (5e-3, 0.2, -2e-5, 3e-3),          # uplift, theta > 0
    (-0.05, 0.7, -1.2e-3, -1e-2),      # uplift, theta < 0
])
def test_resultants_equal_the_quadrature_of_the_toy_pressure(bed, theta, theta_dot, z_cb, z_cb_dot):
    s, c = math.sin(theta), math.cos(theta)
    z_b, z_b_dot = z_cb + B * s, z_cb_dot + B * theta_dot * c

    def p(eta):
        return float(pressure(z_b - eta * s, z_b_dot - eta * theta_dot * c, bed))

    points = [z_b / s] if s != 0.0 and 0.0 < z_b / s < 2.0 * B else None
    opts = dict(points=points, epsabs=0.0, epsrel=1e-12, limit=200)
    force = integrate.quad(p, 0.0, 2.0 * B, **opts)[0]
    moment = integrate.quad(lambda eta: p(eta) * (B - eta) * c, 0.0, 2.0 * B, **opts)[0]
    args = (theta, theta_dot, z_cb, z_cb_dot, B, *law_constants(bed))
    for f, m in (law_resultants(*args), law_resultants_jit(*args)):
        assert float(f) == pytest.approx(force, rel=1e-9)
        assert float(m) == pytest.approx(moment, rel=1e-9, abs=1e-12 * abs(force) * B)


# ----------------------------------------------------------------------------- condensation
def paper_damping_by_quadrature(theta, bed):
    """``C(theta)`` of the paper's condensation from the toy's pressure: the damping moment about the
    base centre per unit rotation rate, small angles (z_cb = z_lin without uplift, contact length
    p = sqrt(2 m g / (k theta)) with the edge at z_B = p theta in uplift)."""
    a = abs(theta)
    rate = 1.0                                             # theta' [rad/s]: C is linear in it
    if a <= MG / (2.0 * B * B * K):
        z_lin = MG / (2.0 * B * K)
        f = lambda u: float(bed.contact_law.damping_pressure(z_lin + u * a, u * rate, C)) * u
        return integrate.quad(f, -B, B, epsabs=0.0, epsrel=1e-12)[0] / rate
    p = math.sqrt(2.0 * MG / (K * a))
    f = lambda eta: float(bed.contact_law.damping_pressure((p - eta) * a, (p / 2.0 - eta) * rate, C)) * (B - eta)
    return integrate.quad(f, 0.0, p, epsabs=0.0, epsrel=1e-12)[0] / rate


def test_paper_condensation_damping_is_the_quadrature_of_the_toy_pressure(bed):
    paper = condensation.get("paper")
    theta_ul = float(paper.uplift_threshold(BLOCK, bed))
    thetas = np.array([0.0, 0.3, -0.9, 1.5, -4.0, 20.0]) * theta_ul
    got = paper.rocking_damping(thetas, BLOCK, bed)
    expected = [paper_damping_by_quadrature(t, bed) for t in thetas]
    np.testing.assert_allclose(got, expected, rtol=1e-9)
    kernel = paper.sdof_kernel(BLOCK, bed)
    compiled = [kernel.damping_stiffness(kernel.record[0], float(t))[0] for t in thetas]
    np.testing.assert_allclose(compiled, expected, rtol=1e-9)


# ----------------------------------------------------------------------------- linearization
def test_linearization_with_the_toy_law_gives_the_gaussian_expectation_of_its_damping(bed):
    """eq. (31): ``c_eq = E[C(theta)]`` for zero-mean Gaussian theta; at a level with real uplift."""
    t = output_times(10.0, 0.5)
    res = solve_moments(BLOCK, bed, WhiteNoise(3e-4, ConstantEnvelope()), t, condensation="paper")   # its C
    assert int(res["status"]) == 0
    var = float(res["var_theta"][-1])
    sigma = math.sqrt(var)
    theta_ul = MG / (2.0 * B * B * K)
    assert float(res["peak_p_uplift"]) > 0.05 and sigma > 0.3 * theta_ul      # the tail counts

    def weighted(th):
        return paper_damping_by_quadrature(th, bed) * math.exp(-0.5 * th * th / var) / math.sqrt(2 * math.pi * var)

    expected = 2.0 * (integrate.quad(weighted, 0.0, theta_ul, epsrel=1e-10)[0]
                      + integrate.quad(weighted, theta_ul, 12.0 * sigma, epsrel=1e-10, limit=200)[0])
    assert float(res["c_eq"][-1]) == pytest.approx(expected, rel=1e-6)
    # the Winkler bed of the same dashpot has less damping (no z zdot part): the toy's weights reached the solver
    winkler = solve_moments(BLOCK, Foundation(k=K, c=C, eps=0.0), WhiteNoise(3e-4, ConstantEnvelope()), t,
                            condensation="paper")
    assert float(winkler["c_eq"][0]) < 0.5 * float(res["c_eq"][0])
