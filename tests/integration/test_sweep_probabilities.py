"""Every point of a sweep with [accuracy] or [fragility] carries p_overturn and p_exceed, their standard
errors and the model that produced them (p_source); every point carries p_rocking_start."""

import numpy as np
import pytest
import xarray as xr

from helpers import GRID

from screening.analysis.fragility import STORED, best_exceedance
from screening.analysis.trust import OVERTURN_LIMIT
from screening.analysis.probabilities import monte_carlo_source
from screening.core.status import (AnswerQuantity, BestMethod, EscalationModel, PointStatus, ProbabilitySource,
                                   SampleState)
from screening.sweep.study import parse_study
from screening.sweep.run import run_sweep

FRAGILITY = '\n[fragility]\nthresholds = [0.05, 0.3]\nrelative_to = "slenderness"\n'
ACCURACY = GRID.replace("t_end = 4.0", "t_end = 3.0") + "\n[accuracy]\ntarget = 0.15\nbudget_s = 600000\n" + FRAGILITY
SPOTS = GRID + FRAGILITY + "\n[mcs]\npoints = [{index = {eps = 3, S0 = 4}}]\nsamples = 40\n"


def _counted(peaks, state, levels):
    """(p_overturn, [p_exceed]) counted sample by sample (overturned samples exceed every level)."""
    valid = (state == SampleState.standing) | (state == SampleState.overturned)
    over = state == SampleState.overturned
    return over[valid].mean(), [np.mean((peaks[valid] > a) | over[valid]) for a in levels]


def _flat(ds, name):
    v = ds[name]
    return v.values.reshape((-1, v.sizes["threshold"]) if "threshold" in v.dims else -1)


