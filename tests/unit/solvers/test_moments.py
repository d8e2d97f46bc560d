"""The moment equations' solver, on the paper's condensation (pinned here: the package default is
another; a ``condensation=`` argument overrides the pin)."""

from functools import partial

import numpy as np
import pytest
from scipy import integrate

from screening.core.model.cases import PAPER_CASES, paper_case
from screening.core.condensation.paper import damping_inner, uplift_threshold
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi, kanai_tajimi_stationary_moments
from screening.core.excitations.white import WhiteNoise
from screening.core.condensation.uplift_integrals import coefficient_table
from screening.core.condensation import get as get_condensation
from screening.core.model.points import flatten
from screening.kernels.moment_kernels import augmented_rhs
from screening.solvers import moments as _moments
from screening.solvers.moments import oscillator_records
from screening.core.status import PointStatus
from screening.core.model import Foundation
from screening.solvers.timegrid import output_times

solve_moments = partial(_moments.solve_moments, condensation="paper")


def _linear_constants(block, foundation):
    M = block.m_sdof
    k1 = 2 / 3 * block.b**3 * foundation.k - block.m * block.g * block.h
    w = np.sqrt(k1 / M)
    zeta = damping_inner(block, foundation) / (2 * M * w)
    return w, zeta, block.m * block.h / M


@pytest.mark.parametrize("foundation", [Foundation(2.89e7, 8.95e8), Foundation(k=2.89e7, c=3.0e3)])
def test_linear_stationary_variance(paper_block, foundation):
    """No uplift (sigma << theta_ul), eps = 0, constant envelope: pi S0 a^2 / (2 zeta w^3)."""
    S0 = 1e-14
    res = solve_moments(paper_block, foundation, WhiteNoise(S0, ConstantEnvelope()), output_times(12.0, 0.5))
    w, zeta, a = _linear_constants(paper_block, foundation)
    assert res["p_uplift"].max() < 1e-300
    assert res["var_theta"][-1] == pytest.approx(np.pi * S0 * a**2 / (2 * zeta * w**3), rel=1e-3)
    assert res["var_theta_dot"][-1] == pytest.approx(np.pi * S0 * a**2 / (2 * zeta * w), rel=1e-3)
    assert abs(res["cov_theta_theta_dot"][-1]) < 1e-3 * np.sqrt(res["var_theta"][-1] * res["var_theta_dot"][-1])


def test_kanai_tajimi_linear_stationary_variance_matches_frequency_domain(paper_block):
    fnd = Foundation(2.89e7, 8.95e8)
    exc = KanaiTajimi(1e-14, 30.0, 0.3, ConstantEnvelope())
    res = solve_moments(paper_block, fnd, exc, output_times(14.0, 0.5))
    w, zeta, a = _linear_constants(paper_block, fnd)
    H2 = lambda om: a**2 / ((w**2 - om**2) ** 2 + (2 * zeta * w * om) ** 2)
    pts = [-w, -30.0, 30.0, w]
    var = integrate.quad(lambda om: H2(om) * exc.psd(om), -np.inf, np.inf, points=None, limit=500, epsrel=1e-10)[0]
    var_ref = sum(integrate.quad(lambda om: H2(om) * exc.psd(om), lo, hi, limit=500, epsrel=1e-11)[0]
                  for lo, hi in zip([-np.inf] + pts, pts + [np.inf]))
    assert var == pytest.approx(var_ref, rel=1e-6)
    assert res["var_theta"][-1] == pytest.approx(var_ref, rel=1e-3)


