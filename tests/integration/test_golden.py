"""The results frozen before the restructuring (``tests/golden.py``) are reproduced to rtol 1e-9."""

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import golden  # noqa: E402

RTOL = 1e-9


def assert_same_values(new, frozen):
    """rtol 1e-9, except the SL histories and one derived error (documented in ``tests/golden.py``)."""
    assert set(frozen.data_vars) <= set(new.data_vars), set(frozen.data_vars) - set(new.data_vars)
    for name, ref in frozen.data_vars.items():
        got = new[name]
        assert got.shape == ref.shape, name
        got_v, ref_v = np.asarray(got.values, dtype=float), np.asarray(ref.values, dtype=float)
        if name in golden.HISTORY_VARIABLES and ref.dims[-1:] == ("t",):
            scale = np.nanmax(np.abs(ref_v), axis=-1, keepdims=True)
            np.testing.assert_array_equal(np.isnan(got_v), np.isnan(ref_v), err_msg=name)
            with np.errstate(invalid="ignore"):
                excess = np.nanmax(np.abs(got_v - ref_v) - golden.HISTORY_RTOL * scale)
            assert not excess > 0.0, name
        else:
            np.testing.assert_allclose(got_v, ref_v, rtol=RTOL, atol=golden.ABSOLUTE_TOLERANCE.get(name, 0.0),
                                       equal_nan=True, err_msg=name)


def frozen(name):
    with xr.open_dataset(golden.GOLDEN / f"{name}.nc") as ds:
        return ds.load()


def test_quick_study_reproduces_the_frozen_values():
    assert_same_values(golden.compute_quick(), frozen("quick"))


def test_paper_cases_reproduce_the_frozen_values():
    assert_same_values(golden.compute_paper_cases(), frozen("paper_cases"))


def test_trade_study_small_case_reproduces_the_frozen_values(tmp_path):
    assert_same_values(golden.compute_tradeoff(tmp_path), frozen("tradeoff"))


def test_the_golden_files_hold_the_documented_content():
    quick, cases = frozen("quick"), frozen("paper_cases")
    assert quick.sizes["point"] == 100 and quick.sizes["t"] == 401
    assert cases.sizes["point"] == 8
    assert int(quick.spot_n_overturned) > 0          # the heavy-uplift spot point of `make run`
    assert np.all(np.isfinite(cases.peak_var_theta.values))
    with pytest.raises(AssertionError):
        bumped = quick.copy(deep=True)
        bumped["peak_var_theta"] = bumped.peak_var_theta * (1 + 1e-8)
        assert_same_values(bumped, quick)
    with pytest.raises(AssertionError, match="var_theta"):
        bumped = quick.copy(deep=True)
        bumped["var_theta"] = bumped.var_theta * (1 + 1e-6)
        assert_same_values(bumped, quick)
