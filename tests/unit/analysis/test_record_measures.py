"""Intensity measures of one record: the oscillator recurrence against an independent ODE solution."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from screening.analysis.intensity import oscillator_peak, record_measures
from screening.core.records import Record


def test_oscillator_peak_against_ode_reference():
    """Ramped sine input: the Nigam-Jennings recurrence (exact for piecewise-linear input) against
    scipy's RK45 at rtol 1e-10; measured 1e-5 relative (the input's linear interpolation at dt = 1 ms)."""
    period, zeta, wf, amp, dt = 0.5, 0.05, 10.0, 2.0, 0.001
    t = np.arange(0.0, 40.0, dt)
    a = amp * np.sin(wf * t) * np.minimum(t / 10.0, 1.0) ** 2
    w = 2 * math.pi / period
    ref = solve_ivp(lambda s, y: [y[1], -2 * zeta * w * y[1] - w * w * y[0]
                                  - amp * math.sin(wf * s) * min(s / 10.0, 1.0) ** 2],
                    (0.0, 40.0), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=0.01)
    peak = oscillator_peak(a, dt, period, zeta)[0]
    assert peak == pytest.approx(np.max(np.abs(ref.y[0])), rel=1e-4)
    steady = amp / math.sqrt((w * w - wf * wf) ** 2 + (2 * zeta * w * wf) ** 2)
    assert np.max(np.abs(ref.y[0][t > 30])) == pytest.approx(steady, rel=1e-4)
    m = record_measures(Record(a, dt), period=period)
    assert m["pga"] == pytest.approx(amp, rel=1e-6)
    assert m["sa"] == pytest.approx(w * w * peak)
    assert m["arias_intensity"] == pytest.approx(math.pi / (2 * 9.80665) * np.trapezoid(a * a, dx=dt))
