"""The two-fidelity (control-variate) estimator: exact algebra, unbiasedness and honest standard errors
over seeds, the allocation against a brute-force optimum, and paired coupled/condensed samples of the
Monte Carlo engine against an independent plain run."""

import math

import numpy as np
import pytest

from screening.analysis.multifidelity import control_variate_estimate, optimal_ratio, speedup

REPEATS = 400


def _pairs(rng, n, rho, mu_y=1.0, sigma_y=2.0):
    x = rng.normal(size=n)
    y = mu_y + sigma_y * (rho * x + math.sqrt(1 - rho * rho) * rng.normal(size=n))
    return y, x


def test_without_extra_cheap_samples_the_estimate_is_the_plain_one():
    y, x = _pairs(np.random.default_rng(1), 50, 0.9)
    est = control_variate_estimate(y, x)
    assert est.mean == pytest.approx(y.mean(), rel=1e-14)
    assert est.se == pytest.approx(np.std(y, ddof=1) / math.sqrt(50), rel=1e-12)
    assert est.correlation == pytest.approx(np.corrcoef(x, y)[0, 1], rel=1e-12)


@pytest.mark.parametrize("rho, n, m", [(0.95, 40, 360), (0.5, 60, 120), (0.0, 50, 200)])
def test_unbiased_and_its_standard_error_matches_the_scatter_over_seeds(rho, n, m):
    """400 independent repetitions: the mean of the estimates is within 4 of its own standard errors
    of the true mean 1.0; the scatter of the estimates matches the reported standard error (the
    relative sampling error of a standard deviation over 400 repetitions is 1/sqrt(800) = 3.5 %:
    bound 15 %), and both match the closed form sigma_y^2/n [1 - (1 - n/N) rho^2]."""
    rng = np.random.default_rng(7)
    means, ses = [], []
    for _ in range(REPEATS):
        y, x = _pairs(rng, n, rho)
        extra = rng.normal(size=m)
        est = control_variate_estimate(y, x, x_extra=extra)
        means.append(est.mean)
        ses.append(est.se)
    means = np.array(means)
    scatter = np.std(means, ddof=1)
    assert abs(means.mean() - 1.0) <= 4 * scatter / math.sqrt(REPEATS)
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.15)
    theory = 2.0 * math.sqrt((1 - (1 - n / (n + m)) * rho * rho) / n)
    assert scatter / theory == pytest.approx(1.0, abs=0.15)


def test_exceedance_indicators_are_estimated_without_bias():
    """Probabilities: indicators of a latent correlated pair exceeding a level (what paired models'
    peaks do); true P = P(Z > 1) = 0.1587 for the expensive one."""
    rng = np.random.default_rng(11)
    p_true = 0.5 * math.erfc(1 / math.sqrt(2))
    means, ses = [], []
    for _ in range(REPEATS):
        z_cheap = rng.normal(size=250)
        z = 0.95 * z_cheap[:50] + math.sqrt(1 - 0.95 ** 2) * rng.normal(size=50)
        cheap = (z_cheap > 0.9).astype(float)           # the cheap model exceeds a little more often
        est = control_variate_estimate((z > 1.0).astype(float), cheap[:50], x_extra=cheap[50:])
        means.append(est.mean)
        ses.append(est.se)
    means = np.array(means)
    scatter = np.std(means, ddof=1)
    assert abs(means.mean() - p_true) <= 4 * scatter / math.sqrt(REPEATS)
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.15)
    plain = math.sqrt(p_true * (1 - p_true) / 50)
    assert scatter < 0.8 * plain                        # the cheap samples pay


def test_a_known_cheap_mean_is_the_classical_control_variate():
    rng = np.random.default_rng(3)
    means = []
    for _ in range(REPEATS):
        y, x = _pairs(rng, 30, 0.9)
        means.append(control_variate_estimate(y, x, x_mean=0.0).mean)
    scatter = np.std(means, ddof=1)
    assert scatter / (2.0 * math.sqrt((1 - 0.81) / 30)) == pytest.approx(1.0, abs=0.15)


