"""fit-excitation recovers the parameters of synthesised Kanai-Tajimi records.

20 records of 30 s (seed 3, fixed).  Measured: medians of the estimates -3 % (omega_g), +5 %
(zeta_g), -9 % (T1), +5 % (T2); the fitted models' RVT median PGA -3 % (median over records) of the
true model's.  Tolerances below are about twice the measured errors (the median of 20 records
has a sampling error of roughly 1.25 x the single-record scatter / sqrt(20): 5-8 %).
"""

import numpy as np
import pytest

from screening.analysis.fit_excitation import excitation_table, fit_excitation
from screening.analysis.intensity import pga_median
from screening.model.excitation import Envelope, KanaiTajimi, WhiteNoise
from screening.records import Record
from screening.solvers.synthesis import ground_acceleration_samples, spectral_plan
from screening.workflow.study import parse_study

TRUE = KanaiTajimi(2e-3, 15.0, 0.6, Envelope(4.0, 2.0))


@pytest.fixture(scope="module")
def fits():
    plan = spectral_plan(TRUE, 30.0, 200.0)
    acc, _ = ground_acceleration_samples(TRUE, plan, 3, np.arange(20))
    n = int(round(30.0 / plan.dt)) + 1
    return [fit_excitation(Record(a[:n], plan.dt)) for a in acc]


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


def test_white_noise_energy_and_table(fits):
    plan = spectral_plan(WhiteNoise(1e-3), 20.0, 60.0)
    acc, _ = ground_acceleration_samples(WhiteNoise(1e-3), plan, 0, np.arange(10))
    n = int(round(20.0 / plan.dt)) + 1
    s0 = [fit_excitation(Record(a[:n], plan.dt), kind="white", cutoff=60.0)["S0"] for a in acc]
    assert np.median(s0) > 0
    with pytest.raises(ValueError, match="cutoff"):
        fit_excitation(Record(acc[0][:n], plan.dt), kind="white")
    text = excitation_table(fits[0])
    study = parse_study("[block]\nm = 1.0\nb = 0.1\nh = 0.3\n[foundation]\nk = 1e8\nlam = 1e9\n" + text)
    assert study.cases[0].excitation == "kanai_tajimi"
    assert study.cases[0].params["omega_g"] == pytest.approx(fits[0]["omega_g"], rel=1e-5)
