"""The Python API refuses bad arguments with one ValueError naming the parameter and its bound, before any
work or allocation (no ZeroDivisionError, SystemError, MemoryError or silent acceptance)."""

import numpy as np
import pytest

from screening import linearize, monte_carlo, simulate
from screening.core.model import Block, Foundation
from screening.core.model.excitation import Envelope
from screening.core.excitations.white import WhiteNoise
from screening.core.records import Record
from screening.solvers.moments import solve_moments
from screening.core import limits

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
WHITE = WhiteNoise(S0=2.4e-5, envelope=Envelope(4.0, 2.0))
RECORD = Record(0.1 * np.sin(np.linspace(0.0, 6.0, 201)), 0.01, name="sine")


@pytest.fixture
def no_work(monkeypatch):
    """Any integration reached is a failure of the check."""
    import screening.kernels.mcs_kernels as kern
    import screening.solvers.moments as moments

    def boom(*args, **kwargs):
        raise AssertionError("work started before the check")

    monkeypatch.setattr(kern, "chunk_integrator", boom)
    monkeypatch.setattr(moments, "batch_solver", boom)


@pytest.mark.parametrize("kwargs,match", [
    (dict(rtol=0.0), r"'rtol' must be a finite number > 0 and <= 0.01 \(got 0.0\)"),
    (dict(rtol=-1.0), r"'rtol' must be a finite number > 0"),
    (dict(rtol=True), r"'rtol' must be"),
    (dict(t_end=1e6, dt=1e-3), r"'dt': t_end / dt = 1e\+09 output steps; at most 100000"),
])
def test_linearize(no_work, kwargs, match):
    with pytest.raises(ValueError, match=match):
        linearize(BLOCK, BED, WHITE, **kwargs)


def test_solve_moments_history_memory_is_bounded(no_work, monkeypatch):
    monkeypatch.setattr(limits, "MAX_HISTORY_VALUES", 1000)
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=np.array([0.0, 6e7]))
    with pytest.raises(ValueError, match=r"'t_out' asks for 2.41e\+03 history values \(2 points x 201"):
        solve_moments(BLOCK, bed, WHITE, np.linspace(0.0, 10.0, 201))
    with pytest.raises(ValueError, match="'max_steps' must be an integer >= 1"):
        solve_moments(BLOCK, BED, WHITE, np.linspace(0.0, 10.0, 201), max_steps=-1)


@pytest.mark.parametrize("kwargs,match", [
    (dict(rtol=0.0), "'rtol' must be a finite number > 0 and <= 0.01"),
    (dict(max_steps=-1), "'max_steps' must be an integer >= 1"),
    (dict(max_steps=1.5), "'max_steps' must be an integer >= 1"),
    (dict(overturn_resolution=0), r"'overturn_resolution' must be an integer in 1..100000"),
    (dict(output_dt=1e-9), r"'output_dt': t_end / output_dt = 2e\+09 steps; at most 1999999"),
    (dict(t_end=1e6), r"'t_end': t_end / dt = 1e\+08 steps"),
    (dict(t_end=float("nan")), "'t_end' must be a finite number > 0"),
    (dict(theta0=np.datetime64("2020-01-01")), "'theta0' must be a finite number"),
    (dict(max_flight_time=0.0), "'max_flight_time' must be a finite number > 0"),
])
def test_simulate(no_work, kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(BLOCK, BED, RECORD, **kwargs)


def test_simulate_refuses_array_fields(no_work):
    with pytest.raises(ValueError, match=r"'foundation.eps' must be a scalar for simulate \(got an array of shape"):
        simulate(BLOCK, Foundation(k=2.89e7, lam=8.95e8, eps=np.array([0.0, 6e7])), RECORD)


def test_monte_carlo_memory_is_bounded_before_allocation(no_work):
    with pytest.raises(ValueError, match=r"'n_samples' asks for 1e\+09 samples; at most 1e\+06"):
        monte_carlo(BLOCK, BED, WHITE, n_samples=10**9)
    with pytest.raises(ValueError, match=r"'n_samples' asks for 2e\+08 samples x output instants"):
        monte_carlo(BLOCK, BED, WHITE, n_samples=500_000, t_end=20.0, dt=0.05)


@pytest.mark.parametrize("value", [True, np.True_, np.datetime64("2020-01-01T00:00:00", "ns"),
                                   np.timedelta64(5, "s"), np.array([True, False])])
def test_booleans_and_dates_are_not_numbers(value):
    with pytest.raises(ValueError, match="parameter 'S0' must be a finite number > 0"):
        WhiteNoise(S0=value)
