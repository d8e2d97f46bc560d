"""Shared study-file pieces (screening.sweep.config): validation helpers and one-line errors."""

import numpy as np
import pytest

from helpers import TRADE_STUDY
from screening.sweep import config
from screening.sweep.config import StudyError


@pytest.mark.parametrize("call, message", [
    (lambda: config.check_value("a.x", "1"), "a.x: must be a number (got the string '1')"),
    (lambda: config.check_value("a.x", True), "a.x: must be a number (got a boolean)"),
    (lambda: config.check_value("a.x", float("nan")), "a.x: must be a finite number (got nan)"),
    (lambda: config.check_value("a.x", 0.0, 0.0), "a.x: must be a finite number > 0 (got 0.0)"),
    (lambda: config.check_value("a.x", -1, 0.0, True), "a.x: must be a finite number >= 0 (got -1.0)"),
    (lambda: config.check_value("a.x", 0.5, 0.0, upper=1e-2), "a.x: must be a finite number > 0 and <= 0.01 (got 0.5)"),
    (lambda: config.check_value("a.x", 2.0, upper=1.0), "a.x: must be a finite number <= 1 (got 2.0)"),
    (lambda: config.check_integer("a.n", 2.0, 1), "a.n: must be an integer >= 1 (got 2.0)"),
    (lambda: config.check_integer("a.n", 0, 1), "a.n: must be an integer >= 1 (got 0)"),
    (lambda: config.number_list("a.l", []), "a.l: empty list (give at least one value)"),
    (lambda: config.number_list("a.l", 3.0), "a.l: must be a list (got float)"),
    (lambda: config.number_list("a.l", [1.0, "x"]), "a.l[1]: must be a number (got the string 'x')"),
    (lambda: config.integer_list("a.l", [3, 1], 2), "a.l[1]: must be an integer >= 2 (got 1)"),
    (lambda: config.choice({}, "kind", ("p", "q"), "a."), "a.kind: required (one of 'p', 'q')"),
    (lambda: config.choice({"kind": 1}, "kind", ("p", "q"), "a."), "a.kind: must be one of 'p', 'q' (got int)"),
    (lambda: config.check_keys({"y": 1}, ("x",), "a."), "a.y: unknown key (allowed: x)"),
    (lambda: config.table({"a": 3}, "a"), "a: must be a table (got int)"),
    (lambda: config.name_string("f[0].name", ""), "f[0].name: required, a non-empty string (got the string '')"),
    (lambda: config.time_table({"time": {"t_end": 1.0, "dt": 0.3}}), "time.dt: parameter 'dt' must divide"),
])
def test_helpers_raise_one_line_errors_naming_the_key(call, message):
    with pytest.raises(StudyError) as info:
        call()
    assert str(info.value).startswith(message)
    assert "\n" not in str(info.value)


def test_helpers_return_validated_values():
    assert config.check_value("x", 3) == 3.0 and isinstance(config.check_value("x", 3), float)
    assert config.number_list("l", [1, 2.5], lower=0.0) == (1.0, 2.5)
    assert config.integer_list("l", [3, 1], 1) == (3, 1)
    assert config.integer({}, "n", 7, 1, "a.") == 7
    assert config.time_table({}) == (20.0, 0.05)
    assert config.title_and_description({"title": "t"}, "default") == ("t", "")


def test_parse_toml_prefixes_the_source_and_reads_files(tmp_path):
    with pytest.raises(StudyError, match=r"^s\.toml: invalid TOML: "):
        config.parse_toml("a = ", "s.toml", dict)

    def build(raw):
        raise StudyError("block.m: required")

    with pytest.raises(StudyError, match=r"^s\.toml: block\.m: required$"):
        config.parse_toml("a = 1", "s.toml", build)
    assert config.parse_toml("a = 1", "s.toml", dict) == {"a": 1}
    with pytest.raises(StudyError, match="missing.toml: cannot read the study file"):
        config.read_study_text(tmp_path / "missing.toml")


