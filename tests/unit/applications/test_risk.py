"""The risk integral (screening.applications.risk): the closed form of a lognormal fragility under a power-law
hazard, numerical quadrature of a curved hazard, the vouched range's share and bounds, and the hazard
readers' one-line refusals."""

import math

import numpy as np
import pytest
import xarray as xr
from scipy import integrate, stats

from screening.applications.risk import HazardCurve, HazardError, annual_frequency, read_hazard, risk_table


@pytest.mark.parametrize("median, beta, k", [(1.0, 0.4, 2.0), (0.3, 0.25, 3.0), (2.5, 0.6, 1.5)])
def test_power_law_hazard_matches_the_closed_form(median, beta, k):
    """H = k0 x^-k over all x: lambda = k0 median^-k exp(k^2 beta^2 / 2).  The table spans 12 beta either
    side of the median: the part left out below is < Phi(-12) k0 (x_0)^-k, far under the tolerance; the
    midpoint rule's error is ~ (h / beta)^2 / 24 < 1e-4 at h = 1/200."""
    k0 = 1e-4
    x = median * np.exp(np.linspace(-12 * beta, 12 * beta, 30))
    out = annual_frequency(x, k0 * x**-k, median, beta)
    exact = k0 * median**-k * math.exp(k * k * beta * beta / 2)
    assert out["rate"] == pytest.approx(exact, rel=2e-4)
    assert out["share_outside"] == pytest.approx(0.0, abs=1e-12)
    assert out["rate_low"] == pytest.approx(out["rate"]) and out["rate_high"] == pytest.approx(out["rate"])


def test_curved_hazard_matches_quadrature():
    """A hazard curve that is not a power law (log-quadratic): the sum agrees with scipy's adaptive
    quadrature of P(x) |dH/dx| over the same interpolated curve within 1e-4."""
    x = np.geomspace(0.01, 5.0, 12)
    lh = np.log(1e-2) - 1.5 * np.log(x / 0.01) - 0.15 * np.log(x / 0.01) ** 2
    median, beta = 0.4, 0.35

    def dens(u):                   # u = ln x; H log-log linear between the levels
        i = np.clip(np.searchsorted(np.log(x), u) - 1, 0, x.size - 2)
        slope = (lh[i + 1] - lh[i]) / (np.log(x[i + 1]) - np.log(x[i]))
        h = math.exp(np.interp(u, np.log(x), lh))
        return stats.norm.cdf((u - math.log(median)) / beta) * (-slope) * h

    pieces = [integrate.quad(dens, a, b, epsabs=0, epsrel=1e-10)[0] for a, b in zip(np.log(x[:-1]), np.log(x[1:]))]
    expected = sum(pieces) + stats.norm.cdf(math.log(x[-1] / median) / beta) * math.exp(lh[-1])
    assert annual_frequency(x, np.exp(lh), median, beta)["rate"] == pytest.approx(expected, rel=1e-4)


def test_vouched_range_splits_the_rate_and_bounds_it():
    x = np.geomspace(0.01, 10.0, 40)
    h = 1e-3 * x**-2.0
    full = annual_frequency(x, h, 1.0, 0.5)
    part = annual_frequency(x, h, 1.0, 0.5, im_min=0.5, im_max=2.0)
    assert part["rate"] == pytest.approx(full["rate"], rel=1e-6)       # the fitted curve everywhere (2 more grid edges)
    assert 0 < part["rate_vouched"] < part["rate"]
    assert part["share_outside"] == pytest.approx(1 - part["rate_vouched"] / part["rate"])
    # outside [0.5, 2]: only that P does not fall with x -> bounds around the fitted curve's rate
    assert part["rate_low"] <= part["rate"] <= part["rate_high"]
    # the upper bound is the vouched part + P(0.5) x the hazard increment below 0.5 + everything above 2
    h_at = lambda v: float(np.exp(np.interp(np.log(v), np.log(x), np.log(h))))   # noqa: E731
    expected_high = (part["rate_vouched"] + stats.norm.cdf(math.log(0.5) / 0.5) * (h[0] - h_at(0.5)) + h_at(2.0))
    assert part["rate_high"] == pytest.approx(expected_high, rel=1e-3)