def test_the_optimal_ratio_minimises_variance_times_cost_by_brute_force():
    for rho, c1, c2 in [(0.95, 1.0, 0.05), (0.9, 46.0, 1.5), (0.7, 1.0, 0.3), (0.99, 12.0, 0.4)]:
        r = np.linspace(1.0, 400.0, 400_001)
        work = (c1 + r * c2) * (1 - (1 - 1 / r) * rho ** 2)
        assert optimal_ratio(rho, c1, c2) == pytest.approx(r[np.argmin(work)], rel=1e-3, abs=2e-3)
        assert speedup(rho, c1, c2) == pytest.approx(c1 / work.min(), rel=1e-6)


def test_a_perfect_pilot_correlation_asks_for_a_bounded_number_of_cheap_samples():
    from screening.analysis.multifidelity import MAX_RATIO

    assert optimal_ratio(1.0, 10.0, 1.0) == MAX_RATIO
    assert optimal_ratio(1.0, 10.0, 1.0, max_ratio=50.0) == 50.0


def test_the_cheap_model_is_not_worth_it_when_uncorrelated_or_as_expensive():
    assert optimal_ratio(0.0, 1.0, 0.01) == 1.0
    assert speedup(0.0, 1.0, 0.01) < 1.0
    assert speedup(0.9, 1.0, 1.0) < 1.0
    assert speedup(0.95, 30.0, 1.0) > 3.0


@pytest.mark.parametrize("kwargs, word", [({"y": [1, 2], "x": [1, 2]}, "at least 3"),
                                          ({"y": [1, 2, 3], "x": [1, 2]}, "paired"),
                                          ({"y": [1, 2, np.nan], "x": [1, 2, 3]}, "finite"),
                                          ({"y": [1, 2, 3], "x": [1, 2, 3], "x_mean": 0.0, "x_extra": [1.0]}, "either")])
def test_bad_input_names_the_parameter(kwargs, word):
    with pytest.raises(ValueError, match=word):
        control_variate_estimate(**kwargs)


@pytest.mark.slow
def test_paired_condensed_samples_reduce_the_error_of_coupled_exceedance_without_bias():
    """The paper block (fig. 3 case): 64 coupled samples paired with condensed (virtual_work) ones, and
    448 more condensed samples, against an independent 512-sample plain coupled run (other seed):
    P(peak |theta| > a) agrees within 4 combined standard errors, and the paired estimate's standard
    error is never above the plain 64-sample one (at this heavy-uplift point the indicators of the
    two models correlate weakly, about 0.2: the weight follows and the estimate falls back towards
    the plain one, which is the "never worse" half of the contract)."""
    from screening.core.model import Block, Foundation
    from screening.core.excitations import WhiteNoise
    from screening.core.model.cases import PAPER_BED, PAPER_BLOCK
    from screening.solvers.montecarlo import monte_carlo

    block, bed = Block(**PAPER_BLOCK), Foundation(eps=6e7, **PAPER_BED)
    excitation = WhiteNoise(S0=2.4e-3, band_limit_hz=None)      # the paper's case, as measured
    kw = dict(t_end=20.0, dt=0.05)
    coupled = monte_carlo(block, bed, excitation, n_samples=64, model="coupled", seed=5, **kw)
    cheap = monte_carlo(block, bed, excitation, n_samples=512, model="condensed", condensation="virtual_work",
                        seed=5, **kw)
    reference = monte_carlo(block, bed, excitation, n_samples=512, model="coupled", seed=6, **kw)

    def exceeds(ds, level):
        return ((ds.peak_abs_theta.values > level) | ds.overturned.values).astype(float)

    level = 0.3 * math.atan(block.b / block.h)
    y, x = exceeds(coupled, level), exceeds(cheap, level)
    est = control_variate_estimate(y, x[:64], x_extra=x[64:])
    p_ref = exceeds(reference, level).mean()
    se_ref = math.sqrt(max(p_ref * (1 - p_ref), 1e-12) / 512)
    assert 0.05 < p_ref < 0.95                  # a level the test can resolve
    assert abs(est.mean - p_ref) <= 4 * math.hypot(est.se, se_ref)
    assert est.se <= est.plain_se * (1 + 1e-12)
    assert abs(est.weight * np.std(x, ddof=1) / np.std(y, ddof=1) - est.correlation) < 0.1


