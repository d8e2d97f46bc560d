"""Study files (screening.sweep.study): parsing, grids, cases, spot points and one-line errors."""

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from screening.core import condensation
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Foundation
from screening.sweep.study import StudyError, build_models, load_study, parse_study
from screening.core.excitations.base import band_top

STUDIES = Path(__file__).resolve().parents[3] / "studies"

BASE = """
title = "test"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
contact = "hunt_crossley"
k = 2.89e7
lam = 8.95e8
eps = [-6e5, 0.0, 6e7]
[excitation]
kind = "white"
S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}
T1 = 4.0
T2 = 2.0
[time]
t_end = 2.0
dt = 0.05
"""


def edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


# ----------------------------------------------------------------------------- valid studies
def test_base_grid_follows_file_order_and_values():
    s = parse_study(BASE)
    assert s.dims == ("eps", "S0")
    assert s.shape == (3, 5) and s.n_points == 15
    np.testing.assert_array_equal(s.sweeps["eps"], [-6e5, 0.0, 6e7])
    np.testing.assert_allclose(s.sweeps["S0"], np.geomspace(1e-5, 1e-3, 5), rtol=1e-15)
    assert s.sweeps["S0"][0] == 1e-5 and s.sweeps["S0"][-1] == 1e-3     # exact endpoints
    assert not s.has_case_dim and len(s.cases) == 1
    case = s.cases[0]
    assert case.params["k"] == 2.89e7 and case.params["g"] == 9.81
    assert "eps" not in case.params and "S0" not in case.params
    assert s.times[-1] == 2.0 and s.times.size == 41
    assert s.mcs is None


def test_scalar_parameters_make_no_dimension():
    s = parse_study(edit(BASE, "eps = [-6e5, 0.0, 6e7]", "eps = 6e7"))
    assert s.dims == ("S0",)
    assert s.cases[0].params["eps"] == 6e7


def test_single_value_list_is_a_dimension_of_length_one():
    s = parse_study(edit(BASE, "eps = [-6e5, 0.0, 6e7]", "eps = [6e7]"))
    assert s.dims == ("eps", "S0") and s.shape == (1, 5)


def test_linear_range_and_dimension_order():
    text = edit(BASE, "k = 2.89e7", "k = {start = 1e7, stop = 3e7, num = 3}")
    s = parse_study(text)
    assert s.dims == ("k", "eps", "S0")
    np.testing.assert_array_equal(s.sweeps["k"], [1e7, 2e7, 3e7])


#: Study files with their own format (``screening tradeoff``, tested in test_tradeoff_study.py;
#: ``screening cloud``, tested in tests/integration/test_cloud.py).
NOT_SWEEPS = ("speed_accuracy.toml", "cloud_example.toml")


@pytest.mark.parametrize("path", [p for p in sorted(STUDIES.glob("*.toml")) if p.name not in NOT_SWEEPS],
                         ids=lambda p: p.name)
def test_every_shipped_sweep_study_is_valid(path):
    study = load_study(path)
    assert study.n_points >= 1 and study.name == path.stem


def test_condensation_study_compares_both_condensations_at_the_same_points():
    s = load_study(STUDIES / "condensation.toml")
    assert [c.condensation for c in s.cases] == ["paper", "cubic"]
    pairs = [s.mcs.points[i:i + 2] for i in range(0, len(s.mcs.points), 2)]
    assert all(a[0] == 0 and b[0] == 1 and a[1:] == b[1:] for a, b in pairs)


def test_quick_study_is_small_and_default_like():
    s = load_study(STUDIES / "quick.toml")
    assert s.name == "quick"
    assert s.dims == ("eps", "S0") and s.n_points == 100
    assert s.cases[0].excitation == "white"
    assert s.mcs is not None and s.mcs.samples <= 200


