"""Per-point inputs of a sweep: the intensity measures of every point's excitation, and S0 where the
study gives the intensity as a target median PGA (``excitation.pga``)."""

import numpy as np
import pytest
import xarray as xr

from helpers import CASES, GRID, quiet

from screening.analysis.intensity import intensity_measures
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

PGA_KT = GRID.replace("S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}", "pga = [0.5, 1.0, 2.0]").replace(
    'kind = "white"', 'kind = "kanai_tajimi"\nomega_g = 15.6\nzeta_g = 0.6').replace(
    "k = 2.89e7", "k = [2.89e7, 6e7]")


def _run(client, tmp_path, text):
    study = parse_study(text, name="s", source="s.toml")
    run_sweep(study, tmp_path / "r.nc", client=client, batch_size=4, progress=False, log=quiet)
    return xr.open_dataset(tmp_path / "r.nc").load()


def test_a_target_pga_study_stores_s0_per_point_and_meets_its_target(client, tmp_path):
    ds = _run(client, tmp_path, PGA_KT)
    assert ds["S0"].dims == ("k", "eps", "pga") and ds["S0"].attrs["units"] == "m2 s-3"
    # S0 grows with the square of the target and is the same on both beds: a PGA is a property of the
    # ground motion (band-limited to the excitation's 25 Hz), not of what stands on it
    ratio = ds["S0"].isel(pga=2) / ds["S0"].isel(pga=0)
    np.testing.assert_allclose(ratio, 16.0, rtol=1e-12)
    np.testing.assert_array_equal(ds["S0"].isel(k=0), ds["S0"].isel(k=1))
    assert float(ds["band_limit_hz"]) == 25.0 and ds["band_limit_hz"].attrs["units"] == "Hz"   # the coordinate
    # stored median PGA = the target, and an independent evaluation from the stored S0 agrees
    target = ds["pga"].broadcast_like(ds["pga_median"])
    np.testing.assert_allclose(ds["pga_median"], target, rtol=1e-9)
    np.testing.assert_allclose(intensity_measures(ds)["pga_median"].transpose(*ds["pga_median"].dims),
                               ds["pga_median"], rtol=1e-9)
    assert (ds["status"] != -1).all()                     # no task failed


@pytest.mark.parametrize("text", [GRID, CASES], ids=["grid", "cases"])
def test_intensity_measures_per_point_match_the_dataset_evaluation(client, tmp_path, text):
    ds = _run(client, tmp_path, text)
    assert "S0" not in ds.data_vars                        # a coordinate or a parameter, not per point
    independent = intensity_measures(ds)
    for name, units in (("pga_median", "m s-2"), ("rms_acceleration", "m s-2"), ("arias_intensity", "m s-1")):
        assert ds[name].attrs["units"] == units
        expected = independent[name].broadcast_like(ds[name]).transpose(*ds[name].dims)
        np.testing.assert_allclose(ds[name], expected, rtol=1e-9)


def test_a_batch_whose_models_cannot_be_built_is_flagged_and_the_run_goes_on(client, tmp_path, monkeypatch):
    """A ValueError while the client builds a batch's models (e.g. S0 from a target PGA at extreme
    scales) fails that batch like a failed task (status task_failed, one warning), never the run."""
    from screening.sweep import _submit  # the client side of the tasks builds the models

    real = _submit.batch_point_models

    def refuses_the_second(study, batch):
        if batch.index == 1:
            raise ValueError("parameter 'S0' must be a finite number > 0 (got nan)")
        return real(study, batch)

    monkeypatch.setattr(_submit, "batch_point_models", refuses_the_second)
    study = parse_study(GRID, name="s", source="s.toml")
    messages = []
    run_sweep(study, tmp_path / "r.nc", client=client, batch_size=4, progress=False, log=messages.append)
    with xr.open_dataset(tmp_path / "r.nc") as ds:
        status = ds["status"].values.reshape(-1)
    np.testing.assert_array_equal(status[4:8], -1)
    assert (status[:4] != -1).all() and (status[8:] != -1).all()
    assert any("batch 1" in m and "must be a finite number" in m for m in messages)