def _write(tmp_path, text, name="h.csv"):
    f = tmp_path / name
    f.write_text(text)
    return f


OQ = ('#,,,,,"generated_by=\'OpenQuake engine 3.26\', start_date=\'2026-01-01\', checksum=1, kind=\'mean\', '
      'investigation_time=50.0, imt=\'PGA\'"\n'
      "lon,lat,depth,poe-0.0500000,poe-0.1000000,poe-0.2000000,poe-0.4000000,poe-0.8000000\n"
      "{row}\n")


def test_openquake_hazard_curve_becomes_annual_rates(tmp_path):
    poe = [0.9, 0.5, 0.1, 0.01, 0.0]
    curve = read_hazard(_write(tmp_path, OQ.format(row="10.0,45.0,-0.1," + ",".join(map(str, poe)))))
    assert curve.imt == "PGA" and curve.units == "g"
    np.testing.assert_allclose(curve.im, [0.05, 0.1, 0.2, 0.4])          # the level never exceeded is left out
    np.testing.assert_allclose(curve.rate, -np.log1p(-np.array(poe[:4])) / 50.0, rtol=1e-12)
    # a level certainly exceeded (poe printed as 1) has no finite rate: left out, and said
    curve = read_hazard(_write(tmp_path, OQ.format(row="10.0,45.0,-0.1,1.000000e+00,0.5,0.1,0.01,0.0")))
    np.testing.assert_allclose(curve.im, [0.1, 0.2, 0.4])
    assert "1 level(s) with poe 1 left out" in curve.source


@pytest.mark.parametrize("text, where", [
    (OQ.format(row="10.0,45.0,-0.1,0.9,0.95,0.1,0.01,0.0"), "h.csv:3: poe-0.1000000: the hazard curve is not decreasing"),
    (OQ.format(row="10.0,45.0,-0.1,0.9,0.5,x,0.01,0.0"), "h.csv:3: poe-0.2000000: not a number"),
    ("PGA [g], annual_rate [1/yr]\n0.1, 1e-2\n0.2, 2e-2\n", "h.csv:3: annual_rate [1/yr]: the hazard curve is not decreasing"),
    ("PGA [g], annual_rate [1/yr]\n0.1, 1e-2\n0.05, 1e-3\n", "h.csv:3: PGA [g]: intensity 0.05 is not above"),
    ("PGA [furlongs], annual_rate [1/yr]\n0.1, 1e-2\n", "h.csv:1: PGA [furlongs]: unknown units"),
    ("im, rate\n0.1, 1e-2\n", "h.csv:1: header: expected 'IMT [units], annual_rate [1/yr]'"),
    ("PGA [g], annual_rate [1/yr]\n0.1, -1e-2\n0.2, -2e-2\n", "h.csv:2: annual_rate [1/yr]: -0.01 must be > 0"),
])
def test_bad_hazard_curves_are_one_line_naming_file_line_and_field(tmp_path, text, where):
    with pytest.raises(HazardError) as err:
        read_hazard(_write(tmp_path, text))
    message = str(err.value)
    assert "\n" not in message and message.endswith(message.split(": ", 1)[1])
    assert where in message


def _frag(units="m s-2", intensity="pga"):
    return xr.Dataset({"fit_median": (("case",), [2.0, 4.0], {"units": units, "intensity": intensity}),
                       "beta": (("case",), [0.4, 0.3]), "fit_flag": (("case",), np.int8([0, 0])),
                       "fit_median_se": (("case",), [0.2, 0.4]), "beta_se": (("case",), [0.05, 0.05]),
                       "fit_im_min": (("case",), [1.0, 1.0]), "fit_im_max": (("case",), [8.0, 8.0]),
                       "threshold_rad": 0.1, intensity: ("pga", [1.0, 8.0])},
                      coords={"case": [0, 1], "case_name": ("case", ["vase-tall", "bust"])})