# ---------------------------------------------------------------- nonlinear functionals (delta method)
def _histories(rng, n, rhos, sigma=2.0):
    """Paired Gaussian 'histories' (samples x times): the cheap one standard normal, the expensive one with
    variance sigma^2 and correlation rho_t with it at each time (the squares then correlate at rho_t^2)."""
    rhos = np.asarray(rhos)
    x = rng.normal(size=(n, rhos.size))
    y = 0.3 + sigma * (rhos * x + np.sqrt(1 - rhos ** 2) * rng.normal(size=(n, rhos.size)))
    return y, x


def test_the_variance_influence_reproduces_the_engines_variance_and_standard_error():
    from screening.analysis.multifidelity import variance_influence
    from screening.solvers.montecarlo import ensemble_statistics

    rng = np.random.default_rng(2)
    theta = rng.standard_t(5, size=(300, 4))
    valid = rng.random(300) > 0.1
    value, psi = variance_influence(theta, valid)
    ref = ensemble_statistics(theta, theta, np.zeros_like(theta, dtype=bool), valid)
    np.testing.assert_allclose(value, ref["var_theta"], rtol=1e-12)
    assert np.abs(psi.sum(axis=0)).max() < 1e-9 * np.abs(psi).max()      # centred over the samples
    # first order: var(psi)/n = (m4 - s^4)/n_valid, the engine's (m4 - (k-3)/(k-1) s^4)/k up to O(1/k)
    se = np.sqrt(np.var(psi, axis=0, ddof=1) / 300)
    np.testing.assert_allclose(se, ref["var_theta_se"], rtol=0.02)


@pytest.mark.parametrize("n, m", [(40, 360), (80, 80)])
def test_the_two_fidelity_variance_is_unbiased_and_its_standard_error_matches_the_scatter(n, m):
    """Ensemble variance (true 4.0) at three times with correlations 0.99, 0.9, 0.5 between the models
    (0.98, 0.81, 0.25 between their squares): over 400 seeds the mean estimate is within 4 of its own
    standard errors of 4.0 plus the O(1/n) bias of the estimated weight (bounded by 2 % here), and the
    scatter matches the mean reported standard error within 15 % (sampling error of a scatter over 400
    repetitions 3.5 %, plus the SE's own first-order error)."""
    from screening.analysis.multifidelity import multifidelity_variance

    rng = np.random.default_rng(17)
    rhos = [0.99, 0.9, 0.5]
    est, ses, plain = [], [], []
    for _ in range(REPEATS):
        y, x = _histories(rng, n, rhos)
        x_all = np.vstack([x, rng.normal(size=(m, 3))])
        r = multifidelity_variance(y, np.ones(n, bool), x_all, np.ones(n + m, bool))
        est.append(r.mean)
        ses.append(r.se)
        plain.append(r.plain_mean)
    est, ses = np.array(est), np.array(ses)
    scatter = est.std(axis=0, ddof=1)
    assert np.all(np.abs(est.mean(axis=0) - 4.0) <= 4 * scatter / math.sqrt(REPEATS) + 0.02 * 4.0)
    np.testing.assert_allclose(scatter / ses.mean(axis=0), 1.0, atol=0.15)
    # and the gain is the one promised: var of a Gaussian variance 2 sigma^4/n, times 1 - (1 - n/N) rho^4
    theory = np.sqrt(2 * 16.0 / n * (1 - (1 - n / (n + m)) * np.array(rhos) ** 4))
    np.testing.assert_allclose(scatter / theory, 1.0, atol=0.15)
    assert np.all(scatter <= np.std(plain, axis=0, ddof=1) * 1.05)


