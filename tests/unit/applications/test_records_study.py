"""The block and bed of a study for record analyses (screening.applications.records_study): the study file read with
its ``[records]`` table taken out and no excitation needed, the one case picked, swept block and bed parameters
fixed by ``--set`` values (excitation parameters ignored: the record is the excitation)."""

import pytest

from screening.sweep.config import StudyError
from screening.applications.records_study import block_and_foundation, load_record_study, pick_case
from screening.sweep.study import EXAMPLE_STUDY, parse_study

NO_EXCITATION = EXAMPLE_STUDY.split("[excitation]")[0]


def _write(tmp_path, text):
    path = tmp_path / "bed.toml"
    path.write_text(text)
    return path


def test_the_records_table_is_taken_out_and_the_excitation_is_optional(tmp_path):
    study, records = load_record_study(_write(tmp_path, NO_EXCITATION + '[records]\nfiles = ["a.AT2", "b.AT2"]\n'))
    assert records == {"files": ["a.AT2", "b.AT2"]}
    assert study.cases[0].excitation == "white" and study.name == "bed"
    study, records = load_record_study(_write(tmp_path, EXAMPLE_STUDY))
    assert records is None and study.dims == ("eps",)


def test_a_records_key_that_is_not_a_table_is_refused(tmp_path):
    with pytest.raises(StudyError, match="records: must be a table"):
        load_record_study(_write(tmp_path, 'records = "a.AT2"\n' + EXAMPLE_STUDY))


def test_a_swept_bed_parameter_must_be_set_and_the_set_value_is_used():
    study = parse_study(EXAMPLE_STUDY)
    with pytest.raises(StudyError, match=r"foundation.eps is swept in the study; fix it with --set eps=VALUE "
                                         r"\(swept values: 0, 6e\+07\)"):
        block_and_foundation(study)
    block, foundation, case = block_and_foundation(study, overrides={"eps": 3e7, "b": 0.05})
    assert (float(block.b), float(foundation.eps), float(foundation.k)) == (0.05, 3e7, 2.89e7)
    assert case is pick_case(study)


def test_only_block_and_bed_parameters_can_be_set():
    study = parse_study(EXAMPLE_STUDY)
    with pytest.raises(StudyError, match="--set S0: only block and foundation parameters can be set"):
        block_and_foundation(study, overrides={"eps": 0.0, "S0": 1.0})
    with pytest.raises(StudyError, match="--set colour"):
        block_and_foundation(study, overrides={"eps": 0.0, "colour": 1.0})


def test_an_unknown_case_is_named_with_the_cases_there_are():
    study = parse_study(EXAMPLE_STUDY)
    with pytest.raises(StudyError, match=r"--case 'soft': no such case \(cases: "):
        pick_case(study, "soft")