def test_risk_table_ranks_objects_and_carries_names_and_standard_errors():
    x = np.geomspace(0.01, 3.0, 40)                                       # g
    rows = risk_table(_frag(), HazardCurve("PGA", "g", x, 1e-4 * x**-2.0, "t"), 50.0)
    assert [r["object"] for r in rows] == ["vase-tall", "bust"]           # the lower median is the higher risk
    r = rows[0]
    exact = 1e-4 * (2.0 / 9.80665) ** -2.0 * math.exp(4 * 0.16 / 2)
    assert r["annual_rate"] == pytest.approx(exact, rel=1e-3) and r["rank"] == 1
    assert r["probability"] == pytest.approx(1 - math.exp(-50 * r["annual_rate"]))
    # delta method on the closed form: d ln(lambda) / d ln(median) = -k, d ln(lambda) / d beta = k^2 beta
    se = r["annual_rate"] * math.hypot(2.0 * 0.2 / 2.0, 4 * 0.4 * 0.05)
    assert r["annual_rate_se"] == pytest.approx(se, rel=2e-2)


def test_risk_table_refuses_another_imt_or_units(tmp_path):
    x = np.geomspace(0.01, 3.0, 10)
    with pytest.raises(HazardError, match=r"^h.csv:1: imt: the hazard curve is for SA\(0.3\), the fragility for PGA"):
        risk_table(_frag(), HazardCurve("SA(0.3)", "g", x, 1e-4 * x**-2.0, "t"), 50.0, "h.csv")
    with pytest.raises(HazardError, match="^h.csv:1: imt: the fragility is over 'S0'"):   # no OpenQuake IMT
        risk_table(_frag("m2 s-3", "S0"), HazardCurve("PGA", "g", x, 1e-4 * x**-2.0, "t"), 50.0, "h.csv")


def test_probit_fit_standard_errors_match_the_scatter_of_replicated_fits():
    """Points with known standard errors (at most 15 % of p and of 1 - p: where the error is as large as p itself
    the probit is far from linear and the delta method does not hold), 4000 replicated noisy sets (seed 0): the
    scatter of the fitted median and beta matches fit_standard_errors within 8 % (the sampling error of a
    standard deviation from 4000 replicates is 1.1 %; the rest allows for the delta method's linearisation)."""
    from screening.analysis.fragility import fit_fragility_curve, fit_standard_errors, lognormal_fragility

    x = np.array([0.4, 0.6, 0.9, 1.3, 2.0, 3.0])
    p = lognormal_fragility(x, 1.2, 0.45)
    se = 0.15 * p * (1 - p)
    rng = np.random.default_rng(0)
    fits = np.array([fit_fragility_curve(x, np.clip(p + se * rng.standard_normal(x.size), 1e-5, 1 - 1e-5))[:2]
                     for _ in range(4000)])
    median_se, beta_se = fit_standard_errors(x, p, se)
    assert np.std(fits[:, 0]) == pytest.approx(median_se, rel=0.08)
    assert np.std(fits[:, 1]) == pytest.approx(beta_se, rel=0.08)
    assert math.isnan(fit_standard_errors(x, p, np.where(x > 1, se, np.nan))[0])   # a point without one: unknown


def test_a_fit_without_its_own_range_is_vouched_over_its_records():
    """A cloud or multiple-stripe fit has no fit_im_min / fit_im_max: the range of its records' (stripes')
    intensities stands in, so the share from outside it is said."""
    frag = xr.Dataset({"fit_median": ((), 2.0, {"units": "m s-2", "intensity": "stripe_pga"}), "beta": 0.4,
                       "fit_flag": np.int8(0), "threshold_rad": 0.01, "stripe_pga": ("level", [1.0, 2.0, 4.0])})
    x = np.geomspace(0.01, 3.0, 40)
    row = risk_table(frag, HazardCurve("PGA", "g", x, 1e-4 * x**-2.0, "t"), 50.0)[0]
    assert (row["im_min"], row["im_max"]) == (1.0, 4.0) and 0 < row["share_outside_vouched"] < 1