def test_kanai_tajimi_filter_block_of_the_moment_equations_is_stationary_at_closed_form(paper_block):
    """The filter entries of the 4x4 Lyapunov right-hand side vanish at the closed-form moments."""
    S0, wg, zg = 2e-4, 10.0, 0.4
    (block, bed, exc), _ = flatten(paper_block, Foundation(2.89e7, 8.95e8), KanaiTajimi(S0, wg, zg))
    var_u, var_ud, _ = kanai_tajimi_stationary_moments(S0, wg, zg)
    y = np.zeros(10)
    y[7], y[8], y[9] = var_u, 0.0, var_ud  # (22 23 33) entries
    dy = np.zeros(10)
    filt = exc.filter()
    fa, fb, fc = (np.ascontiguousarray(m[0]) for m in filt[:3])
    augmented_rhs(1e3, 1.0, 0.0, 2.0 * np.pi * S0, fa, fb, fc, float(filt.D[0]), y, dy, np.empty((4, 4)),
                  np.empty((4, 4)))
    np.testing.assert_allclose(dy[7:], 0.0, atol=1e-12 * var_ud * wg)


@pytest.mark.parametrize("name", list(PAPER_CASES))
def test_time_step_convergence_on_paper_cases(name):
    """Halving the largest step and tightening the tolerance 32x (= halving a 5th-order step)."""
    t = output_times(20.0, 0.05)
    base = solve_moments(*paper_case(name), t)
    for kwargs in ({"h_max": 0.005}, {"rtol": 1e-7 / 32}):
        fine = solve_moments(*paper_case(name), t, **kwargs)
        assert fine["peak_var_theta"] == pytest.approx(base["peak_var_theta"], rel=1e-3)
    half = solve_moments(*paper_case(name), t, h_max=0.0025)
    assert half["peak_var_theta"] == pytest.approx(fine["peak_var_theta"], rel=1e-5)


def test_point_alone_or_in_batch_gives_identical_results(paper_block):
    t = output_times(20.0, 0.05)
    eps = np.array([-6e5, 0.0, 6e7, -5e8])
    S0 = np.array([1e-5, 5e-4, 2.4e-3, 1e-4])
    batch = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, eps), WhiteNoise(S0), t)
    for i in range(4):
        one = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, eps[i]), WhiteNoise(S0[i]), t)
        for key, value in one.items():
            np.testing.assert_array_equal(batch[key][i], value)


def test_negative_no_uplift_stiffness_is_flagged_at_start_without_touching_other_points(paper_block):
    t = output_times(20.0, 0.05)
    fnd = Foundation(2.89e7, 8.95e8, np.array([-1e9, 6e7]))
    res = solve_moments(paper_block, fnd, WhiteNoise(1e-4), t)
    assert res["status"][0] == PointStatus.k_eq_negative and res["t_stop"][0] == 0.0
    assert res["k_eq"][0, 0] < 0 and np.all(np.isnan(res["var_theta"][0, 1:]))
    alone = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, 6e7), WhiteNoise(1e-4), t)
    assert res["status"][1] == PointStatus.ok
    np.testing.assert_array_equal(res["var_theta"][1], alone["var_theta"])


def test_near_toppling_point_stops_cleanly_with_a_flag(paper_block):
    t = output_times(20.0, 0.05)
    res = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, 0.0), WhiteNoise(np.array([1.0, 1e-4])), t)
    assert res["status"][0] in (PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness)
    stop = res["t_stop"][0]
    assert 0 < stop < 20.0
    before = t <= stop
    assert np.all(np.isfinite(res["var_theta"][0, before])) and np.all(np.isnan(res["var_theta"][0, ~before]))
    assert res["status"][1] == PointStatus.ok and np.all(np.isfinite(res["var_theta"][1]))


def test_step_budget_is_flagged(paper_block):
    res = solve_moments(paper_block, Foundation(2.89e7, 8.95e8), WhiteNoise(1e-4), output_times(20.0, 0.05),
                        max_steps=50)
    assert res["status"] == PointStatus.step_budget_exhausted and res["n_steps"] == 50 and res["t_stop"] < 20.0


