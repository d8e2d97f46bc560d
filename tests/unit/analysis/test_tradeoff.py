"""Speed-accuracy trade study (screening.analysis.tradeoff): metrics, study-file validation, a tiny end-to-end run."""

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from screening.analysis import tradeoff as to
from screening.model.excitation import Envelope, WhiteNoise
from screening.solvers.moments import solve_moments
from screening.model import Block, Foundation
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.timegrid import output_times

ROOT = Path(__file__).resolve().parents[3]


# ============================================================================ metrics
def test_peak_with_se_ignores_nan_and_takes_se_at_the_peak():
    v = np.array([0.0, 1.0, 3.0, np.nan, 2.0])
    se = np.array([0.0, 0.1, 0.3, 9.0, 0.2])
    assert to.peak_with_se(v, se) == (3.0, 0.3)
    assert to.peak_with_se(v) == (3.0, 0.0)
    peak, s = to.peak_with_se(np.full(4, np.nan), np.ones(4))
    assert math.isnan(peak) and math.isnan(s)
    peaks, ses = to.peak_with_se(np.array([[1.0, 5.0], [7.0, 2.0]]), np.array([[0.1, 0.5], [0.7, 0.2]]))
    np.testing.assert_array_equal(peaks, [5.0, 7.0])
    np.testing.assert_array_equal(ses, [0.5, 0.7])


def test_relative_and_peak_errors():
    assert to.relative_difference(1.1, 1.0) == pytest.approx(0.1)
    assert math.isnan(to.relative_difference(1.0, 0.0))
    assert math.isnan(to.relative_difference(1.0, np.nan))
    t = np.linspace(0, 1, 11)
    b = np.sin(np.pi * t) + 1.0
    assert to.peak_relative_error(0.8 * b, b) == pytest.approx(-0.2)
    # peaks at different instants: only the maxima matter
    a = np.roll(b, 3) * 1.5
    assert to.peak_relative_error(a, b) == pytest.approx(0.5)


def test_time_averaged_relative_error_known_answers():
    t = np.linspace(0.0, 1.0, 101)
    b = 1.0 + 0.0 * t
    assert to.time_averaged_relative_error(1.1 * b, b, t) == pytest.approx(0.1)
    assert to.time_averaged_relative_error(b, b, t) == 0.0
    # linear deviation: int_0^1 t dt / int_0^1 1 dt = 1/2 (trapezoid is exact)
    assert to.time_averaged_relative_error(1.0 + t, b, t) == pytest.approx(0.5)
    # only where the reference is defined: an undefined second half does not count
    ref = np.where(t <= 0.5, 1.0, np.nan)
    est = np.where(t <= 0.5, 1.2, 100.0)
    assert to.time_averaged_relative_error(est, ref, t) == pytest.approx(0.2)
    # batched over leading axes; zero reference -> NaN
    out = to.time_averaged_relative_error(np.stack([1.1 * b, 0.7 * b]), b, t)
    np.testing.assert_allclose(out, [0.1, 0.3])
    assert math.isnan(to.time_averaged_relative_error(b, 0.0 * b, t))


def test_noise_floor_combined_se_and_significance():
    t = np.linspace(0.0, 2.0, 21)
    b = 2.0 + np.sin(t)
    assert to.time_averaged_relative_se(0.05 * b, b, t) == pytest.approx(0.05)
    assert float(to.combined_se(3.0, 4.0)) == pytest.approx(5.0)
    assert to.is_significant(0.3, 0.1) is True
    assert to.is_significant(-0.3, 0.1) is True
    assert to.is_significant(0.2, 0.1) is False          # exactly 2 SE is not beyond
    assert to.is_significant(np.nan, 0.1) is False
    np.testing.assert_array_equal(to.is_significant(np.array([0.5, 0.05]), np.array([0.1, 0.1])), [True, False])


def test_classify_error():
    assert to.classify_error(0.05, 0.01, 0.10) == "within"
    assert to.classify_error(-0.30, 0.02, 0.10) == "outside"
    assert to.classify_error(0.09, 0.02, 0.10) == "ambiguous"
    assert to.classify_error(0.12, 0.02, 0.10) == "ambiguous"
    assert to.classify_error(np.nan, 0.02, 0.10) == "undefined"


