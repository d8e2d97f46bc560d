"""Results frozen before the restructuring (``tests/golden.py``) are reproduced on any machine.

Deterministic values to 10 x the solver's tolerance, Monte Carlo values as paired estimates
(most samples to 1e-5, the moments within their sampling error): the reasons are in
``tests/golden.py``, and ``python tests/golden.py --perturb`` shows both halves at work.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import golden  # noqa: E402


def frozen(name):
    with xr.open_dataset(golden.GOLDEN / f"{name}.nc") as ds:
        return ds.load()


def test_quick_study_reproduces_the_frozen_values():
    golden.compare(golden.compute_quick(), frozen("quick"))


def test_paper_cases_reproduce_the_frozen_values():
    golden.compare(golden.compute_paper_cases(), frozen("paper_cases"))


def test_trade_study_small_case_reproduces_the_frozen_values(tmp_path):
    golden.compare_tradeoff(golden.compute_tradeoff(tmp_path), frozen("tradeoff"))


def test_the_golden_files_hold_the_documented_content():
    quick, cases = frozen("quick"), frozen("paper_cases")
    assert quick.sizes["point"] == 100 and quick.sizes["t"] == 401
    assert cases.sizes["point"] == 8
    assert int(quick.spot_n_overturned) > 0          # the heavy-uplift spot point of `make run`: chaotic samples
    assert golden.mc_prefixes(quick) == ["spot"]
    assert len(golden.mc_prefixes(cases)) == 6
    assert np.all(np.isfinite(cases.peak_var_theta.values))


def _bumped(ds, name, factor):
    out = ds.copy(deep=True)
    out[name] = out[name] * factor
    return out


@pytest.mark.parametrize("name", ["peak_var_theta", "var_theta", "p_uplift"])
def test_a_deterministic_change_of_ten_tolerances_fails(name):
    quick = frozen("quick")
    golden.compare(_bumped(quick, name, 1 + 0.5 * golden.DETERMINISTIC_RTOL), quick)   # within: holds
    with pytest.raises(AssertionError, match=name):
        golden.compare(_bumped(quick, name, 1 + 10 * golden.DETERMINISTIC_RTOL), quick)


def test_the_monte_carlo_comparison_tolerates_chaotic_samples_and_catches_a_shift():
    """40 % of the samples changed at random (what chaos near toppling does on another machine)
    holds; every sample moved by 1 % (what a 1 % change of the bed does) fails; moments shifted by
    5 standard errors fail; an overturned count off by far more than its binomial error fails."""
    quick = frozen("quick")
    rng = np.random.default_rng(0)
    n = quick.sizes["spot_sample"]
    chaotic = quick.copy(deep=True)
    idx = rng.choice(n, size=int(0.4 * n), replace=False)
    peaks = chaotic.spot_peak_abs_theta.values.copy()
    peaks[idx] *= rng.uniform(0.5, 1.5, idx.size)
    chaotic["spot_peak_abs_theta"] = ("spot_sample", peaks)
    golden.compare(chaotic, quick)

    with pytest.raises(AssertionError, match="median sample"):
        golden.compare(_bumped(quick, "spot_peak_abs_theta", 1.01), quick)

    shifted = quick.copy(deep=True)
    shifted["spot_var_theta"] = quick.spot_var_theta + 5 * np.sqrt(2) * quick.spot_var_theta_se
    with pytest.raises(AssertionError, match="standard errors"):
        golden.compare(shifted, quick)

    more = quick.copy(deep=True)
    more["spot_n_overturned"] = quick.spot_n_overturned + 30
    with pytest.raises(AssertionError, match="n_overturned"):
        golden.compare(more, quick)


@pytest.mark.slow
def test_the_comparison_holds_under_last_bit_and_integrator_noise_and_fails_on_a_physics_change(capsys):
    """Recomputes everything six times (about 1-2 minutes): see ``golden.perturb``."""
    assert golden.perturb() == 0, capsys.readouterr().out
