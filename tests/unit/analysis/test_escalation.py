"""Choice of the escalated points, their model and sample count (screening.analysis.escalation)."""

import numpy as np
import pytest

from screening.analysis.escalation import (GRID_COST_S, GRID_DOUBLING_COST_S, GRID_REFERENCE_POINTS, MAX_POINTS,
                                           MAX_SAMPLES, MIN_SAMPLES, PRIOR_STEPS_PER_S, PROBABILITY_SE,
                                           RODAS_STEP_FACTOR, STEP_COST_S, condensed_cells, cover_points,
                                           escalation_candidates, escalation_model, estimated_cost, grid_point_cost,
                                           meets_target, prior_cost, probabilities_met, probability_samples,
                                           samples_needed, transition_first, transition_points)
from screening.solvers.estimates import binomial_estimate
from screening.analysis.trust import shipped_calibration
from screening.core.status import BestMethod, EscalationModel, PointStatus, Trust


def test_candidates_are_the_points_the_rule_does_not_promise():
    status = np.array([0, 0, 0, 1, -1, 0])
    trust = np.array([Trust.trusted, Trust.trusted, Trust.check, Trust.untrusted, Trust.untrusted, Trust.untrusted])
    # the last point: SL is 35-45 % too low, but the atlas interval (a factor 1.09 each way about its centre) is
    # narrower than the target: the atlas-corrected value promises it, no Monte Carlo
    low = np.array([-0.05, -0.3, -0.05, np.nan, np.nan, -0.45])
    high = np.array([0.05, 0.05, 0.4, np.nan, np.nan, -0.35])
    assert escalation_candidates(status, trust, low, high, 0.15).tolist() == [False, True, True, True, False, False]
    assert escalation_candidates(status, trust, low, high, 0.05).tolist() == [False, True, True, True, False, True]


def test_cover_points_start_at_the_worst_corner_and_spread_over_the_region():
    g = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0), indexing="ij"), -1).reshape(-1, 2)
    candidates = g[:, 0] >= 5                               # the untrusted half
    priority = g[:, 0] + g[:, 1]
    chosen = cover_points(g, candidates, priority, 4)
    assert chosen[0] == np.argmax(np.where(candidates, priority, -1))      # the worst corner first
    assert np.all(candidates[chosen])
    pts = g[chosen]
    # the four corners of the candidate region, not a cluster around the worst one
    assert np.ptp(pts[:, 0]) == 4 and np.ptp(pts[:, 1]) == 9
    assert cover_points(g, np.zeros(100, bool), priority, 4).size == 0
    assert cover_points(g, candidates, priority, 500).size == candidates.sum()


def test_samples_scale_with_the_inverse_square_of_the_target():
    # relative SE 0.3 with 32 samples -> (0.3 / 0.075)^2 x 32 = 512 for a target of 0.15, x 1.5 safety
    assert samples_needed(0.3, 32, 0.15, safety=1.0) == 512
    assert samples_needed(0.3, 32, 0.15) == 768
    assert samples_needed(0.01, 32, 0.15) == MIN_SAMPLES
    assert samples_needed(5.0, 32, 0.01) == MAX_SAMPLES
    assert samples_needed(float("nan"), 32, 0.15, most=700) == 700


def test_condensed_only_where_the_calibration_shows_it_close_to_coupled():
    cells = condensed_cells(shipped_calibration(), 0.15)
    assert cells[("softening", 0)] and not cells[("hardening", 0)]       # paper condensation errs on hardening beds
    ind = {"peak_p_uplift": np.array([0.001, 0.001, 0.001, 0.001, 0.001]),
           "k_eq_margin": np.array([0.9, 0.9, 0.9, 0.9, 0.1]), "sigma_ratio": np.full(5, 0.01),
           "decay_excess": np.array([1.0, 1.0, 1.0, 50.0, 1.0])}
    models = escalation_model(ind, np.array([0, 0, 0, 0, 0]), np.array(["paper", "paper", "cubic", "paper", "paper"]),
                              np.array([-6e5, 6e7, -6e5, -6e5, -6e5]), cells)
    c, k = int(EscalationModel.condensed), int(EscalationModel.coupled)
    assert models.tolist() == [c, k, k, k, k]          # hardening, cubic, lock-in, near toppling: coupled
    stopped = escalation_model(ind, np.full(5, int(PointStatus.k_eq_negative)), "paper", -6e5, cells)
    assert np.all(stopped == k)