def test_accuracy_study_points_carry_probabilities_from_the_best_model(client, tmp_path):
    run_sweep(parse_study(ACCURACY), tmp_path / "a.nc", client=client, progress=False, log=lambda m: None)
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        ds = ds.load()
    src, p_over, se_over = _flat(ds, "p_source"), _flat(ds, "p_overturn"), _flat(ds, "p_overturn_se")
    p_exc, se_exc = _flat(ds, "p_exceed"), _flat(ds, "p_exceed_se")
    slender = _flat(ds, "slenderness")
    # Monte Carlo where it ran, with the model that ran, counted from the stored sample peaks
    at = ds["esc_grid_index"].values
    assert at.size >= 1
    for j, i in enumerate(at):
        model = EscalationModel(int(ds["esc_model"].values[j])).name
        assert src[i] == monte_carlo_source(model)
        n = int(ds["esc_samples"].values[j])
        over, exc = _counted(ds["esc_peak_abs_theta"].values[j, :n], ds["esc_sample_state"].values[j, :n],
                             [0.05 * slender[i], 0.3 * slender[i]])
        assert p_over[i] == pytest.approx(over, abs=1e-15)
        np.testing.assert_allclose(p_exc[i], exc, atol=1e-15)
        assert np.isfinite(se_over[i]) and se_over[i] > 0
    # the corrected linearization: the up-crossing of the moments rescaled to the best estimates
    corrected = np.flatnonzero(src == ProbabilitySource.corrected_linearization_gaussian)
    assert corrected.size >= 1
    for j, (threshold, relative_to) in enumerate([(1.0, "slenderness"), (0.05, "slenderness"), (0.3, "slenderness")]):
        p, low, high, _ = (a.values.reshape(-1) for a in best_exceedance(ds, threshold, relative_to))
        got, se = (p_over, se_over) if j == 0 else (p_exc[:, j - 1], se_exc[:, j - 1])
        np.testing.assert_allclose(got[corrected], p[corrected], rtol=1e-12)
        floor = (OVERTURN_LIMIT - p) / 2                # what the trust rule leaves open below a small p
        np.testing.assert_allclose(se[corrected], np.maximum(np.abs(high - low) / 4, floor)[corrected], rtol=1e-12)
    # no standard error where nothing vouches for the number; one everywhere else
    unreliable = src == ProbabilitySource.unreliable
    assert np.all(np.isnan(se_over[unreliable])) and np.all(np.isfinite(se_over[~unreliable]))
    assert np.all(np.isnan(se_exc[unreliable])) and np.all(np.isfinite(se_exc[~unreliable]))
    assert set(np.unique(src)) <= {*[int(s) for s in ProbabilitySource],
                                   *[monte_carlo_source(m.name) for m in EscalationModel]}
    # which quantity answers each point: the probabilities where the linearization stopped; the study's
    # fragility surface only where the probabilities answer and no Monte Carlo ran
    answer = _flat(ds, "answer_quantity")
    stopped = np.isin(_flat(ds, "status"), [PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness])
    assert np.all(answer[stopped] == AnswerQuantity.probabilities_stopped)
    surface = src == ProbabilitySource.study_fragility_surface
    assert np.all(answer[surface] != AnswerQuantity.variance) and not np.any(np.isin(np.flatnonzero(surface), at))
    assert ds["answer_quantity"].attrs["flag_meanings"].split() == [m.name for m in AnswerQuantity]
    assert ds.attrs["answer_note"].startswith(f"answers: variance {np.sum(answer == 0)}, probabilities "
                                              f"{np.sum(answer != 0)}")
    assert f"unreliable: {np.sum(_flat(ds, 'best_method') == BestMethod.unreliable)} variance" in ds.attrs["answer_note"]
    # overturned samples count as exceeding: p_exceed >= p_overturn, and falls with the threshold
    assert np.all(p_exc[:, 1] >= p_over - 1e-12) and np.all(p_exc[:, 0] >= p_exc[:, 1] - 1e-12)
    assert ds["p_source"].attrs["flag_meanings"].split()[:len(ProbabilitySource)] == [m.name for m in ProbabilitySource]
    assert "probabilities_note" in ds.attrs and ds["p_overturn"].attrs["units"] == "1"


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_fragility_study_points_carry_probabilities_and_the_spot_check_replaces_its_point(client, tmp_path, suffix):
    if suffix == ".zarr":
        pytest.importorskip("zarr")
    from screening.io.reader import open_result

    report = run_sweep(parse_study(SPOTS), tmp_path / f"s{suffix}", client=client, progress=False,
                       log=lambda m: None)
    with open_result(tmp_path / f"s{suffix}") as ds:
        ds = ds.load()
    src = ds["p_source"].values
    spot = (3, 4)
    assert src[spot] == monte_carlo_source("coupled")
    over, exc = _counted(ds["mcs_peak_abs_theta"].values[0], ds["mcs_sample_state"].values[0],
                         [0.05 * float(ds["slenderness"][spot]), 0.3 * float(ds["slenderness"][spot])])
    assert float(ds["p_overturn"][spot]) == pytest.approx(over, abs=1e-15)
    np.testing.assert_allclose(ds["p_exceed"].values[spot], exc, atol=1e-15)
    # elsewhere the linearization's Gaussian up-crossing where the point is trusted; missing values where
    # nothing vouches for a number (p_source unreliable)
    rest = np.ones(src.shape, bool)
    rest[spot] = False
    vouched = rest & (src != ProbabilitySource.unreliable)
    unvouched = rest & (src == ProbabilitySource.unreliable)
    assert vouched.any() and unvouched.any()
    for j, thr in enumerate((0.05, 0.3)):
        ref = ds.rocking.exceedance_probability(thr, relative_to="slenderness").values
        np.testing.assert_allclose(ds["p_exceed"].values[..., j][vouched], ref[vouched], rtol=1e-4, atol=1e-12)
        assert np.all(np.isnan(ds["p_exceed"].values[..., j][unvouched]))
    ref = ds.rocking.exceedance_probability(1.0, relative_to="slenderness").values
    np.testing.assert_allclose(ds["p_overturn"].values[vouched], ref[vouched], rtol=1e-4, atol=1e-12)
    assert np.all(np.isnan(ds["p_overturn"].values[unvouched]) & np.isnan(ds["p_overturn_se"].values[unvouched]))
    trusted = rest & (ds["sl_trust"].values == 0) & (ds["status"].values == 0)
    np.testing.assert_array_equal(src[rest], np.where(trusted[rest], ProbabilitySource.linearization_gaussian,
                                                      ProbabilitySource.unreliable))
    assert np.all(np.isnan(ds["p_overturn_se"].values[rest & ~trusted]))
    # the text summary puts the probabilities, with their standard errors, beside the spot check's variances
    from screening.analysis.probabilities import probability_text, spot_check_probabilities
    from screening.report.text import describe

    prob = spot_check_probabilities(ds)
    assert prob["p_overturn"][0] == pytest.approx(over, abs=1e-15)
    np.testing.assert_allclose(prob["p_exceed"][0], exc, atol=1e-15)
    text = describe(ds)
    spot_line = next(line for line in text.splitlines() if "peak var_theta rel. error" in line)
    assert f"P(overturn) {probability_text(over, float(ds['p_overturn_se'][spot]))}" in spot_line
    assert f"P(|theta| > 0.3 slenderness) {probability_text(exc[1], ds['p_exceed_se'].values[spot][1])}" in spot_line
    assert spot_line.endswith(" *") == (over > 0.05)
    assert "by source: " in text and "probability that rocking starts" in text
    assert report.probabilities == {name: int(np.sum(src == code)) for name, code in
                                    (("unreliable", 0), ("linearization_gaussian", 1), ("monte_carlo_coupled", 10))
                                    if np.any(src == code)}


