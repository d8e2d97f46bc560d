"""model = "auto": the measured validity rule (screening/data/model_choice.toml) picks the Monte Carlo model per
point, never outside the intervals the benchmark measured; resolved once at set-up."""

import math
import warnings

import numpy as np
import pytest

import screening
from screening.core.model import Block, Foundation
from screening.solvers import mc_registry, model_choice as mc
from screening.solvers.montecarlo import monte_carlo

STATUE = Block(m=1200.0, b=0.25, h=0.9)
STIFF = Foundation(k=1e10, lam=2.08e11)         # the statue study's bed: vertical damping ratio 0.05
INSIDE = Foundation(k=3e6, lam=1081203.03)        # a soft bed where the stiff-bed model passed (damping ratio 0.05)
SOFT = Foundation(k=1.1e6, lam=3.6e9)           # theta_ul / atan(b/h) = 0.32, softer than any bed measured
EQUIPMENT = Block(m=300.0, b=0.3, h=0.9)
KT = screening.KanaiTajimi(1e-6, 15.6, 0.6)


def test_shipped_rule_is_data_with_its_benchmark_and_bounds():
    rules, fallback = mc.rules()
    assert fallback == "coupled"
    (rule,) = [r for r in rules if r.model == "stiff_bed"]
    assert rule.benchmark == "benchmarks/stiff_bed_validity.py"
    assert {name for name, _ in rule.bounds} == set(mc.INDICATORS)        # every indicator bounded by the table
    assert rule.bound("theta_ul_over_slenderness")[0] > 0                 # not below the stiffest bed measured
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


@pytest.mark.parametrize("bed", [Foundation(k=2.89e7, lam=8.95e8), Foundation(k=1e9, c=3e4)])
def test_vertical_damping_ratio_against_the_decay_of_a_free_vertical_bounce(bed):
    """zeta_v from the logarithmic decrement of the block bouncing freely on the bed (small amplitude about the
    static indentation, the law's damping pressure integrated over the base), and the inverse of the beds'
    helpers."""
    from scipy.integrate import solve_ivp

    from screening.analysis.beds import c_from_vertical_damping, lam_from_vertical_damping

    block = Block(m=8.67, b=0.035, h=0.21)
    m, b, k, g = 8.67, 0.035, bed.k, 9.81
    z_st = m * g / (2 * b * k)

    def rhs(_, y):
        z, v = y
        force = 2 * b * (k * z + bed.contact_law.damping_pressure(z, v, bed.damping))
        return [v, g - force / m]

    w = math.sqrt(2 * b * k / m)
    sol = solve_ivp(rhs, (0, 40 * 2 * math.pi / w), [z_st * 1.001, 0.0], rtol=1e-11, atol=1e-12 * z_st,
                    dense_output=True, max_step=0.05 / w)
    t = np.linspace(0, sol.t[-1], 400_000)
    dz = sol.sol(t)[0] - z_st
    peaks = [abs(dz[i]) for i in range(1, t.size - 1) if dz[i] > dz[i - 1] and dz[i] >= dz[i + 1] and dz[i] > 0]
    delta = math.log(peaks[0] / peaks[3]) / 3
    zeta = delta / math.sqrt(4 * math.pi**2 + delta**2)
    assert mc.vertical_damping_ratio(block, bed) == pytest.approx(zeta, rel=2e-3)
    helper = lam_from_vertical_damping if bed.law == "hunt_crossley" else c_from_vertical_damping
    assert helper(k, m, b, mc.vertical_damping_ratio(block, bed)) == pytest.approx(bed.damping, rel=1e-12)