def test_transition_points_are_where_each_curve_goes_from_0_to_1_along_the_intensity():
    # two curves (eps = 0, eps = 6e7) along S0, stored out of order (S0 = 3, 1, 2, 4, 5, 6): read in the
    # order of S0; two levels (P(overturn), P(exceed))
    s0 = np.array([3.0, 1.0, 2.0, 4.0, 5.0, 6.0])
    over = np.array([[0.0, 0.0, 0.0, 0.0, 0.5, 0.99],            # eps = 0: 0.5 at S0 = 5
                     [0.001, 0.0, 0.0, np.nan, np.nan, np.nan]])  # eps = 6e7: the linearization stopped from S0 = 4
    exceed = np.array([[0.01, 0.0, 0.0, 1.0, 1.0, 1.0],           # a jump across the band from S0 = 3 to 4
                       [0.0, 0.0, 0.0, np.nan, np.nan, np.nan]])
    p = np.stack([over.reshape(-1), exceed.reshape(-1)], axis=-1)
    got = transition_points(p, (2, 6), axis=1, intensity=s0).reshape(2, 6)
    assert got[0].tolist() == [True, False, False, True, True, False]   # jump 3 -> 4, 0.5 at 5; 0.99 is above
    assert got[1].tolist() == [True, False, False, True, False, False]  # the last known and the first stopped
    # without a swept intensity the band alone decides
    assert transition_points(p, (2, 6)).reshape(2, 6)[0].tolist() == [False, False, False, False, True, False]
    # the grid's other order gives the same points
    assert np.array_equal(transition_points(p.reshape(2, 6, 2).transpose(1, 0, 2).reshape(12, 2), (6, 2), axis=0,
                                            intensity=s0).reshape(6, 2).T, got)


def test_transition_points_come_first_then_the_coverage_of_the_others():
    rng = np.random.default_rng(3)
    features = rng.normal(size=(40, 3))
    candidates = rng.random(40) < 0.8
    priority = rng.random(40)
    transition = np.zeros(40, dtype=bool)
    # without transition points the order is the coverage order, unchanged
    np.testing.assert_array_equal(transition_first(features, candidates, transition, priority, 12),
                                  cover_points(features, candidates, priority, 12))
    transition[[2, 5, 7, 30, 31]] = True
    order = transition_first(features, candidates, transition, priority, 12)
    first = [i for i in (2, 5, 7, 30, 31) if candidates[i]]
    assert sorted(order[:len(first)].tolist()) == first            # every transition candidate, first
    assert order[0] == max(first, key=lambda i: priority[i])       # the first by priority
    assert len(order) == 12 and len(set(order.tolist())) == 12 and np.all(candidates[order])
    assert not np.any(transition[order[len(first):]])
    # many transition points: all of them (up to the cap), however small the count
    transition[:] = True
    assert len(transition_first(features, candidates, transition, priority, 3)) == int(candidates.sum())
    assert len(transition_first(features, candidates, transition, priority, 3, most_transition=5)) == 5


def test_probability_samples_reach_the_standard_error_aimed_at():
    for hits, used in (([32], 64), ([3, 20, 60], 64), ([64], 64)):
        n = probability_samples(hits, used)
        assert MIN_SAMPLES <= n <= MAX_SAMPLES
        q = (np.asarray(hits) + 2.0) / (used + 4.0)               # the pilot's fractions at n samples
        se = np.sqrt(q * (1 - q) / (n + 4.0))
        assert np.all(se <= PROBABILITY_SE + 1e-12) and (n == MIN_SAMPLES or np.max(se) > 0.99 * PROBABILITY_SE)
    assert probability_samples([], 0) == MAX_SAMPLES
    assert probability_samples([32], 64, most=200) == 200
    assert probabilities_met([140], 280) == bool(binomial_estimate(140, 280)[1] <= PROBABILITY_SE)
    assert probabilities_met([0, 140], 280) and not probabilities_met([0, 140], 200)