def test_p_rocking_start_is_the_closed_form_at_every_point(client, tmp_path):
    """Without [accuracy] or [fragility]: no p_overturn, but p_rocking_start and the uplift acceleration."""
    from screening.core import condensation
    from screening.analysis.intensity import rocking_start_probability
    from screening.analysis.probabilities import uplift_acceleration
    from screening.core.model import Block, Foundation
    from screening.core.excitations.white import WhiteNoise
    from screening.solvers.synthesis import default_cutoff

    study = parse_study(GRID)
    run_sweep(study, tmp_path / "g.nc", client=client, progress=False, log=lambda m: None)
    with xr.open_dataset(tmp_path / "g.nc") as ds:
        assert "p_overturn" not in ds and "p_source" not in ds
        point = ds.isel(eps=2, S0=3)
        block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, eps=float(point["eps"]))
        a_ul = uplift_acceleration(block, bed, condensation.get(study.cases[0].condensation))
        assert float(point["uplift_acceleration"]) == pytest.approx(float(a_ul), rel=1e-12)
        expected = rocking_start_probability(WhiteNoise(float(point["S0"])), 4.0, default_cutoff(block, bed), a_ul)
        assert float(point["p_rocking_start"]) == pytest.approx(expected, rel=1e-9)
        p = ds["p_rocking_start"].values
        assert np.all(np.diff(p, axis=1) >= 0) and p.min() < 0.5 < p.max()       # grows with S0
        assert ds["p_rocking_start"].attrs["units"] == "1" and ds["uplift_acceleration"].attrs["units"] == "m s-2"


OVERTURNING = GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]", "eps = 6e7").replace(
    "S0 = {start = 1e-5, stop = 2.4e-3, num = 5, log = true}", "S0 = [6e-4, 1.2e-3, 2.4e-3, 4.8e-3]").replace(
    "t_end = 4.0", "t_end = 20.0").replace("dt = 0.05", "dt = 0.1") + FRAGILITY + """
[mcs]
points = [{index = {S0 = 0}}, {index = {S0 = 1}}, {index = {S0 = 2}}, {index = {S0 = 3}}]
samples = 40
"""


@pytest.mark.slow
def test_fragility_over_pga_for_the_overturning_limit_state(client, tmp_path):
    """screening fragility --im pga --limit-state overturn fits p_overturn over the median PGA (points whose
    p_source is unreliable left out) and exports the limit state "overturn"; --threshold is refused."""
    import csv

    from screening.analysis.fragility import fit_lognormal_fragility
    from screening.cli import main

    result = tmp_path / "o.nc"
    (tmp_path / "o.toml").write_text(OVERTURNING)
    run_sweep(parse_study(OVERTURNING), result, client=client, progress=False, log=lambda m: None)
    assert main(["fragility", str(result), "--im", "pga", "--limit-state", "overturn"]) == 0
    with xr.open_dataset(result) as ds:
        p = ds["p_overturn"].where(ds["p_source"] != ProbabilitySource.unreliable).values
        pga = ds["pga_median"].values
    assert np.sum((p > 0) & (p < 1)) >= 2 and np.all(np.diff(p[np.isfinite(p)]) >= 0)
    median, beta = fit_lognormal_fragility(pga, p)
    with open(tmp_path / "o_overturn_pga.csv") as fh:
        row = next(csv.DictReader(fh))
    assert float(row["median"]) == pytest.approx(median, rel=1e-6)
    assert float(row["beta"]) == pytest.approx(beta, rel=1e-5)
    assert pga[p < 0.5].max() < median < pga[p > 0.5].min()
    assert float(row["threshold_rad"]) == pytest.approx(np.arctan(0.035 / 0.21), rel=1e-7)     # 8 digits in the CSV
    xml = (tmp_path / "o_overturn_pga.xml").read_text()
    assert "<limitStates>overturn</limitStates>" in xml and 'ls="overturn"' in xml
    with xr.open_dataset(tmp_path / "o_overturn_pga.nc") as frag:
        assert frag.attrs["limit_state"] == "overturn"
        assert frag.attrs["method"] == STORED          # the stored answers, not the up-crossing
        np.testing.assert_array_equal(frag["p_exceed"].values, p)
    assert main(["fragility", str(result), "--im", "pga", "--limit-state", "overturn", "--threshold", "0.1"]) == 2
