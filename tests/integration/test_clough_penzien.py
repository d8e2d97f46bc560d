"""The Clough–Penzien excitation, added as one module and its registration, through every layer:
its filter's stationary covariance against the frequency-domain variance integral (quadrature of its
PSD), the linearization (stationary rocking variance of the block at rest against the quadrature of
``|H|^2 S``), the Monte Carlo synthesis (sample variance and band-averaged sample PSD within the
sampling error), the intensity measures (the RVT oscillator covariance against quadrature), studies
(keys and ranges) and sweeps (its parameters as dimensions, with CF attributes)."""

import math

import numpy as np
import pytest
from helpers import CASES, quiet
from scipy import integrate

from screening.core import condensation, excitations
from screening.solvers import schema
from screening.analysis.intensity import input_measures, oscillator_covariance
from screening.core.excitations.clough_penzien import CloughPenzien
from screening.core.model import Block, ConstantEnvelope, Foundation
from screening.core.excitations import KanaiTajimi
from screening.analysis.linearization import linearize
from screening.solvers.moments import solve_moments
from screening.solvers.synthesis import band_limited_variance, ground_acceleration
from screening.solvers.timegrid import output_times
from screening.sweep.study import StudyError, build_models, parse_study

S0, WG, ZG, WF, ZF = 2e-4, 15.0, 0.6, 1.5, 0.8
CP = CloughPenzien(S0, WG, ZG, WF, ZF, ConstantEnvelope())
BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
BREAKS = (-WG, -WF, 0.0, WF, WG)


def psd_integral(weight, lo=-np.inf, hi=np.inf, peaks=()):
    """``int weight(omega) S(omega) d omega`` by adaptive quadrature, split at the filter frequencies
    and at the ``peaks`` of the weight."""
    edges = [lo] + sorted(b for b in (*BREAKS, *peaks) if lo < b < hi) + [hi]
    return sum(integrate.quad(lambda w: weight(w) * float(CP.psd(w)), a, b, limit=500, epsabs=0.0, epsrel=1e-11)[0]
               for a, b in zip(edges[:-1], edges[1:]))


def test_registered_psd_is_the_kanai_tajimi_one_high_passed():
    assert excitations.get("clough_penzien") is CloughPenzien
    w = np.array([0.0, 0.3, 1.5, 15.0, 80.0])
    kt = KanaiTajimi(S0, WG, ZG).psd(w)
    np.testing.assert_allclose(CP.psd(w), kt * w**4 / ((WF**2 - w**2) ** 2 + (2 * ZF * WF * w) ** 2), rtol=1e-14)
    np.testing.assert_allclose(CP.psd(w), excitations.transfer_psd(CP.filter(), S0, w), rtol=1e-10, atol=1e-30)


def test_stationary_covariance_equals_the_frequency_domain_variances():
    P = CP.stationary_covariance()
    A, B, C, D = CP.filter()
    var_a = float(C @ P @ C)
    assert var_a == pytest.approx(psd_integral(lambda w: 1.0), rel=1e-8)
    # the high-pass state v: |V/A|^2 = 1/w^4, finite thanks to the filter (a KT input would diverge)
    assert P[2, 2] == pytest.approx(psd_integral(lambda w: 1.0 / max(w**4, 1e-300)), rel=1e-7)


def linear_constants():
    paper = condensation.get("paper")
    m = BLOCK.m_sdof
    w = math.sqrt(paper.stiffness_at_rest(BLOCK, BED) / m)
    zeta = paper.damping_at_rest(BLOCK, BED) / (2.0 * m * w)
    return w, zeta, BLOCK.m * BLOCK.h / m


def test_linearization_reaches_the_stationary_variance_of_the_frequency_domain():
    exc = CloughPenzien(1e-12, WG, ZG, WF, ZF, ConstantEnvelope())       # far below uplift: linear
    res = solve_moments(BLOCK, BED, exc, output_times(14.0, 0.5))
    assert int(res["status"]) == 0 and float(res["peak_p_uplift"]) < 1e-12
    w, zeta, a = linear_constants()
    h2 = lambda om: a**2 / ((w**2 - om**2) ** 2 + (2 * zeta * w * om) ** 2)
    expected = psd_integral(h2, peaks=(-w, w)) * 1e-12 / S0
    assert res["var_theta"][-1] == pytest.approx(expected, rel=1e-3)