def test_paper_cases_hold_the_eight_configurations():
    s = load_study(STUDIES / "paper_cases.toml")
    assert s.dims == ("case",) and s.shape == (8,)
    got = {(c.excitation, c.params["eps"], c.params["S0"]) for c in s.cases}
    expected = {("white", 6e7, 2.4e-5), ("white", 6e7, 2.4e-3), ("white", -6e5, 5e-4),
                ("white", -6e5, 6.5e-4), ("kanai_tajimi", 6e7, 2.5e-4), ("kanai_tajimi", 6e7, 4e-4),
                ("kanai_tajimi", -6e5, 1.8e-4), ("kanai_tajimi", -6e5, 2e-4)}
    assert got == expected
    for c in s.cases:
        assert (c.params["m"], c.params["b"], c.params["h"]) == (8.67, 0.035, 0.21)
        assert (c.params["k"], c.params["lam"]) == (2.89e7, 8.95e8)
        assert (c.params["T1"], c.params["T2"]) == (4.0, 2.0)
        if c.excitation == "kanai_tajimi":
            assert (c.params["omega_g"], c.params["zeta_g"]) == (10.0, 0.4)
        else:
            assert "omega_g" not in c.params
    assert s.t_end == 20.0
    assert s.mcs.points == tuple((i,) for i in range(8))


def test_cases_combine_with_base_sweeps_as_outer_product():
    text = BASE + """
[[case]]
name = "soft"
foundation.k = 1e7
[[case]]
name = "winkler"
foundation = {contact = "winkler", c = 2e4, lam = 0.0}
"""
    with pytest.raises(StudyError, match=r"case 'winkler': foundation\.lam: does not apply"):
        parse_study(text)          # set by the case itself: an error
    s = parse_study(text.replace(", lam = 0.0", ""))   # inherited from the base: ignored
    assert s.dims == ("case", "eps", "S0") and s.shape == (2, 3, 5)
    assert s.cases[0].params["k"] == 1e7 and s.cases[0].contact == "hunt_crossley"
    assert s.cases[1].contact == "winkler" and s.cases[1].params["c"] == 2e4
    assert "lam" not in s.cases[1].params


def test_condensation_defaults_to_the_package_default_and_cases_may_switch_it():
    s = parse_study(BASE)
    assert s.cases[0].condensation == condensation.DEFAULT_CONDENSATION
    text = edit(BASE, "eps = [-6e5, 0.0, 6e7]", "eps = [0.0, 6e7]") + """
[[case]]
name = "default"
[[case]]
name = "paper"
foundation.condensation = "paper"
[[case]]
name = "cubic"
foundation.condensation = "cubic"
"""
    s = parse_study(text)
    assert [c.condensation for c in s.cases] == [condensation.DEFAULT_CONDENSATION, "paper", "cubic"]
    # the names are looked up once, when the study is parsed: the solvers get the objects
    assert [c.condensation_model for c in s.cases] == [condensation.get(condensation.DEFAULT_CONDENSATION),
                                                       condensation.get("paper"), condensation.get("cubic")]
    s = parse_study(edit(BASE, 'contact = "hunt_crossley"', 'contact = "hunt_crossley"\ncondensation = "cubic"'))
    assert s.cases[0].condensation == "cubic"      # -6e5 1/m^2 carries the paper block


@pytest.mark.parametrize("value, needle", [
    ('"exact"', r"foundation\.condensation: must be one of 'paper', 'cubic', 'virtual_work' \(got 'exact'\)"),
    ("1", r"foundation\.condensation: must be one of .* \(got int\)"),
])
def test_bad_condensation_names_the_key(value, needle):
    with pytest.raises(StudyError, match=needle):
        parse_study(edit(BASE, 'contact = "hunt_crossley"', f'contact = "hunt_crossley"\ncondensation = {value}'))


def test_cubic_condensation_checks_every_grid_point_before_any_work():
    # |eps| (m g / (2 b k))^2 = 2/27 at eps = -(2/27) / z_lin^2; z_lin = 8.67*9.81/(2*0.035*k)
    k = 1e6
    z_lin = 8.67 * 9.81 / (2 * 0.035 * k)
    limit = -(2.0 / 27.0) / z_lin**2
    text = edit(BASE, "k = 2.89e7", f"k = {k!r}")
    text = edit(text, "eps = [-6e5, 0.0, 6e7]", f"eps = [0.0, {0.5 * limit!r}, {1.01 * limit!r}]")
    text = edit(text, 'contact = "hunt_crossley"', 'contact = "hunt_crossley"\ncondensation = "cubic"')
    with pytest.raises(StudyError, match=r"foundation\.condensation: 'cubic' needs .* at eps = "):
        parse_study(text)
    parse_study(text.replace(f", {1.01 * limit!r}]", "]"))            # the carrying beds pass
    parse_study(text.replace('condensation = "cubic"', 'condensation = "paper"'))   # the paper's has no limit