def test_target_is_met_when_two_standard_errors_fit_in_it():
    peak = np.array([1.0, 1.0, 1.0, np.nan, 0.0])
    se = np.array([0.075, 0.0751, np.nan, 0.01, 0.0])
    assert meets_target(peak, se, 0.15).tolist() == [True, False, False, False, False]


def test_sample_size_rule_reaches_the_target_on_a_heavy_tailed_peak():
    # a variance estimated from a heavy-tailed response (student t, 5 dof): pilot of 64, main run with the
    # safety factor, then one top-up from the main run's SE, as the escalation does.  Measured with this
    # seed: 50 % of 400 repetitions reach target / 2 after the main run, 93 % after the top-up (a 32-sample
    # pilot without factor or top-up: 20 %); the bound leaves 4 binomial SEs (1.3 % each)
    rng = np.random.default_rng(7)

    def rel_se(x):
        return np.sqrt(np.var(x ** 2, ddof=1) / x.size) / np.var(x, ddof=1)

    met = []
    for _ in range(400):
        rel = rel_se(rng.standard_t(5, size=64))
        n = samples_needed(rel, 64, 0.15, most=10**6)
        rel = rel_se(rng.standard_t(5, size=n))
        if rel > 0.075:
            rel = rel_se(rng.standard_t(5, size=samples_needed(rel, n, 0.15, most=10**6)))
        met.append(rel <= 0.075)
    assert np.mean(met) >= 0.87


def test_cost_model_is_linear_in_the_steps_and_cheaper_for_the_condensed_model():
    c, k = EscalationModel.condensed, EscalationModel.coupled
    assert estimated_cost(2_000_000, k) == pytest.approx(2_000_000 * STEP_COST_S[k], rel=1e-12)
    assert estimated_cost(1000, c) < estimated_cost(1000, k)
    assert prior_cost(64, 20.0, k) == pytest.approx(estimated_cost(64 * 20.0 * PRIOR_STEPS_PER_S, k), rel=1e-12)


def test_cost_model_adds_the_synthesis_grid_and_escalation_runs_report_it():
    from screening.core.model import Block, Foundation
    from screening.core.excitations.white import WhiteNoise
    from screening.solvers.synthesis import spectral_plan, synthesis_cutoff
    from screening.sweep.execution import escalation_task

    k = EscalationModel.coupled
    n = GRID_REFERENCE_POINTS
    assert estimated_cost(1000, k, n) == pytest.approx(1000 * STEP_COST_S[k] + n * GRID_COST_S, rel=1e-12)
    # a point costs more on a larger grid (one GRID_DOUBLING_COST_S per doubling), the same for any number of
    # samples: 100 samples of n points cost 100 x one sample's synthesis
    assert grid_point_cost(8 * n) - grid_point_cost(n) == pytest.approx(3 * GRID_DOUBLING_COST_S, rel=1e-12)
    assert estimated_cost(0, k, 100 * 8 * n, samples=100) == pytest.approx(100 * estimated_cost(0, k, 8 * n), rel=1e-12)
    assert estimated_cost(0, k, 100 * 8 * n, samples=100) < estimated_cost(0, k, 100 * 8 * n)
    assert grid_point_cost(1) > 0.0
    block, bed, motion = Block(m=8.67, b=0.035, h=0.21), Foundation(k=1e9, lam=1e10, eps=0.0), WhiteNoise(S0=1e-5)
    out = escalation_task(block, bed, motion, None, 3, "coupled", 0.2, 0.05, 0)
    plan = spectral_plan(motion, 0.2, synthesis_cutoff(motion, block, bed))    # to the top of the 25-Hz band
    assert int(out["n_grid"]) == 3 * plan.n_times                  # the grid the samples were synthesized on
    assert not out["rodas"]                                          # a lightly damped bed: the explicit pair
    assert estimated_cost(1000, k, 0, rodas=True) == pytest.approx(1000 * STEP_COST_S[k] * RODAS_STEP_FACTOR)