def test_peak_is_refined_inside_steps(paper_block):
    t = output_times(20.0, 0.05)
    res = solve_moments(*paper_case("fig3_white_hardening_high"), t)
    sampled = res["var_theta"]
    assert res["peak_var_theta"] >= sampled.max()
    assert res["peak_var_theta"] == pytest.approx(sampled.max(), rel=1e-3)
    assert abs(res["t_peak_var_theta"] - t[sampled.argmax()]) <= 0.05
    dense = solve_moments(*paper_case("fig3_white_hardening_high"), output_times(20.0, 0.001))
    assert res["peak_var_theta"] == pytest.approx(dense["var_theta"].max(), rel=1e-6)


def test_uplift_occupancy_is_eq58_of_the_variance(paper_block):
    fnd = Foundation(2.89e7, 8.95e8, -6e5)
    res = solve_moments(paper_block, fnd, WhiteNoise(5e-4), output_times(20.0, 0.05))
    from scipy.special import erfc
    tu = uplift_threshold(paper_block, fnd)
    s = np.sqrt(res["var_theta"][1:])
    np.testing.assert_allclose(res["p_uplift"][1:], erfc(tu / (np.sqrt(2) * s)), rtol=1e-12)


def test_undamped_bed_stays_finite(paper_block):
    res = solve_moments(paper_block, Foundation(2.89e7, 0.0, 0.0), WhiteNoise(1e-6), output_times(20.0, 0.05))
    assert res["status"] in (PointStatus.ok, PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness)
    assert np.all(np.isfinite(res["var_theta"][: int(res["t_stop"] / 0.05)]))


def test_bad_output_grid_is_rejected(paper_block):
    with pytest.raises(ValueError, match="t_out"):
        solve_moments(paper_block, Foundation(2.89e7, 8.95e8), WhiteNoise(1e-4), np.array([0.0, 1.0, 0.5]))


# ---------------------------------------------------------------- cubic condensation
from screening.core.condensation import cubic  # noqa: E402
from screening.solvers import moments as lyapunov  # noqa: E402
from screening.core.condensation.api import equivalent_coefficients_from_moments  # noqa: E402
from screening.analysis import linearization as _linearization  # noqa: E402

linearize = partial(_linearization.linearize, condensation="paper")


@pytest.mark.parametrize("excitation", [WhiteNoise(2.4e-3), KanaiTajimi(2e-3, 10.0, 0.4)], ids=["white", "kt"])
def test_cubic_with_eps_zero_reproduces_the_paper_solution(paper_block, excitation):
    t = output_times(20.0, 0.05)
    bed = Foundation(2.89e7, 8.95e8, 0.0)
    paper = solve_moments(paper_block, bed, excitation, t)
    cub = solve_moments(paper_block, bed, excitation, t, condensation="cubic")
    assert paper["status"] == cub["status"] == PointStatus.ok
    assert paper["peak_p_uplift"] > 0.05                       # the uplift tables are exercised
    assert cub["peak_var_theta"] == pytest.approx(paper["peak_var_theta"], rel=1e-6)
    for name in ("var_theta", "var_theta_dot"):
        np.testing.assert_allclose(cub[name], paper[name], rtol=0, atol=1e-5 * np.max(paper[name]))


@pytest.mark.parametrize("foundation", [Foundation(2.89e7, 8.95e8, 6e7), Foundation(k=2.89e7, c=3.0e3, eps=-2e7)])
def test_cubic_linear_stationary_variance_uses_the_rest_indentation(paper_block, foundation):
    """No uplift, constant envelope: pi S0 a^2 / (2 zeta w^3) with the cubic K(0), C(0)."""
    S0 = 1e-14
    res = solve_moments(paper_block, foundation, WhiteNoise(S0, ConstantEnvelope()), output_times(12.0, 0.5),
                        condensation="cubic")
    M = paper_block.m_sdof
    w = np.sqrt(cubic.stiffness_at_rest(paper_block, foundation) / M)
    zeta = cubic.damping_at_rest(paper_block, foundation) / (2 * M * w)
    a = paper_block.m * paper_block.h / M
    expected = np.pi * S0 * a**2 / (2 * zeta * w**3)
    assert res["var_theta"][-1] == pytest.approx(expected, rel=1e-3)
    paper = solve_moments(paper_block, foundation, WhiteNoise(S0, ConstantEnvelope()), output_times(12.0, 0.5))
    assert abs(paper["var_theta"][-1] / expected - 1) > 0.01        # the condensations differ here