def test_refused_condensation_names_the_first_failing_bed_and_the_reason():
    # at k = 2.89e7 the cubic condensation carries the paper block down to eps ~ -4.2e7 1/m^2
    text = edit(BASE, "eps = [-6e5, 0.0, 6e7]", "eps = [0.0, -1e8, -2e8]")
    with pytest.raises(StudyError) as info:
        parse_study(edit(text, 'contact = "hunt_crossley"', 'contact = "hunt_crossley"\ncondensation = "cubic"'))
    message = str(info.value)
    assert "'cubic' needs a bed it can condense and the one at eps = -100000000.0 is not (" in message
    assert "parameter 'foundation.eps'" in message and message.endswith("; use condensation = 'paper'")


def test_build_models_structure():
    text = edit(BASE, 'kind = "white"', 'kind = "kanai_tajimi"\nomega_g = 10.0\nzeta_g = 0.4')
    s = parse_study(text)
    block, foundation, excitation = build_models(s.cases[0], {"eps": np.array([1.0, 2.0]), "S0": 1e-4})
    assert isinstance(foundation, Foundation) and isinstance(excitation, KanaiTajimi)
    assert isinstance(excitation.envelope, Envelope)
    np.testing.assert_array_equal(foundation.eps, [1.0, 2.0])
    assert block.I_cm == pytest.approx(8.67 * (0.035**2 + 0.21**2) / 3)

    text = edit(BASE, 'contact = "hunt_crossley"', 'contact = "winkler"')
    text = edit(text, "lam = 8.95e8", "c = 2e4")
    text = edit(text, "T1 = 4.0\nT2 = 2.0", 'envelope = "constant"')
    s = parse_study(text)
    _, foundation, excitation = build_models(s.cases[0], {"eps": 0.0, "S0": 1e-4})
    assert isinstance(foundation, Foundation) and foundation.winkler and foundation.c == 2e4
    assert isinstance(excitation, WhiteNoise) and isinstance(excitation.envelope, ConstantEnvelope)


def test_intensity_as_a_target_pga_gives_the_s0_of_that_median_pga():
    from screening.analysis.intensity import pga_median

    text = edit(BASE, "S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", "pga = [0.5, 2.0]")
    text = edit(text, 'kind = "white"', 'kind = "kanai_tajimi"\nomega_g = 15.6\nzeta_g = 0.6')
    s = parse_study(text)
    assert s.dims == ("eps", "pga") and s.shape == (3, 2)
    pga = np.array([0.5, 2.0])
    block, bed, excitation = build_models(s.cases[0], {"eps": 0.0, "pga": pga}, s.t_end)
    assert excitation.band_limit_hz == 25.0            # the ground motion's band (default 25 Hz), to its top
    for target, s0 in zip(pga, excitation.S0):         # an independent evaluation of the median PGA
        assert pga_median(KanaiTajimi(s0, 15.6, 0.6), s.t_end, band_top(25.0)) == pytest.approx(target, rel=1e-9)
    # the same PGA is the same ground motion on a statue's mortar and a cabinet's pads
    mortar = build_models(s.cases[0], {"eps": 0.0, "pga": pga, "k": 2.89e7}, s.t_end)[2]
    pads = build_models(s.cases[0], {"eps": 0.0, "pga": pga, "k": 2.0e5}, s.t_end)[2]
    np.testing.assert_array_equal(mortar.S0, pads.S0)
    # and the study's own band limit is the one used
    wide = parse_study(edit(text, "zeta_g = 0.6", "zeta_g = 0.6\nband_limit_hz = 50"))
    s0_wide = build_models(wide.cases[0], {"eps": 0.0, "pga": pga}, s.t_end)[2].S0
    for target, s0 in zip(pga, s0_wide):
        assert pga_median(KanaiTajimi(s0, 15.6, 0.6, band_limit_hz=50.0), s.t_end,
                          band_top(50.0)) == pytest.approx(target, rel=1e-9)
    assert np.all(s0_wide < excitation.S0)             # a wider band: more acceleration per unit S0
    with pytest.raises(ValueError, match="t_end"):
        build_models(s.cases[0], {"eps": 0.0, "pga": pga})


