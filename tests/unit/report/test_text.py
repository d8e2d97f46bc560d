"""What ``screening info`` prints (screening.report.text), on small datasets built here: the best-estimate counts
by method and the escalation's figures, the probability lines with their source counts, the near-toppling count
against the threshold and the rocking-start range, each against counts and extremes computed here."""

import numpy as np
import pytest
import xarray as xr

from screening.analysis.probabilities import TOPPLING_FRACTION, source_codes
from screening.report import text
from screening.core.status import BestMethod


def test_the_best_line_counts_each_method_and_the_escalations_figures():
    methods = [BestMethod.linearization, BestMethod.linearization, BestMethod.corrected_linearization]
    ds = xr.Dataset({"best_method": ("S0", methods)}, attrs={"accuracy_target": 0.05})
    assert text.best_line(ds) == ("best estimates ([accuracy] target 0.05): linearization 2, "
                                  "corrected_linearization 1")
    ds = ds.assign(esc=("escalation", [0, 1])).assign_attrs(accuracy_n_short_of_target=1, accuracy_cost_s=12.34,
                                                           accuracy_budget_s=600, accuracy_cpu_s=10.0)
    assert text.best_line(ds).endswith("; Monte Carlo at 2 point(s), 1 short of the target's standard error, "
                                       "12.3 of 600 CPU s by the cost model (10.0 s measured)")
    ds = ds.assign_attrs(accuracy_wall_s=431.2)                    # the budget in wall seconds
    assert text.best_line(ds).endswith("1 short of the target's standard error, 431 of 600 wall s (12.3 CPU s by "
                                       "the cost model, 10.0 s measured)")
    ds = ds.assign_attrs(interim_result="written at 06:00 while the [accuracy] stage ran")
    assert text.best_line(ds).endswith("; INTERIM result: written at 06:00 while the [accuracy] stage ran")


def test_the_probability_lines_count_sources_and_the_points_near_toppling():
    codes = source_codes()
    names = sorted(codes)[:2]
    source = [codes[names[0]], codes[names[1]], codes[names[1]], codes[names[0]]]
    p = np.array([0.001, TOPPLING_FRACTION * 2, 0.3, 0.9])
    se = np.array([0.0005, 0.01, np.nan, 0.02])                     # the third is not vouched for
    ds = xr.Dataset({"p_source": ("S0", source), "p_overturn": ("S0", p), "p_overturn_se": ("S0", se),
                     "p_rocking_start": ("S0", [np.nan, 0.2, 0.05, 0.7])})
    lines = text.probability_lines(ds)
    by_code = sorted(names, key=codes.get)                           # counted in the order of the codes
    assert lines[0].endswith(f"by source: {by_code[0]} 2, {by_code[1]} 2")
    vouched = np.isfinite(se)
    near = int(np.sum(vouched & (p > TOPPLING_FRACTION)))
    assert lines[1].startswith("  p_overturn where vouched for: 0.001 .. 0.9; ")
    assert f"; {near} point(s) above" in lines[1]
    assert lines[2].endswith(": 0.05 .. 0.7")
    assert len(lines) == 3
    # with the accounting of which quantity answers the points, one more line after the sources
    ds.attrs["answer_note"] = "answers: variance 3, probabilities 1 (linearization stopped 1); unreliable: ..."
    assert text.probability_lines(ds)[2] == f"  {ds.attrs['answer_note']} (answer_quantity)"


@pytest.mark.parametrize("ds", [xr.Dataset(), xr.Dataset({"p_rocking_start": ("S0", [np.nan, np.nan])})])
def test_nothing_is_said_without_probabilities(ds):
    assert text.probability_lines(ds) == []