def test_synthesized_records_have_the_band_limited_variance_and_psd():
    n, t_end, cutoff = 400, 40.0, 60.0
    t, acc, plan = ground_acceleration(CP, t_end, cutoff, n, seed=11)
    late = t >= 2.0
    x = acc[:, late]
    expected = band_limited_variance(CP, plan.cutoff)
    assert plan.stationary_variance == pytest.approx(expected, rel=1e-4)
    # variance per record over time and records; records are independent: SE from their spread
    per_record = (x**2).mean(axis=1)
    se = per_record.std(ddof=1) / math.sqrt(n)
    assert abs(per_record.mean() - expected) < 3.0 * se and se < 0.05 * expected
    # band-averaged periodogram (two-sided PSD estimate, Hann window against leakage from the steep
    # low-frequency flank) against the PSD integral over the band
    dt = t[1] - t[0]
    window = np.hanning(x.shape[1])
    spec = np.abs(np.fft.rfft(x * window, axis=1)) ** 2 * dt / (2.0 * np.pi * np.sum(window**2))
    freq = 2.0 * np.pi * np.fft.rfftfreq(x.shape[1], dt)
    for lo, hi in ((0.5, 3.0), (8.0, 20.0), (30.0, 50.0)):
        band = (freq >= lo) & (freq < hi)
        per_record = spec[:, band].mean(axis=1)
        got, se = per_record.mean(), per_record.std(ddof=1) / math.sqrt(n)
        want = psd_integral(lambda w: 1.0, lo, hi) / (hi - lo)
        assert abs(got - want) < 3.0 * se + 0.02 * want, (lo, hi, got, want, se)   # 2 %: window smoothing at the band edges


def test_intensity_oscillator_covariance_is_the_frequency_domain_variance():
    period, damping = 1.0, 0.05
    t, var_u, _, _ = oscillator_covariance(CP, period, 40.0, damping)
    wn = 2.0 * math.pi / period
    h2 = lambda om: 1.0 / ((wn**2 - om**2) ** 2 + (2 * damping * wn * om) ** 2)
    expected = psd_integral(h2, peaks=(-wn, wn))
    assert var_u[-1] == pytest.approx(expected, rel=2e-3)
    measures = input_measures(CP, 20.0, 60.0)
    lam0 = band_limited_variance(CP, 60.0)
    assert measures["rms_acceleration"] == pytest.approx(math.sqrt(lam0), rel=1e-9)   # constant envelope


#: The block and bed of the shared test cases, Clough-Penzien input swept over omega_f.
STUDY = CASES[:CASES.index("[excitation]")] + """[excitation]
kind = "clough_penzien"
S0 = 2e-4
omega_g = 15.0
zeta_g = 0.6
omega_f = [0.5, 1.5]
zeta_f = 0.8
envelope = "constant"
[time]
t_end = 2.0
dt = 0.5
"""


def test_studies_take_its_keys_validate_their_ranges_and_sweep_them():
    study = parse_study(STUDY)
    assert study.dims == ("omega_f",)
    _, _, exc = build_models(study.cases[0], {"omega_f": 0.5})
    assert isinstance(exc, CloughPenzien) and exc.omega_f == 0.5 and exc.zeta_f == 0.8
    with pytest.raises(StudyError, match=r"excitation\.zeta_f.*> 0"):
        parse_study(STUDY.replace("zeta_f = 0.8", "zeta_f = -0.1"))
    with pytest.raises(StudyError, match=r"excitation\.zeta_f: required"):
        parse_study(STUDY.replace("zeta_f = 0.8\n", ""))
    with pytest.raises(StudyError, match=r"excitation\.(omega|zeta)_f: does not apply to kind = 'kanai_tajimi'"):
        parse_study(STUDY.replace('"clough_penzien"', '"kanai_tajimi"'))
    assert schema.PARAMETERS["omega_f"]["units"] == "rad s-1"


def test_linearize_sweeps_its_parameters_as_dimensions():
    exc = CloughPenzien(2e-4, WG, ZG, np.array([0.5, 1.5, 4.0]), ZF, ConstantEnvelope())
    ds = linearize(BLOCK, BED, exc, t_end=6.0, dt=0.5)
    assert ds.attrs["excitation"] == "clough_penzien" and ds["omega_f"].attrs["units"] == "rad s-1"
    assert (ds["status"].values == 0).all()
    # a stiffer high-pass takes more of the low-frequency input away: less rocking
    peak = ds["peak_var_theta"].values
    assert peak[0] > peak[1] > peak[2]


def test_a_sweep_over_its_parameter_writes_what_the_solver_gives(client, tmp_path):
    import xarray as xr

    from screening.sweep.run import run_sweep

    study = parse_study(STUDY)
    out = tmp_path / "cp.nc"
    report = run_sweep(study, out, client=client, batch_size=1, progress=False, log=quiet)
    assert report.status_counts == {"ok": 2}
    with xr.open_dataset(out) as ds:
        assert ds["var_theta"].dims == ("omega_f", "t") and ds.attrs["excitation"] == "clough_penzien"
        assert ds["omega_f"].attrs["units"] == "rad s-1" and float(ds["zeta_f"]) == 0.8
        direct = solve_moments(*build_models(study.cases[0], {"omega_f": study.sweeps["omega_f"]}), study.times)
        stored = ds["var_theta"].values                      # histories are stored in single precision
        np.testing.assert_array_equal(stored, direct["var_theta"].astype(stored.dtype))