@pytest.mark.parametrize("old_new, needle", [
    (("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", "S0 = 1e-3\npga = 1.0"),
     "excitation.pga: give the intensity as S0 or as pga, not both"),
    (("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", ""), "excitation.S0: required (or give a target"),
    (("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", "pga = -1.0"), "excitation.pga: must be"),
    (("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", "pga = [1.0, 1e9]"),
     "excitation.pga: must be a number in 1e-06..1000 m s-2 (got 1000000000.0)"),
    (("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}", "S0 = 1e-3\nband_limit_hz = 0"),
     "excitation.band_limit_hz: must be"),
])
def test_intensity_keys_errors(old_new, needle):
    text = edit(BASE, *old_new)
    with pytest.raises(StudyError, match=re.escape(needle)):
        parse_study(text)


def test_spot_points_by_value_index_and_case():
    text = BASE + '[mcs]\npoints = [{eps = 6e7, S0 = 1e-3}, {index = {eps = 0, S0 = 1}}]\nsamples = 10\n'
    s = parse_study(text)
    assert s.mcs.points == ((2, 4), (0, 1))
    assert s.mcs.model == "auto" and s.mcs.seed == 0 and s.mcs.samples == 10      # the default: per point
    s = parse_study(BASE + '[mcs]\npoints = "auto"\ncount = 2\n')
    assert s.mcs.points == "auto" and s.mcs.count == 2
    assert parse_study(BASE + "[mcs]\nenabled = false\n").mcs is None


def test_key_tracks_the_text():
    a, b = parse_study(BASE), parse_study(BASE)
    assert a.key == b.key and len(a.key) == 64
    assert parse_study(BASE + "# comment\n").key != a.key


@settings(max_examples=60, deadline=None)
@given(start=st.floats(1e-8, 1e3), ratio=st.floats(1.001, 1e4), num=st.integers(1, 40),
       log=st.booleans())
def test_ranges_have_num_values_and_exact_endpoints(start, ratio, num, log):
    stop = start * ratio
    text = edit(BASE, "S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}",
                f"S0 = {{start = {start!r}, stop = {stop!r}, num = {num}, log = {str(log).lower()}}}")
    values = parse_study(text).sweeps["S0"]
    assert values.size == num
    assert values[0] == start
    if num > 1:
        assert values[-1] == stop
        assert np.all(np.diff(values) > 0)


# ----------------------------------------------------------------------------- errors
BAD = [
    ("unknown top-level key", ("title", "foo = 1\ntitle"), "foo: unknown key"),
    ("unknown block key", ("h = 0.21", "h = 0.21\nwidth = 1.0"), "block.width: unknown key"),
    ("wrong type", ("m = 8.67", 'm = "heavy"'), "block.m: must be a number"),
    ("boolean is no number", ("m = 8.67", "m = true"), "block.m: must be a number"),
    ("not sweepable", ("m = 8.67", "m = [8.0, 9.0]"), "block.m: must be a number"),
    ("empty list", ("eps = [-6e5, 0.0, 6e7]", "eps = []"), "foundation.eps: empty list"),
    ("num = 0", ("num = 5", "num = 0"), "excitation.S0.num: must be an integer >= 1"),
    ("num not integer", ("num = 5", "num = 5.0"), "excitation.S0.num"),
    ("range key missing", ("stop = 1e-3, ", ""), "excitation.S0.stop: required"),
    ("range unknown key", ("log = true", "log = true, step = 2"), "excitation.S0.step: unknown key"),
    ("log of non-positive", ("start = 1e-5", "start = 0.0"), "excitation.S0.start: must be a finite number > 0"),
    ("T2 >= T1", ("T2 = 2.0", "T2 = 4.0"), "excitation.T2: must be smaller than excitation.T1"),
    ("negative k", ("k = 2.89e7", "k = -2.89e7"), "foundation.k: must be a finite number > 0"),
    ("nan k", ("k = 2.89e7", "k = nan"), "foundation.k"),
    ("infinite eps", ("eps = [-6e5, 0.0, 6e7]", "eps = inf"), "foundation.eps"),
    ("negative in list", ("lam = 8.95e8", "lam = [1.0, -2.0]"), "foundation.lam[1]: must be a finite number >= 0"),
    ("repeated values", ("eps = [-6e5, 0.0, 6e7]", "eps = [1.0, 1.0]"), "foundation.eps: values must be strictly"),
    ("missing required", ("m = 8.67\n", ""), "block.m: required"),
    ("missing S0", ("S0 = {start = 1e-5, stop = 1e-3, num = 5, log = true}\n", ""), "excitation.S0: required"),
    ("bad kind", ('kind = "white"', 'kind = "pink"'), "excitation.kind: must be one of"),
    ("bad contact", ('contact = "hunt_crossley"', 'contact = "glue"'), "foundation.contact: must be one of"),
    ("filter key on white noise", ('kind = "white"', 'kind = "white"\nomega_g = 10.0'),
     "excitation.omega_g: does not apply to kind = 'white'"),
    ("kanai-tajimi without zeta_g", ('kind = "white"', 'kind = "kanai_tajimi"\nomega_g = 10.0'),
     "excitation.zeta_g: required for kind = 'kanai_tajimi'"),
    ("winkler without c", ('contact = "hunt_crossley"\nk = 2.89e7\nlam = 8.95e8',
                           'contact = "winkler"\nk = 2.89e7'), "foundation.c: required"),
    ("lam on winkler", ('contact = "hunt_crossley"', 'contact = "winkler"\nc = 1.0'),
     "foundation.lam: does not apply to contact = 'winkler'"),
    ("T1 with constant envelope", ('T1 = 4.0', 'envelope = "constant"\nT1 = 4.0'),
     "excitation.T1: does not apply to envelope = 'constant'"),
    ("dt does not divide t_end", ("dt = 0.05", "dt = 0.3"), "time.dt"),
    ("negative t_end", ("t_end = 2.0", "t_end = -2.0"), "time.t_end"),
    ("block not a table", ("[block]\nm = 8.67\nb = 0.035\nh = 0.21", "block = 3"), "block: must be a table"),
    ("rtol too large", ("[time]", "[solver]\nrtol = 2.0\n[time]"), "solver.rtol"),
    ("invalid TOML", ("[block]", "[block"), "invalid TOML"),
]