def test_overturned_samples_leave_the_variance_ensemble_of_each_model_as_in_the_engine():
    """Samples invalid in one model only: the two-fidelity estimate stays unbiased for the expensive model's
    conditional variance (here that of the valid ones, |z| < 2: 1 - 2 phi(2) 2 / (2 Phi(2) - 1) = 0.7737)."""
    from screening.analysis.multifidelity import multifidelity_variance

    rng = np.random.default_rng(23)
    truth = 1 - 2 * 2 * math.exp(-2) / math.sqrt(2 * math.pi) / math.erf(2 / math.sqrt(2))
    est, ses = [], []
    for _ in range(REPEATS):
        x = rng.normal(size=(300, 1))
        y = 0.95 * x[:60] + math.sqrt(1 - 0.95 ** 2) * rng.normal(size=(60, 1))
        r = multifidelity_variance(y, np.abs(y[:, 0]) < 2, x, np.abs(x[:, 0]) < 2.2)
        est.append(float(r.mean[0]))
        ses.append(float(r.se[0]))
    scatter = np.std(est, ddof=1)
    assert abs(np.mean(est) - truth) <= 4 * scatter / math.sqrt(REPEATS) + 0.02 * truth
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.15)


def test_two_fidelity_probabilities_are_unbiased_with_honest_errors_and_diverged_samples_left_out():
    """p_overturn (latent z > 1.5) and p_exceed(1.0) (latent peak |z| > 1.0, or overturned) of paired latent
    Gaussians at correlation 0.95, 3 % of each model's samples diverged at random; truths from the normal
    distribution; the scatter over 400 seeds against the mean reported SE within 15 %."""
    from screening.analysis.multifidelity import multifidelity_probabilities

    rng = np.random.default_rng(29)
    phi = lambda a: 0.5 * math.erfc(a / math.sqrt(2))        # noqa: E731
    truth = [phi(1.5), 2 * phi(1.0)]                          # |z| > 1 covers z > 1.5
    est, ses = [], []
    for _ in range(REPEATS):
        zx = rng.normal(size=400)
        zy = 0.95 * zx[:80] + math.sqrt(1 - 0.95 ** 2) * rng.normal(size=80)
        r = multifidelity_probabilities(np.abs(zy), zy > 1.5, rng.random(80) > 0.03,
                                        np.abs(zx), zx > 1.4, rng.random(400) > 0.03, levels=[1.0])
        est.append([e.mean for e in r])
        ses.append([e.se for e in r])
    est, ses = np.array(est), np.array(ses)
    scatter = est.std(axis=0, ddof=1)
    assert np.all(np.abs(est.mean(axis=0) - truth) <= 4 * scatter / math.sqrt(REPEATS) + 0.003)
    np.testing.assert_allclose(scatter / ses.mean(axis=0), 1.0, atol=0.15)
    plain = np.sqrt(np.array(truth) * (1 - np.array(truth)) / 80)
    assert np.all(scatter < 0.85 * plain)                     # the cheap samples pay


def test_the_mean_is_the_special_case_of_the_functional():
    from screening.analysis.multifidelity import conditional_mean_influence, control_variate_functional

    y, x = _pairs(np.random.default_rng(5), 40, 0.8)
    extra = np.random.default_rng(6).normal(size=100)
    a = control_variate_estimate(y, x, x_extra=extra)
    value_y, psi_y = conditional_mean_influence(y)
    value_x, psi_x = conditional_mean_influence(x)
    b = control_variate_functional(value_y, psi_y, value_x, np.concatenate([x, extra]).mean(), psi_x, 140)
    assert (a.mean, a.se, a.weight) == pytest.approx((b.mean, b.se, b.weight), rel=1e-12)
    # by hand: ybar - alpha (xbar_n - xbar_N)
    alpha = np.cov(x, y)[0, 1] / np.var(x, ddof=1)
    assert a.mean == pytest.approx(y.mean() - alpha * (x.mean() - np.concatenate([x, extra]).mean()), rel=1e-12)


# ---------------------------------------------------------------- allocation and the fallback rule
def test_the_allocation_gives_the_plain_standard_error_at_the_predicted_cost():
    from screening.analysis.multifidelity import allocate

    a = allocate(0.95, 30.0, 1.0, 1000)
    assert a.estimator == "multifidelity"
    r, rho2 = a.ratio, 0.95 ** 2
    # variance of the estimate: sigma^2/n (1 - (1 - n/N) rho^2) <= sigma^2 / 1000 (ceil: within one sample)
    assert 1 / a.n_expensive * (1 - (1 - a.n_expensive / a.n_cheap) * rho2) <= 1 / 1000 * (1 + 2 / a.n_expensive)
    assert 1000 * 30.0 / (a.n_expensive * 30.0 + a.n_cheap * 1.0) == pytest.approx(a.gain, rel=0.02)
    assert a.n_cheap == pytest.approx(r * a.n_expensive, abs=1)


