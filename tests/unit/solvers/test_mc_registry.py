"""The Monte Carlo model registry (screening.solvers.mc_registry): a model registered from outside the
package runs through monte_carlo and simulate, and every place that chooses a model takes the
registered names (studies, cloud studies, the simulate command)."""

import numpy as np
import pytest

import screening
from screening.core.model import Block, Foundation
from screening.core.excitations.white import WhiteNoise
from screening.solvers import mc_registry
from screening.solvers.mc_models import CondensedModel
from screening.sweep.study import StudyError, parse_study

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8)


class _Doubled(CondensedModel):
    """A toy model: the condensed model with every angle reported doubled (the engine must use it)."""

    name = "toy_doubled"

    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        inner = super().integrator(block, foundation, condensation, max_flight_time)

        def run(*args):
            inner(*args)
            args[9][...] *= 2.0            # out_theta
            args[14][...] *= 2.0           # peak
        return run


@pytest.fixture
def toy():
    model = mc_registry.register(_Doubled())
    yield model
    mc_registry.unregister(model.name)


def test_a_registered_model_runs_in_monte_carlo_and_simulate(toy):
    kw = dict(n_samples=4, t_end=1.0, dt=0.1, seed=3, progress=False)
    base = screening.monte_carlo(BLOCK, BED, WhiteNoise(1e-4), model="condensed", **kw)
    doubled = screening.monte_carlo(BLOCK, BED, WhiteNoise(1e-4), model="toy_doubled", **kw)
    np.testing.assert_array_equal(doubled.peak_abs_theta.values, 2.0 * base.peak_abs_theta.values)
    np.testing.assert_allclose(doubled.var_theta.values, 4.0 * base.var_theta.values, rtol=1e-12)
    assert doubled.attrs["model"] == "toy_doubled"
    a_g = np.sin(np.linspace(0, 20, 200))
    s_base = screening.simulate(BLOCK, BED, a_g, dt=0.01, model="condensed")
    s_toy = screening.simulate(BLOCK, BED, a_g, dt=0.01, model=toy)
    np.testing.assert_array_equal(s_toy.theta.values, 2.0 * s_base.theta.values)


def test_unknown_model_is_refused_listing_the_registered_ones():
    with pytest.raises(ValueError, match=r"parameter 'model' must be one of \('coupled', 'condensed', 'stiff_bed'"):
        screening.monte_carlo(BLOCK, BED, WhiteNoise(1e-4), model="rigid", n_samples=2)


STUDY = """
[block]
m = 1200.0
b = 0.25
h = 0.9
[foundation]
contact = "hunt_crossley"
k = 1e10
lam = 2e11
[excitation]
kind = "white"
S0 = [1e-3, 2e-3]
[time]
t_end = 2.0
dt = 0.05
[mcs]
model = MODEL
"""


def test_study_accepts_the_stiff_bed_model_and_lists_the_allowed_values():
    assert parse_study(STUDY.replace("MODEL", '"stiff_bed"')).mcs.model == "stiff_bed"
    with pytest.raises(StudyError, match="mcs.model: must be one of.*stiff_bed"):
        parse_study(STUDY.replace("MODEL", '"rigid"'))


