"""The Monte Carlo tolerance rule (``rtol="auto"``) and the in-step peak of ``|theta|``.

* :func:`~screening.solvers.montecarlo.auto_rtol`: the rule ``rtol_0 min(1, sqrt(n_0 / n))`` and its use by
  :func:`~screening.solvers.montecarlo.monte_carlo` (recorded in ``attrs["rtol"]``; ``rtol=None`` keeps the
  fixed per-model tolerance).
* :func:`~screening.kernels.mcs_kernels.step_peak` against a dense evaluation of the same cubic Hermite
  interpolant (numpy, 20,001 points) and against a closed-form peak (a sine).
* The default tolerance's bias against ``rtol = 1e-10`` on the same samples (slow): within a tenth of
  the plain standard error at the rule's sample count, checked at two paired SEs.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from screening.core.model import Block, Foundation
from screening.core.model.excitation import Envelope
from screening.core.excitations.white import WhiteNoise
from screening.kernels import mcs_kernels as kern
from screening.solvers import montecarlo as mc

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)


def test_auto_rtol_rule():
    base, n0 = mc.AUTO_RTOL["coupled"], mc.AUTO_RTOL_SAMPLES
    assert mc.auto_rtol("coupled", 2) == base == mc.auto_rtol("coupled", n0)
    assert mc.auto_rtol("coupled", 4 * n0) == pytest.approx(base / 2, rel=1e-12)
    assert mc.auto_rtol("coupled", 100 * n0) == pytest.approx(base / 10, rel=1e-12)
    assert mc.auto_rtol("condensed", 10**6) == mc.DEFAULT_RTOL["condensed"]     # no measured rule: fixed
    assert mc.auto_rtol(mc.mc_registry.get("coupled"), n0) == base


@pytest.mark.parametrize("rtol,expected", [("auto", None), (None, "fixed"), (3e-6, 3e-6)])
def test_monte_carlo_records_the_tolerance(rtol, expected):
    ds = mc.monte_carlo(BLOCK, BED, WhiteNoise(1e-5, envelope=Envelope(0.5, 0.25)), n_samples=3, t_end=0.5, dt=0.25,
                        rtol=rtol, progress=False)
    want = {None: mc.auto_rtol("coupled", 3), "fixed": mc.DEFAULT_RTOL["coupled"]}.get(expected, expected)
    assert ds.attrs["rtol"] == want


@pytest.mark.parametrize("rtol", ["tight", -1e-6, float("nan")])
def test_bad_rtol_is_refused(rtol):
    with pytest.raises(ValueError, match="parameter 'rtol'"):
        mc.monte_carlo(BLOCK, BED, WhiteNoise(1e-5), n_samples=3, t_end=0.5, dt=0.25, rtol=rtol)


def _dense_hermite_peak(h, theta0, rate0, theta1, rate1, n=20_001):
    s = np.linspace(0.0, 1.0, n)
    p = ((2 * s**3 - 3 * s**2 + 1) * theta0 + (s**3 - 2 * s**2 + s) * h * rate0
         + (3 * s**2 - 2 * s**3) * theta1 + (s**3 - s**2) * h * rate1)
    return float(np.max(np.abs(p)))


def test_step_peak_matches_dense_interpolant():
    rng = np.random.default_rng(4)
    for _ in range(400):
        h = 10 ** rng.uniform(-5, -2)
        theta0, theta1 = rng.normal(0, 1e-2, 2)
        rate0, rate1 = rng.normal(0, 1.0, 2)
        got = kern.step_peak(0.0, h, theta0, rate0, theta1, rate1)
        dense = _dense_hermite_peak(h, theta0, rate0, theta1, rate1)
        if rate0 * rate1 < 0:          # an extremum inside: the dense grid finds it to (h rate / n)^2
            assert max(got, abs(theta0)) == pytest.approx(dense, rel=1e-7, abs=1e-12)   # the start: previous step
        else:                          # monotone step: the end value (the start was the previous step's end)
            assert got == abs(theta1)
    assert kern.step_peak(0.5, 1e-3, 0.1, 1.0, 0.1, -1.0) == 0.5         # an earlier peak stays


@pytest.mark.parametrize("h", [0.01, 0.02, 0.04])
def test_step_peak_of_a_sine(h):
    """theta = sin(w t), w = 20 rad/s, a step straddling the crest: the end points miss 1 by (w h)^2 / 8,
    the interpolant by O((w h)^4); the error falls 16x per halving of h."""
    w, t0 = 20.0, math.pi / 40 - 0.3 * h
    t1 = t0 + h
    got = kern.step_peak(0.0, h, math.sin(w * t0), w * math.cos(w * t0), math.sin(w * t1), w * math.cos(w * t1))
    ends = max(math.sin(w * t0), math.sin(w * t1))
    assert 1.0 - ends > 0.02 * (w * h) ** 2                  # the end points do miss the crest
    assert abs(got - 1.0) <= (w * h) ** 4 / 100             # the interpolant does not (measured ~1/384)


@pytest.mark.slow
def test_default_bias_within_a_tenth_of_the_sampling_error():
    """The coupled model at ``rtol="auto"`` (``AUTO_RTOL`` at up to ``AUTO_RTOL_SAMPLES`` samples) against
    ``rtol = 1e-10`` on the same 96 samples (seed 5), the paper block at moderate uplift: every statistic of
    ``benchmarks/bench_mc_tolerance.py`` within ``|bias| <= 0.1 SE(n_0) + 3 SE(bias)`` (``SE(n_0)``: the plain
    standard error scaled from 96 samples to ``n_0``; ``SE(bias)``: the paired jackknife SE of the bias,
    so the check fails by chance with probability about 0.1 % per statistic)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
    import bench_mc_tolerance as bench

    block, bed, exc = bench.CASES["paper white moderate (p_ul 0.3)"]
    n = 96
    runs = {}
    for rtol in ("auto", 1e-10):
        ds, _ = bench.run(block, bed, exc, n, 5, rtol=rtol)
        runs[rtol] = bench.sample_arrays(ds)
    assert ds.attrs["rtol"] == 1e-10
    bias = bench.paired_bias(runs["auto"], runs[1e-10], bench.peak_levels(runs[1e-10]))
    scale = math.sqrt(n / mc.AUTO_RTOL_SAMPLES)
    for name, (b, b_se, se) in bias.items():
        assert abs(b) <= 0.1 * se * scale + 3.0 * b_se, (name, b, b_se, se * scale)
    assert bias["peak var_theta"][2] > 0 and bias["E[peak]"][2] > 0      # the statistics do vary