def test_threshold_rule_and_rule_error():
    p = np.array([0.001, 0.01, 0.1, 0.5, 0.9])
    passed = np.array([True, True, False, True, False])
    assert to.threshold_rule(p, passed, "below") == (0.1, 2)
    assert to.threshold_rule(p, np.ones(5, bool), "below") == (math.inf, 5)
    assert to.threshold_rule(p, np.zeros(5, bool), "below") == (0.001, 0)
    margin = np.array([1.0, 0.99, 0.9, 0.7, 0.3])
    assert to.threshold_rule(margin, passed, "above") == (0.9, 2)
    with pytest.raises(ValueError, match="direction"):
        to.threshold_rule(p, passed, "left")
    np.testing.assert_allclose(to.rule_error([-0.2, 0.05], [0.1, 0.3], "worst"), [0.2, 0.3])
    np.testing.assert_allclose(to.rule_error([-0.2, 0.05], [0.1, 0.3], "peak"), [0.2, 0.05])
    assert np.isnan(to.rule_error([np.nan], [0.1], "worst")[0])
    with pytest.raises(ValueError, match="metric"):
        to.rule_error([0.1], [0.1], "median")


def test_safe_indicator_range_is_conservative_at_mixed_levels():
    p = np.array([0.001, 0.03, 0.1, 0.3, 0.301, 0.85])
    # everything passes
    assert to.safe_indicator_range(p, np.ones(6, bool)) == (0.85, 6, None)
    # a failure at 0.3 while another point at (almost) the same level passes: that level is not safe
    passed = np.array([True, True, True, False, True, True])
    assert to.safe_indicator_range(p, passed) == (0.1, 3, 3)
    # failing at the lowest level: no safe range
    p_safe, n_safe, i_fail = to.safe_indicator_range(p, np.array([False, True, True, True, True, True]))
    assert math.isnan(p_safe) and n_safe == 0 and i_fail == 0


def _synthetic_trade_dataset(p, margin, eps, peak_err_condensed, peak_err_coupled):
    n = len(p)
    err = np.zeros((3, 2, n))
    err[0, 0] = peak_err_coupled            # sl_vs_coupled
    err[1, 0] = peak_err_condensed          # sl_vs_condensed
    return xr.Dataset(
        {"sl_peak_p_uplift": ("point", np.asarray(p, float)), "k_eq_margin": ("point", np.asarray(margin, float)),
         "peak_rel_error": (("comparison", "quantity", "point"), err),
         "time_avg_rel_error": (("comparison", "quantity", "point"), np.abs(err))},
        coords={"comparison": list(to.COMPARISONS), "quantity": list(to.QUANTITIES),
                "point_name": ("point", [f"pt{i}" for i in range(n)]), "eps": ("point", np.asarray(eps, float))})


def test_derive_rules_known_answer_and_bed_groups():
    ds = _synthetic_trade_dataset(p=[0.001, 0.1, 0.5, 0.001, 0.1, 0.5], margin=[1, 1, 0.9, 1, 0.95, 0.5],
                                  eps=[6e7, 6e7, 6e7, -6e5, -6e5, -6e5],
                                  peak_err_condensed=[0.01, -0.02, -0.05, -0.05, -0.08, -0.4],
                                  peak_err_coupled=[-0.15, -0.3, -0.9, -0.05, -0.08, -0.5])
    rules = to.derive_rules(ds, thresholds=(0.10,))
    by = {(r["reference"], r["group"]): r for r in rules}
    assert set(g for _, g in by) == {"all", "eps=6e+07", "eps=-600000"}
    r = by[("condensed", "all")]
    assert (r["p_safe"], r["n_safe"], r["fail_name"], r["n_pass"]) == (0.1, 4, "pt5", 5)
    assert r["fail_error"] == pytest.approx(-0.4)
    assert r["margin_bound"] == 0.5 and r["n_margin"] == 5
    assert by[("condensed", "eps=6e+07")]["fail_name"] == ""             # hardening bed: all pass
    assert math.isnan(by[("coupled", "eps=6e+07")]["p_safe"])            # fails at the lowest level
    assert by[("coupled", "eps=-600000")]["p_safe"] == 0.1
    text = to.rule_text(r, "peak", "var_theta")
    assert "p_uplift <= 0.1" in text and "pt5: -40 %" in text
    assert "no safe p_uplift range" in to.rule_text(by[("coupled", "eps=6e+07")], "peak", "var_theta")


