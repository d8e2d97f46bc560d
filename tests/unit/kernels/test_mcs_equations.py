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


# ---------------------------------------------------------------- the exact full-contact propagator
def _hermite_input(c, dt):
    """The cubic Hermite input of the data ``c = (u_j, dt u'_j, u_{j+1}, dt u'_{j+1})`` on ``[0, dt]``."""
    def u(t):
        s = t / dt
        return ((2 * s**3 - 3 * s**2 + 1) * c[0] + (s**3 - 2 * s**2 + s) * c[1] + (3 * s**2 - 2 * s**3) * c[2]
                + (s**3 - s**2) * c[3])
    return u


@pytest.mark.parametrize("fraction", [1.0, 0.5])
def test_full_contact_propagator_matches_a_fine_adaptive_integration(fraction):
    """``x' = L x + B u(t) + (0, N_1(t), 0, N_3(t))`` with a cubic Hermite ``u`` and a remainder ramp ``N0 + (N1 -
    N0) t / dt``: the propagator's ``Phi x0 + W c + Psi1 N0 + Psi2 (N1 - N0)`` (rows 0-15, at ``dt / 2`` rows
    16-31) against DOP853 at rtol 1e-13, within 1e-9 of each component's size."""
    from scipy.integrate import solve_ivp

    from screening.core.model import Block

    block, bed = Block(m=600.0, b=0.2, h=0.8), Foundation(k=1e10, lam=3e11, eps=0.0)
    rec = kern.model_record(block, bed, paper.PAPER)
    rest = (0.0, 0.0, rest_indentation(block, bed), 0.0)
    dt = 8.9e-4
    prop = kern.full_contact_propagator(rec, rest, dt)
    L = np.zeros((4, 4))
    L[0, 1] = L[2, 3] = 1.0
    L[1], L[3] = prop[33], prop[34]
    B = np.array([0.0, prop[35, 3], 0.0, 0.0])
    x0 = np.array([3e-7, 2e-4, -4e-9, 1e-5])
    c = np.array([0.7, -0.3, 1.1, 0.4])
    n0, n1 = np.array([0.0, 2e-3, 0.0, -5e-4]), np.array([0.0, -1e-3, 0.0, 3e-4])
    u = _hermite_input(c, dt)
    scale = np.array([1e-6, 1e-3, 1e-8, 1e-5])              # the components' sizes

    def rhs(t, x):
        return L @ x + B * u(t) + n0 + (n1 - n0) * t / dt

    ref = solve_ivp(rhs, (0.0, fraction * dt), x0, method="DOP853", rtol=1e-13, atol=1e-16 * scale).y[:, -1]
    r = 0 if fraction == 1.0 else 16
    got = (prop[r:r + 4] @ x0 + prop[r + 4:r + 8] @ c + prop[r + 8:r + 12] @ n0
           + prop[r + 12:r + 16] @ (n1 - n0))
    assert prop[35, 2] == pytest.approx(2 * block.b * bed.k / block.m, rel=1e-6)      # K_z = 2 b k / m
    assert np.all(np.abs(got - ref) <= 1e-9 * scale), (got - ref) / scale
    assert np.max(np.abs(ref - x0) / scale) > 0.1                                          # the step moves x


def test_exact_step_error_estimate_bounds_its_error_on_the_nonlinear_bed():
    """One exact step of the full coupled equations (Hunt-Crossley, cubic bed term) in quiet full contact against
    DOP853 at rtol 1e-12: the error in the integrator's norm (rtol 1e-6, the state scales) is within its estimate."""
    from scipy.integrate import solve_ivp

    from screening.core.model import Block
    from screening.kernels import mcs_kernels
    from screening.solvers.mc_models import quasi_static_indentation, state_scales

    block, bed = Block(m=600.0, b=0.2, h=0.8), Foundation(k=1e10, lam=3e11, eps=2e7)
    rec = kern.model_record(block, bed, paper.PAPER)
    p = rec[()]
    z_st = quasi_static_indentation(block, bed, 0.0)
    rest = np.array([0.0, 0.0, z_st, 0.0])
    dt = 8.9e-4
    prop = kern.full_contact_propagator(rec, rest, dt)
    theta_ul = z_st / block.b
    c = 0.2 * np.array([0.5, 0.2, 0.6, -0.1])                             # [m s-2]
    x0 = np.array([prop[35, 3] * c[0] / prop[35, 1], 0.0, 0.0, 0.0])     # quasi-static under the input
    assert 0.01 < x0[0] / theta_ul < 0.3
    u = _hermite_input(c, dt)
    m1, m3 = mcs_kernels._remainder(prop, p, *x0, c[0])
    u_mid = u(0.5 * dt)
    xe, est, _, quiet = mcs_kernels._exact_step(prop, p, *x0, *c, u_mid, c[2], m1, m3)

    def rhs(t, y):
        a1, a3 = kern.coupled_accelerations(y[0], y[1], y[2], y[3], u(t), p)
        return [y[1], a1, y[3], a3]

    y0 = rest + x0
    scale_abs = 1e-6 * state_scales(block, bed)
    ref = solve_ivp(rhs, (0.0, dt), y0, method="DOP853", rtol=1e-12, atol=1e-6 * scale_abs).y[:, -1]
    got = rest + np.array(xe)
    sc = scale_abs + 1e-6 * np.maximum(np.abs(y0), np.abs(got))
    error = np.sqrt(np.mean(((got - ref) / sc) ** 2))
    estimate = np.sqrt(np.mean((np.array(est) / sc) ** 2))
    assert quiet and z_rest_ok(got, block)
    assert estimate <= 1.0                                    # the step would be taken
    assert error <= max(estimate, 1e-2), (error, estimate)


def z_rest_ok(y, block):
    """Full contact: both base edges in the bed."""
    return y[2] - block.b * abs(math.sin(y[0])) > 0.0
