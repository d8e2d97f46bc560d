"""The resume record of a sweep (screening.io.store.PartialStore)."""

import numpy as np
import pytest

from helpers import quiet

from screening.io.errors import SweepError
from screening.sweep.grid import Batch
from screening.io.store import PartialStore

LAYOUT = {"n_points": 4, "shape": [4], "batch_size": 2, "study_file": "s.toml"}


def test_parts_round_trip_and_are_tied_to_the_study_key(tmp_path):
    store = PartialStore(tmp_path / "r.nc")
    assert store.open("key-1", LAYOUT, quiet)["batch_size"] == 2
    batch = Batch(index=1, case=0, lo=2, hi=4)
    store.save_batch(batch, {"status": np.array([0, 1], dtype=np.int8)})
    store.save_spot(0, (3,), {"n_used": np.int32(5)})
    np.testing.assert_array_equal(store.load_batch(batch)["status"], [0, 1])
    assert int(store.load_spot(0, (3,))["n_used"]) == 5
    assert store.load_spot(0, (2,)) is None                 # another point: not this record
    store.close()

    messages = []
    other = PartialStore(tmp_path / "r.nc")
    other.open("key-2", {**LAYOUT, "batch_size": 3}, messages.append)
    assert any("discarding partial results" in m for m in messages)
    assert other.load_batch(batch) is None and other.manifest["batch_size"] == 3
    other.remove()
    assert not (tmp_path / "r.nc.partial").exists()


def test_a_second_store_on_the_same_output_is_refused(tmp_path):
    first = PartialStore(tmp_path / "r.nc")
    first.open("key", LAYOUT, quiet)
    try:
        with pytest.raises(SweepError, match="another run is writing"):
            PartialStore(tmp_path / "r.nc").open("key", LAYOUT, quiet)
    finally:
        first.close()
