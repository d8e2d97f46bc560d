import numpy as np
import pytest
import xarray as xr
from scipy import integrate, stats

from helpers import GRID

from screening import Block, Foundation, WhiteNoise, linearize
from screening.solvers.schema import PARAMETERS
from screening.analysis.fragility import (exceedance_probability_from_moments, fit_lognormal_fragility,
                                 lognormal_fragility, mcs_exceedance_probability,
                                 oscillator_bandwidth, upcrossing_rate, vanmarcke_factor)


def test_stationary_rate_is_rice():
    s, sv, a = 2e-3, 0.09, np.array([1e-3, 4e-3, 8e-3])
    nu = upcrossing_rate(s**2, sv**2, 0.0, a)
    np.testing.assert_allclose(nu, (sv / (np.pi * s)) * np.exp(-a**2 / (2 * s**2)), rtol=1e-13)


@pytest.mark.parametrize("rho", [-0.8, -0.2, 0.3, 0.9])
def test_correlated_rate_matches_quadrature_of_rice_integral(rho):
    s, sv, a = 1.5e-3, 0.07, 2.2e-3
    cov = np.array([[s * s, rho * s * sv], [rho * s * sv, sv * sv]])
    pdf = stats.multivariate_normal(mean=[0, 0], cov=cov).pdf
    up = integrate.quad(lambda v: v * pdf([a, v]), 0, np.inf, epsrel=1e-11)[0]
    down = integrate.quad(lambda v: -v * pdf([-a, v]), -np.inf, 0, epsrel=1e-11)[0]
    assert upcrossing_rate(s * s, sv * sv, rho * s * sv, a) == pytest.approx(up + down, rel=1e-8)


def test_rate_is_zero_before_motion_and_finite():
    assert upcrossing_rate(0.0, 0.0, 0.0, 1e-3) == 0.0
    assert np.isfinite(upcrossing_rate(1e-12, 1e-9, 0.0, 1.0))


def test_poisson_probability_for_a_stationary_record():
    t = np.linspace(0, 20, 2001)
    s, sv, a = 1e-3, 0.04, 3e-3
    p = exceedance_probability_from_moments(t, np.full_like(t, s * s), np.full_like(t, sv * sv),
                                            np.zeros_like(t), a, method="poisson")
    nu = sv / (np.pi * s) * np.exp(-a**2 / (2 * s * s))
    assert p == pytest.approx(-np.expm1(-nu * 20.0), rel=1e-10)


def test_bandwidth_of_linear_oscillator_matches_spectral_moments():
    for zeta in (0.02, 0.1, 0.4):
        H2 = lambda w: 1.0 / ((1 - w * w) ** 2 + (2 * zeta * w) ** 2)
        lam = [integrate.quad(lambda w: w**i * H2(w), 0, np.inf, limit=400, epsrel=1e-11, points=None)[0]
               for i in range(3)]
        delta = np.sqrt(1 - lam[1] ** 2 / (lam[0] * lam[2]))
        assert oscillator_bandwidth(zeta) == pytest.approx(delta, rel=1e-6)


def test_vanmarcke_factor_limits():
    assert vanmarcke_factor(1.0, 300.0, 0.3) == pytest.approx(1.0, rel=1e-12)  # high barrier: Poisson
    assert vanmarcke_factor(1.0, 30.0, 0.3) == pytest.approx(-np.expm1(-np.sqrt(np.pi / 2) * 0.3**1.2 * 30), rel=1e-12)
    assert 0 < vanmarcke_factor(1.0, 2.0, 0.2) < 1.0  # clumping of narrow-band crossings
    assert vanmarcke_factor(0.0, 1.0, 0.2) == 0.0


def test_lognormal_fit_recovers_parameters_from_probabilities():
    im = np.logspace(-5, -2, 25)
    median, beta = fit_lognormal_fragility(im, lognormal_fragility(im, 3e-4, 0.7))
    assert median == pytest.approx(3e-4, rel=1e-9) and beta == pytest.approx(0.7, rel=1e-9)


def test_lognormal_fit_recovers_parameters_from_binomial_samples():
    rng = np.random.default_rng(11)
    im = np.logspace(-5, -2, 15)
    n = 400
    k = rng.binomial(n, lognormal_fragility(im, 3e-4, 0.6))
    median, beta = fit_lognormal_fragility(im, n_exceed=k, n_total=n)
    # sampling error of the MLE with 15 x 400 trials is a few percent
    assert median == pytest.approx(3e-4, rel=0.1) and beta == pytest.approx(0.6, rel=0.15)