def test_resolve_case_and_build_models():
    tables = {"block": {"m": 8.67, "b": 0.035, "h": 0.21}, "foundation": {"k": 2.89e7, "lam": 8.95e8},
              "excitation": {"kind": "white"}}
    case = config.resolve_case("c", tables, {"eps": None, "S0": None}, "")
    assert case.params["g"] == 9.81 and case.params["T1"] == 4.0 and case.condensation == config.DEFAULTS["condensation"]
    block, foundation, excitation = config.build_models(case, {"eps": np.array([1.0, 2.0]), "S0": 1e-4})
    np.testing.assert_array_equal(foundation.eps, [1.0, 2.0])
    assert block.m == 8.67 and excitation.S0 == 1e-4
    with pytest.raises(StudyError, match=r"^excitation\.S0: required \(or give a target median PGA"):
        config.resolve_case("c", tables, {"eps": None}, "")


SWEEP = TRADE_STUDY.split("[[family]]")[0] + '[excitation]\nkind = "white"\nS0 = 1e-5\n'


@pytest.mark.parametrize("old, new, needle", [
    ("h = 0.21", "h = 0.21\nwidth = 3", "block.width: unknown key (allowed: m, b, h, I_cm, g)"),
    ("m = 8.67", 'm = "heavy"', "block.m: must be a number (got the string 'heavy')"),
    ("b = 0.035", "b = -0.035", "block.b: must be a finite number >= 1e-06 and <= 1000 (got -0.035)"),
    ("h = 0.21\n", "", "block.h: required"),
    ("k = 2.89e7", "k = 0.0", "foundation.k: must be a finite number > 0 (got 0.0)"),
    ("lam = 8.95e8", "lam = 8.95e8\nc = 3.0", "foundation.c: does not apply to contact = 'hunt_crossley'"),
    ("dt = 0.05", "dt = 0.03", "time.dt: parameter 'dt' must divide"),
    ("t_end = 2.0", "t_end = -2.0", "time.t_end: must be a finite number > 0 (got -2.0)"),
])
def test_sweep_and_trade_studies_share_the_model_tables_and_their_one_line_errors(old, new, needle):
    from screening.applications.tradeoff_study import parse_tradeoff_study
    from screening.sweep.study import parse_study

    messages = []
    for parse, text in ((parse_study, SWEEP), (parse_tradeoff_study, TRADE_STUDY)):
        parse(text, source="s.toml")                     # the base texts are valid
        with pytest.raises(StudyError) as info:
            parse(text.replace(old, new, 1), source="s.toml")
        messages.append(str(info.value))
    assert messages[0] == messages[1]
    assert messages[0].startswith(f"s.toml: {needle}") and "\n" not in messages[0]


# ----------------------------------------------------------------------------- [cluster]
def _cluster(**keys):
    return config.cluster_table({"cluster": {"kind": "slurm", "memory": "8GB", **keys}})


def test_a_cluster_table_has_defaults_that_leave_before_the_walltime():
    assert config.cluster_table({}) is None
    spec = _cluster(walltime="02:00:00", cores=4, jobs=10, queue="short", job_script_prologue=["module load x"])
    # margin min(5 min, walltime / 20) = 300 s: lifetime 2 h - 600 s, stagger 300 s, ending 300 s before the walltime
    assert (spec.walltime_s, spec.lifetime_s, spec.lifetime_stagger_s) == (7200.0, 6600.0, 300.0)
    assert (spec.cores, spec.jobs, spec.queue, spec.job_script_prologue, spec.batch_size) == \
        (4, 10, "short", ("module load x",), None)
    assert spec.numba_cache_dir == config.NUMBA_CACHE_DEFAULT
    short = _cluster(walltime="00:10:00")                          # margin 30 s
    assert (short.lifetime_s, short.lifetime_stagger_s) == (540.0, 30.0)
    assert _cluster(lifetime="50m", lifetime_stagger=120).lifetime_s == 3000.0