def test_compare_sl_against_a_noisy_reference():
    t = np.linspace(0.0, 10.0, 201)
    ref = np.sin(np.pi * t / 10.0) ** 2                    # peak 1 at t = 5
    se = 0.02 * ref
    r = to.compare(0.9 * ref, ref, t, est_se=None, ref_se=se)
    assert r["peak_rel_error"] == pytest.approx(-0.1)
    assert r["peak_rel_se"] == pytest.approx(0.02)
    assert r["peak_significant"] is True                   # 0.1 > 2 x 0.02
    assert r["time_avg_rel_error"] == pytest.approx(0.1)
    assert r["time_avg_rel_se"] == pytest.approx(0.02)
    assert r["time_avg_significant"] is True
    r2 = to.compare(0.97 * ref, ref, t, est_se=0.02 * ref, ref_se=se)   # MCS vs MCS: SEs in quadrature
    assert r2["peak_rel_se"] == pytest.approx(0.02 * math.sqrt(2))
    assert r2["peak_significant"] is False


# ============================================================================ study file
STUDY_FILE = ROOT / "studies" / "speed_accuracy.toml"


def test_the_shipped_study_parses_and_spans_both_excitations_and_eps_signs():
    study = to.load_tradeoff_study(STUDY_FILE)
    kinds = {f.kind for f in study.families}
    assert kinds == {"white", "kanai_tajimi"}
    eps = {e for f in study.families for e in f.eps}
    assert any(e > 0 for e in eps) and any(e < 0 for e in eps)
    n_points = sum(len(f.eps) * f.n_intensities for f in study.families)
    assert 12 <= n_points <= 16
    targets = [p for f in study.families for p in (f.target_peak_p_uplift or ())]
    assert min(targets) <= 0.003 and max(targets) >= 0.8
    assert study.mcs["samples"] == 1000 and study.mcs["threads"] == 1
    assert study.convergence["samples"] == (100, 300, 1000, 3000)
    assert 1.0 in study.convergence["rtol_factors"]
    assert len(study.convergence["points"]) >= 2


GOOD = """
title = "t"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[time]
t_end = 2.0
dt = 0.05
[[family]]
name = "w"
kind = "white"
eps = [6e7]
S0 = [1e-5, 2e-5]
[mcs]
samples = 50
[convergence]
points = [{family = "w", eps = 6e7, index = 1}]
samples = [20, 50]
rtol_samples = 20
rtol_factors = [1.0, 32.0]
"""


def _edit(text, old, new):
    assert old in text
    return text.replace(old, new)


@pytest.mark.parametrize("old, new, key", [
    ("title = \"t\"", "title = \"t\"\nbogus = 1", "'bogus'"),
    ("[mcs]\nsamples = 50", "[mcs]\nsampels = 50", "'mcs.sampels'"),
    ("[mcs]\nsamples = 50", "[mcs]\nsamples = 1", "'mcs.samples'"),
    ("[mcs]\nsamples = 50", "[mcs]\nsamples = 50.5", "'mcs.samples'"),
    ("kind = \"white\"", "kind = \"white\"\nwidth = 2", "'family[0].width'"),
    ("kind = \"white\"", "kind = \"pink\"", "'family[0].kind'"),
    ("kind = \"white\"", "kind = \"white\"\nomega_g = 10.0", "'family[0].omega_g'"),
    ("kind = \"white\"", "kind = \"kanai_tajimi\"", "'family[0].omega_g'"),
    ("S0 = [1e-5, 2e-5]", "S0 = [1e-5, 2e-5]\ntarget_peak_p_uplift = [0.1]", "'family[0].S0'"),
    ("S0 = [1e-5, 2e-5]", "S0 = [1e-5, -2e-5]", "'family[0].S0[1]'"),
    ("S0 = [1e-5, 2e-5]", "target_peak_p_uplift = [0.1, 1.5]", "'family[0].target_peak_p_uplift[1]'"),
    ("eps = [6e7]\n", "", "'family[0].eps'"),
    ("eps = [6e7]", "eps = []", "'family[0].eps'"),
    ("k = 2.89e7", "k = -1.0", "'foundation.k'"),
    ("lam = 8.95e8", "lam = 8.95e8\nc = 3.0", "'foundation.c'"),
    ("h = 0.21", "h = 0.21\nwidth = 3", "'block.width'"),
    ("dt = 0.05", "dt = 0.03", "'time.dt'"),
    ("rtol_factors = [1.0, 32.0]", "rtol_factors = [0.5, 32.0]", "'convergence.rtol_factors'"),
    ("rtol_samples = 20", "rtol_samples = 30", "'convergence.rtol_samples'"),
    ("index = 1}", "index = 2}", "'convergence.points[0].index'"),
    ("eps = 6e7, index", "eps = 5e7, index", "'convergence.points[0].eps'"),
    ("{family = \"w\"", "{family = \"x\"", "'convergence.points[0].family'"),
    ("[convergence]", "[rule]\nmetric = \"median\"\n[convergence]", "'rule.metric'"),
    ("[convergence]", "[sl]\nrtol = 0.5\n[convergence]", "'sl.rtol'"),
    ("[time]", "[excitation]\nT1 = 2.0\nT2 = 3.0\n[time]", "'excitation.T2'"),
])
def test_bad_study_raises_value_error_naming_the_key(old, new, key):
    to.parse_tradeoff_study(GOOD)                            # the base text is valid
    with pytest.raises(ValueError, match=re.escape(key)):
        to.parse_tradeoff_study(_edit(GOOD, old, new))


