"""The client side of the sweep's tasks (screening.sweep._submit): which linearization histories a spot task
returns, the stand-ins for a refused batch or a failed spot check, the zarr batch task writing its region, and the
checks run on the workers.  Submission itself runs in the sweep tests (test_sweep*.py, test_accuracy*.py)."""

from types import SimpleNamespace

import numpy as np
import pytest

from screening.solvers.outputs import HISTORY_VARIABLES, client_variables
from screening.core.status import SampleState
from screening.sweep import _submit
from screening.sweep.execution import SPOT_HISTORIES, SPOT_LINEAR


def _study(stored, at_spots=()):
    return SimpleNamespace(output=SimpleNamespace(stored=tuple(stored), at_spots=tuple(at_spots)))


def test_a_spot_task_returns_the_comparison_histories_the_grid_does_not_store_and_the_spot_only_ones():
    assert _submit.spot_linear_names(_study(HISTORY_VARIABLES)) == ()
    assert _submit.spot_linear_names(_study(())) == tuple(n for n in HISTORY_VARIABLES if n in SPOT_LINEAR)
    extra = next(n for n in HISTORY_VARIABLES if n not in SPOT_LINEAR)
    names = _submit.spot_linear_names(_study(SPOT_LINEAR, at_spots=(extra,)))
    assert names == (extra,)
    assert list(names) == sorted(names, key=HISTORY_VARIABLES.index)       # in the declaration order


def test_a_failed_spot_check_is_nan_histories_and_every_sample_failed():
    out = _submit.failed_spot(5, 4, linear_names=("var_theta",))
    assert set(SPOT_HISTORIES) | {"sl_var_theta"} <= set(out)
    assert all(out[n].shape == (5,) and np.isnan(out[n]).all() for n in (*SPOT_HISTORIES, "sl_var_theta"))
    assert (int(out["n_used"]), int(out["n_overturned"]), int(out["n_diverged"])) == (0, 0, 0)
    assert out["sample_state"].dtype == np.int8
    assert out["sample_state"].tolist() == [SampleState.diverged_or_failed] * 4
    assert np.isnan(out["peak_abs_theta"]).all() and out["peak_abs_theta"].shape == (4,)


def test_a_refused_batch_fails_with_its_message():
    with pytest.raises(ValueError, match="^no bed for b = 0.5$"):
        _submit.refused_batch("no bed for b = 0.5")


def test_the_zarr_batch_task_writes_its_region_and_returns_what_the_client_keeps(monkeypatch):
    full = {name: np.arange(3.0) for name in (*client_variables(), "var_theta")}
    monkeypatch.setattr(_submit, "solve_batch", lambda *args: dict(full, args=args))
    written, marked = [], []

    class Store:
        def __init__(self, path, mode):
            assert (path, mode) == ("s.zarr", "r+")

        def chunk_files(self, names, slabs):
            return {"slabs": slabs}

    monkeypatch.setattr(_submit, "ZarrFormat", Store)
    monkeypatch.setattr(_submit, "write_region", lambda fmt, shape, histories, batch, out: written.append(
        (batch, sorted(out))))
    batch = SimpleNamespace(index=7, lo=0, hi=3)
    target = SimpleNamespace(store="s.zarr", shape=(3,), histories=("var_theta",), variables=("var_theta",),
                             mark_done=lambda batch, files: marked.append((batch, files)))
    kept = _submit.solve_and_store_batch(target, batch, 1, 2)
    assert written == [(batch, sorted(dict(full, args=None)))]
    assert marked == [(batch, {"slabs": [(slice(0, 3),)]})]          # marked after its region is written
    assert sorted(kept) == sorted(client_variables())


def test_a_worker_sees_a_folder_only_if_it_exists(tmp_path):
    assert _submit.sees_folder(str(tmp_path)) and not _submit.sees_folder(str(tmp_path / "absent"))
    (tmp_path / "file").write_text("")
    assert not _submit.sees_folder(str(tmp_path / "file"))
