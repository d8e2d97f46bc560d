"""A study's [mcs] spot checks with model = "stiff_bed": the sweep runs the stiff-bed model at the spot
point (the per-sample peaks equal a direct monte_carlo call with the same seed) and records it."""

import numpy as np
import xarray as xr

from helpers import quiet
from screening.solvers.montecarlo import monte_carlo
from screening.sweep.study import build_models, parse_study
from screening.sweep.run import run_sweep

STATUE = """
title = "statue on mortar"
[block]
m = 1200.0
b = 0.25
h = 0.9
[foundation]
k = 1e10
lam = 2e11
[excitation]
kind = "kanai_tajimi"
omega_g = 15.6
zeta_g = 0.6
S0 = [0.005, 0.015]
[time]
t_end = 4.0
dt = 0.05
[mcs]
points = [{S0 = 0.015}]
samples = 6
model = "stiff_bed"
seed = 2
"""


def test_spot_check_runs_the_stiff_bed_model(client, tmp_path):
    study = parse_study(STATUE)
    out = tmp_path / "s.nc"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["mcs_model"] == "stiff_bed"
        spot = ds["mcs_peak_abs_theta"].values[0]
    block, foundation, excitation = build_models(study.cases[0], {"S0": 0.015})
    direct = monte_carlo(block, foundation, excitation, n_samples=6, model="stiff_bed", t_end=4.0, dt=0.05, seed=2,
                         progress=False)
    coupled = monte_carlo(block, foundation, excitation, n_samples=6, model="coupled", t_end=4.0, dt=0.05, seed=2,
                          progress=False)
    np.testing.assert_array_equal(spot, direct.peak_abs_theta.values)
    assert not np.array_equal(spot, coupled.peak_abs_theta.values)


def test_auto_spot_checks_record_the_model_chosen_per_point(client, tmp_path):
    """model = "auto" (the default): a bed inside the measured rule (k = 3e6 with a vertical damping ratio of
    0.05) gets the stiff-bed model, a softer bed (k = 1.1e6: theta_ul / atan(b/h) = 0.32, beyond the softest
    measured) the coupled model; the file's per-spot mcs_model says which, with CF flag attributes."""
    from screening.solvers import mc_registry

    text = (STATUE.replace('model = "stiff_bed"\n', "").replace("k = 1e10", "k = [3e6, 1.1e6]")
            .replace("lam = 2e11", "lam = 1081203.03")
            .replace("points = [{S0 = 0.015}]", "points = [{S0 = 0.015, k = 3e6}, {S0 = 0.015, k = 1.1e6}]"))
    study = parse_study(text)
    assert study.mcs.model == "auto"
    out = tmp_path / "a.nc"
    run_sweep(study, out, client=client, progress=False, log=quiet)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["mcs_model"] == "auto"
        assert ds["mcs_model"].dtype == np.int8               # an integer flag variable (a failed spot check: -1)
        codes = ds["mcs_model"].values.astype(int)
        meanings = ds["mcs_model"].attrs["flag_meanings"].split()
        assert list(ds["mcs_model"].attrs["flag_values"]) == list(range(-1, len(meanings) - 1))
        spot = ds["mcs_peak_abs_theta"].values[0]
    named = dict(zip(ds["mcs_model"].attrs["flag_values"].tolist(), meanings))
    assert [named[c] for c in codes] == ["stiff_bed_fast", "coupled"]      # auto runs the stiff-bed model's sampler
    assert meanings == ["none", *mc_registry.names()]
    block, foundation, excitation = build_models(study.cases[0], {"S0": 0.015, "k": 3e6})
    direct = monte_carlo(block, foundation, excitation, n_samples=6, model="stiff_bed_fast", t_end=4.0, dt=0.05,
                         seed=2, progress=False)
    np.testing.assert_array_equal(spot, direct.peak_abs_theta.values)