def test_study_syntax_error_and_missing_family():
    with pytest.raises(to.TradeoffStudyError, match="TOML syntax"):
        to.parse_tradeoff_study("title = ")
    with pytest.raises(to.TradeoffStudyError, match="'family'"):
        to.parse_tradeoff_study("title = \"x\"\n[block]\nm = 1.0\nb = 0.1\nh = 0.2\n[foundation]\nk = 1e7\nlam = 1e8\n")


def test_calibration_hits_the_target_uplift_probability():
    block = Block(m=8.67, b=0.035, h=0.21)
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=-6e5)
    t = output_times(4.0, 0.05)
    S0 = to.calibrate_intensity(block, bed, lambda s: WhiteNoise(s, Envelope(4.0, 2.0)), 0.05, t)
    p = float(solve_moments(block, bed, WhiteNoise(S0, Envelope(4.0, 2.0)), t)["peak_p_uplift"])
    assert p == pytest.approx(0.05, rel=0.02)
    assert S0 == to.round_significant(S0, 3)
    with pytest.raises(ValueError, match="not"):
        to.calibrate_intensity(block, bed, lambda s: WhiteNoise(s, Envelope(4.0, 2.0)), 0.05, t,
                               log10_bounds=(-10.0, -8.0))


# ============================================================================ end to end
TINY = GOOD.replace("[mcs]\nsamples = 50", "[mcs]\nsamples = 50\nseed = 3") + """
[sl]
rtol_sweep = [1e-5, 1e-7]
h_max_sweep = [0.1]
timing_repeats = 1
"""


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("tradeoff")
    path = d / "tiny.toml"
    path.write_text(TINY)
    ds, paths, rules = to.run_tradeoff(path, d / "out", progress=None)
    return d, ds, paths, rules


def test_end_to_end_structure(tiny_run):
    d, ds, paths, rules = tiny_run
    for key in ("nc", "md", "csv", "error_vs_cost", "validity"):
        assert paths[key].exists() and paths[key].stat().st_size > 0, key
    assert paths["nc"].name == "tiny.nc" and paths["validity"].name == "tiny_validity.png"
    raw = xr.open_dataset(paths["nc"])
    assert raw.attrs["Conventions"] == "CF-1.8"
    assert list(raw.approach_name.values) == ["sl", "condensed_mcs", "coupled_mcs"]   # labels: aux coordinates
    assert "approach" not in raw.coords
    saved = to.from_file_layout(raw)
    assert saved.sizes["point"] == 2 and saved.sizes["t"] == 41 and saved.sizes["approach"] == 3
    assert list(saved.approach.values) == ["sl", "condensed_mcs", "coupled_mcs"]
    np.testing.assert_array_equal(saved.var_theta.values, ds.var_theta.values)
    assert saved.peak_var_theta.attrs["units"] == "rad2"
    np.testing.assert_array_equal(saved.peak_var_theta.sel(approach="coupled_mcs").values,
                                  np.nanmax(ds.var_theta.sel(approach="coupled_mcs").values, axis=-1))
    assert saved.var_theta.attrs["units"] == "rad2" and saved.cost.attrs["units"] == "s"
    assert saved.S0.attrs["units"] == "m2 s-3" and saved.t.attrs["units"] == "s"
    assert saved.peak_rel_error.dims == ("comparison", "quantity", "point")
    assert saved.cv_peak_var_theta.sizes == {"rep_point": 1, "cv_model": 2, "n_samples": 2}
    assert saved.sl_cost.sizes["sl_setting"] == 3
    assert np.all(saved.cost > 0)
    assert "SL within" in saved.attrs["rules"]
    raw.close()
    md = paths["md"].read_text()
    assert "Cost ratio SL : condensed MCS : coupled MCS" in md and "Validity rules" in md
    assert "**Recommended:** Use SL alone for" in md
    assert len(rules) == 4 and {r["reference"] for r in rules} == {"condensed", "coupled"}


