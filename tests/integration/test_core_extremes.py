"""Property tests: at the edges of the parameter space the core gives finite numbers or a flag.

Ranges (issue 6), all SI: ``S0`` 1e-12 .. 1e8 m2 s-3 (past the level where the linearized
block topples for practically every block below), ``eps`` -1e7 .. 1e9 m-2 (and 0 exactly;
the negative end makes the no-uplift stiffness negative for many blocks), ``k`` 1e4 .. 1e10
N m-2, ``lam`` 0 exactly and 1 .. 1e11 N s m-3 (Winkler ``c`` 0 and 1e-3 .. 1e7 N s m-2),
``omega_g`` 0.5 .. 200 rad/s, ``zeta_g`` 0.01 .. 2, ``m`` 0.1 .. 1e4 kg, ``b`` 5 mm .. 2 m
and ``b/h`` from 0.02 (very slender) to 5 (very squat); both envelopes.  The corners of these
ranges are tried explicitly (``@example``); hypothesis is deterministic (fixed seed, no
example database) with a bounded number of examples.
"""

from functools import partial

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, seed, settings, strategies as st

from screening.core.condensation.paper import uplift_threshold
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.condensation import api
from screening.core.condensation.paper import coefficient_constants
from screening.solvers import moments
from screening.core.status import PointStatus
from screening.core.model import Block, Foundation
from screening.solvers.timegrid import output_times

# the paper's condensation, pinned: these are the edges of its closed forms (the default condensation
# refuses the softest beds of these ranges before any work)
equivalent_coefficients = partial(api.equivalent_coefficients, condensation="paper")
solve_moments = partial(moments.solve_moments, condensation="paper")

log_uniform = lambda lo, hi: st.floats(np.log10(lo), np.log10(hi)).map(lambda e: 10.0**e)

#: b/h from 0.02 (slenderness h/b = 50) to 5 (h/b = 0.2)
blocks = st.builds(lambda m, b, slender: Block(m, b, b * slender),
                   log_uniform(0.1, 1e4), log_uniform(0.005, 2.0), log_uniform(0.2, 50.0))
eps_values = st.one_of(st.just(0.0), log_uniform(1.0, 1e9), log_uniform(1.0, 1e7).map(lambda e: -e))
foundations = st.one_of(
    st.builds(Foundation, log_uniform(1e4, 1e10), st.one_of(st.just(0.0), log_uniform(1.0, 1e11)), eps_values),
    st.builds(lambda k, c, eps: Foundation(k=k, c=c, eps=eps), log_uniform(1e4, 1e10),
              st.one_of(st.just(0.0), log_uniform(1e-3, 1e7)), eps_values),
)
envelopes = st.sampled_from([Envelope(4.0, 2.0), ConstantEnvelope(), Envelope(60.0, 0.05)])
excitations = st.one_of(
    st.builds(WhiteNoise, log_uniform(1e-12, 1e8), envelopes),
    st.builds(KanaiTajimi, log_uniform(1e-12, 1e8), log_uniform(0.5, 200.0), log_uniform(0.01, 2.0), envelopes),
)

# corners of the ranges
SLENDER_LIGHT = Block(0.1, 0.005, 0.25)          # b/h = 0.02
SLENDER_HEAVY = Block(1e4, 0.04, 2.0)            # b/h = 0.02
SQUAT_LIGHT = Block(0.1, 2.0, 0.4)               # b/h = 5
SQUAT_HEAVY = Block(1e4, 2.0, 0.4)               # b/h = 5
STIFF_DAMPED = Foundation(1e10, 1e11, 1e9)
SOFT_UNDAMPED_SOFTENING = Foundation(1e4, 0.0, -1e7)
STIFF_UNDAMPED = Foundation(1e10, 0.0, 0.0)
SOFT_DAMPED = Foundation(1e4, 1e11, 0.0)
WINKLER_CORNER = Foundation(k=1e10, c=1e7, eps=-1e7)


