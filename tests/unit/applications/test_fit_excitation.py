"""fit-excitation recovers the parameters of synthesised Kanai-Tajimi records.

20 records of 30 s (seed 3, fixed).  Measured: medians of the estimates -3 % (omega_g), +5 %
(zeta_g), -1 % (T1), +2 % (T2); the fitted models' RVT median PGA -3 % (median over records) of the
true model's (benchmarks/fit_excitation_recovery.py).  Tolerances below are about twice the measured
errors (the median of 20 records has a sampling error of roughly 1.25 x the single-record scatter / sqrt(20): 5-8 %).
"""

import numpy as np
import pytest

from screening.applications.fit_excitation import excitation_table, fit_excitation
from screening.analysis.intensity import pga_median
from screening.core.model.excitation import Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.records import Record
from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan
from screening.sweep.study import parse_study

TRUE = KanaiTajimi(2e-3, 15.0, 0.6, Envelope(4.0, 2.0))


def _records(indices):
    plan = spectral_plan(TRUE, 30.0, 200.0)
    acc, _ = ground_acceleration_samples(TRUE, plan, 3, np.asarray(indices))
    n = int(round(30.0 / plan.dt)) + 1
    return [Record(a[:n], plan.dt) for a in acc]


@pytest.fixture(scope="module")
def fits():
    return [fit_excitation(r) for r in _records(np.arange(20))]


@pytest.mark.slow
def test_parameters_recovered(fits):
    med = {k: np.median([f[k] for f in fits]) for k in ("omega_g", "zeta_g", "T1", "T2")}
    assert med["omega_g"] == pytest.approx(15.0, rel=0.10)
    assert med["zeta_g"] == pytest.approx(0.6, rel=0.15)
    assert med["T1"] == pytest.approx(4.0, rel=0.20)
    assert med["T2"] == pytest.approx(2.0, rel=0.20)
    true = pga_median(TRUE, 30.0, 200.0)
    ratios = [pga_median(KanaiTajimi(f["S0"], f["omega_g"], f["zeta_g"], Envelope(f["T1"], f["T2"])), 30.0, 200.0)
              / true for f in fits]
    assert np.median(ratios) == pytest.approx(1.0, abs=0.08)
    # the peak intensity S0 max q^2 (= S0 here: q peaks at 1 for T1 = 2 T2) is what the fit identifies
    # (measured median +1 %, benchmarks/fit_excitation_recovery.py); the study's S0 alone is not
    assert np.median([f["S0_peak"] for f in fits]) == pytest.approx(2e-3, rel=0.10)
    assert all(f["flags"] == [] or all("DC offset" not in x for x in f["flags"]) for f in fits)
    assert np.median([f["husid_max_deviation"] for f in fits]) < 0.1
    rates = [f["zero_crossing_rate_record"] / f["zero_crossing_rate_model"] for f in fits]
    assert np.median(rates) == pytest.approx(1.0, abs=0.3)


def test_white_noise_energy_and_table():
    plan = spectral_plan(WhiteNoise(1e-3), 20.0, 60.0)
    acc, _ = ground_acceleration_samples(WhiteNoise(1e-3), plan, 0, np.arange(10))
    n = int(round(20.0 / plan.dt)) + 1
    s0 = [fit_excitation(Record(a[:n], plan.dt), kind="white", cutoff=60.0)["S0"] for a in acc]
    assert np.median(s0) > 0
    with pytest.raises(ValueError, match="cutoff"):
        fit_excitation(Record(acc[0][:n], plan.dt), kind="white")
    first = fit_excitation(_records([0])[0])              # one record: the 20 of ``fits`` are for the slow test
    text = excitation_table(first)
    study = parse_study("[block]\nm = 1.0\nb = 0.1\nh = 0.3\n[foundation]\nk = 1e8\nlam = 1e9\n" + text)
    assert study.cases[0].excitation == "kanai_tajimi"
    assert study.cases[0].params["omega_g"] == pytest.approx(first["omega_g"], rel=1e-5)


def test_envelope_peak_matches_a_dense_evaluation():
    from screening.applications.fit_excitation import envelope_peak

    for T1, T2 in ((4.0, 2.0), (6.0, 2.5), (3.303, 3.290)):
        t = np.linspace(0.0, 20.0, 2_000_001)
        assert envelope_peak(T1, T2) == pytest.approx(np.max(Envelope(T1, T2)(t)), rel=1e-9)
    assert envelope_peak(4.0, 2.0) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("make, needle", [
    (lambda t: np.ones_like(t), "constant"),
    (lambda t: np.where(np.arange(t.size) == 1500, 1.0, 0.0), "impulse"),
    (lambda t: np.where(np.arange(t.size) == 1500, 1e3, 0.0) + 1e-3 * np.sin(9 * t), "spike"),
    (lambda t: np.where(np.arange(t.size) == 10, np.nan, np.sin(9 * t)), "non-finite"),
    (lambda t: np.sin(9 * t[:40]), "at least 64 samples"),
])
def test_records_that_cannot_be_fitted_are_refused_in_one_line(make, needle):
    t = np.arange(3000) * 0.01
    with pytest.raises(ValueError, match=needle):
        fit_excitation(Record(make(t), 0.01))