def test_an_escalated_stiff_bed_run_reports_what_its_cost_model_needs():
    """The escalation task hands on the full-contact share and the exact-contact flag of its run (the accuracy
    stage charged every stiff-bed run the single cost per step without them: 682 CPU s predicted for 106 measured
    on the acceptance collection); with them the run is charged FAST_COSTS_S."""
    from screening.analysis.beds import lam_from_vertical_damping
    from screening.core.excitations.kanai_tajimi import KanaiTajimi
    from screening.core.model import Block, Foundation
    from screening.sweep.execution import escalation_task

    statue = Block(m=1200.0, b=0.25, h=0.9)
    bed = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, statue.m, statue.b, 0.05)))
    out = escalation_task(statue, bed, KanaiTajimi(0.015, 15.6, 0.6), None, 4, "stiff_bed_fast", 2.0, 0.05, 0)
    assert bool(out["exact"]) and 0.0 <= float(out["full_contact"]) <= 1.0
    sb = EscalationModel.stiff_bed
    charged = estimated_cost(out["n_steps"], sb, out["n_grid"], False, 4, full_contact=out["full_contact"],
                             exact=True)
    assert charged < estimated_cost(out["n_steps"], sb, out["n_grid"], False, 4, full_contact=out["full_contact"])

def test_stiff_bed_cost_splits_exact_intervals_from_adaptive_steps_as_documented():
    from screening.analysis.escalation import (STIFF_BED_ADAPTIVE_COST_S, STIFF_BED_EXACT_COST_S,
                                               STIFF_BED_RUN_COST_S)

    sb = EscalationModel.stiff_bed
    samples, points = 64, 15_596                     # the statue's k = 1e10 grid per sample
    grid = samples * points
    intervals = samples * (points - 1)
    synth = grid * grid_point_cost(points)
    # the documented formula, term by term: E = min(f x intervals, steps), A = steps - E
    for f, steps in ((1.0, 1_023_000), (0.5, 700_000), (0.05, 460_000), (0.9, 10_000), (0.0, 300_000)):
        exact = min(f * intervals, steps)
        expected = exact * STIFF_BED_EXACT_COST_S + (steps - exact) * STIFF_BED_ADAPTIVE_COST_S \
            + STIFF_BED_RUN_COST_S + synth
        assert estimated_cost(steps, sb, grid, samples=samples, full_contact=f) == pytest.approx(expected, rel=1e-12)
    # finite and non-negative on the whole range; more steps cost more; at equal steps, a larger full-contact
    # share (more exact intervals, each cheaper than an adaptive step) costs less
    shares = np.linspace(0.0, 1.0, 21)
    for steps in (0, 1000, 500_000, 5_000_000):
        cost = np.array([estimated_cost(steps, sb, grid, samples=samples, full_contact=f) for f in shares])
        assert np.all(np.isfinite(cost)) and np.all(cost > 0)
        assert np.all(np.diff(cost) <= 0.0)
    steps = np.linspace(0, 3e6, 31)
    for f in (0.0, 0.3, 1.0):
        cost = np.array([estimated_cost(s, sb, grid, samples=samples, full_contact=f) for s in steps])
        assert np.all(np.diff(cost) > 0.0)
    assert STIFF_BED_EXACT_COST_S < STIFF_BED_ADAPTIVE_COST_S
    # a share outside [0, 1] is clipped, not extrapolated
    assert estimated_cost(5e5, sb, grid, samples=samples, full_contact=1.7) == estimated_cost(
        5e5, sb, grid, samples=samples, full_contact=1.0)
    # without the share: the single cost per step
    assert estimated_cost(1000, sb) == pytest.approx(1000 * STEP_COST_S[sb], rel=1e-12)