def test_end_to_end_numbers_match_direct_calls(tiny_run):
    _, ds, _, _ = tiny_run
    block = Block(m=8.67, b=0.035, h=0.21)
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    t = output_times(2.0, 0.05)
    j = 1
    S0 = float(ds.S0[j])
    assert S0 == 2e-5
    exc = WhiteNoise(S0, Envelope(4.0, 2.0))
    sl = solve_moments(block, bed, exc, t, rtol=1e-7)
    np.testing.assert_array_equal(ds.var_theta.sel(approach="sl").values[j], sl["var_theta"])
    assert float(ds.sl_peak_p_uplift[j]) == float(sl["peak_p_uplift"])
    assert float(ds.k_eq_margin[j]) == pytest.approx(float(sl["min_k_eq"]) / sl["k_eq"][0])
    mc = monte_carlo(block, bed, exc, n_samples=50, model="coupled", t_end=2.0, dt=0.05, seed=3, progress=False)
    np.testing.assert_allclose(ds.var_theta.sel(approach="coupled_mcs").values[j], mc.var_theta.values, rtol=1e-12)
    np.testing.assert_allclose(ds.var_theta_se.sel(approach="coupled_mcs").values[j], mc.var_theta_se.values,
                               rtol=1e-12)
    assert int(ds.n_overturned.sel(mcs_model="coupled")[j]) == int(mc.n_overturned)
    err = float(ds.peak_rel_error.sel(comparison="sl_vs_coupled", quantity="var_theta")[j])
    assert err == pytest.approx(to.peak_relative_error(sl["var_theta"], mc.var_theta.values), rel=1e-12)
    tavg = float(ds.time_avg_rel_error.sel(comparison="sl_vs_coupled", quantity="var_theta")[j])
    assert tavg == pytest.approx(to.time_averaged_relative_error(sl["var_theta"], mc.var_theta.values, t))
    # the convergence study reuses the grid run at the grid's sample count and is its own reference there
    peak, _ = to.peak_with_se(mc.var_theta.values)
    assert float(ds.cv_peak_var_theta.sel(cv_model="coupled", n_samples=50)[0]) == pytest.approx(peak, rel=1e-12)
    assert float(ds.cv_deviation_vs_reference.sel(cv_model="coupled", n_samples=50)[0]) == 0.0
    assert float(ds.tol_change_vs_tightest.sel(cv_model="coupled", rtol_factor=1.0)[0]) == 0.0


CHECKER = Path(sys.executable).parent / "compliance-checker"


@pytest.mark.skipif(not CHECKER.exists(), reason="IOOS compliance-checker is not installed")
def test_result_file_passes_cf18_strict(tiny_run):
    _, _, paths, _ = tiny_run
    proc = subprocess.run([str(CHECKER), "--test=cf:1.8", "--criteria=strict", str(paths["nc"])],
                          capture_output=True, text=True, timeout=300)
    report = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "All tests passed!" in proc.stdout, report
    assert "exceptions occurred" not in report, report


def test_main_rerenders_from_netcdf_and_rejects_bad_files(tiny_run, capsys):
    d, ds, paths, _ = tiny_run
    paths["md"].unlink()
    assert to.main([str(d / "tiny.toml"), "--out-dir", str(d / "out"), "--from-nc"]) == 0
    out = capsys.readouterr().out
    assert "Recommended: " in out and "SL : condensed : coupled = 1 :" in out
    assert paths["md"].exists()
    bad = d / "bad.toml"
    bad.write_text(TINY.replace("[mcs]", "[mcs]\nbogus = 1"))
    assert to.main([str(bad), "--out-dir", str(d / "out2")]) == 2
    assert "'mcs.bogus'" in capsys.readouterr().err
    assert not (d / "out2").exists()
    assert to.main([str(d / "tiny.toml"), "--out-dir", str(d / "nowhere"), "--from-nc"]) == 2
    assert "does not exist" in capsys.readouterr().err