def test_time_step_and_cutoff_are_checked():
    a = np.random.default_rng(0).normal(size=3000)
    with pytest.raises(ValueError, match="'dt' must be a number of seconds"):
        fit_excitation(Record(a, 1e300))               # refused by the record itself
    with pytest.raises(ValueError, match="dt must be in 1e-05..1 s"):
        fit_excitation(Record(a, 5e-6))                # a valid record, too finely sampled to fit
    for bad in (0.0, -5.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="cutoff"):
            fit_excitation(Record(a, 0.01), kind="white", cutoff=bad)


def test_harmonic_record_and_dc_offset_are_flagged():
    t = np.arange(3000) * 0.01
    harmonic = fit_excitation(Record(np.sin(2 * np.pi * 2.0 * t), 0.01))
    assert any("nearly harmonic" in f for f in harmonic["flags"])
    assert any("envelope is not identified" in f for f in harmonic["flags"])
    record = _records([0])[0]
    shifted = fit_excitation(Record(record.acceleration + 0.5, record.dt))
    assert any("DC offset" in f for f in shifted["flags"])
    # the offset is removed before the fit: same estimates as the record without it (to the rounding of
    # the envelope deviance, flat to 1e-12 over 1e-5 in log T: the offset itself would move them by %)
    plain = fit_excitation(Record(record.acceleration - record.acceleration.mean(), record.dt))
    for key in ("S0", "omega_g", "zeta_g", "T1", "T2"):
        assert shifted[key] == pytest.approx(plain[key], rel=1e-4)


def test_degenerate_envelope_is_flagged_and_the_peak_intensity_kept():
    """A record whose Husid curve asks for T1 ~ T2: the flag, and S0_peak equal to the record's own
    intensity at its peak (S0 compensates the vanishing envelope of eq. 57, S0_peak does not)."""
    true = KanaiTajimi(1.0, 15.0, 0.6, Envelope(3.303, 3.290))
    plan = spectral_plan(true, 30.0, 200.0)
    acc, _ = ground_acceleration_samples(true, plan, 5, np.arange(4))
    n = int(round(30.0 / plan.dt)) + 1
    fits_ = [fit_excitation(Record(a[:n], plan.dt)) for a in acc]
    # every fit with T1 / T2 < 1.1 is flagged; a record may also be fitted as well by a non-degenerate
    # envelope of the same shape (seed 5: one of four, T1 = 4.05 s, T2 = 2.29 s), whose S0 then means what
    # it says (within a factor 2 of S0_peak)
    for fit in fits_:
        degenerate = fit["T1"] / fit["T2"] < 1.1
        assert degenerate == any("nearly degenerate" in f for f in fit["flags"])
        assert degenerate or fit["S0_peak"] <= fit["S0"] <= 2 * fit["S0_peak"]
    assert sum(fit["T1"] / fit["T2"] < 1.1 for fit in fits_) >= 3
    from screening.applications.fit_excitation import envelope_peak
    peak = 1.0 * envelope_peak(3.303, 3.290) ** 2
    assert np.median([f["S0_peak"] for f in fits_]) == pytest.approx(peak, rel=0.3)
    assert np.median([f["S0"] for f in fits_]) > 10 * np.median([f["S0_peak"] for f in fits_])


def test_envelope_of_a_modulated_sine_is_recovered():
    """Window energies of ``q(t) sin(omega t)`` with many cycles per window are ``Q_k / 2``: the deviance
    is minimal at the true envelope, which the fit returns (to the ripple of the windows' partial cycles)."""
    from screening.applications.fit_excitation import fit_envelope
    t = np.arange(0, 30.0, 0.002)
    for T1, T2 in ((6.0, 2.5), (2.5, 1.0), (4.0, 3.0)):
        q = 4.0 * (np.exp(-t / T1) - np.exp(-t / T2))
        fit = fit_envelope(Record(q * np.sin(2 * np.pi * 37.0 * t), 0.002))
        assert fit == pytest.approx((T1, T2), rel=0.01)


SOFT = KanaiTajimi(5e-3, 8.0, 0.4, Envelope(6.0, 2.5))


@pytest.mark.slow
def test_soft_soil_envelope_times_and_pga_recovered_within_10_percent():
    """20 soft-soil records of 30 s (seed 3, as the benchmark): the median T1 and T2 within 10 % (the
    least-squares fit of the Husid curve left them -14 % and +21 %, standard errors 8 % and 12 %); the
    fitted models' median PGA within 10 %.  Measured: T1 -3 %, T2 +4 %, PGA within 4 %."""
    plan = spectral_plan(SOFT, 30.0, 200.0)
    acc, _ = ground_acceleration_samples(SOFT, plan, 3, np.arange(20))
    n = int(round(30.0 / plan.dt)) + 1
    fits_ = [fit_excitation(Record(a[:n], plan.dt)) for a in acc]
    assert np.median([f["T1"] for f in fits_]) == pytest.approx(6.0, rel=0.10)
    assert np.median([f["T2"] for f in fits_]) == pytest.approx(2.5, rel=0.10)
    cut = 2 * np.pi * 25.0
    true = pga_median(SOFT, 30.0, cut)
    pga = [pga_median(KanaiTajimi(f["S0"], f["omega_g"], f["zeta_g"], Envelope(f["T1"], f["T2"])), 30.0, cut)
           for f in fits_]
    assert np.median(pga) == pytest.approx(true, rel=0.10)
