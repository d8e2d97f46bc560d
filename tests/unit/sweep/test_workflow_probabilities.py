"""The last stage of a sweep's probabilities (screening.sweep.probabilities.finish_probabilities) near
toppling: the study's fragility surface where Monte Carlo did not run, and which quantity answers each point.
A result stand-in and synthetic Monte Carlo runs drawn from a known fragility curve (fixed seeds)."""

import numpy as np
import pytest
from scipy import special

from screening.core.status import (AnswerQuantity, BestMethod, EscalationModel, PointStatus, ProbabilitySource,
                                   SampleState)
from screening.core.status import Trust
from screening.sweep.probabilities import finish_probabilities, surface_estimates
from screening.sweep.study import EXAMPLE_STUDY, parse_study

N = 21
S0 = np.geomspace(1e-4, 1e-2, N)
STUDY = EXAMPLE_STUDY.replace("eps = [0.0, 6e7]", "eps = 0.0").replace(
    "S0 = 1e-4", f"S0 = {{start = 1e-4, stop = 1e-2, num = {N}, log = true}}") + "\n[accuracy]\ntarget = 0.15\n"


def truth(s0):
    """A lognormal fragility in S0: median 1e-3 m2 s-3, beta 0.5."""
    return special.ndtr(np.log(s0 / 1e-3) / 0.5)


class Result(dict):
    """The reads and writes of a result that finish_probabilities uses."""

    def __init__(self, status, best, **values):
        super().__init__(**values)
        self.status, self.sl_trust = np.asarray(status), np.full(N, Trust.untrusted)
        self.peak_p_uplift = np.where(self.status == PointStatus.ok, 0.5, np.nan)
        self["best_method"] = best

    def commit(self):
        pass

    def read(self, name):
        return np.asarray(self[name], dtype=float)

    def write(self, name, region, values):
        self[name] = np.asarray(values)

    def add(self, variables):
        self.update({v.name: np.asarray(v.values) for v in variables})

    def grid_coordinates(self):
        return ""

    def set_attrs(self, **attrs):
        self.update(attrs)


def _values(res):
    """The per-point values the run hands the stage (:func:`screening.sweep.run.stage_inputs`), from the fake."""
    return {name: res.read(name) for name in ("p_overturn", "p_overturn_se", "sl_error_low", "sl_error_high",
                                              "theta_ul", "slenderness", "best_method")}


def _runs(at, prob, seed, samples=1000):
    rng = np.random.default_rng(seed)
    runs = []
    for i in at:
        over = rng.random(samples) < prob[i]
        state = np.where(over, SampleState.overturned, SampleState.standing).astype(np.int8)
        runs.append({"peak_abs_theta": np.where(over, 0.5, 0.01), "sample_state": state})
    return np.asarray(at), np.full(len(at), int(EscalationModel.coupled), dtype=np.int8), runs


def _result():
    """Points 11-19 odd stopped near toppling, the rest ok with a vouched-for linearization."""
    status = np.full(N, PointStatus.ok)
    status[11:20:2] = PointStatus.k_eq_negative
    best = np.where(status == PointStatus.ok, BestMethod.linearization, BestMethod.unreliable)
    return Result(status, best, p_overturn=np.zeros(N), p_overturn_se=np.full(N, 1e-3),
                  sl_error_low=np.full(N, -0.05), sl_error_high=np.full(N, 0.05), theta_ul=np.full(N, 1e-3),
                  slenderness=np.full(N, 0.165))


