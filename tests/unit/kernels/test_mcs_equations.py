"""The equations of a Monte Carlo sample (screening.kernels.mcs_equations) against numpy: the compiled
condensed acceleration against the condensations' numpy laws (paper and cubic), the coupled
accelerations against a direct solve of eqs. (7)-(8), rest as their equilibrium, the input gains
against the accelerations' change with the input."""

import math

import numpy as np
import pytest

from screening.core.condensation import cubic, get as get_condensation, paper
from screening.core.condensation.paper import rocking_damping, rocking_stiffness, uplift_threshold
from screening.core.model import Foundation
from screening.core.physics.contact import contact_resultants, rest_indentation
from screening.kernels import mcs_equations as kern
from test_montecarlo import BLOCK, HC

CUBIC_MCS_BEDS = [HC, Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), Foundation(k=2.89e7, lam=8.95e8, eps=-2e7),
                  Foundation(k=2.89e7, c=2e4, eps=6e7), Foundation(k=2.89e7, c=2e4, eps=-2e7)]


def _model_record(foundation, cond=None):
    """The compiled kernels' model record of BLOCK on ``foundation`` (a scalar record)."""
    return kern.model_record(BLOCK, foundation, cond or paper.PAPER)[()]


@pytest.mark.parametrize("foundation", [HC, Foundation(k=2.89e7, lam=8.95e8, eps=-6e5),
                                        Foundation(k=2.89e7, c=2e4, eps=6e7),
                                        Foundation(k=2.89e7, c=2e4, eps=-6e5)],
                         ids=["hc+", "hc-", "winkler+", "winkler-"])
def test_compiled_condensed_coefficients_match_screening_condensed(foundation):
    p = paper.sdof_record(BLOCK, foundation)[0]
    model = _model_record(foundation, paper.PAPER)
    tu = uplift_threshold(BLOCK, foundation)
    theta = np.concatenate([np.linspace(-0.16, 0.16, 201), [tu, -tu, 0.0, tu * (1 + 1e-9), 0.5 * tu]])
    c_ref = rocking_damping(theta, BLOCK, foundation)
    k_ref = rocking_stiffness(theta, BLOCK, foundation)
    for i, th in enumerate(theta):
        c, k = paper.damping_stiffness_jit(p, th)
        assert c == pytest.approx(c_ref[i], rel=1e-12)
        assert k == pytest.approx(k_ref[i], rel=1e-11, abs=1e-9 * abs(k_ref).max())
    a_ref = (BLOCK.m * BLOCK.h * 0.7 - c_ref * 0.3 - k_ref * theta) / BLOCK.m_sdof
    for i, th in enumerate(theta):
        assert kern.condensed_acceleration(paper.damping_stiffness_jit, p, th, 0.3, 0.7, model) == pytest.approx(
            a_ref[i], rel=1e-11, abs=1e-9)


@pytest.mark.parametrize("foundation", [HC, Foundation(k=2.89e7, c=2e4, eps=-6e5)], ids=["hc", "winkler"])
def test_coupled_accelerations_solve_eqs_7_and_8(foundation):
    """Compare with a direct numpy solve of the 2x2 system (7)–(8) for (z_cb'', theta'')."""
    p = _model_record(foundation)
    m, g, h, I = BLOCK.m, BLOCK.g, BLOCK.h, BLOCK.I_cm
    rng = np.random.default_rng(0)
    for _ in range(50):
        theta, theta_dot = rng.uniform(-0.15, 0.15), rng.normal(0, 1.0)
        z, z_dot, a = rng.uniform(-2e-3, 3e-4), rng.normal(0, 1e-2), rng.normal(0, 3.0)
        F, M = contact_resultants(theta, theta_dot, z, z_dot, BLOCK.b, foundation.k, foundation.eps,
                                  foundation.damping, foundation.winkler)
        s, c = math.sin(theta), math.cos(theta)
        lhs = np.array([[m, m * h * s], [m * h * s, I + m * h * h]])
        rhs = np.array([m * g - F - m * h * theta_dot**2 * c, m * h * a * c - M + m * h * g * s])
        z_dd, th_dd = np.linalg.solve(lhs, rhs)
        got_th, got_z = kern.coupled_accelerations(theta, theta_dot, z, z_dot, a, p)
        assert got_th == pytest.approx(th_dd, rel=1e-9, abs=1e-9)
        assert got_z == pytest.approx(z_dd, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("eps", [6e7, 0.0, -6e5])
def test_static_equilibrium_is_at_rest(eps):
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=eps)
    p = _model_record(foundation)
    th_dd, z_dd = kern.coupled_accelerations(0.0, 0.0, rest_indentation(BLOCK, foundation), 0.0, 0.0, p)
    assert th_dd == 0.0
    assert abs(z_dd) < 1e-12 * BLOCK.g


@pytest.mark.parametrize("foundation", CUBIC_MCS_BEDS, ids=["hc+", "hc-", "hc-cap", "winkler+", "winkler-cap"])
def test_compiled_cubic_coefficients_match_screening_cubic_condensation(foundation):
    p = cubic.sdof_record(BLOCK, foundation)[0]
    model = _model_record(foundation, cubic.CUBIC)
    tu = cubic.uplift_threshold(BLOCK, foundation)
    assert model["theta_ul"] == tu and p["theta_ul"] == tu
    assert model["theta_cap"] == cubic.capacity_angle(BLOCK, foundation)
    theta = np.concatenate([np.linspace(-0.16, 0.16, 201), tu * np.array([1, -1, 0, 1 + 1e-9, 0.5, 0.999, 3.0])])
    c_ref = cubic.rocking_damping(theta, BLOCK, foundation)
    k_ref = cubic.rocking_stiffness(theta, BLOCK, foundation)
    for i, th in enumerate(theta):
        c, k = cubic.damping_stiffness_jit(p, th)
        assert c == pytest.approx(c_ref[i], rel=1e-10)
        assert k == pytest.approx(k_ref[i], rel=1e-11, abs=1e-9 * abs(k_ref).max())
        assert cubic.damping_stiffness_jit(p, th) == (c, k)
    a_ref = (BLOCK.m * BLOCK.h * 0.7 - c_ref * 0.3 - k_ref * theta) / BLOCK.m_sdof
    for i, th in enumerate(theta):
        assert kern.condensed_acceleration(cubic.damping_stiffness_jit, p, th, 0.3, 0.7, model) == pytest.approx(
            a_ref[i], rel=1e-10, abs=1e-9)


@pytest.mark.parametrize("theta", [0.0, 0.01, -0.07])
def test_input_gain_is_the_derivative_of_the_accelerations(theta):
    p = kern.model_record(BLOCK, HC, get_condensation("paper"))[()]
    z = rest_indentation(BLOCK, HC)
    a0 = kern.coupled_accelerations(theta, 0.3, z, 1e-4, 0.0, p)
    a1 = kern.coupled_accelerations(theta, 0.3, z, 1e-4, 1.0, p)
    g1, g3 = kern.input_gain(kern.MODEL_COUPLED, theta, p)
    assert g1 == pytest.approx(a1[0] - a0[0], rel=1e-9)          # the accelerations are linear in x_g''
    assert g3 == pytest.approx(a1[1] - a0[1], rel=1e-9, abs=1e-12)
    assert kern.input_gain(kern.MODEL_CONDENSED, theta, p) == pytest.approx((BLOCK.m * BLOCK.h / BLOCK.m_sdof, 0.0))
