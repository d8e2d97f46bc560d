"""model = "auto": the measured validity rule (screening/data/model_choice.toml) picks the Monte Carlo model per
point, never outside the intervals the benchmark measured; resolved once at set-up."""

import math
import warnings

import numpy as np
import pytest

import screening
from screening.model import Block, Foundation
from screening.solvers import mc_registry, model_choice as mc
from screening.solvers.montecarlo import monte_carlo

STATUE = Block(m=1200.0, b=0.25, h=0.9)
STIFF = Foundation(k=1e10, lam=1e8)
SOFT = Foundation(k=2e6, lam=1e7)
KT = screening.KanaiTajimi(1e-6, 15.6, 0.6)


def test_shipped_rule_is_data_with_its_benchmark_and_bounds():
    rules, fallback = mc.rules()
    assert fallback == "coupled"
    (rule,) = [r for r in rules if r.model == "stiff_bed"]
    assert rule.benchmark == "benchmarks/stiff_bed_validity.py"
    assert rule.bound("theta_ul_over_slenderness") == (0.0, 0.05)
    assert rule.excitations == ("kanai_tajimi",)
    assert "condensed" not in [r.model for r in rules]      # no measured rule: never picked


def test_indicators_against_their_closed_forms():
    """theta_ul = m g / (2 b^2 k) on a linear bed; w_v = sqrt(2 b k / m); w_r = sqrt(((2/3) b^3 k - m g h) / m0)."""
    ind = mc.indicators(STATUE, STIFF)
    alpha = math.atan2(0.25, 0.9)
    theta_ul = 1200.0 * 9.81 / (2 * 0.25**2 * 1e10)
    m0 = 1200.0 * (0.25**2 + 0.9**2) / 3 + 1200.0 * 0.9**2
    w_r = math.sqrt((2 / 3 * 0.25**3 * 1e10 - 1200.0 * 9.81 * 0.9) / m0)
    assert ind["slenderness"] == pytest.approx(alpha, rel=1e-12)
    assert ind["theta_ul_over_slenderness"] == pytest.approx(theta_ul / alpha, rel=1e-3)
    assert ind["vertical_over_rocking"] == pytest.approx(math.sqrt(2 * 0.25 * 1e10 / 1200.0) / w_r, rel=1e-9)


def test_auto_picks_the_stiff_bed_model_only_inside_every_measured_interval():
    assert mc.choose(STATUE, STIFF, "kanai_tajimi")[0] == "stiff_bed"
    name, why = mc.choose(STATUE, SOFT, "kanai_tajimi")               # theta_ul / alpha = 0.17
    assert name == "coupled" and "theta_ul_over_slenderness" in why
    name, why = mc.choose(STATUE, STIFF, "white")                     # white noise was not measured
    assert name == "coupled" and "'white'" in why
    name, why = mc.choose(Block(m=8.67, b=0.035, h=0.21), STIFF, "kanai_tajimi")   # slenderness 0.165
    assert name == "coupled" and "slenderness" in why
    assert mc.choose(STATUE, STIFF, None)[0] == "coupled"              # records: not measured


def test_auto_never_picks_outside_the_rule_on_a_random_design():
    """Over random blocks and beds, whatever "auto" picks other than the fallback lies inside every interval of
    that model's rule (and every point inside the rule gets it: the rule lists one cheap model)."""
    rng = np.random.default_rng(3)
    (rule,) = mc.rules()[0]
    picked = 0
    for _ in range(300):
        b, h = rng.uniform(0.05, 0.5), rng.uniform(0.3, 2.0)
        block = Block(m=rng.uniform(10, 3000), b=b, h=h)
        k = 10 ** rng.uniform(5, 12)
        bed = Foundation(k=k, lam=1e6)
        if 2 / 3 * b**3 * k <= block.m * 9.81 * h:
            continue
        name, _ = mc.choose(block, bed, "kanai_tajimi")
        ind = mc.indicators(block, bed)
        inside = all(lo <= ind[n] <= hi for n, (lo, hi) in rule.bounds)
        assert (name == "stiff_bed") == inside
        picked += name == "stiff_bed"
    assert picked > 0


def test_a_bad_rule_file_is_refused_naming_the_entry():
    good = {"fallback": "coupled", "model": [{"name": "stiff_bed", "slenderness": [0.2, 0.3],
                                              "excitations": ["kanai_tajimi"]}]}
    assert mc.parse_rules(good)[0][0].bounds == (("slenderness", (0.2, 0.3)),)
    for bad, match in (({"model": [{"name": "rigid", "excitations": ["white"], "slenderness": [0, 1]}]}, "name"),
                       ({"model": [{"name": "stiff_bed", "excitations": ["white"], "height": [0, 1]}]}, "indicator"),
                       ({"model": [{"name": "stiff_bed", "excitations": ["white"], "slenderness": [1, 0]}]}, "low <= high"),
                       ({"model": [{"name": "stiff_bed", "excitations": ["white"]}]}, "vouch everywhere"),
                       ({"model": [{"name": "stiff_bed", "slenderness": [0, 1]}]}, "excitations"),
                       ({"fallback": "auto"}, "fallback")):
        with pytest.raises(ValueError, match=match):
            mc.parse_rules(bad)


def test_monte_carlo_resolves_auto_once_and_records_the_model_that_ran():
    kw = dict(n_samples=2, t_end=0.2, dt=0.1, progress=False)
    stiff = monte_carlo(STATUE, STIFF, KT, model="auto", **kw)
    assert stiff.attrs["model"] == "stiff_bed"
    direct = monte_carlo(STATUE, STIFF, KT, model="stiff_bed", **kw)
    np.testing.assert_array_equal(stiff.peak_abs_theta.values, direct.peak_abs_theta.values)
    white = monte_carlo(STATUE, STIFF, screening.WhiteNoise(1e-6), model="auto", **kw)
    assert white.attrs["model"] == "coupled"
    assert mc.resolve("auto", STATUE, STIFF, KT) is mc_registry.get("stiff_bed")
    assert "auto" in mc.choices() and "auto" not in mc_registry.names()


def test_stiff_bed_outside_its_validity_warns_or_is_refused_when_strict():
    kw = dict(n_samples=2, t_end=0.1, dt=0.05, progress=False)
    with pytest.warns(UserWarning, match=r"'stiff_bed' outside its measured validity: theta_ul_over_slenderness"):
        monte_carlo(STATUE, SOFT, KT, model="stiff_bed", **kw)
    with pytest.raises(ValueError, match=r"^model 'stiff_bed' outside its measured validity: excitation 'white'"):
        monte_carlo(STATUE, STIFF, screening.WhiteNoise(1e-6), model="stiff_bed", strict_validity=True, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monte_carlo(STATUE, STIFF, KT, model="stiff_bed", strict_validity=True, **kw)   # inside: silent
    with pytest.raises(ValueError, match="parameter 'strict_validity'"):
        monte_carlo(STATUE, STIFF, KT, model="stiff_bed", strict_validity="yes", **kw)


def test_the_stiff_bed_validity_limit_is_the_shipped_rule():
    from screening.solvers import stiff_bed

    assert stiff_bed.validity_limit() == mc.rule_of("stiff_bed").bound("theta_ul_over_slenderness")[1]
    assert stiff_bed.validity(STATUE, STIFF)[1] == f"theta_ul / atan(b/h) <= {stiff_bed.validity_limit():g}"
