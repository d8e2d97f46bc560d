"""The sweep study's own tables, validated in one pass (:func:`screening.sweep.tables.study_fields`)."""

import pytest

from screening.sweep.config import StudyError, parse_toml
from screening.sweep.inventory import with_collection
from screening.sweep.study import EXAMPLE_STUDY
from screening.sweep.tables import DEFAULT_BUDGET_S, study_fields


def _fields(text):
    return parse_toml(text, "t.toml", lambda raw: study_fields(raw, text, "t", "t.toml", collect=with_collection))


def test_the_example_study_gives_its_grid_and_the_default_budget():
    fields = _fields(EXAMPLE_STUDY + "\n[accuracy]\ntarget = 0.3\n")
    assert len(fields["sweeps"]["eps"]) == 2 and fields["accuracy"].budget_s == DEFAULT_BUDGET_S


@pytest.mark.parametrize("table, message", [
    ("[accuracy]\ntarget = 0.3\nbudget_s = 0", "accuracy.budget_s: must be a finite number > 0"),
    ("[output]\nhistories = \"some\"", "output.histories"),
])
def test_a_bad_value_of_a_sweep_table_is_one_line_naming_its_key(table, message):
    with pytest.raises(StudyError, match=message.replace(".", r"\.")) as err:
        _fields(EXAMPLE_STUDY + "\n" + table + "\n")
    assert "\n" not in str(err.value)


def test_the_key_hashes_the_text_but_not_the_cluster_table():
    a = _fields(EXAMPLE_STUDY)["key"]
    assert _fields(EXAMPLE_STUDY + '\n[cluster]\nkind = "slurm"\nmemory = "8GB"\njobs = 4\n')["key"] == a
    assert _fields(EXAMPLE_STUDY.replace("S0 = 1e-4", "S0 = 2e-4"))["key"] != a
