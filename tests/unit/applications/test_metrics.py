"""Error metrics of the trade study (screening.applications.metrics): known answers, NaN handling, rules."""

import math

import numpy as np
import pytest
import xarray as xr

from screening.applications import metrics
from screening.applications.tradeoff_study import COMPARISONS, QUANTITIES
from screening.report.tradeoff_text import rule_text


def test_peak_with_se_ignores_nan_and_takes_se_at_the_peak():
    v = np.array([0.0, 1.0, 3.0, np.nan, 2.0])
    se = np.array([0.0, 0.1, 0.3, 9.0, 0.2])
    assert metrics.peak_with_se(v, se) == (3.0, 0.3)
    assert metrics.peak_with_se(v) == (3.0, 0.0)
    peak, s = metrics.peak_with_se(np.full(4, np.nan), np.ones(4))
    assert math.isnan(peak) and math.isnan(s)
    peaks, ses = metrics.peak_with_se(np.array([[1.0, 5.0], [7.0, 2.0]]), np.array([[0.1, 0.5], [0.7, 0.2]]))
    np.testing.assert_array_equal(peaks, [5.0, 7.0])
    np.testing.assert_array_equal(ses, [0.5, 0.7])


def test_relative_and_peak_errors():
    assert metrics.relative_difference(1.1, 1.0) == pytest.approx(0.1)
    assert math.isnan(metrics.relative_difference(1.0, 0.0))
    assert math.isnan(metrics.relative_difference(1.0, np.nan))
    t = np.linspace(0, 1, 11)
    b = np.sin(np.pi * t) + 1.0
    assert metrics.peak_relative_error(0.8 * b, b) == pytest.approx(-0.2)
    # peaks at different instants: only the maxima matter
    a = np.roll(b, 3) * 1.5
    assert metrics.peak_relative_error(a, b) == pytest.approx(0.5)


def test_time_averaged_relative_error_known_answers():
    t = np.linspace(0.0, 1.0, 101)
    b = 1.0 + 0.0 * t
    assert metrics.time_averaged_relative_error(1.1 * b, b, t) == pytest.approx(0.1)
    assert metrics.time_averaged_relative_error(b, b, t) == 0.0
    # linear deviation: int_0^1 t dt / int_0^1 1 dt = 1/2 (trapezoid is exact)
    assert metrics.time_averaged_relative_error(1.0 + t, b, t) == pytest.approx(0.5)
    # only where the reference is defined: an undefined second half does not count
    ref = np.where(t <= 0.5, 1.0, np.nan)
    est = np.where(t <= 0.5, 1.2, 100.0)
    assert metrics.time_averaged_relative_error(est, ref, t) == pytest.approx(0.2)
    # batched over leading axes; zero reference -> NaN
    out = metrics.time_averaged_relative_error(np.stack([1.1 * b, 0.7 * b]), b, t)
    np.testing.assert_allclose(out, [0.1, 0.3])
    assert math.isnan(metrics.time_averaged_relative_error(b, 0.0 * b, t))


def test_noise_floor_combined_se_and_significance():
    t = np.linspace(0.0, 2.0, 21)
    b = 2.0 + np.sin(t)
    assert metrics.time_averaged_relative_se(0.05 * b, b, t) == pytest.approx(0.05)
    assert float(metrics.combined_se(3.0, 4.0)) == pytest.approx(5.0)
    assert metrics.is_significant(0.3, 0.1) is True
    assert metrics.is_significant(-0.3, 0.1) is True
    assert metrics.is_significant(0.2, 0.1) is False          # exactly 2 SE is not beyond
    assert metrics.is_significant(np.nan, 0.1) is False
    np.testing.assert_array_equal(metrics.is_significant(np.array([0.5, 0.05]), np.array([0.1, 0.1])), [True, False])


def test_classify_error():
    assert metrics.classify_error(0.05, 0.01, 0.10) == "within"
    assert metrics.classify_error(-0.30, 0.02, 0.10) == "outside"
    assert metrics.classify_error(0.09, 0.02, 0.10) == "ambiguous"
    assert metrics.classify_error(0.12, 0.02, 0.10) == "ambiguous"
    assert metrics.classify_error(np.nan, 0.02, 0.10) == "undefined"