def test_the_exact_contact_sampler_is_charged_its_own_constants():
    """``exact=True`` on the stiff-bed model (the exact-contact sampler, what ``auto`` runs): the same split of
    exact intervals and adaptive steps, at FAST_COSTS_S, with its own grid term (measured / predicted on 32 runs of
    benchmarks/bench_stiff_mcs.py --stiff-bed --sampler stiff_bed_fast: 0.89-1.17)."""
    from screening.analysis.escalation import FAST_COSTS_S as c

    sb = EscalationModel.stiff_bed
    samples, points = 64, 11_249
    grid, intervals = samples * points, samples * (points - 1)
    for f, steps in ((1.0, 745_000), (0.1, 360_000), (0.0, 150_000)):
        exact = min(f * intervals, steps)
        expected = exact * c["exact"] + (steps - exact) * c["adaptive"] + c["run"] + grid * c["grid"]
        got = estimated_cost(steps, sb, grid, samples=samples, full_contact=f, exact=True)
        assert got == pytest.approx(expected, rel=1e-12)
        assert got < estimated_cost(steps, sb, grid, samples=samples, full_contact=f)     # cheaper than the reference
    assert c["exact"] < c["adaptive"]
    # before any run: a second of record and sample at the costliest fitted run's rate, below the reference's prior
    from screening.analysis.escalation import FAST_PRIOR_S_PER_S, prior_cost
    assert prior_cost(64, 20.0, sb, exact=True) == pytest.approx(64 * 20.0 * FAST_PRIOR_S_PER_S, rel=1e-12)
    assert prior_cost(64, 20.0, sb, exact=True) < prior_cost(64, 20.0, sb)
    assert prior_cost(64, 20.0, EscalationModel.coupled, exact=True) == prior_cost(64, 20.0, EscalationModel.coupled)

def test_full_contact_share_is_the_mean_occupancy_out_of_the_used_samples():
    from screening.analysis.escalation import full_contact_share

    rng = np.random.default_rng(3)
    uplift = rng.random((40, 401)) < np.linspace(0.0, 0.8, 401)       # samples x instants, uplift flags
    p = uplift.mean(axis=0)
    # independent count: instants in full contact over all instants of the used samples
    assert full_contact_share(p, 40, 40) == pytest.approx(np.count_nonzero(~uplift) / uplift.size, rel=1e-12)
    assert full_contact_share(p, 30, 40) == pytest.approx(0.75 * np.count_nonzero(~uplift) / uplift.size, rel=1e-12)
    assert full_contact_share(np.full(5, np.nan), 0, 8) == 0.0      # every sample overturned: nothing exact
    assert full_contact_share(np.zeros(5), 8, 8) == 1.0


def test_auto_escalation_takes_the_stiff_bed_model_only_where_the_rule_picks_it():
    from screening.analysis.escalation import auto_escalation_model

    calibrated = np.array([EscalationModel.condensed, EscalationModel.coupled, EscalationModel.coupled], dtype=np.int8)
    got = auto_escalation_model(calibrated, ["coupled", "stiff_bed", "coupled"])
    np.testing.assert_array_equal(got, [EscalationModel.condensed, EscalationModel.stiff_bed, EscalationModel.coupled])
    assert got.dtype == np.int8
    assert STEP_COST_S[EscalationModel.stiff_bed] > 0


def test_best_method_names_the_stiff_bed_monte_carlo():
    from screening.analysis.correction import best_estimates

    n = 3
    value, se, method, _ = best_estimates(np.ones(n), np.zeros(n, dtype=np.int8), np.zeros(n, dtype=np.int8),
                                          np.full(n, -0.5), np.full(n, 0.5), 0.15, np.zeros((n, 1)),
                                          np.array([0, 1, 2]), np.array([2.0, 3.0, 4.0]), np.array([0.1, 0.1, 0.1]),
                                          np.array([EscalationModel.stiff_bed, EscalationModel.condensed,
                                                    EscalationModel.coupled]))
    np.testing.assert_array_equal(method, [BestMethod.stiff_bed_monte_carlo, BestMethod.condensed_monte_carlo,
                                           BestMethod.coupled_monte_carlo])
    np.testing.assert_array_equal(value, [2.0, 3.0, 4.0])
