"""The correction learner (screening.analysis.correction): leave-one-out on synthetic data with a known answer."""

import dataclasses

import numpy as np
import pytest

from screening.analysis.correction import (MAX_SE, MIN_POINTS, best_estimates, fit_correction, point_features,
                                           predict_correction, within_band)
from screening.core.status import BestMethod, EscalationModel, PointStatus, Trust


def synthetic(n, noise, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 1.0, size=(n, 2))
    y = -0.2 - 1.5 * x[:, 0] + 0.5 * x[:, 1]
    return x, y, y + noise * rng.standard_normal(n)


def test_smooth_truth_is_recovered_within_the_reported_error():
    x, truth, y = synthetic(200, noise=0.02)
    corr = fit_correction(x, y, np.full(y.size, 0.02))
    assert corr.usable and corr.n == 200
    # neighbours ~0.07 apart on a slope of ~1.6: interpolation error ~0.05 plus the noise
    assert corr.loo_rms < 0.1
    x_new, truth_new, _ = synthetic(300, noise=0.0, seed=1)
    y_hat, se, reached = predict_correction(corr, x_new)
    assert reached.mean() > 0.95
    # the reported standard error covers the error at least as often as a Gaussian 2-sigma band would (95 %),
    # with a margin for 300 draws (binomial SE 1.3 %)
    covered = np.abs(y_hat[reached] - truth_new[reached]) <= 2 * se[reached]
    assert covered.mean() >= 0.9


def test_leave_one_out_residual_is_the_prediction_without_the_point():
    x, _, y = synthetic(12, noise=0.1, seed=3)
    corr = fit_correction(x, y)
    for i in (0, 5, 11):
        keep = np.arange(12) != i
        without = dataclasses.replace(corr, z=corr.z[keep], y=corr.y[keep], y_se=corr.y_se[keep],
                                      loo_residuals=corr.loo_residuals[keep], nn_distance=corr.nn_distance[keep])
        y_hat, _, _ = predict_correction(without, x[i:i + 1])
        assert corr.loo_residuals[i] == pytest.approx(y[i] - y_hat[0], rel=1e-9, abs=1e-12)


def test_noise_without_structure_is_not_vouched_for_and_extrapolation_is_not_reached():
    rng = np.random.default_rng(2)
    x = rng.uniform(0, 1, size=(20, 2))
    corr = fit_correction(x, rng.standard_normal(20) * 2.0)
    _, se, reached = predict_correction(corr, rng.uniform(0, 1, size=(50, 2)))
    assert np.mean(se[reached] > MAX_SE) > 0.9
    x, _, y = synthetic(20, noise=0.02)
    corr = fit_correction(x, y)
    _, _, reached = predict_correction(corr, np.array([[0.5, 0.5], [5.0, 0.5], [np.nan, 0.5]]))
    assert reached.tolist() == [True, False, False]
    assert not fit_correction(x[:MIN_POINTS - 1], y[:MIN_POINTS - 1]).usable


def test_point_features_logs_wide_positive_columns_and_drops_constant_ones():
    f = point_features({"S0": np.array([1e-5, 1e-4, 1e-3]), "eps": np.array([-1.0, 0.0, 2.0]),
                        "m": np.array([8.0, 8.0, 8.0])})
    assert f.shape == (3, 2)
    np.testing.assert_allclose(f[:, 0], [-5, -4, -3])
    np.testing.assert_allclose(f[:, 1], [-1, 0, 2])


def test_best_estimates_label_every_point_and_never_invent():
    rng = np.random.default_rng(4)
    n = 200
    x = rng.uniform(0, 1, size=(n, 2))
    sl = np.full(n, 1e-6)
    true = sl * np.exp(-0.3 - 1.0 * x[:, 0])
    status = np.zeros(n, dtype=int)
    status[-1] = PointStatus.k_eq_negative
    trust = np.full(n, int(Trust.check))
    trust[:10] = Trust.trusted
    low, high = np.full(n, -0.3), np.full(n, 3.0)      # SL over-predicts by 35-270 %: inside the band
    low[:10], high[:10] = -0.05, 0.08                   # the rule promises 0.15 there
    x[5] = [9.0, 9.0]                                    # far outside the escalated points (but promised)
    x[150] = [9.0, 9.0]                                  # far outside: the correction must not reach it
    esc = np.arange(20, 60)
    mc = true[esc] * (1 + 0.02 * rng.standard_normal(esc.size))
    models = np.where(esc % 2, int(EscalationModel.coupled), int(EscalationModel.condensed))
    value, se, method, corr = best_estimates(sl, status, trust, low, high, 0.15, x, esc, mc, 0.02 * mc, models)
    assert corr.usable
    assert np.all(method[:10] == BestMethod.linearization) and np.all(value[:10] == sl[:10])
    assert np.all(method[esc] == np.where(esc % 2, BestMethod.coupled_monte_carlo, BestMethod.condensed_monte_carlo))
    np.testing.assert_array_equal(value[esc], mc)
    corrected = method == BestMethod.corrected_linearization
    assert corrected.sum() > 100
    err = value[corrected] / true[corrected] - 1
    assert np.all(np.abs(err) < 4 * se[corrected] / value[corrected])
    for i in (150, n - 1):                               # extrapolation, stopped SL
        assert method[i] == BestMethod.unreliable and np.isnan(se[i])
    assert np.isnan(value[n - 1])