@pytest.mark.parametrize("old_new, needle", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_studies_give_one_line_errors_naming_the_key(old_new, needle):
    text = edit(BASE, *old_new)
    with pytest.raises(StudyError) as info:
        parse_study(text, source="bad.toml")
    message = str(info.value)
    assert needle in message
    assert "\n" not in message
    assert message.startswith("bad.toml: ")
    assert isinstance(info.value, ValueError)


BAD_EXTRA = [
    ("samples < 2", "[mcs]\nsamples = 1\n", "mcs.samples: must be an integer >= 2"),
    ("bad model", '[mcs]\nmodel = "exact"\n', "mcs.model: must be one of"),
    ("off-grid spot", "[mcs]\npoints = [{eps = 6e7, S0 = 2e-3}]\n", "mcs.points[0].S0: 0.002 is not a grid value"),
    ("spot misses a dim", "[mcs]\npoints = [{eps = 6e7}]\n", "mcs.points[0]: missing 'S0'"),
    ("spot unknown dim", "[mcs]\npoints = [{eps = 6e7, S0 = 1e-3, k = 1.0}]\n", "mcs.points[0].k: not a grid"),
    ("spot index out of range", "[mcs]\npoints = [{index = {eps = 3, S0 = 0}}]\n",
     "mcs.points[0].index.eps: must be an integer index in 0..2"),
    ("count with explicit points", "[mcs]\npoints = [{eps = 6e7, S0 = 1e-3}]\ncount = 2\n", "mcs.count"),
    ("duplicate spots", "[mcs]\npoints = [{eps = 6e7, S0 = 1e-3}, {index = {eps = 2, S0 = 4}}]\n",
     "mcs.points: the same grid point is listed twice"),
    ("empty spot list", "[mcs]\npoints = []\n", "mcs.points: empty list"),
    ("case without name", "[[case]]\nfoundation.k = 1e7\n", "case[0].name: required"),
    ("duplicate case", '[[case]]\nname = "a"\n[[case]]\nname = "a"\n', "case[1].name: duplicate"),
    ("case overrides swept key", '[[case]]\nname = "a"\nfoundation.eps = 1.0\n',
     "case 'a': foundation.eps: is swept in the base study"),
    ("case sweeps", '[[case]]\nname = "a"\nfoundation.k = [1e7, 2e7]\n',
     "case 'a': foundation.k: a case sets scalars only"),
    ("case unknown key", '[[case]]\nname = "a"\ntime = {t_end = 3.0}\n', "case 'a': time: unknown key"),
    ("case bad value", '[[case]]\nname = "a"\nblock.h = -1.0\n', "case 'a': block.h: must be a finite number >= 1e-06 and <= 1000"),
    ("base key used by no case", '[[case]]\nname = "a"\nfoundation = {contact = "winkler", c = 1.0}\n',
     "foundation.lam: does not apply to any case"),
]


@pytest.mark.parametrize("extra, needle", [b[1:] for b in BAD_EXTRA], ids=[b[0] for b in BAD_EXTRA])
def test_bad_mcs_and_case_tables(extra, needle):
    with pytest.raises(StudyError) as info:
        parse_study(BASE + extra, source="bad.toml")
    assert needle in str(info.value)
    assert "\n" not in str(info.value)


def test_unreadable_file_is_a_study_error(tmp_path):
    with pytest.raises(StudyError, match="cannot read the study file"):
        load_study(tmp_path / "missing.toml")


def test_the_documented_example_parses():
    import textwrap

    import screening.sweep.study as study_module

    doc = study_module.__doc__
    block = doc.split("Example (SI units throughout)::\n")[1].split("\nNamed cases")[0]
    s = parse_study(textwrap.dedent(block), source="example")
    assert s.dims == ("eps", "S0") and s.shape == (3, 20)
    assert s.mcs.points == "auto" and s.mcs.count == 3


# ----------------------------------------------------------------------------- [output]
def test_output_table_chooses_the_stored_histories():
    from screening.solvers.moments import HISTORY_VARIABLES

    assert parse_study(BASE).output.stored == HISTORY_VARIABLES
    assert parse_study(BASE + '[output]\nhistories = "none"\n').output.stored == ()
    chosen = parse_study(BASE + '[output]\nvariables = ["p_uplift", "var_theta"]\n').output
    assert chosen.histories == "all" and chosen.stored == ("var_theta", "p_uplift")   # canonical order
    assert parse_study(BASE + '[output]\nhistories = "none"\n').key != parse_study(BASE).key


@pytest.mark.parametrize("table, message", [
    ('histories = "some"', r"^<string>: output\.histories: must be one of 'all', 'spots', 'none' \(got 'some'\)$"),
    ("histories = 1", r"^<string>: output\.histories: must be one of"),
    ('variables = ["var_theta", "theta"]', r"^<string>: output\.variables\[1\]: must be one of 'var_theta'"),
    ("variables = []", r"^<string>: output\.variables: empty list"),
    ('variables = "var_theta"', r"^<string>: output\.variables: must be a list"),
    ('variables = ["k_eq", "k_eq"]', r"^<string>: output\.variables: a variable is listed twice$"),
    ('histories = "none"\nvariables = ["k_eq"]', r"^<string>: output\.variables: only with histories = 'all' or 'spots'$"),
    ("dt = 0.1", r"^<string>: output\.dt: unknown key"),
])
def test_output_table_errors_name_the_key(table, message):
    with pytest.raises(StudyError, match=message) as info:
        parse_study(BASE + "[output]\n" + table + "\n")
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------------------- [fragility]
def test_fragility_table():
    frag = parse_study(BASE + '[fragility]\nthresholds = [0.5, 1.0]\nrelative_to = "theta_ul"\n').fragility
    assert frag.thresholds == (0.5, 1.0) and frag.relative_to == "theta_ul" and frag.method == "vanmarcke"
    assert parse_study(BASE).fragility is None
    assert parse_study(BASE + '[fragility]\nthresholds = [0.01]\nmethod = "poisson"\n').fragility.relative_to is None


@pytest.mark.parametrize("table, message", [
    ("relative_to = 'theta_ul'", r"^<string>: fragility\.thresholds: required"),
    ("thresholds = [0.5, -1.0]", r"^<string>: fragility\.thresholds\[1\]: "),
    ("thresholds = []", r"^<string>: fragility\.thresholds: empty list"),
    ("thresholds = [0.5, 0.5]", r"^<string>: fragility\.thresholds: a threshold is listed twice$"),
    ("thresholds = [0.5]\nrelative_to = 'b'", r"^<string>: fragility\.relative_to: must be one of 'slenderness'"),
    ("thresholds = [0.5]\nmethod = 'rice'", r"^<string>: fragility\.method: must be one of 'vanmarcke', 'poisson'"),
    ("thresholds = [0.5]\nlevels = [1]", r"^<string>: fragility\.levels: unknown key"),
])
def test_fragility_table_errors_name_the_key(table, message):
    with pytest.raises(StudyError, match=message) as info:
        parse_study(BASE + "[fragility]\n" + table + "\n")
    assert "\n" not in str(info.value)


def test_spot_histories_need_spot_checks():
    with pytest.raises(StudyError, match=r"^<string>: output\.histories: 'spots' stores the histories at the \[mcs\]"):
        parse_study(BASE + '[output]\nhistories = "spots"\n')
    study = parse_study(BASE + '[output]\nhistories = "spots"\nvariables = ["k_eq"]\n[mcs]\nsamples = 10\n')
    assert study.output.stored == () and study.output.at_spots == ("k_eq",)


# ----------------------------------------------------------------------------- [accuracy]
def test_accuracy_is_off_by_default_and_read_with_defaults():
    assert parse_study(BASE).accuracy is None
    acc = parse_study(BASE + "\n[accuracy]\ntarget = 0.15\n").accuracy
    assert (acc.target, acc.budget_s, acc.seed) == (0.15, 600.0, 0)
    acc = parse_study(BASE + "\n[accuracy]\ntarget = 0.05\nbudget_s = 30\nseed = 4\n").accuracy
    assert (acc.target, acc.budget_s, acc.seed) == (0.05, 30.0, 4)
    assert parse_study(BASE + "\n[accuracy]\nbudget_s = 30\n").accuracy is None     # no target: no escalation


@pytest.mark.parametrize("line, needle", [
    ("target = 0", r"accuracy\.target: must be a finite number > 0 and <= 1"),
    ("target = 1.5", r"accuracy\.target: must be a finite number > 0 and <= 1"),
    ("target = 'x'", r"accuracy\.target: must be a number"),
    ("target = 0.1\nbudget_s = 0", r"accuracy\.budget_s: must be a finite number > 0 and <= 604800"),
    ("target = 0.1\nseed = -1", r"accuracy\.seed"),
    ("target = 0.1\nsamples = 3", r"accuracy\.samples: unknown key"),
])
def test_bad_accuracy_key_names_the_key_and_range(line, needle):
    with pytest.raises(StudyError, match=needle):
        parse_study(BASE + f"\n[accuracy]\n{line}\n")


STATUE_STUDY = STUDIES / "statue_accuracy.toml"


def test_mcs_and_accuracy_default_to_auto_and_accept_the_registered_models():
    text = STATUE_STUDY.read_text() + "\n[mcs]\ncount = 1\n"
    s = parse_study(text)
    assert s.mcs.model == "auto" and s.accuracy.model == "auto" and s.mcs.strict_validity is False
    s = parse_study(text.replace("target = 0.15", 'target = 0.15\nmodel = "coupled"'))
    assert s.accuracy.model == "coupled"
    with pytest.raises(StudyError, match=r"accuracy.model: must be one of .*'auto'"):
        parse_study(text.replace("target = 0.15", 'target = 0.15\nmodel = "rigid"'))


def test_strict_validity_refuses_the_stiff_bed_model_outside_its_rule_in_one_line_before_any_work():
    soft = (STATUE_STUDY.read_text().replace("k = 1e10 ", "k = {start = 1.1e6, stop = 1e10, num = 3, log = true} ")
            + '\n[mcs]\ncount = 1\nmodel = "stiff_bed"\n')
    with pytest.warns(UserWarning, match=r"mcs.model: model 'stiff_bed' outside its measured validity"):
        parse_study(soft)                                   # not strict: a warning, the study loads
    with pytest.raises(StudyError) as err:
        parse_study(soft + "strict_validity = true\n")
    text = str(err.value)
    assert "\n" not in text and "theta_ul_over_slenderness" in text and "model_choice.toml" in text
    assert "k = 1100000.0" in text and "strict_validity = true" in text       # the first point outside
    inside = STATUE_STUDY.read_text().replace("k = 1e10 ", "k = 3e6 ").replace("lam = 2.08e11", "lam = 1081203.03")
    parse_study(inside + '\n[mcs]\ncount = 1\nmodel = "stiff_bed"\nstrict_validity = true\n')     # inside
    with pytest.raises(StudyError, match="mcs.strict_validity: must be true or false"):
        parse_study(soft + "strict_validity = 1\n")
