"""The declarations of the sweep-grid variables: one per name, read by the schema and the writers."""

import numpy as np
import pytest

from screening.solvers import schema
from screening.solvers import outputs
from screening.core.status import PointStatus, Trust
from screening.io.zarrfile import ZARR_FILL


def test_each_variable_declared_once_with_a_known_stage_and_type():
    names = [o.name for o in outputs.GRID_OUTPUTS]
    assert len(names) == len(set(names))
    for o in outputs.GRID_OUTPUTS:
        assert o.stage in outputs.STAGES, o
        assert o.when in outputs.WHEN, o
        assert o.shape in ("history", "point", "threshold"), o
        assert np.dtype(o.dtype).kind in "fi", o
        assert "long_name" in o.attrs, o


def test_schema_reads_the_declarations():
    """What the schema gives for the sweep's tables (the per-point inputs' own first) is the declaration's."""
    for o in outputs.GRID_OUTPUTS:
        got = schema.attributes(o.name, schema.SWEEP_INPUTS if o.name in schema.SWEEP_INPUTS else schema.SWEEP)
        assert list(got) == list(o.attrs), o.name
        for key, value in o.attrs.items():
            assert np.array_equal(got[key], value), (o.name, key)


def test_failed_values_are_failures_and_zarr_fills_them():
    assert outputs.failed_value("status") == PointStatus.task_failed
    assert outputs.failed_value("sl_trust") == Trust.untrusted
    assert np.isnan(outputs.failed_value("peak_var_theta"))
    assert ZARR_FILL == {"status": int(PointStatus.task_failed), "sl_trust": int(Trust.untrusted)}


@pytest.mark.parametrize("probabilities, fragility", [(False, False), (True, False), (False, True)])
def test_selected_follows_the_study(probabilities, fragility):
    chosen = [o.name for o in outputs.selected(("k_eq", "var_theta"), ("S0",), probabilities, fragility)]
    assert chosen[:2] == ["k_eq", "var_theta"]                     # the stored histories, in their order
    assert "var_theta_dot" not in chosen and "S0" in chosen
    assert ("p_overturn" in chosen) == (probabilities or fragility)
    assert ("p_exceed" in chosen) == fragility
    assert "S0" not in [o.name for o in outputs.selected(derived=())]


def test_failed_array_and_cast_shapes_and_types():
    history, status = outputs.OUTPUTS["var_theta"], outputs.OUTPUTS["status"]
    a = history.failed_array(3, nt=5)
    assert a.shape == (3, 5) and a.dtype == np.float32 and np.isnan(a).all()
    b = outputs.OUTPUTS["p_exceed"].failed_array(3, n_thresholds=2)
    assert b.shape == (3, 2) and b.dtype == np.float64
    c = status.cast(np.zeros((2, 3), dtype=np.int64), (2, 3))
    assert c.shape == (6,) and c.dtype == np.int8
    d = outputs.OUTPUTS["theta_ul"].cast(np.array([[1.0], [2.0]]), (2, 3))      # broadcast over the batch
    assert d.tolist() == [1.0, 1.0, 1.0, 2.0, 2.0, 2.0]
    e = history.cast(np.ones((2, 3, 4)), (2, 3))
    assert e.shape == (6, 4) and e.dtype == np.float32


def test_the_solver_lists_come_from_the_declarations():
    assert outputs.HISTORY_VARIABLES == ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq",
                                         "p_uplift")
    assert set(outputs.linearize_variables()) < set(outputs.solver_summaries())
    assert "n_rejected" in outputs.solver_summaries() and "n_rejected" not in outputs.linearize_variables()
    assert outputs.client_variables() == ("status", "sl_trust", "peak_p_uplift")


def test_schema_finds_a_variable_only_the_registry_declares(monkeypatch):
    toy = outputs.Output("toy_margin", "trust", "f8", {"units": "1", "long_name": "a toy margin"})
    monkeypatch.setitem(outputs.OUTPUTS, toy.name, toy)
    assert schema.attributes("toy_margin") == {"units": "1", "long_name": "a toy margin"}
    with pytest.raises(KeyError, match="not declared"):
        schema.attributes("toy_margin_2")
