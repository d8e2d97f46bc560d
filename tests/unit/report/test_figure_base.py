"""What every figure shares (screening.report.figure_base): the flagged and untrusted points of a grid and of its
slices (against a mask built by hand), the summary of the flags, the log-spacing test, and the atomic PNG write."""

import numpy as np
import pytest
import xarray as xr

from screening.report import figure_base as fb
from screening.core.status import PointStatus, Trust

STATUS = np.array([[PointStatus.ok, PointStatus.k_eq_negative, PointStatus.ok],
                   [PointStatus.ok, PointStatus.ok, PointStatus.non_finite_moments]])
TRUST = np.array([[Trust.trusted, Trust.untrusted, Trust.untrusted],
                  [Trust.check, Trust.trusted, Trust.untrusted]])


def _grid():
    return xr.Dataset({"status": (("b", "S0"), STATUS), "sl_trust": (("b", "S0"), TRUST)},
                      coords={"b": ("b", [0.03, 0.05], {"units": "m"}),
                              "S0": ("S0", [1e-4, 1e-3, 1e-2], {"units": "m2 s-3"})})


def test_flagged_points_are_those_not_ok_and_untrusted_only_ok_ones():
    flagged, untrusted = fb.point_flags(_grid())
    np.testing.assert_array_equal(flagged, STATUS != PointStatus.ok)
    np.testing.assert_array_equal(untrusted, (STATUS == PointStatus.ok) & (TRUST == Trust.untrusted))


def test_a_slice_and_an_order_of_the_grid_give_the_same_points():
    flagged, untrusted = fb.point_flags(_grid(), index={"b": 1})
    assert flagged.tolist() == [False, False, True] and untrusted.tolist() == [False, False, False]
    flagged_t, _ = fb.point_flags(_grid(), order=("S0", "b"))
    np.testing.assert_array_equal(flagged_t, (STATUS != PointStatus.ok).T)


def test_without_a_trust_rule_nothing_is_untrusted():
    flagged, untrusted = fb.point_flags(_grid().drop_vars("sl_trust"))
    assert flagged.sum() == 2 and not untrusted.any()


def test_the_flag_summary_counts_each_status_and_trust():
    text = fb.flag_summary(_grid())
    assert text.startswith("status: ok 4, ")
    assert "k_eq_negative 1" in text and "non_finite_moments 1" in text
    assert text.endswith("trusted 2, check 1, untrusted 3")


@pytest.mark.parametrize("values, expected", [([1e-5, 1e-4, 1e-3], True), ([1.0, 2.0, 3.0], False),
                                              ([1.0, 100.0], False), ([-1.0, 1.0, 100.0], False),
                                              ([1.0, 10.0, 50.0], False), ([1.0, 10.0, 51.0], True)])
def test_values_are_log_spaced_when_positive_three_or_more_and_spanning_over_50(values, expected):
    assert bool(fb.is_log_spaced(values)) is expected


def test_a_figure_is_written_whole_under_its_name_and_nothing_else(tmp_path):
    out = fb.save_figure(fb.new_figure(2.0, 1.5), tmp_path / "f.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["f.png"]