def test_a_correction_that_contradicts_the_trust_band_is_not_vouched_for():
    # y = log(MCS / SL) = 0.15 implies an SL error of exp(-0.15) - 1 = -14 %
    assert within_band(np.array([0.15, 0.15, 0.15]), np.array([-0.2, -1.0, np.nan]),
                       np.array([0.0, -0.158, np.nan])).tolist() == [True, False, True]
    # the calibration's band says SL under-predicts by at least 30 % ([-1, -0.3]); the escalated points
    # nearby say only ~10 %: the corrected value is not vouched for there (unreliable, NaN se)
    rng = np.random.default_rng(5)
    n = 60
    x = rng.uniform(0, 1, size=(n, 2))
    sl = np.full(n, 1e-6)
    status, trust = np.zeros(n, dtype=int), np.full(n, int(Trust.untrusted))
    low, high = np.full(n, -1.0), np.full(n, 0.5)
    low[:5], high[:5] = -1.0, -0.3
    esc = np.arange(10, 50)
    mc = sl[esc] * 1.1 * (1 + 0.02 * rng.standard_normal(esc.size))
    value, se, method, _ = best_estimates(sl, status, trust, low, high, 0.15, x, esc, mc, 0.02 * mc,
                                          np.full(esc.size, int(EscalationModel.coupled)))
    assert np.all(method[:5] == BestMethod.unreliable) and np.all(np.isnan(se[:5]))
    assert np.all(method[50:] == BestMethod.corrected_linearization)


def test_atlas_correction_is_the_centre_of_the_interval_in_log():
    from screening.analysis.correction import INTERVAL_Z, atlas_correction, atlas_promises

    # an interval est +- 1.645 s in log(SL / MC): est = log 0.6, s = 0.1
    est, s = np.log(0.6), 0.1
    low, high = np.expm1(est - INTERVAL_Z * s), np.expm1(est + INTERVAL_Z * s)
    y, se = atlas_correction(np.array([low, -1.0, np.nan]), np.array([high, 0.2, 0.1]))
    assert y[0] == pytest.approx(-est) and se[0] == pytest.approx(s)
    assert np.all(np.isnan(y[1:]))
    # exp(1.645 x 0.1) - 1 = 0.179: promises 0.2, not 0.15
    assert atlas_promises(low, high, 0.2) and not atlas_promises(low, high, 0.15)


def test_best_estimates_use_the_atlas_correction_without_monte_carlo():
    from screening.analysis.correction import INTERVAL_Z, MAX_SE

    rng = np.random.default_rng(6)
    n = 30
    sl = np.full(n, 2e-6)
    est, s = np.log(2.0), np.where(np.arange(n) < 20, 0.1, 1.2 * MAX_SE)     # SL over-predicts by a factor 2
    low, high = np.expm1(est - INTERVAL_Z * s), np.expm1(est + INTERVAL_Z * s)
    status, trust = np.zeros(n, dtype=int), np.full(n, int(Trust.check))
    value, se, method, corr = best_estimates(sl, status, trust, low, high, 0.15, rng.uniform(size=(n, 2)),
                                             np.zeros(0, dtype=int), np.zeros(0), np.zeros(0), np.zeros(0))
    assert not corr.usable
    assert np.all(method[:20] == BestMethod.corrected_linearization)
    np.testing.assert_allclose(value[:20], 1e-6)
    np.testing.assert_allclose(se[:20], 1e-6 * 0.1)
    assert np.all(method[20:] == BestMethod.unreliable) and np.all(np.isnan(se[20:]))
    # the same interval for another peak (atlas=False): no atlas correction
    _, _, method, _ = best_estimates(sl, status, trust, low, high, 0.15, rng.uniform(size=(n, 2)),
                                     np.zeros(0, dtype=int), np.zeros(0), np.zeros(0), np.zeros(0), atlas=False)
    assert np.all(method == BestMethod.unreliable)