def test_threshold_rule_and_rule_error():
    p = np.array([0.001, 0.01, 0.1, 0.5, 0.9])
    passed = np.array([True, True, False, True, False])
    assert metrics.threshold_rule(p, passed, "below") == (0.1, 2)
    assert metrics.threshold_rule(p, np.ones(5, bool), "below") == (math.inf, 5)
    assert metrics.threshold_rule(p, np.zeros(5, bool), "below") == (0.001, 0)
    margin = np.array([1.0, 0.99, 0.9, 0.7, 0.3])
    assert metrics.threshold_rule(margin, passed, "above") == (0.9, 2)
    with pytest.raises(ValueError, match="direction"):
        metrics.threshold_rule(p, passed, "left")
    np.testing.assert_allclose(metrics.rule_error([-0.2, 0.05], [0.1, 0.3], "worst"), [0.2, 0.3])
    np.testing.assert_allclose(metrics.rule_error([-0.2, 0.05], [0.1, 0.3], "peak"), [0.2, 0.05])
    assert np.isnan(metrics.rule_error([np.nan], [0.1], "worst")[0])
    with pytest.raises(ValueError, match="metric"):
        metrics.rule_error([0.1], [0.1], "median")


def test_safe_indicator_range_is_conservative_at_mixed_levels():
    p = np.array([0.001, 0.03, 0.1, 0.3, 0.301, 0.85])
    # everything passes
    assert metrics.safe_indicator_range(p, np.ones(6, bool)) == (0.85, 6, None)
    # a failure at 0.3 while another point at (almost) the same level passes: that level is not safe
    passed = np.array([True, True, True, False, True, True])
    assert metrics.safe_indicator_range(p, passed) == (0.1, 3, 3)
    # failing at the lowest level: no safe range
    p_safe, n_safe, i_fail = metrics.safe_indicator_range(p, np.array([False, True, True, True, True, True]))
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
        coords={"comparison": list(COMPARISONS), "quantity": list(QUANTITIES),
                "point_name": ("point", [f"pt{i}" for i in range(n)]), "eps": ("point", np.asarray(eps, float))})


def test_derive_rules_known_answer_and_bed_groups():
    ds = _synthetic_trade_dataset(p=[0.001, 0.1, 0.5, 0.001, 0.1, 0.5], margin=[1, 1, 0.9, 1, 0.95, 0.5],
                                  eps=[6e7, 6e7, 6e7, -6e5, -6e5, -6e5],
                                  peak_err_condensed=[0.01, -0.02, -0.05, -0.05, -0.08, -0.4],
                                  peak_err_coupled=[-0.15, -0.3, -0.9, -0.05, -0.08, -0.5])
    rules = metrics.derive_rules(ds, thresholds=(0.10,))
    by = {(r["reference"], r["group"]): r for r in rules}
    assert set(g for _, g in by) == {"all", "eps=6e+07", "eps=-600000"}
    r = by[("condensed", "all")]
    assert (r["p_safe"], r["n_safe"], r["fail_name"], r["n_pass"]) == (0.1, 4, "pt5", 5)
    assert r["fail_error"] == pytest.approx(-0.4)
    assert r["margin_bound"] == 0.5 and r["n_margin"] == 5
    assert by[("condensed", "eps=6e+07")]["fail_name"] == ""             # hardening bed: all pass
    assert math.isnan(by[("coupled", "eps=6e+07")]["p_safe"])            # fails at the lowest level
    assert by[("coupled", "eps=-600000")]["p_safe"] == 0.1
    text = rule_text(r, "peak", "var_theta")
    assert "p_uplift <= 0.1" in text and "pt5: -40 %" in text
    assert "no safe p_uplift range" in rule_text(by[("coupled", "eps=6e+07")], "peak", "var_theta")


def test_compare_sl_against_a_noisy_reference():
    t = np.linspace(0.0, 10.0, 201)
    ref = np.sin(np.pi * t / 10.0) ** 2                    # peak 1 at t = 5
    se = 0.02 * ref
    r = metrics.compare(0.9 * ref, ref, t, est_se=None, ref_se=se)
    assert r["peak_rel_error"] == pytest.approx(-0.1)
    assert r["peak_rel_se"] == pytest.approx(0.02)
    assert r["peak_significant"] is True                   # 0.1 > 2 x 0.02
    assert r["time_avg_rel_error"] == pytest.approx(0.1)
    assert r["time_avg_rel_se"] == pytest.approx(0.02)
    assert r["time_avg_significant"] is True
    r2 = metrics.compare(0.97 * ref, ref, t, est_se=0.02 * ref, ref_se=se)   # MCS vs MCS: SEs in quadrature
    assert r2["peak_rel_se"] == pytest.approx(0.02 * math.sqrt(2))
    assert r2["peak_significant"] is False