def test_auto_picks_the_stiff_bed_model_only_inside_every_measured_interval():
    assert mc.choose(STATUE, INSIDE, "kanai_tajimi")[0] == "stiff_bed"
    assert mc.choose(STATUE, STIFF, "kanai_tajimi")[0] == "stiff_bed"          # stiff beds passed under Kanai-Tajimi
    assert mc.choose(EQUIPMENT, Foundation(k=1e9, lam=1e10), "kanai_tajimi")[0] == "stiff_bed"
    name, why = mc.choose(EQUIPMENT, Foundation(k=1e9, lam=1e10), "white")     # failed under white noise
    assert name == "coupled" and "under white" in why
    name, why = mc.choose(STATUE, Foundation(k=1e13, lam=2e13), "kanai_tajimi")   # stiffer than any bed measured
    assert name == "coupled" and "theta_ul_over_slenderness" in why
    name, why = mc.choose(STATUE, SOFT, "kanai_tajimi")               # theta_ul / alpha = 0.32
    assert name == "coupled" and "theta_ul_over_slenderness" in why
    name, why = mc.choose(STATUE, STIFF, "pulse")                     # an excitation kind not measured
    assert name == "coupled" and "'pulse'" in why
    # the paper block (atan(b/h) 0.165) passed on k = 1e9, between the slender block (0.10) and the statues
    assert mc.choose(Block(m=8.67, b=0.035, h=0.21), Foundation(k=1e9, lam=1e10), "kanai_tajimi")[0] == "stiff_bed"
    stocky = Block(m=100.0, b=0.2175, h=0.45)                         # atan(b/h) 0.45: passed at zeta_v 0.02
    assert mc.choose(stocky, Foundation(k=7.7e7, lam=2.0e9), "kanai_tajimi")[0] == "stiff_bed"
    name, why = mc.choose(stocky, Foundation(k=7.7e7, lam=1.18e10), "kanai_tajimi")     # zeta_v 1.3: failed
    assert name == "coupled" and "vertical_damping_ratio" in why
    squat = Block(m=100.0, b=0.38, h=0.45)                            # atan(b/h) 0.70: stockier than any measured
    name, why = mc.choose(squat, Foundation(k=7.7e7, lam=2.0e9), "kanai_tajimi")
    assert name == "coupled" and "slenderness" in why
    assert mc.choose(STATUE, STIFF, "clough_penzien")[0] == "stiff_bed"    # inside the museum objects' box
    name, why = mc.choose(STATUE, INSIDE, "clough_penzien")           # theta_ul / alpha 0.12: beyond 1.1e-3
    assert name == "coupled" and "theta_ul_over_slenderness" in why and "under clough_penzien" in why
    paper_bed = Foundation(k=2.89e7, lam=8.95e8)                      # under the statue: damping ratio 1.38
    name, why = mc.choose(STATUE, paper_bed, "kanai_tajimi")
    assert name == "coupled" and "vertical_damping_ratio" in why
    assert mc.choose(STATUE, STIFF, None)[0] == "coupled"              # records: not measured


def test_auto_never_picks_outside_the_rule_on_a_random_design():
    """Over random blocks and beds, whatever "auto" picks other than the fallback lies inside every interval of
    that model's rule (and every point inside the rule gets it: the rule lists one cheap model)."""
    from screening.analysis.beds import lam_from_vertical_damping

    rng = np.random.default_rng(3)
    (rule,) = mc.rules()[0]
    picked = 0
    for _ in range(300):
        h = rng.uniform(0.3, 2.0)
        b = h * math.tan(rng.uniform(0.25, 0.34))
        block = Block(m=rng.uniform(10, 3000), b=b, h=h)
        k = 10 ** rng.uniform(5, 12)
        bed = Foundation(k=k, lam=float(lam_from_vertical_damping(k, block.m, b, rng.uniform(0.03, 0.055))))
        if 2 / 3 * b**3 * k <= block.m * 9.81 * h:
            continue
        name, _ = mc.choose(block, bed, "white")
        ind = mc.indicators(block, bed)
        inside = all(lo <= ind[n] <= hi for n, (lo, hi) in rule.bounds_for("white"))
        assert (name == "stiff_bed") == inside
        picked += name == "stiff_bed"
    assert picked > 0


def test_auto_runs_the_stiff_bed_rule_with_its_sampler_and_the_box_is_the_models():
    """The shipped stiff-bed rule names its sampler (the exact-contact kernel): "auto" runs it exactly where the
    stiff-bed rule holds, the rule's box and reasons stay the stiff-bed model's, the fallback runs itself; a rule
    without a sampler runs its model; a sampler that is no registered model is refused naming the entry."""
    rule = mc.rule_of("stiff_bed")
    assert rule.sampler == "stiff_bed_fast" and mc.sampler_of("stiff_bed") == "stiff_bed_fast"
    assert mc.sampler_of("coupled") == "coupled"
    for bed, expected in ((INSIDE, "stiff_bed_fast"), (STIFF, "stiff_bed_fast"), (SOFT, "coupled")):
        assert mc.resolve("auto", STATUE, bed, KT).name == expected
        assert mc.choose(STATUE, bed, "kanai_tajimi")[0] == ("stiff_bed" if expected != "coupled" else "coupled")
    plain = mc.parse_rules({"model": [{"name": "stiff_bed", "slenderness": [0.2, 0.3], "excitations": ["white"]}]})
    assert mc.sampler_of("stiff_bed", plain) == "stiff_bed"
    with pytest.raises(ValueError, match=r"model\[0\]\.sampler must be a registered model"):
        mc.parse_rules({"model": [{"name": "stiff_bed", "slenderness": [0.2, 0.3], "excitations": ["white"],
                                   "sampler": "rigid"}]})


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