def _settings(n):
    return settings(max_examples=n, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


# ----------------------------------------------------------------------------- coefficients
@seed(20261122)
@_settings(400)
@given(blocks, foundations, st.one_of(st.just(0.0), log_uniform(1e-12, 1e10)), st.floats(-1.0, 1.0),
       st.one_of(st.just(0.0), log_uniform(1e-6, 1e12)))
@example(SLENDER_LIGHT, STIFF_DAMPED, 1e10, 1.0, 1e12)
@example(SLENDER_HEAVY, SOFT_UNDAMPED_SOFTENING, 1e-12, -1.0, 0.0)
@example(SQUAT_LIGHT, SOFT_DAMPED, 1.0, 0.999, 1e12)
@example(SQUAT_HEAVY, STIFF_UNDAMPED, 1e10, -1.0, 1e-6)
@example(SQUAT_HEAVY, WINKLER_CORNER, 1e-12, 1.0, 1e12)
@example(SLENDER_LIGHT, WINKLER_CORNER, 1e10, -1.0, 1e12)
def test_equivalent_coefficients_are_finite_everywhere(block, foundation, ratio, rho, rate):
    """sigma_theta / theta_ul from 0 to 1e10, sigma_theta_dot / sigma_theta from 0 to 1e12 1/s, |rho| <= 1."""
    s = np.array([0.0, ratio * uplift_threshold(block, foundation)])
    with np.errstate(over="raise", divide="raise", invalid="raise"):  # nothing may hide an inf or 0/0
        c_eq, k_eq = equivalent_coefficients(s, rate * s, rho, block, foundation)
    assert np.all(np.isfinite(c_eq)) and np.all(np.isfinite(k_eq))
    assert np.all(c_eq >= 0)
    assert np.all(c_eq <= coefficient_constants(block, foundation)["C1"] * (1 + 1e-12))   # uplift only softens C


@seed(20261123)
@_settings(300)
@given(blocks, foundations, st.floats(-1.0, 1.0), log_uniform(1e-3, 1e4))
@example(SLENDER_LIGHT, STIFF_DAMPED, 1.0, 1e4)
@example(SQUAT_HEAVY, SOFT_DAMPED, -1.0, 1e4)
@example(SQUAT_LIGHT, SOFT_UNDAMPED_SOFTENING, 0.5, 1e-3)
@example(SLENDER_HEAVY, WINKLER_CORNER, -0.7, 10.0)
def test_coefficients_approach_their_analytic_limits(block, foundation, rho, rate):
    """sigma_theta -> 0: the no-uplift values (plus the secant of the cubic term);
    sigma_theta -> inf: c_eq -> 0, k_eq -> -m g h + eps m^2 g^2 b / k, velocity coupling -> 0."""
    const = coefficient_constants(block, foundation)
    c1, K0, mgh, E0, tu = (const[n] for n in ("C1", "K0", "mgh", "E0", "theta_ul"))
    eps, k, b = foundation.eps, foundation.k, block.b
    scale = K0 + mgh + abs(eps) * E0                   # magnitude of the terms of k_eq

    # sigma_theta = 0 exactly: no uplift, exact values
    c0, k0 = equivalent_coefficients(0.0, 0.0, rho, block, foundation)
    assert c0 == pytest.approx(c1, rel=1e-14, abs=0.0)
    assert k0 == pytest.approx(K0 - mgh + 0.5 * eps * E0, rel=1e-13, abs=1e-13 * scale)

    # sigma_theta -> 0: uplift negligible (p_out ~ erfc(35)), only the cubic secant term remains
    s = 0.02 * tu
    c_small, k_small = equivalent_coefficients(s, rate * s, rho, block, foundation)
    assert c_small == pytest.approx(c1, rel=1e-14, abs=0.0)
    assert k_small - k0 == pytest.approx(eps * 1.2 * k * b**5 * s**2, rel=1e-9, abs=1e-13 * scale)

    # sigma_theta -> inf, no velocity coupling (rho = 0): the limits, with the documented rates
    r = 1e12
    c_big, k_big = equivalent_coefficients(r * tu, rate * r * tu, 0.0, block, foundation)
    assert 0.0 <= c_big <= 2e-6 * c1                   # ~1.7 r^-1/2 (Hunt-Crossley), ~r^-1 (Winkler)
    assert k_big == pytest.approx(-mgh + eps * E0, rel=0.0, abs=1e-6 * scale)

    # velocity coupling D = k_eq(rho = 0) - k_eq(rho) vanishes as sigma_theta grows
    coupling = []
    for r in (1e4, 1e8, 1e12):
        _, k_rho = equivalent_coefficients(r * tu, rate * r * tu, rho, block, foundation)
        _, k_nil = equivalent_coefficients(r * tu, rate * r * tu, 0.0, block, foundation)
        coupling.append(abs(k_nil - k_rho))
    floor = 1e-12 * (scale + c1 * rate)
    assert coupling[1] <= max(0.011 * coupling[0], floor)     # ~r^-1/2 or faster: 1e4 x r -> <= 1/100
    assert coupling[2] <= max(0.011 * coupling[1], floor)


# ----------------------------------------------------------------------------- the solver
def _check_solution(res, t, block, max_steps):
    """Finite values or a flag; consistent summaries; bounded work."""
    status, stop = int(res["status"]), float(res["t_stop"])
    assert status in {int(s) for s in PointStatus if s >= PointStatus.ok}
    assert 0.0 <= stop <= t[-1]
    done = t <= stop
    assert done[0]
    for name in ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq", "p_uplift"):
        assert np.all(np.isfinite(res[name][done])), name
        assert np.all(np.isnan(res[name][~done])), name
    assert np.all(res["var_theta"][done] >= 0) and np.all(res["var_theta_dot"][done] >= 0)
    assert np.all((res["p_uplift"][done] >= 0) & (res["p_uplift"][done] <= 1))
    for name in ("peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq"):
        assert np.isfinite(res[name]), name        # summaries are finite whatever the status
    assert 0 <= int(res["n_rejected"]) <= int(res["n_steps"]) <= max_steps
    peak, sigmax2 = float(res["peak_var_theta"]), block.slenderness**2
    if status == PointStatus.ok:
        assert stop == t[-1]
        assert float(res["min_k_eq"]) > 0 and peak <= sigmax2
    elif status == PointStatus.k_eq_negative:
        assert float(res["min_k_eq"]) <= 0 or stop == 0.0
    elif status == PointStatus.sigma_theta_beyond_slenderness:
        assert peak > sigmax2
    elif status == PointStatus.step_budget_exhausted:
        assert int(res["n_steps"]) == max_steps and stop < t[-1]
    return status


@seed(20261122)
@_settings(300)
@given(blocks, foundations, excitations)
@example(SLENDER_LIGHT, STIFF_DAMPED, KanaiTajimi(1e8, 200.0, 2.0))
@example(SLENDER_HEAVY, SOFT_UNDAMPED_SOFTENING, WhiteNoise(1e-12))
@example(SQUAT_LIGHT, STIFF_DAMPED, KanaiTajimi(1e-12, 0.5, 0.01, ConstantEnvelope()))
@example(SQUAT_HEAVY, SOFT_DAMPED, WhiteNoise(1e8, ConstantEnvelope()))
@example(SQUAT_HEAVY, STIFF_UNDAMPED, KanaiTajimi(1e-12, 200.0, 0.01))
@example(SQUAT_LIGHT, WINKLER_CORNER, WhiteNoise(1e8))
@example(Block(8.67, 0.035, 0.21), Foundation(1e10, 1e11, 0.0), WhiteNoise(2.4e-3))
def test_solver_returns_finite_values_or_a_flag(block, foundation, excitation):
    t = output_times(20.0, 0.5)
    res = solve_moments(block, foundation, excitation, t, max_steps=20_000)
    _check_solution(res, t, block, 20_000)


def _no_uplift_stiffness(block, foundation):
    c = coefficient_constants(block, foundation)
    return c["K0"] - c["mgh"] + 0.5 * foundation.eps * c["E0"]


@seed(20261124)
@_settings(150)
@given(blocks, log_uniform(1e4, 1e10), st.one_of(st.just(0.0), log_uniform(1.0, 1e11)),
       st.one_of(st.just(0.0), log_uniform(1.0, 1e7).map(lambda e: -e)), log_uniform(1e-12, 1e8), st.booleans())
@example(Block(8.67, 0.035, 0.21), 2.89e7, 8.95e8, -1e7, 2.4e-3, False)       # the paper block, eps = -1e7
@example(SLENDER_HEAVY, 1e10, 0.0, 0.0, 1e-12, True)                            # K0 < m g h without eps
def test_negative_no_uplift_stiffness_is_flagged_at_the_start(block, k, lam, eps, S0, kt):
    foundation = Foundation(k, lam, eps)
    k1 = _no_uplift_stiffness(block, foundation)
    assume(k1 < 0)
    c_eq, k_eq = equivalent_coefficients(0.0, 0.0, 0.0, block, foundation)
    assert np.isfinite(c_eq) and k_eq == pytest.approx(k1, rel=1e-12)
    excitation = KanaiTajimi(S0, 10.0, 0.4) if kt else WhiteNoise(S0)
    t = output_times(4.0, 0.5)
    res = solve_moments(block, foundation, excitation, t)
    assert int(res["status"]) == PointStatus.k_eq_negative
    assert float(res["t_stop"]) == 0.0 and int(res["n_steps"]) == 0
    assert res["k_eq"][0] == pytest.approx(k1, rel=1e-12) and res["var_theta"][0] == 0.0
    assert np.all(np.isnan(res["var_theta"][1:]))
    assert float(res["min_k_eq"]) == pytest.approx(k1, rel=1e-12)


def test_corner_grid_in_one_batch_is_finite_or_flagged_and_reaches_the_blow_up_level():
    """Every corner of the ranges at once (one vectorised call, paper mass and base): finite or
    flagged.  At S0 = 1e8 (the top of the range) no corner survives unflagged; at S0 = 1e-12 no
    point passes the slenderness angle and k_eq is only ever negative from the start."""
    t = output_times(20.0, 0.5)
    shape = (4, 2, 2, 3, 2)
    ratio = np.array([0.02, 0.2, 1.0, 5.0]).reshape(4, 1, 1, 1, 1)         # b/h
    k = np.array([1e4, 1e10]).reshape(1, 2, 1, 1, 1)
    lam = np.array([0.0, 1e11]).reshape(1, 1, 2, 1, 1)
    eps = np.array([-1e7, 0.0, 1e9]).reshape(1, 1, 1, 3, 1)
    S0 = np.array([1e-12, 1e8]).reshape(1, 1, 1, 1, 2)
    block = Block(8.67, 0.035 * np.ones(shape), 0.035 / ratio * np.ones(shape))
    foundation = Foundation(k, lam, eps)
    k1 = _no_uplift_stiffness(block, foundation)
    for excitation in (WhiteNoise(S0), KanaiTajimi(S0, 0.5, 0.01), KanaiTajimi(S0, 200.0, 2.0)):
        res = solve_moments(block, foundation, excitation, t, max_steps=20_000)
        assert res["status"].shape == shape
        for idx in np.ndindex(shape):
            one = {name: value[idx] for name, value in res.items()}
            _check_solution(one, t, Block(8.67, 0.035, 0.035 / ratio.flat[idx[0]]), 20_000)
        low, high = res["status"][..., 0], res["status"][..., 1]
        assert np.all(high != PointStatus.ok)
        assert np.all(low != PointStatus.sigma_theta_beyond_slenderness)
        np.testing.assert_array_equal(low == PointStatus.k_eq_negative, k1[..., 0] < 0)
        assert np.all(res["t_stop"][..., 0][low == PointStatus.k_eq_negative] == 0.0)
        assert np.any(low == PointStatus.ok)


@pytest.mark.parametrize("excitation", [KanaiTajimi(1e-200, 10.0, 0.4), WhiteNoise(1e-305)],
                         ids=["kanai_tajimi_1e-200", "white_1e-305"])
def test_vanishing_intensity_far_below_the_range_does_not_raise(excitation):
    t = output_times(4.0, 0.5)
    res = solve_moments(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 6e7), excitation, t)
    assert int(res["status"]) == PointStatus.ok and np.all(np.isfinite(res["var_theta"]))


@pytest.mark.parametrize("S0", [1e50, 1e150, 1e300])
def test_absurd_intensities_stop_with_a_flag(S0):
    """Far beyond the blow-up level the moments overflow: still a flag (incl. non_finite_moments), no exception."""
    t = output_times(20.0, 0.5)
    blk = Block(8.67, 0.035, 0.21)
    fnd = Foundation(np.array([2.89e7, 1e10, 2.89e7]), np.array([8.95e8, 0.0, 1e11]), np.array([6e7, 1e9, -1e7]))
    for exc in (WhiteNoise(S0), KanaiTajimi(S0, 200.0, 0.01), KanaiTajimi(S0, 0.5, 2.0)):
        res = solve_moments(blk, fnd, exc, t, max_steps=20_000)
        for i in range(3):
            one = {name: value[i] for name, value in res.items()}
            assert _check_solution(one, t, blk, 20_000) != PointStatus.ok
