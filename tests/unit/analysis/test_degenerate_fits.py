"""Fits the data cannot support are flagged with a named reason, never ``ok``, and nothing overflows; the
linearization's stopped points are missing values, and fits leave out (and count) what nothing vouches for.

Issue 36 items 3 and 8, and the "no stopped point reads as an answer" item of the collection issue."""

import io
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import xarray as xr

from screening.analysis.fragility import (add_fit, exceedance_probability, fit_binomial_fragility,
                                          fit_fragility_curve, linearized_exceedance, unvouched_points)
from screening.applications.im_fragility import write_nrml
from screening.core.status import FitFlag, PointStatus, ProbabilitySource, Trust


def test_a_nearly_flat_noisy_curve_is_not_fitted_as_ok():
    """Item 3: Monte Carlo noise along a narrow sweep gave fit_flag ok, median 2.8e136, beta 609."""
    pga = np.linspace(3.0, 3.3, 7)
    p = np.array([0.31, 0.30, 0.32, 0.30, 0.31, 0.31, 0.32])
    median, beta, flag = fit_fragility_curve(pga, p)
    assert flag in (FitFlag.not_identified, FitFlag.median_outside_data)
    assert math.isnan(median) and math.isnan(beta)


def test_a_median_beyond_the_intensities_is_flagged():
    pga = np.array([1.0, 1.5, 2.0])
    p = 0.5 * np.array([0.02, 0.06, 0.12]) / 0.12 * 0.2     # rising, but far below one half
    assert fit_fragility_curve(pga, p)[2] == FitFlag.median_outside_data


def test_a_good_curve_is_still_ok():
    pga = np.geomspace(1.0, 4.0, 7)
    from scipy.special import ndtr

    median, beta, flag = fit_fragility_curve(pga, ndtr(np.log(pga / 2.0) / 0.4))
    assert flag == FitFlag.ok and median == pytest.approx(2.0) and beta == pytest.approx(0.4)


@pytest.mark.parametrize("levels, k, expected", [
    ([1.0], [4], FitFlag.not_identified),                       # one stripe: beta has SE 2624
    ([1.0, 1.0, 1.0], [3, 5, 4], FitFlag.not_identified),       # repeated level: the optimizer's start
    ([1.0, 2.0, 3.0], [9, 5, 1], FitFlag.non_positive_beta),    # falling counts: beta 3.1e17
    ([1.0, 2.0, 3.0], [0, 10, 10], FitFlag.separated),          # all or nothing at every stripe
], ids=["one_stripe", "repeated_level", "falling", "separated"])
def test_binomial_fits_the_data_cannot_determine_are_flagged(levels, k, expected):
    """Item 8: fit_binomial_fragility returned such betas without a flag."""
    fit = fit_binomial_fragility(levels, k, 10)
    assert fit["flag"] != FitFlag.ok
    if expected != FitFlag.non_positive_beta:
        assert fit["flag"] == expected
    else:                                                       # falling: either reason, never ok
        assert fit["flag"] in (FitFlag.non_positive_beta, FitFlag.not_identified, FitFlag.median_outside_data)


def test_a_well_posed_binomial_fit_is_ok():
    fit = fit_binomial_fragility([0.5, 1.0, 2.0], [1, 5, 9], 10)
    assert fit["flag"] == FitFlag.ok and fit["beta_se"] < fit["beta"]


def _fit_dataset(median=1.0, beta=0.5):
    frag = xr.Dataset({"fit_median": median, "beta": beta, "fit_flag": np.int8(FitFlag.ok),
                       "threshold_rad": 0.05, "pga_median": ("pga", [1.0, 2.0])},
                      attrs={"intensity_variable": "pga_median"})
    frag["fit_median"].attrs.update(intensity="pga_median", units="m s-2")
    return frag


def test_the_nrml_writer_never_overflows(tmp_path):
    """Item 3: beta 609 (or --modelling-dispersion 37) made write_nrml raise OverflowError and write nothing."""
    path = write_nrml(_fit_dataset(beta=609.0), tmp_path / "f.xml")
    text = path.read_text()
    ET.fromstring(text)                                          # well formed
    assert "<params" not in text and "beyond a float" in text