def test_a_rule_narrowed_for_one_excitation_kind():
    """by_excitation narrows the common intervals for one kind; a record (no kind) gets the narrowest of all."""
    raw = {"model": [{"name": "stiff_bed", "excitations": ["kanai_tajimi", "white"], "slenderness": [0.2, 0.35],
                      "theta_ul_over_slenderness": [0.0, 1.0],
                      "by_excitation": {"kanai_tajimi": {"slenderness": [0.2, 0.3]}}}]}
    rule_set = mc.parse_rules(raw)
    (rule,) = rule_set[0]
    assert dict(rule.bounds_for("kanai_tajimi"))["slenderness"] == (0.2, 0.3)
    assert dict(rule.bounds_for("white"))["slenderness"] == (0.2, 0.35)
    assert rule.bound("slenderness") == (0.2, 0.35)
    equipment, bed = Block(m=300.0, b=0.3, h=0.9), Foundation(k=1e9, lam=1e10)       # slenderness 0.322
    assert mc.choose(equipment, bed, "white", rule_set)[0] == "stiff_bed"
    name, why = mc.choose(equipment, bed, "kanai_tajimi", rule_set)
    assert name == "coupled" and "slenderness = 0.322 outside the measured [0.2, 0.3] of stiff_bed under" in why
    assert mc.vouches(rule, equipment, bed, None, check_excitation=False) == (True, "")      # a record: white holds
    squat = Block(m=300.0, b=0.4, h=0.9)                                                     # slenderness 0.418
    ok, why = mc.vouches(rule, squat, bed, None, check_excitation=False)
    assert not ok and "slenderness = 0.418" in why
    for narrower, match in (({"white_noise": {"slenderness": [0.2, 0.3]}}, "one of the excitations"),
                            ({"white": {"slenderness": [0.1, 0.3]}}, "inside the common interval"),
                            ({"white": {"vertical_over_rocking": [1, 2]}}, "inside the common interval"),
                            ({"white": {"height": [1, 2]}}, "not an indicator")):
        with pytest.raises(ValueError, match=match):
            mc.parse_rules({"model": [{**raw["model"][0], "by_excitation": narrower}]})


def test_monte_carlo_resolves_auto_once_and_records_the_model_that_ran():
    kw = dict(n_samples=2, t_end=0.2, dt=0.1, progress=False)
    stiff = monte_carlo(STATUE, INSIDE, KT, model="auto", **kw)
    assert stiff.attrs["model"] == "stiff_bed_fast"              # the stiff-bed model, run by its sampler
    direct = monte_carlo(STATUE, INSIDE, KT, model="stiff_bed_fast", **kw)
    np.testing.assert_array_equal(stiff.peak_abs_theta.values, direct.peak_abs_theta.values)
    soft = monte_carlo(STATUE, SOFT, KT, model="auto", **kw)
    assert soft.attrs["model"] == "coupled"
    assert mc.resolve("auto", STATUE, INSIDE, KT) is mc_registry.get("stiff_bed_fast")
    assert "auto" in mc.choices() and "auto" not in mc_registry.names()


class _Pulse(screening.KanaiTajimi):
    """A Kanai-Tajimi ground motion under another kind: an excitation the rule was not measured under."""

    kind = "pulse"


def test_stiff_bed_outside_its_validity_warns_or_is_refused_when_strict():
    kw = dict(n_samples=2, t_end=0.1, dt=0.05, progress=False)
    with pytest.warns(UserWarning, match=r"'stiff_bed' outside its measured validity: theta_ul_over_slenderness"):
        monte_carlo(STATUE, SOFT, KT, model="stiff_bed", **kw)
    with pytest.raises(ValueError, match=r"^model 'stiff_bed' outside its measured validity: excitation 'pulse'"):
        monte_carlo(STATUE, STIFF, _Pulse(1e-6, 15.6, 0.6), model="stiff_bed", strict_validity=True, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monte_carlo(STATUE, INSIDE, KT, model="stiff_bed", strict_validity=True, **kw)   # inside: silent
    with pytest.raises(ValueError, match="parameter 'strict_validity'"):
        monte_carlo(STATUE, INSIDE, KT, model="stiff_bed", strict_validity="yes", **kw)


def test_the_stiff_bed_validity_limit_is_the_shipped_rule():
    from screening.solvers import stiff_bed

    assert stiff_bed.validity_limit() == mc.rule_of("stiff_bed").bound("theta_ul_over_slenderness")[1]
    assert stiff_bed.validity(STATUE, STIFF)[1] == f"theta_ul / atan(b/h) <= {stiff_bed.validity_limit():g}"


# ----------------------------------------------------------------------------- the shipped validity table
def _validity_table():
    """The rows of the shipped validity table (``screening/data/stiff_bed_validity.csv``, written by
    ``benchmarks/stiff_bed_validity.py --report --csv``), the comment lines dropped."""
    import csv
    from importlib import resources

    text = resources.files("screening.data").joinpath(mc.VALIDITY_TABLE).read_text("utf-8")
    return list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))