@pytest.mark.parametrize("rho, c_lo", [(0.9, 1 / 3), (0.4, 0.01), (float("nan"), 0.01), (0.9, 1 / 1.5)])
def test_plain_monte_carlo_where_the_cheap_model_does_not_pay(rho, c_lo):
    """Today's costs (condensed ~1/3 of coupled, stiff bed ~1/1.5) at rho 0.9: predicted speed-up < MIN_GAIN."""
    from screening.analysis.multifidelity import MIN_GAIN, allocate

    a = allocate(rho, 1.0, c_lo, 500)
    assert (a.estimator, a.n_expensive, a.n_cheap) == ("plain", 500, 0)
    assert not math.isfinite(rho) or speedup(rho, 1.0, c_lo) < MIN_GAIN


@pytest.mark.parametrize("rho, target", [(0.9, 3.0), (0.95, 3.0), (0.99, 5.0), (0.9, 1.5)])
def test_the_cost_ratio_needed_gives_the_speedup_asked_for(rho, target):
    from screening.analysis.multifidelity import cost_ratio_needed

    w = cost_ratio_needed(rho, target)
    assert speedup(rho, w, 1.0) == pytest.approx(target, rel=1e-6)          # independent: the brute-force-tested one


def test_no_cost_ratio_beats_free_cheap_samples():
    from screening.analysis.multifidelity import cost_ratio_needed

    assert cost_ratio_needed(0.8, 1 / (1 - 0.64) + 0.01) == math.inf
    assert cost_ratio_needed(0.5, 1.2) < math.inf


def test_the_escalation_plans_a_paired_point_from_its_pilot_on_the_cost_model():
    """Costs per sample from the cost model's steps (coupled 1e5 steps, condensed 1e4, each at its
    STEP_COST_S), never fewer coupled samples than the pilot's, plain where the gain is too small."""
    from screening.analysis import escalation as esc
    from screening.analysis.multifidelity import allocate
    from screening.core.status import EscalationModel

    pilot = {"n_steps": 64 * 100_000, "n_grid": 0, "rodas": False, "cheap_n_steps": 64 * 10_000, "cheap_n_grid": 0,
             "correlation": 0.99}
    c_hi = esc.estimated_cost(100_000, EscalationModel.coupled)
    c_lo = esc.estimated_cost(10_000, EscalationModel.condensed)
    step = esc.STEP_COST_S
    assert c_hi / c_lo == pytest.approx(10.0 * step[EscalationModel.coupled] / step[EscalationModel.condensed])
    plan = esc.paired_plan(pilot, EscalationModel.coupled, 64, 5000)
    assert plan == allocate(0.99, c_hi, c_lo, 5000) and plan.estimator == "multifidelity" and plan.n_expensive > 64
    small = esc.paired_plan(pilot, EscalationModel.coupled, 64, 100)
    assert small.n_expensive == 64 and small.n_cheap >= allocate(0.99, c_hi, c_lo, 100).n_cheap
    assert esc.paired_plan({**pilot, "correlation": 0.5}, EscalationModel.coupled, 64, 1000).estimator == "plain"
    assert esc.paired_model(EscalationModel.condensed) is None