def test_low_passed_samples_are_the_same_realization_without_its_high_band():
    """A model with its own input band reads the coupled model's samples with the components above the
    band removed: against the full plan with those amplitudes zeroed (1e-12), read at every stride-th
    grid point; the coarse grid keeps the plan's oversampling of the kept band, covers the record and
    has its own FFT (a divisor of the plan's length: synthesis costs in proportion to it)."""
    import dataclasses

    from screening.solvers.synthesis import OVERSAMPLING, low_passed, spectral_plan, stationary_samples

    plan = spectral_plan(screening.KanaiTajimi(0.02, 15.6, 0.6), 20.0, 6000.0)
    low, stride = low_passed(plan, 800.0)
    assert stride > 1 and abs(low.cutoff - 800.0) <= plan.d_omega
    assert low.dt == stride * plan.dt and low.d_omega == plan.d_omega and low.n_fft * stride == plan.n_fft
    assert low.dt <= np.pi / (OVERSAMPLING * low.cutoff) * (1 + 1e-12)
    assert (low.n_times - 1) * low.dt >= 20.0
    zeroed = dataclasses.replace(plan, n_times=stride * (low.n_times - 1) + 1, amplitudes=np.where(np.arange(plan.n_frequencies) < low.n_frequencies,
                                                           plan.amplitudes, 0.0))
    a, ad = stationary_samples(low, 4, [0, 3])
    b, bd = stationary_samples(zeroed, 4, [0, 3])
    b, bd = b[:, ::stride], bd[:, ::stride]
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max())
    np.testing.assert_allclose(ad, bd, rtol=0, atol=1e-12 * np.abs(bd).max())
    assert low_passed(plan, 4000.0) == (plan, 1)            # not below half the cutoff: the plan itself


def test_band_option_low_passes_what_any_model_reads_and_is_recorded():
    """``band=`` gives every model the same samples low-passed at that band (the coupled model as the stiff-bed
    model's judge on the same ground motions); at or above half the cutoff it is the full plan itself."""
    from screening.solvers.montecarlo import monte_carlo

    block, bed = screening.Block(m=1200.0, b=0.25, h=0.9), screening.Foundation(k=1e10, lam=2e11)
    motion = screening.KanaiTajimi(0.015, 15.6, 0.6, band_limit_hz=None)    # synthesized to 3 x the vertical mode
    kw = dict(n_samples=3, t_end=1.0, dt=0.05, progress=False, seed=5)
    full = monte_carlo(block, bed, motion, model="coupled", **kw)
    same = monte_carlo(block, bed, motion, model="coupled", band=0.6 * full.attrs["cutoff_rad_s"], **kw)
    low = monte_carlo(block, bed, motion, model="coupled", band=157.0, **kw)
    np.testing.assert_array_equal(same.peak_abs_theta.values, full.peak_abs_theta.values)
    assert same.attrs["input_band_rad_s"] == full.attrs["cutoff_rad_s"]
    assert abs(low.attrs["input_band_rad_s"] - 157.0) <= full.attrs["d_omega_rad_s"]
    assert low.attrs["input_grid_points"] < full.attrs["input_grid_points"] / 10
    assert not np.array_equal(low.peak_abs_theta.values, full.peak_abs_theta.values)
    with pytest.raises(ValueError, match="parameter 'band'"):
        monte_carlo(block, bed, motion, model="coupled", band=-1.0, **kw)


class _Accepted(Exception):
    """Raised where the engine would go on to run: the model's check passed."""


@pytest.mark.parametrize("model", ["coupled", "condensed", "stiff_bed"])
@pytest.mark.parametrize("condensation", ["paper", "cubic", "virtual_work"])
def test_simulate_and_monte_carlo_refuse_and_accept_the_same_condensations(monkeypatch, model, condensation):
    """The model's own check is the one place that refuses a condensation it cannot use: a model that does not
    read it takes the default and the paper's only (what callers pass for "none"), the condensed model any; both
    entry points stop there with the same one line naming the parameter, before any work."""
    def accepted(*args, **kwargs):
        raise _Accepted()

    monkeypatch.setattr(mc_registry, "check_validity", accepted)        # called right after the model's check
    calls = {"simulate": lambda: screening.simulate(BLOCK, BED, np.zeros(100), dt=0.01, model=model,
                                                    condensation=condensation),
             "monte_carlo": lambda: screening.monte_carlo(BLOCK, BED, WhiteNoise(1e-4), n_samples=10**12,
                                                          model=model, condensation=condensation, seed=0)}
    outcomes = {}
    for name, call in calls.items():
        try:
            call()
        except _Accepted:
            outcomes[name] = "accepted"
        except ValueError as exc:
            outcomes[name] = str(exc)
    refused = model != "condensed" and condensation == "cubic"
    expected = (f"parameter 'condensation' applies to model='condensed' only "
                f"(got condensation='cubic' with model={model!r})") if refused else "accepted"
    assert outcomes == {"simulate": expected, "monte_carlo": expected}