@pytest.mark.parametrize("keys, message", [
    ({"walltim": "01:00:00"}, "cluster.walltim: unknown key (allowed: kind, cores, memory,"),
    ({"kind": "sge"}, "cluster.kind: must be one of"),
    ({"kind": None}, "cluster.kind: required (slurm, pbs, local)"),
    ({"memory": None}, "cluster.memory: required (the memory of one job"),
    ({"memory": "lots"}, "cluster.memory: must be an amount of memory like"),
    ({"cores": 0}, "cluster.cores: must be an integer in 1..1024 (got 0)"),
    ({"jobs": 2.5}, "cluster.jobs: must be an integer"),
    ({"walltime": "1h"}, "cluster.walltime: must be HH:MM:SS, more than zero (got '1h')"),
    ({"lifetime": "59m"}, "cluster.lifetime: 3540 s + lifetime_stagger 180 s must end before the walltime"),
    ({"lifetime": "-5m"}, "cluster.lifetime: must be a positive duration"),
    ({"lifetime": "10m", "lifetime_stagger": "10m"}, "cluster.lifetime_stagger: must be shorter than the lifetime"),
    ({"queue": "a\n#SBATCH --x"}, "cluster.queue: must be a non-empty string of one line"),
    ({"job_extra_directives": "--exclusive"}, "cluster.job_extra_directives: must be a list of strings"),
    ({"kind": "local", "job_script_prologue": ["module load x"]}, "cluster.job_script_prologue: not used by kind"),
    ({"batch_size": 0}, "cluster.batch_size: must be an integer"),
])
def test_a_bad_cluster_table_is_one_line_naming_the_key(keys, message):
    table = {"kind": "slurm", "memory": "8GB", **keys}
    table = {k: v for k, v in table.items() if v is not None}
    with pytest.raises(StudyError) as err:
        config.cluster_table({"cluster": table})
    assert str(err.value).startswith(message) and "\n" not in str(err.value), str(err.value)


def test_an_excitation_defined_after_import_is_a_study_kind_with_its_keys_and_attributes():
    """Subclassing Excitation with a kind registers it; the study tables and the CF schema read the registry
    when used, so its kind, its parameter (a key of [excitation], sweepable, range-checked) and the
    parameter's attributes are known without a re-import."""
    from dataclasses import dataclass, field

    from screening.core import excitations
    from screening.core.excitations.base import Excitation, Parameter
    from screening.core.excitations.white import WhiteNoise
    from screening.core.model.excitation import Envelope
    from screening.solvers import schema
    from screening.sweep.study import parse_study

    @dataclass(frozen=True)
    class LateNoise(Excitation):
        S0: float
        late_q: float
        envelope: Envelope = field(default_factory=Envelope)
        band_limit_hz: float | None = None

        kind = "late_noise"
        description = "white noise with a toy parameter"
        parameters = {"late_q": Parameter("1", "toy parameter", 0.0, False, 10.0)}

        def shaping_filter(self):
            return WhiteNoise(self.S0, band_limit_hz=None).shaping_filter()

    text = ('[block]\nm = 1200.0\nb = 0.25\nh = 0.9\n[foundation]\nk = 1e10\nlam = 2e11\n'
            '[excitation]\nkind = "late_noise"\nS0 = 1e-3\nlate_q = LATE\n[time]\nt_end = 2.0\ndt = 0.05\n')
    try:
        assert excitations.get("late_noise") is LateNoise and "late_noise" in config.EXCITATIONS
        assert "late_q" in config.SWEEPABLE and "late_q" in config.TABLE_KEYS["excitation"]
        assert config.NUMERIC["late_q"] == ("excitation", 0.0, False, 10.0)
        assert schema.attributes("late_q") == {"units": "1", "long_name": "toy parameter"}
        assert parse_study(text.replace("LATE", "[1.0, 2.0]")).sweeps["late_q"].tolist() == [1.0, 2.0]
        with pytest.raises(StudyError, match="late_q"):
            parse_study(text.replace("LATE", "20.0"))
    finally:
        excitations.unregister("late_noise")
    assert "late_q" not in config.NUMERIC and "late_noise" not in config.EXCITATIONS
