"""The linearization's per-point indicators (screening.analysis.indicators), read by the trust rules."""

import numpy as np
import pytest

from screening.analysis import indicators, trust


def test_trust_indicators():
    out = indicators.trust_indicators(0.2, 5.0, 10.0, 4e-6, 0.1, 1e-6, 1e-3)
    assert out["k_eq_margin"] == pytest.approx(0.5)
    assert out["sigma_ratio"] == pytest.approx(2e-3 / 0.1)
    assert out["decay_excess"] == pytest.approx(0.25 / 1e-3)
    # the trust module serves the same functions
    assert trust.trust_indicators is indicators.trust_indicators
    assert trust.indicators_from_dataset is indicators.indicators_from_dataset


def test_envelope_fraction_is_the_envelope_at_the_end_over_its_peak():
    import xarray as xr

    t = np.linspace(0.0, 20.0, 401)
    ds = xr.Dataset(coords={"t": t, "T1": 4.0, "T2": 2.0})
    # independent: q(t) = 4 (exp(-t/T1) - exp(-t/T2)) peaks at t* = ln(T1/T2) T1 T2 / (T1 - T2) = 4 ln 2
    q = lambda x: 4.0 * (np.exp(-x / 4.0) - np.exp(-x / 2.0))              # noqa: E731
    peak = q(4.0 * np.log(2.0))
    assert float(indicators.envelope_fraction(ds)) == pytest.approx(q(20.0) ** 2 / peak**2, rel=1e-3)   # the 0.05 s grid misses the peak by < 1e-3
    assert float(indicators.envelope_fraction(ds.assign_attrs(envelope="constant"))) == 1.0
