"""Status code spaces (screening.core.status): built once from screening/data/status_codes.toml."""

import pickle

import numba
import numpy as np
import pytest

from screening.core import status
from screening.core.status import (CODE_SPACES, DIVERGENCE_TEXT, DivergenceReason, PointStatus, Trust,
                                   flag_attributes)

SPACES = [getattr(status, name) for name in CODE_SPACES]


@pytest.mark.parametrize("codes", SPACES, ids=lambda c: c.__name__)
def test_every_code_space_has_unique_codes_names_and_a_meaning_per_member(codes):
    table = {k: v for k, v in CODE_SPACES[codes.__name__].items() if k != "doc"}
    assert [m.name for m in codes] == list(table)                  # no alias swallowed a member
    assert len({int(m) for m in codes}) == len(table)
    assert all(isinstance(m.meaning, str) and m.meaning for m in codes)
    assert codes.__doc__ == CODE_SPACES[codes.__name__]["doc"]


@pytest.mark.parametrize("codes", SPACES, ids=lambda c: c.__name__)
def test_members_survive_pickling(codes):
    """Dask ships members between processes."""
    for member in codes:
        assert pickle.loads(pickle.dumps(member)) is member


def test_compiled_code_reads_members_as_integer_constants():
    ok, failed = PointStatus.ok, PointStatus.task_failed

    @numba.njit
    def classify(code):
        return 1 if code == ok else (2 if code == failed else 0)

    assert [classify(0), classify(-1), classify(3)] == [1, 2, 0]


def test_known_codes_and_texts():
    assert (int(PointStatus.ok), int(PointStatus.task_failed), int(PointStatus.beyond_float_range)) == (0, -1, 5)
    assert DIVERGENCE_TEXT[DivergenceReason.long_flight] == "flight longer than max_flight_time"
    attrs = flag_attributes(Trust, "trust")
    np.testing.assert_array_equal(attrs["flag_values"], [0, 1, 2])
    assert attrs["flag_meanings"] == "trusted check untrusted" and attrs["flag_values"].dtype == np.int8
