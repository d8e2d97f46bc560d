"""The excitation interface (screening.core.excitations.base): a shaping filter's PSD and its stationary
covariance, each checked against an independent computation."""

import numpy as np
import pytest
from scipy import integrate, linalg

from screening.core.excitations.base import Filter, stationary_covariance, transfer_psd


def _filter():
    """A stable two-state filter with a direct term (not Kanai-Tajimi: any filter must do)."""
    return Filter(np.array([[0.0, 1.0], [-40.0, -3.0]]), np.array([0.0, 2.0]), np.array([-5.0, 1.0]), np.array(0.5))


def test_the_transfer_psd_is_s0_times_the_squared_gain():
    f, s0 = _filter(), 0.02
    for w in (0.0, 3.0, 6.3, 50.0):
        s = 1j * w
        gain = (f.C[0] * f.B[1] + f.C[1] * s * f.B[1]) / (s * s + 3.0 * s + 40.0) + 0.5   # by hand
        assert transfer_psd(f, s0, w) == pytest.approx(s0 * abs(gain) ** 2, rel=1e-12)


def test_the_stationary_covariance_solves_the_lyapunov_equation_and_matches_the_spectrum():
    f, s0 = _filter(), 0.02
    p = stationary_covariance(f, s0)
    q = 2 * np.pi * s0 * np.outer(f.B, f.B)
    np.testing.assert_allclose(p, linalg.solve_continuous_lyapunov(f.A, -q), rtol=1e-12, atol=1e-14 * np.abs(p).max())
    # the variance of the strictly proper part C x equals the integral of its PSD over all frequencies
    proper = Filter(f.A, f.B, f.C, np.array(0.0))
    var = 2 * integrate.quad(lambda w: transfer_psd(proper, s0, w), 0, np.inf, limit=400)[0]
    assert f.C @ p @ f.C == pytest.approx(var, rel=1e-7)


def test_the_covariance_is_batched_over_leading_axes():
    f = _filter()
    batch = Filter(np.stack([f.A, 2 * f.A]), np.stack([f.B, f.B]), np.stack([f.C, f.C]), np.array([0.5, 0.5]))
    p = stationary_covariance(batch, np.array([0.02, 0.02]))
    np.testing.assert_allclose(p[0], stationary_covariance(f, 0.02), rtol=1e-13)
    np.testing.assert_allclose(p[1], stationary_covariance(Filter(2 * f.A, f.B, f.C, f.D), 0.02), rtol=1e-13)
