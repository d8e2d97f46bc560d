"""The trade-study file (screening.applications.tradeoff_study): the shipped study, one-line errors naming the key."""

import re
from pathlib import Path

import pytest

from helpers import TRADE_STUDY
from screening.applications.tradeoff_study import load_tradeoff_study, parse_tradeoff_study
from screening.sweep.config import StudyError

ROOT = Path(__file__).resolve().parents[3]
STUDY_FILE = ROOT / "studies" / "speed_accuracy.toml"


def test_the_shipped_study_parses_and_spans_both_excitations_and_eps_signs():
    study = load_tradeoff_study(STUDY_FILE)
    kinds = {f.kind for f in study.families}
    assert kinds == {"white", "kanai_tajimi"}
    eps = {e for f in study.families for e in f.eps}
    assert any(e > 0 for e in eps) and any(e < 0 for e in eps)
    n_points = sum(len(f.eps) * f.n_intensities for f in study.families)
    assert 12 <= n_points <= 16
    targets = [p for f in study.families for p in (f.target_peak_p_uplift or ())]
    assert min(targets) <= 0.003 and max(targets) >= 0.8
    assert study.mcs["samples"] == 1000 and study.mcs["threads"] == 1
    assert study.convergence["samples"] == (100, 300, 1000, 3000)
    assert 1.0 in study.convergence["rtol_factors"]
    assert len(study.convergence["points"]) >= 2


GOOD = TRADE_STUDY


def _edit(text, old, new):
    assert old in text
    return text.replace(old, new)


@pytest.mark.parametrize("old, new, key", [
    ("title = \"example trade study\"", "title = \"example trade study\"\nbogus = 1", "bogus"),
    ("[mcs]\nsamples = 50", "[mcs]\nsampels = 50", "mcs.sampels"),
    ("[mcs]\nsamples = 50", "[mcs]\nsamples = 1", "mcs.samples"),
    ("[mcs]\nsamples = 50", "[mcs]\nsamples = 50.5", "mcs.samples"),
    ("kind = \"white\"", "kind = \"white\"\nwidth = 2", "family[0].width"),
    ("kind = \"white\"", "kind = \"pink\"", "family[0].kind"),
    ("kind = \"white\"", "kind = \"white\"\nomega_g = 10.0", "family[0].omega_g"),
    ("kind = \"white\"", "kind = \"kanai_tajimi\"", "family[0].omega_g"),
    ("S0 = [1e-5, 2e-5]", "S0 = [1e-5, 2e-5]\ntarget_peak_p_uplift = [0.1]", "family[0].S0"),
    ("S0 = [1e-5, 2e-5]", "S0 = [1e-5, -2e-5]", "family[0].S0[1]"),
    ("S0 = [1e-5, 2e-5]", "target_peak_p_uplift = [0.1, 1.5]", "family[0].target_peak_p_uplift[1]"),
    ("eps = [6e7]\n", "", "family[0].eps"),
    ("eps = [6e7]", "eps = []", "family[0].eps"),
    ("k = 2.89e7", "k = -1.0", "foundation.k"),
    ("lam = 8.95e8", "lam = 8.95e8\nc = 3.0", "foundation.c"),
    ("h = 0.21", "h = 0.21\nwidth = 3", "block.width"),
    ("dt = 0.05", "dt = 0.03", "time.dt"),
    ("rtol_factors = [1.0, 32.0]", "rtol_factors = [0.5, 32.0]", "convergence.rtol_factors"),
    ("rtol_samples = 20", "rtol_samples = 30", "convergence.rtol_samples"),
    ("index = 1}", "index = 2}", "convergence.points[0].index"),
    ("eps = 6e7, index", "eps = 5e7, index", "convergence.points[0].eps"),
    ("{family = \"w\"", "{family = \"x\"", "convergence.points[0].family"),
    ("[convergence]", "[rule]\nmetric = \"median\"\n[convergence]", "rule.metric"),
    ("[convergence]", "[sl]\nrtol = 0.5\n[convergence]", "sl.rtol"),
    ("[time]", "[excitation]\nT1 = 2.0\nT2 = 3.0\n[time]", "excitation.T2"),
])
def test_bad_study_raises_value_error_naming_the_key(old, new, key):
    parse_tradeoff_study(GOOD)                            # the base text is valid
    with pytest.raises(StudyError, match=re.escape(f"bad.toml: {key}: ")) as info:   # "source: key: message"
        parse_tradeoff_study(_edit(GOOD, old, new), source="bad.toml")
    assert str(info.value).startswith(f"bad.toml: {key}: ") and "\n" not in str(info.value)
    assert isinstance(info.value, ValueError)


def test_study_syntax_error_and_missing_family():
    with pytest.raises(StudyError, match="invalid TOML"):
        parse_tradeoff_study("title = ")
    with pytest.raises(StudyError, match="family: at least one"):
        parse_tradeoff_study("title = \"x\"\n[block]\nm = 1.0\nb = 0.1\nh = 0.2\n[foundation]\nk = 1e7\nlam = 1e8\n")


def test_families_carry_the_shared_model_case_and_the_condensation_object():
    from screening.core.condensation import DEFAULT_CONDENSATION, Condensation
    from screening.sweep.config import build_models

    study = parse_tradeoff_study(GOOD)
    assert isinstance(study.condensation, Condensation) and study.condensation.name == DEFAULT_CONDENSATION
    case = study.family("w").case
    assert case.excitation == "white" and case.params["T1"] == 4.0 and "eps" not in case.params
    block, bed, exc = build_models(case, {"eps": 6e7, "S0": 1e-5})
    assert (block.m, bed.k, bed.eps, exc.S0) == (8.67, 2.89e7, 6e7, 1e-5)
    cubic = parse_tradeoff_study(_edit(GOOD, "k = 2.89e7", "k = 2.89e7\ncondensation = \"cubic\""))
    assert cubic.condensation.name == "cubic"
    # the cubic condensation's bearing check runs over every family eps, as for a sweep
    with pytest.raises(StudyError, match=r"foundation\.condensation: 'cubic' needs .* at eps = -1"):
        parse_tradeoff_study(_edit(_edit(GOOD, "k = 2.89e7", "k = 2.89e7\ncondensation = \"cubic\""),
                                   "eps = [6e7]", "eps = [6e7, -1e9]"))


@pytest.mark.parametrize("old, new, key", [
    ("[foundation]", "[foundation]\neps = 1.0", "foundation.eps: unknown key"),
    ("lam = 8.95e8", "lam = [1.0, 2.0]", "foundation.lam: must be a number (got a list)"),
    ("[time]", "[excitation]\nenvelope = \"constant\"\n[time]", "excitation.envelope: must be one of 'exponential'"),
    ("[mcs]", "[[family]]\nname = \"w\"\nkind = \"white\"\neps = [1.0]\nS0 = [1.0]\n[mcs]",
     "family[1].name: duplicate family name 'w'"),
])
def test_trade_study_specific_limits_of_the_shared_tables(old, new, key):
    with pytest.raises(StudyError, match=re.escape(key)):
        parse_tradeoff_study(_edit(GOOD, old, new))