def _inside(rule, row):
    return row["excitation"] in rule.excitations and all(lo <= float(row[name]) <= hi
                                                         for name, (lo, hi) in rule.bounds_for(row["excitation"]))


def test_the_shipped_table_passes_and_fails_by_its_own_tolerances():
    """Each row's verdict is the scene's tolerance applied to its numbers: every probability within
    max(0.03, 2.5 SE) of the coupled model's, and where no coupled sample overturns the peak var_theta ratio within
    max(0.15, 2.5 SE of the ratio) of 1 (15 % alone on the rows measured before the ratio's SE was recorded)."""
    rows = _validity_table()
    assert len(rows) >= 100
    probs = ("p_exceed_0.05", "p_exceed_0.1", "p_exceed_0.3", "p_exceed_0.5", "p_overturn")
    for row in rows:
        if row["note"].startswith("refused"):
            assert row["passed"] == "False"
            continue
        tol = [float(row[f"tol_{p}"]) for p in probs]
        assert min(tol) >= 0.03 - 1e-9
        ok = all(abs(float(row[f"diff_{p}"])) <= t for p, t in zip(probs, tol))
        if row["var_ratio"]:
            assert row["n_overturned_coupled"] == "0"
            var_tol = 0.15
            if row.get("tol_var_ratio"):
                var_tol = float(row["tol_var_ratio"])
                se = float(row["var_ratio_se"])
                assert var_tol == pytest.approx(max(0.15, 2.5 * se) if math.isfinite(se) else 0.15, rel=1e-8)
            ok = ok and abs(float(row["var_ratio"]) - 1.0) <= var_tol
        assert row["passed"] == str(ok), row["case"] + " " + row["model"]


def test_the_shipped_rule_never_vouches_beyond_the_shipped_table():
    """Every model with a rule: every measured case inside the rule passed; each bound lies within the values
    measured inside it (never wider than measured, but for the rounding in the 7th digit); each excitation kind of the rule was measured inside it."""
    rows = _validity_table()
    for rule in mc.rules()[0]:
        measured = [r for r in rows if r["model"] == rule.model]
        inside = [r for r in measured if _inside(rule, r)]
        assert inside, rule.model
        failed = [r["case"] for r in inside if r["passed"] != "True"]
        assert not failed, f"{rule.model} vouched for where it failed: {failed}"
        for kind in rule.excitations:
            of_kind = [r for r in inside if r["excitation"] == kind]
            assert of_kind, f"{rule.model} vouched for under {kind} where nothing was measured"
            for name, (low, high) in rule.bounds_for(kind):
                values = [float(r[name]) for r in of_kind]
                assert min(values) <= low * (1 + 1e-6) and high <= max(values) * (1 + 1e-6), (kind, name)


def test_a_point_just_outside_each_measured_bound_gets_the_fallback(monkeypatch):
    """The statue on a soft bed, inside the rule under Kanai-Tajimi, with one indicator moved just past one end
    of its interval (a relative 1e-6), gets the coupled model, the reason naming that indicator; on each end (the
    intervals are closed) it keeps the stiff-bed model."""
    rule = mc.rule_of("stiff_bed")
    inside = mc.indicators(STATUE, INSIDE)
    assert mc.choose(STATUE, INSIDE, "kanai_tajimi")[0] == "stiff_bed"
    for name, (low, high) in rule.bounds_for("kanai_tajimi"):
        for edge, step in ((low, -1e-6), (high, 1e-6)):
            for value, expected in ((edge * (1 + step), "coupled"), (edge, "stiff_bed")):
                monkeypatch.setattr(mc, "indicators", lambda block, foundation: {**inside, name: value})
                got, why = mc.choose(STATUE, INSIDE, "kanai_tajimi")
                assert got == expected, (name, value)
                if expected == "coupled":
                    assert why.startswith(f"coupled: {name} = ")