@pytest.mark.slow
def test_the_two_fidelity_variance_of_engine_samples_is_unbiased_and_its_error_honest_over_seeds():
    """The paper block on a linear bed (eps = 0), 3 s records: 30 seeds of 64 coupled samples (the escalation's
    pilot) paired with 256 condensed (virtual_work) ones; var_theta at t = 2 s.  The mean estimate agrees with an
    independent 600-sample plain coupled run within 4 combined standard errors, and the scatter over the seeds
    matches the mean reported standard error within 40 % (a standard deviation from 30 repetitions has a relative
    sampling error of 1/sqrt(58) = 13 %: 3 of those)."""
    from screening.analysis.multifidelity import multifidelity_variance
    from screening.core.model import Block, Foundation
    from screening.core.excitations import WhiteNoise
    from screening.core.model.cases import PAPER_BED, PAPER_BLOCK
    from screening.solvers.montecarlo import monte_carlo

    block, bed, excitation = Block(**PAPER_BLOCK), Foundation(eps=0.0, **PAPER_BED), WhiteNoise(S0=1e-3)
    kw = dict(t_end=3.0, dt=0.05, sample_histories=True)
    k = 40                                                   # t = 2 s
    est, ses = [], []
    for seed in range(30):
        hi = monte_carlo(block, bed, excitation, n_samples=64, model="coupled", seed=100 + seed, **kw)
        lo = monte_carlo(block, bed, excitation, n_samples=256, model="condensed", condensation="virtual_work",
                         seed=100 + seed, **kw)
        r = multifidelity_variance(hi.theta_sample.values, ~(hi.overturned.values | hi.diverged.values),
                                   lo.theta_sample.values, ~(lo.overturned.values | lo.diverged.values))
        est.append(r.mean[k])
        ses.append(r.se[k])
    ref = monte_carlo(block, bed, excitation, n_samples=600, model="coupled", seed=7, t_end=3.0, dt=0.05)
    scatter = np.std(est, ddof=1)
    assert abs(np.mean(est) - ref.var_theta.values[k]) <= 4 * math.hypot(scatter / math.sqrt(30),
                                                                          ref.var_theta_se.values[k])
    assert scatter / np.mean(ses) == pytest.approx(1.0, abs=0.4)


def test_the_engines_sample_histories_are_the_ones_behind_its_variance():
    from screening.core.model import Block, Foundation
    from screening.core.excitations import WhiteNoise
    from screening.core.model.cases import PAPER_BED, PAPER_BLOCK
    from screening.solvers.montecarlo import monte_carlo

    args = (Block(**PAPER_BLOCK), Foundation(eps=6e7, **PAPER_BED), WhiteNoise(S0=1e-3))
    ds = monte_carlo(*args, n_samples=6, model="condensed", t_end=1.0, sample_histories=True)
    used = ~(ds.overturned.values | ds.diverged.values)
    np.testing.assert_allclose(ds.theta_sample.values[used].var(axis=0, ddof=1), ds.var_theta.values,
                               rtol=1e-12, atol=1e-300)
    assert ds.theta_sample.attrs["units"] == "rad" and "theta_sample" not in monte_carlo(
        *args, n_samples=2, model="condensed", t_end=0.2)
    with pytest.raises(ValueError, match="'sample_histories' must be True or False"):
        monte_carlo(*args, n_samples=2, sample_histories=1)


def test_a_paired_escalation_run_falls_back_to_plain_where_the_cheap_model_refuses_the_point():
    from screening.core.model import Block, Foundation
    from screening.core.excitations import WhiteNoise
    from screening.core.model.cases import PAPER_BED, PAPER_BLOCK
    from screening.solvers import mc_registry
    from screening.solvers.mc_models import CondensedModel
    from screening.core.status import EscalationEstimator
    from screening.sweep.execution import escalation_task

    class Refuses(CondensedModel):
        name = "refuses_every_bed"

        def check(self, block, foundation, condensation):
            raise ValueError("parameter 'foundation' is outside this model's range")

    mc_registry.register(Refuses())
    try:
        args = (Block(**PAPER_BLOCK), Foundation(eps=6e7, **PAPER_BED), WhiteNoise(S0=1e-3), "paper", 4, "condensed",
                0.3, 0.05, 0)
        paired = escalation_task(*args, cheap=("refuses_every_bed", "paper", 8))
        plain = escalation_task(*args)
    finally:
        mc_registry.unregister("refuses_every_bed")
    assert paired["estimator"] == EscalationEstimator.plain_monte_carlo and paired["cheap_samples"] == 0
    assert (paired["peak_var_theta"], paired["peak_var_theta_se"]) == (plain["peak_var_theta"],
                                                                       plain["peak_var_theta_se"])