def test_a_model_defined_after_import_is_seen_by_studies_the_schema_the_escalation_and_the_cli():
    """Defining a subclass with its own name and flag code registers it: read when used, the study validator,
    the CF flags of mcs_model, p_source and esc_model, the escalation's cost model, best-estimate method,
    counters line and the simulate command's choices all know it, with the declared codes; the built-in
    models keep theirs."""
    from screening.analysis import escalation as esc
    from screening.cli.records import cmd_simulate
    from screening.core.status import BestMethod
    from screening.solvers import schema
    from screening.sweep.accuracy import accuracy_line

    class LateModel(CondensedModel):
        name = "late_toy"
        flag_code = 9
        escalation_code = 7
        step_cost_s = 3e-6
        best_method = BestMethod.condensed_monte_carlo

    try:
        assert mc_registry.code("late_toy") == 9 and isinstance(mc_registry.get("late_toy"), LateModel)
        assert mc_registry.codes()["coupled"] == 0 and mc_registry.codes()["stiff_bed_fast"] == 3
        assert parse_study(STUDY.replace("MODEL", '"late_toy"')).mcs.model == "late_toy"
        study = parse_study(STUDY.replace("MODEL", '"auto"') + '[accuracy]\ntarget = 0.2\nmodel = "late_toy"\n')
        assert study.accuracy.model == "late_toy"
        flags = schema.attributes("mcs_model")
        assert dict(zip(flags["flag_meanings"].split(), flags["flag_values"].tolist()))["late_toy"] == 9
        sources = schema.attributes("p_source")
        assert dict(zip(sources["flag_meanings"].split(), sources["flag_values"].tolist()))["monte_carlo_late_toy"] == 19
        escalated = schema.attributes("esc_model")
        assert escalated["flag_meanings"].split() == ["condensed", "coupled", "stiff_bed", "late_toy"]
        assert escalated["flag_values"].tolist() == [0, 1, 2, 7]
        assert esc.estimated_cost(1000, 7) == pytest.approx(1000 * 3e-6) and esc.STEP_COST_S[7] == 3e-6
        assert esc.auto_escalation_model([1, 1], ["late_toy", "coupled"]).tolist() == [7, 1]
        assert mc_registry.escalation_model(7).best_method == BestMethod.condensed_monte_carlo
        model = next(p for p in cmd_simulate.params if p.name == "model")
        assert "late_toy" in model.type.choices
        info = {"target": 0.2, "n_candidates": 3, "n_escalated": 1, "n_coupled": 0, "n_condensed": 0, "n_late_toy": 1,
                "n_short": 0, "wall_s": 1.0, "budget_s": 10.0, "cost_s": 1.0, "cpu_s": 1.0, "loo_rms": 0.1,
                "correction_usable": True, "methods": {}}
        assert "0 coupled, 0 condensed, 1 late-toy;" in accuracy_line(info)
    finally:
        mc_registry.unregister("late_toy")
    assert "late_toy" not in schema.attributes("mcs_model")["flag_meanings"]
    with pytest.raises(StudyError, match="mcs.model: must be one of"):
        parse_study(STUDY.replace("MODEL", '"late_toy"'))


def test_a_declared_flag_code_cannot_be_taken_twice():
    with pytest.raises(ValueError, match="flag_code 1 of Monte Carlo model 'clash' is 'condensed'"):
        class Clash(CondensedModel):
            name = "clash"
            flag_code = 1
    assert "clash" not in mc_registry.names()