def test_mcs_exceedance_counts_overturned_samples():
    p, se = mcs_exceedance_probability([0.1, 0.3, 0.05, 0.2], 0.15, overturned=[False, False, True, False])
    assert p == 0.75 and se == pytest.approx(np.sqrt(0.75 * 0.25 / 4))


def test_accessor_on_a_linearization_result():
    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, -6e5)
    ds = linearize(block, bed, WhiteNoise(5e-4))
    p_small = float(ds.rocking.exceedance_probability(1e-3))
    p_large = float(ds.rocking.exceedance_probability(1e-2))
    assert 0 < p_large < p_small <= 1
    p_rel = float(ds.rocking.exceedance_probability(0.05, relative_to="slenderness"))
    p_abs = float(ds.rocking.exceedance_probability(0.05 * np.arctan(0.035 / 0.21)))
    assert p_rel == pytest.approx(p_abs, rel=1e-12)
    p_poisson = float(ds.rocking.exceedance_probability(5e-3, method="poisson"))
    p_vanm = float(ds.rocking.exceedance_probability(5e-3, method="vanmarcke"))
    assert p_vanm < p_poisson


def test_fragility_curve_over_s0_from_a_batch():
    S0 = np.logspace(-6, -3, 13)
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 0.0), WhiteNoise(S0))
    curve = ds.rocking.fragility_curve(0.5, dim="S0", relative_to="theta_ul")
    p, median, beta = curve["p_exceed"], curve["fit_median"], curve["beta"]
    assert p.dims == ("S0",) and np.all(np.diff(p.values) >= 0)
    assert S0[0] < float(median) < S0[-1] and 0 < float(beta) < 5
    assert median.attrs["units"] == PARAMETERS["S0"]["units"] and beta.attrs["units"] == "1"


@pytest.mark.parametrize("S0, ratio", [(2e-6, 0.4), (5e-6, 0.4), (5e-6, 0.6)])
def test_gaussian_fragility_matches_monte_carlo_peaks_on_a_linear_case(S0, ratio):
    """No uplift (sigma_theta < theta_ul / 5), eps = 0: the condensed model is linear and Gaussian.

    Tolerance: 3 binomial standard errors of the 1000-sample estimate plus 0.03 for the
    Vanmarcke approximation itself (measured: 0.004-0.037 above the Monte Carlo value here,
    while the Poisson approximation is 0.1-0.2 above it).
    """
    from screening import Envelope, uplift_threshold
    from screening.solvers.montecarlo import monte_carlo

    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 0.0)
    exc = WhiteNoise(S0=S0, envelope=Envelope(T1=4.0, T2=2.0))
    ds = linearize(block, bed, exc)
    level = ratio * float(uplift_threshold(block, bed))
    assert float(ds["p_uplift"].max()) < 1e-5
    mc = monte_carlo(block, bed, exc, n_samples=1000, model="condensed", seed=1)
    p_mcs, se = mcs_exceedance_probability(mc["peak_abs_theta"].values, level, mc["overturned"].values)
    p_vanmarcke = float(ds.rocking.exceedance_probability(level, method="vanmarcke"))
    p_poisson = float(ds.rocking.exceedance_probability(level, method="poisson"))
    assert 0.05 < p_mcs < 0.95
    assert abs(p_vanmarcke - p_mcs) < 3 * se + 0.03
    assert p_poisson > p_vanmarcke                      # Poisson ignores clumping: conservative


# ---------------------------------------------------------------- thresholds read from the dataset
def test_theta_ul_threshold_of_a_cubic_result_is_the_stored_one():
    from screening.analysis.fragility import threshold_angle
    from screening.core.condensation import cubic

    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 6e7)
    ds = linearize(block, bed, WhiteNoise(5e-4), t_end=4.0, condensation="cubic")
    level = threshold_angle(ds, 0.5, "theta_ul")
    assert float(level) == 0.5 * float(ds["theta_ul"]) == 0.5 * cubic.uplift_threshold(block, bed)
    assert float(level) != pytest.approx(0.5 * block.m * block.g / (2 * block.b**2 * bed.k), rel=1e-3)  # not the paper's
    assert float(ds.rocking.threshold_angle(0.2, "slenderness")) == 0.2 * block.slenderness


def test_stored_slenderness_is_read_and_the_geometry_is_only_a_fallback():
    from screening.analysis.fragility import model_quantity, threshold_angle

    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8), WhiteNoise(1e-4), t_end=2.0)
    assert float(threshold_angle(ds.assign(slenderness=0.5), 0.1, "slenderness")) == pytest.approx(0.05, rel=1e-15)
    old = ds.drop_vars("slenderness")                      # a file written before slenderness was stored
    assert float(model_quantity(old, "slenderness")) == float(ds["slenderness"])
    with pytest.raises(KeyError, match="slenderness.*missing b, h"):
        model_quantity(old.drop_vars(["b", "h"]), "slenderness")
    with pytest.raises(KeyError, match="theta_ul"):
        threshold_angle(ds.drop_vars("theta_ul"), 0.5, "theta_ul")
    with pytest.raises(ValueError, match="relative_to"):
        threshold_angle(ds, 0.5, "height")


