"""The array layout of a result (screening.io.layout): moved here with the functions from test_grid.py."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import CASES

from screening.core.condensation import DEFAULT_CONDENSATION
from screening.io.layout import hyperslabs, parameter_table
from screening.sweep.study import parse_study


@settings(max_examples=200, deadline=None)
@given(shape=st.lists(st.integers(1, 5), min_size=0, max_size=4), data=st.data())
def test_hyperslabs_cover_a_flat_range_exactly(shape, data):
    shape = tuple(shape)
    n = int(np.prod(shape, dtype=np.int64))
    lo = data.draw(st.integers(0, n - 1))
    hi = data.draw(st.integers(lo + 1, n))
    flat = np.arange(n).reshape(shape)
    pieces = hyperslabs(lo, hi, shape)
    got = np.concatenate([np.atleast_1d(flat[s] if s else flat).ravel() for s, _, _ in pieces])
    np.testing.assert_array_equal(got, np.arange(lo, hi))
    for s, a, b in pieces:
        np.testing.assert_array_equal(np.atleast_1d(flat[s] if s else flat).ravel(), np.arange(a, b))
    assert len(pieces) <= max(1, 2 * len(shape) - 1)


def test_parameter_table_splits_constants_per_case_values_and_labels():
    constants, per_case, labels, case_labels = parameter_table(parse_study(CASES))
    assert constants["m"] == 8.67 and constants["I_cm"] == pytest.approx(8.67 * (0.035**2 + 0.21**2) / 3)
    np.testing.assert_array_equal(per_case["eps"], [6e7, -6e5])
    assert np.isnan(per_case["omega_g"][0]) and per_case["omega_g"][1] == 10.0
    assert "S0" not in constants and "S0" not in per_case                  # swept
    assert labels == {"contact": "hunt_crossley", "condensation": DEFAULT_CONDENSATION, "envelope": "exponential"}
    assert case_labels == {"excitation": ["white", "kanai_tajimi"]}