def test_compiled_cubic_coefficients_match_the_quadrature(paper_block, cubic_bed):
    (block, bed), _ = flatten(paper_block, cubic_bed)
    kernel = get_condensation("cubic").moment_kernel(block, bed)
    tables = kernel.tables
    tu = cubic.uplift_threshold(paper_block, cubic_bed)
    assert kernel.records["inv_theta_ul2"][0] == 1.0 / tu**2
    k_scale = cubic.stiffness_at_rest(paper_block, cubic_bed)
    ratios = np.concatenate([[0.0, 1e-7], np.logspace(-3, np.log10(4 * paper_block.slenderness / tu), 41)])
    var = (ratios * tu) ** 2
    for rho in (-0.9, 0.0, 0.9):
        cov = rho * var * 40.0
        c_ref, k_ref = equivalent_coefficients_from_moments(var, cov, paper_block, cubic_bed, condensation="cubic")
        for i in range(var.size):
            c, k = kernel.coefficients(kernel.records[0], tables[0], var[i], cov[i])
            assert c == pytest.approx(c_ref[i], rel=1e-6)
            assert k == pytest.approx(k_ref[i], rel=1e-6, abs=1e-9 * k_scale)


def test_cubic_point_alone_or_in_batch_gives_identical_results(paper_block, monkeypatch):
    monkeypatch.setattr(lyapunov, "CHUNK", 3)              # several chunks, one split mid-row
    t = output_times(20.0, 0.05)
    eps = np.array([-6e5, 0.0, 6e7])[:, None]
    S0 = np.array([1e-5, 5e-4])[None, :]
    batch = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, eps), WhiteNoise(S0), t, condensation="cubic")
    assert batch["var_theta"].shape == (3, 2, t.size)
    for i in range(3):
        for j in range(2):
            one = solve_moments(paper_block, Foundation(2.89e7, 8.95e8, eps[i, 0]), WhiteNoise(S0[0, j]), t,
                                condensation="cubic")
            for key, value in one.items():
                np.testing.assert_array_equal(batch[key][i, j], value)


def test_condensation_is_validated_before_any_work(paper_block):
    t = output_times(20.0, 0.05)
    with pytest.raises(ValueError, match=r"'condensation'.*\('paper', 'cubic', 'virtual_work'\)"):
        solve_moments(paper_block, Foundation(2.89e7, 8.95e8), WhiteNoise(1e-4), t, condensation="exact")
    with pytest.raises(ValueError, match="'condensation'"):
        linearize(paper_block, Foundation(2.89e7, 8.95e8), WhiteNoise(1e-4), condensation="Cubic")
    beds = Foundation(2.89e7, 8.95e8, np.array([6e7, -3e8]))       # the second cannot carry the block
    with pytest.raises(ValueError, match="'foundation.eps'"):
        solve_moments(paper_block, beds, WhiteNoise(1e-4), t, condensation="cubic")