# ---------------------------------------------------------------- broadcast linearize results
def test_accessor_on_a_broadcast_linearization_equals_point_by_point_results():
    eps, S0 = np.array([-6e5, 6e7]), np.array([1e-5, 2e-4, 5e-4])
    block = Block(8.67, 0.035, 0.21)
    ds = linearize(block, Foundation(2.89e7, 8.95e8, eps), WhiteNoise(S0), t_end=6.0)
    for relative_to, threshold in ((None, 2e-3), ("theta_ul", 2.0), ("slenderness", 0.02)):
        p = ds.rocking.exceedance_probability(threshold, relative_to)
        assert p.dims == ("eps", "S0") and p.attrs["units"] == "1" and p.name == "p_exceed"
        for i, e in enumerate(eps):
            for j, s in enumerate(S0):
                one = linearize(block, Foundation(2.89e7, 8.95e8, e), WhiteNoise(s), t_end=6.0)
                assert float(p[i, j]) == pytest.approx(
                    float(one.rocking.exceedance_probability(threshold, relative_to)), rel=1e-9, abs=1e-15)
    curve = ds.rocking.fragility_curve(2.0, dim="S0", relative_to="theta_ul")
    assert curve["fit_median"].dims == ("eps",) and curve["fit_median"].attrs["intensity"] == "S0"
    frag = ds.rocking.fragility_dataset(2.0, relative_to="theta_ul")
    assert set(frag.data_vars) == {"p_exceed", "fit_median", "beta", "fit_flag", "fit_n_unvouched", "threshold_rad",
                                   "fit_im_min", "fit_im_max"}     # the vouched range of each curve
    np.testing.assert_array_equal(frag["threshold_rad"].values, 2.0 * ds["theta_ul"].values)


# ---------------------------------------------------------------- Monte Carlo results
def test_exceedance_of_a_monte_carlo_result_is_the_sample_fraction_with_its_standard_error():
    from screening import monte_carlo

    block, bed = Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8, 6e7)
    mc = monte_carlo(block, bed, WhiteNoise(5e-3), n_samples=12, model="coupled", t_end=6.0, dt=0.1, seed=3,
                     progress=False)
    assert 0 < int(mc.n_overturned) < 12                    # overturned samples count as exceedances
    for threshold, relative_to in ((0.1, None), (100.0, "theta_ul"), (0.8, "slenderness")):
        level = threshold * {None: 1.0, "theta_ul": float(mc["theta_ul"]), "slenderness": block.slenderness}[
            relative_to]
        used = ~mc["diverged"].values
        expected, se = mcs_exceedance_probability(mc["peak_abs_theta"].values[used], level,
                                                  mc["overturned"].values[used])
        p = mc.rocking.exceedance_probability(threshold, relative_to)
        assert p.name == "mcs_p_exceed" and p.attrs["units"] == "1"
        assert float(p) == pytest.approx(expected, abs=1e-15)
        assert float(p["mcs_p_exceed_se"]) == pytest.approx(se, abs=1e-15)
        assert 0 < float(p) < 1
    frag = mc.rocking.fragility_dataset(100.0, relative_to="theta_ul")
    assert set(frag.data_vars) == {"mcs_p_exceed", "mcs_p_exceed_se", "threshold_rad"}
    assert frag.attrs["method"] == "monte_carlo" and frag["mcs_p_exceed_se"].attrs["units"] == "1"
    with pytest.raises(ValueError, match="'dim'"):
        mc.rocking.fragility_curve(100.0, relative_to="theta_ul")