def test_the_modelling_dispersion_is_refused_beyond_its_range(capsys):
    from screening.cli import main

    assert main(["fragility", "no_such_result.nc", "--threshold", "0.1", "--modelling-dispersion", "37"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--modelling-dispersion" in err[0] and "<= 3" in err[0]


def test_stopped_points_are_missing_values_not_one():
    """Where the linearization stopped (k_eq_negative, sigma beyond slenderness) P is NaN, not 1."""
    t = np.linspace(0.0, 10.0, 101)
    ones = np.ones((3, t.size))
    p = linearized_exceedance(t, 1e-4 * ones, 1e-2 * ones, 0 * ones, 0.1 * ones, 10.0 * ones, np.ones(3),
                              [PointStatus.ok, PointStatus.k_eq_negative, PointStatus.sigma_theta_beyond_slenderness],
                              np.full(3, 0.03))
    assert np.isfinite(p[0]) and np.isnan(p[1:]).all()
    ds = xr.Dataset({name: (("S0", "t"), v * ones) for name, v in
                     (("var_theta", 1e-4), ("var_theta_dot", 1e-2), ("cov_theta_theta_dot", 0.0))},
                    coords={"t": t, "S0": [1.0, 2.0, 3.0]})
    ds["status"] = ("S0", np.array([0, 1, 2], dtype=np.int8))
    q = exceedance_probability(ds, 0.03, method="poisson")
    assert np.isfinite(q.values[0]) and np.isnan(q.values[1:]).all()


def test_a_fit_leaves_out_the_points_nothing_vouches_for_and_counts_them():
    from scipy.special import ndtr

    pga = np.geomspace(1.0, 4.0, 8)
    p = ndtr(np.log(pga / 2.0) / 0.4)
    trust = np.full(8, Trust.trusted, dtype=np.int8)
    status = np.zeros(8, dtype=np.int8)
    trust[[1, 3]] = Trust.untrusted                               # unvouched, status ok
    status[7] = PointStatus.k_eq_negative                         # stopped
    p_read = p.copy()
    p_read[[1, 3]] = 0.99                                         # garbage a fit must not see
    ds = xr.Dataset({"sl_trust": ("pga", trust), "status": ("pga", status)}, coords={"pga": pga})
    assert unvouched_points(ds).values.tolist() == [False, True, False, True, False, False, False, True]
    out = add_fit(xr.Dataset({"p_exceed": ("pga", p_read)}, coords={"pga": pga}), ds, pga, "pga")
    assert int(out["fit_n_unvouched"]) == 3 and int(out["fit_flag"]) == FitFlag.ok
    assert float(out["fit_median"]) == pytest.approx(2.0) and float(out["beta"]) == pytest.approx(0.4)
    # nothing vouched for: a named reason, not a fit
    ds["sl_trust"][:] = Trust.untrusted
    out = add_fit(xr.Dataset({"p_exceed": ("pga", p)}, coords={"pga": pga}), ds, pga, "pga")
    assert int(out["fit_flag"]) == FitFlag.untrusted and np.isnan(float(out["fit_median"]))


def test_stored_probabilities_are_fitted_by_their_source():
    """A sweep's stored p_overturn / p_exceed: the points whose p_source is unreliable are left out."""
    from screening.analysis.fragility import STORED

    pga = np.geomspace(1.0, 4.0, 6)
    source = np.full(6, ProbabilitySource.linearization_gaussian, dtype=np.int8)
    source[[0, 5]] = ProbabilitySource.unreliable
    ds = xr.Dataset({"p_source": ("pga", source)}, coords={"pga": pga})
    assert unvouched_points(ds).values.tolist() == [True, False, False, False, False, True]
    p = xr.DataArray([0.9, 0.1, 0.3, 0.6, 0.8, 0.1], dims="pga", attrs={"method": STORED})
    out = add_fit(xr.Dataset({"p_exceed": p}, coords={"pga": pga}), ds, pga, "pga")
    assert int(out["fit_n_unvouched"]) == 2 and int(out["fit_flag"]) == FitFlag.ok