def test_linearize_records_the_condensation(paper_block):
    exc = WhiteNoise(2.4e-5, Envelope(4.0, 2.0))
    bed = Foundation(2.89e7, 8.95e8, 6e7)
    paper = linearize(paper_block, bed, exc)
    cub = linearize(paper_block, bed, exc, condensation="cubic")
    assert paper.attrs["condensation"] == "paper" and cub.attrs["condensation"] == "cubic"
    assert float(paper.theta_ul) == uplift_threshold(paper_block, bed)
    assert float(cub.theta_ul) == cubic.uplift_threshold(paper_block, bed)
    assert cub.attrs["theta_capacity"] == np.inf and cub.attrs["peak_p_beyond_capacity"] == 0.0
    # hardening bed: the true rest indentation is smaller, the block softer and less damped
    assert float(cub.peak_var_theta) > 1.05 * float(paper.peak_var_theta)


def test_linearize_reports_the_reach_beyond_the_capacity_angle(paper_block):
    bed = Foundation(2.89e7, 8.95e8, -2e7)
    ds = linearize(paper_block, bed, WhiteNoise(5e-4, Envelope(4.0, 2.0)), condensation="cubic")
    cap = cubic.capacity_angle(paper_block, bed)
    assert ds.attrs["theta_capacity"] == pytest.approx(cap, rel=1e-14)
    from scipy.special import erfc
    expected = erfc(cap / np.sqrt(2 * float(ds.peak_var_theta)))
    assert ds.attrs["peak_p_beyond_capacity"] == pytest.approx(expected, rel=1e-12)
    assert 0.0 < ds.attrs["peak_p_beyond_capacity"] < 1.0


def test_compiled_uplift_probability_and_envelope_are_their_numpy_references(paper_block):
    """The solver's p_uplift history is eq. (58) of its own var_theta; its stage gains are m h q(t) / M."""
    from screening.core.condensation.api import uplift_probability
    from screening.kernels import dopri

    bed = Foundation(2.89e7, 8.95e8, -6e5)
    res = solve_moments(paper_block, bed, WhiteNoise(6.5e-4), output_times(20.0, 0.05))
    ok = np.isfinite(res["var_theta"])
    ref = uplift_probability(np.sqrt(res["var_theta"][ok]), paper_block, bed, condensation="paper")
    assert ref.max() > 0.5                                       # the heavy-uplift regime is exercised
    np.testing.assert_allclose(res["p_uplift"][ok], ref, rtol=1e-12, atol=1e-300)
    (block, fnd, exc), _ = flatten(paper_block, bed, WhiteNoise(1e-4, Envelope(4.0, 2.0)))
    osc = oscillator_records(block, fnd, exc, get_condensation("paper"))[0]
    from screening.kernels.moment_kernels import envelope_state, initial_gain, stage_gains

    gain = paper_block.m * paper_block.h / paper_block.m_sdof
    for t, h in ((0.0, 0.01), (2.7, 0.3), (19.5, 0.5)):
        e1, e2 = envelope_state(osc, t)
        *gains, f1, f2 = stage_gains(osc, e1, e2, h)
        got = np.array([initial_gain(osc, e1, e2), *gains])
        expected = gain * Envelope(4.0, 2.0)(t + np.array([0.0, *dopri.C[1:6]]) * h)
        np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-16)
        # the factors carry the envelope state to t + h
        np.testing.assert_allclose([e1 * f1, e2 * f2], envelope_state(osc, t + h), rtol=1e-15)


@pytest.mark.parametrize("exc", [WhiteNoise(np.array([1e-5, 2.4e-3])), KanaiTajimi(np.array([1e-5, 2.4e-3]), 15.6, 0.6)])
def test_summaries_without_histories_are_those_with_histories(paper_block, exc):
    """histories=False skips the output stores only: every summary is bit for bit the same."""
    t = output_times(20.0, 0.05)
    bed = Foundation(2.89e7, 8.95e8, np.array([-6e5, 6e7]))
    full = solve_moments(paper_block, bed, exc, t)
    bare = solve_moments(paper_block, bed, exc, t, histories=False)
    assert "var_theta" in full and not set(bare) & {"var_theta", "p_uplift", "c_eq"}
    for key, value in bare.items():
        np.testing.assert_array_equal(value, full[key], err_msg=key)