# ---------------------------------------------------------------- sweeps whose cases differ in geometry
#: the sweep tests' grid with eps fixed and three blocks of different b, h as cases
CASES = GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]\n", "").replace('title = "sweep test"', 'title = "three shapes"') + """
[[case]]
name = "slim"
[[case]]
name = "squat"
block.b = 0.06
block.h = 0.15
[[case]]
name = "tall"
block.b = 0.03
block.h = 0.30
[mcs]
points = "auto"
count = 1
samples = 6
model = "condensed"
"""


@pytest.fixture(scope="module")
def geometry_sweep(tmp_path_factory, one_worker):
    from helpers import quiet
    from screening.sweep.study import parse_study
    from screening.sweep.run import run_sweep

    path = tmp_path_factory.mktemp("cases") / "cases.nc"
    run_sweep(parse_study(CASES, name="cases"), path, client=one_worker, progress=False, log=quiet)
    return path


@pytest.mark.parametrize("threshold, relative_to", [(0.3, "slenderness"), (3.0, "theta_ul")])
def test_fragility_of_cases_with_different_blocks(geometry_sweep, threshold, relative_to):
    from screening.analysis.fragility import fragility_dataset
    from screening.io.reader import open_result

    with open_result(geometry_sweep) as ds:
        ds = ds.load()
    assert ds["b"].dims == ("case",) and len(set(ds["b"].values)) == 3
    frag = fragility_dataset(ds, threshold, relative_to)
    assert frag["p_exceed"].dims == ("case", "S0") and frag["fit_median"].dims == ("case",)
    if relative_to == "slenderness":                       # stored per point: atan(b/h) of each case
        per_case = xr.DataArray(np.arctan2(ds["b"].values, ds["h"].values), dims="case")
        np.testing.assert_allclose(ds["slenderness"].values, per_case.broadcast_like(ds["slenderness"]).values,
                                   rtol=1e-15)
        expected = threshold * ds["slenderness"]
    else:                                                  # per point: (case, S0)
        expected = threshold * ds["theta_ul"]
    assert frag["threshold_rad"].dims == expected.dims
    np.testing.assert_allclose(frag["threshold_rad"].values, expected.values, rtol=1e-15)
    assert len({round(float(x), 12) for x in np.ravel(frag["threshold_rad"].values)}) >= 3   # the cases differ
    for c in range(3):                                      # each case alone gives the same probabilities
        alone = fragility_dataset(ds.isel(case=c), threshold, relative_to)
        np.testing.assert_allclose(alone["p_exceed"].values, frag["p_exceed"].isel(case=c).values, rtol=1e-14)
    assert np.isfinite(frag["mcs_p_exceed"].values).all() and frag["p_exceed_at_spot"].dims == ("spot",)


@pytest.mark.parametrize("relative_to, threshold", [("slenderness", "0.3"), ("theta_ul", "3")])
def test_fragility_command_on_cases_with_different_blocks(geometry_sweep, tmp_path, relative_to, threshold):
    from screening.analysis.fragility import fragility_dataset
    from screening.cli import main
    from screening.io.reader import open_result

    out = tmp_path / f"frag_{relative_to}.nc"
    assert main(["fragility", str(geometry_sweep), "--threshold", threshold, "--relative-to", relative_to,
                 "--out", str(out)]) == 0
    with open_result(geometry_sweep) as ds, xr.open_dataset(out) as frag:
        expected = fragility_dataset(ds, float(threshold), relative_to)
        assert frag["p_exceed"].dims == ("case", "S0") and frag["fit_median"].dims == ("case",)
        np.testing.assert_array_equal(frag["p_exceed"].values, expected["p_exceed"].values)
        np.testing.assert_array_equal(frag["threshold_rad"].values, expected["threshold_rad"].values)
        assert frag["fit_median"].attrs["units"] == PARAMETERS["S0"]["units"]


@pytest.mark.parametrize("method", ["vanmarcke", "poisson"])
def test_linearized_exceedance_on_plain_arrays_is_the_dataset_function(method):
    """The batch task's plain-array twin gives what exceedance_probability gives on the dataset, point by point,
    unstable points included (probability 1)."""
    from screening.analysis.fragility import exceedance_probability, linearized_exceedance

    S0 = xr.DataArray([1e-5, 3e-4, 2.4e-3, 2e-2], dims="S0")
    block = Block(8.67, 0.035, 0.21)
    ds = linearize(block, Foundation(2.89e7, 8.95e8, 0.0), WhiteNoise(S0), t_end=3.0)
    n = ds.sizes["S0"]
    flat = {name: ds[name].transpose("S0", "t").values for name in
            ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "c_eq", "k_eq")}
    for threshold in (0.2, 0.6):
        ref = exceedance_probability(ds, threshold, "slenderness", method).values
        got = linearized_exceedance(ds["t"].values, *flat.values(), np.full(n, block.m_sdof), ds["status"].values,
                                    threshold * np.broadcast_to(ds["slenderness"].values, (n,)), method)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=0)
        assert np.isfinite(ref).any() and (np.isnan(ref) == np.isnan(got)).all()
    with pytest.raises(ValueError, match="method"):
        linearized_exceedance(ds["t"].values, *flat.values(), np.full(n, block.m_sdof), ds["status"].values,
                              np.ones(n), "rice")