def test_near_toppling_points_take_the_surface_inside_the_monte_carlo_points_and_nothing_beyond():
    study = parse_study(STUDY)
    mc = list(range(0, 18, 2))                       # Monte Carlo at S0 index 0, 2, ..., 16
    res = _result()
    lines = []
    counts = finish_probabilities(study, res, _values(res), escalated=_runs(mc, truth(S0), seed=11),
                                  log=lines.append)
    src, p, se, answer = res["p_source"], res["p_overturn"], res["p_overturn_se"], res["answer_quantity"]
    surface = ProbabilitySource.study_fragility_surface
    # Monte Carlo where it ran
    assert np.all(src[mc] == 10)
    # the stopped points inside the Monte Carlo points' range: the surface, within 3 of its SE of the truth
    inside = [11, 13, 15]
    assert np.all(src[inside] == surface) and np.all(answer[inside] == AnswerQuantity.probabilities_stopped)
    assert np.all(np.abs(p[inside] - truth(S0[inside])) <= 3 * se[inside]) and np.all(se[inside] > 0)
    # beyond the last Monte Carlo point: nothing vouches for a number (the answer is still the probabilities)
    beyond = [17, 19]
    assert np.all(src[beyond] == ProbabilitySource.unreliable) and np.all(np.isnan(se[beyond]))
    assert np.all(answer[beyond] == AnswerQuantity.probabilities_stopped)
    # an ok point whose overturning is material at 2 SE by the surface: probabilities, from the surface
    material = [i for i in range(1, 17, 2) if i not in inside]
    for i in material:
        expect = truth(S0[i]) > 0.05 + 4 * 0.01
        if expect:
            assert answer[i] == AnswerQuantity.probabilities_overturning and src[i] == surface
        if answer[i] == AnswerQuantity.variance:
            assert src[i] == ProbabilitySource.linearization_gaussian and p[i] == 0.0
    low = [i for i in material if truth(S0[i]) < 1e-3]
    assert low and all(answer[i] == AnswerQuantity.variance for i in low)
    assert counts == {name: int(np.sum(src == code)) for name, code in
                      (("unreliable", 0), ("linearization_gaussian", 1), ("study_fragility_surface", 3),
                       ("monte_carlo_coupled", 10)) if np.any(src == code)}
    # the accounting: 5 stopped points have no vouched variance, 2 of them no answer at all
    n_var, n_prob = int(np.sum(answer == 0)), int(np.sum(answer != 0))
    assert res["answer_note"].startswith(f"answers: variance {n_var}, probabilities {n_prob} (linearization "
                                         f"stopped 5")
    assert res["answer_note"].endswith("; unreliable: 5 variance, 2 without any reliable answer")
    assert lines[0] == res["answer_note"] and "vouched for" in lines[1] and "S0" in res["fragility_surface_note"]


def test_a_surface_the_leave_one_out_check_rejects_is_used_nowhere():
    """Overturning that swings up and down along S0: no probit form follows it."""
    study = parse_study(STUDY)
    wavy = special.ndtr(2 * np.sin(3 * np.linspace(-1.5, 1.5, N)))
    res = _result()
    finish_probabilities(study, res, _values(res), escalated=_runs(list(range(0, 21, 2)), wavy, seed=12))
    assert not np.any(res["p_source"] == ProbabilitySource.study_fragility_surface)
    assert np.all(res["p_source"][11:20:2] == ProbabilitySource.unreliable)
    assert "not vouched for (leave-one-out" in res["fragility_surface_note"]


def test_surfaces_are_fitted_per_case_and_only_where_every_level_is_vouched_for():
    s0 = np.tile(S0, 2)
    case = np.repeat([0, 1], N)
    mc = list(range(0, 18, 2))
    counts = {i: np.array([np.round(1000 * truth(s0[i]))]) for i in mc}        # case 0 only, the expected counts
    p, se, usable, notes = surface_estimates({"S0": s0}, case, counts, {i: 1000 for i in mc})
    assert usable[:17].all() and not usable[17:].any()
    assert np.all(np.isnan(p[N:])) and notes[1].startswith("case 1: no Monte Carlo point")
    assert p[8, 0] == pytest.approx(truth(s0[8]), abs=1e-3)
    # a second level (a threshold) exceeded by every sample at all but two points: no form for it, so no
    # surface for either level (one p_source per point)
    both = {i: np.array([c[0], 1000 - (i in (0, 2))]) for i, c in counts.items()}
    _, _, usable2, notes2 = surface_estimates({"S0": s0}, case, both, {i: 1000 for i in mc})
    assert not usable2.any() and "p_exceed[0]: no fragility surface" in notes2[1]


def test_a_study_without_swept_inputs_gets_no_surface():
    p, se, usable, notes = surface_estimates({}, np.zeros(1, dtype=int), {0: np.array([3.0])}, {0: 10})
    assert not usable.any() and np.isnan(p).all() and "no fragility surface" in notes[0]
