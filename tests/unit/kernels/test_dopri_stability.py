"""Linear stability of the shared Dormand–Prince pair (:mod:`screening.kernels.dopri`).

``stability_function`` is checked against ``exp(z)`` (its error must shrink as ``|z|^6``: a 5th-order
solution), and ``stability_bound`` against fixed steps of the tableau on a damped oscillator, an
independent time-stepping of the same linear mode: just below the bound its amplitude decays, just
above it grows.
"""

import math

import numpy as np
import pytest

from screening.kernels import dopri


def test_stability_function_is_fifth_order():
    """|R(z) - e^z| ~ C |z|^6: halving z divides the error by 2^6 = 64 (within 10 %)."""
    for angle in (0.3, 1.5, 2.6):
        z = 0.1 * complex(math.cos(angle), math.sin(angle))
        ratio = abs(dopri.stability_function(z) - np.exp(z)) / abs(dopri.stability_function(z / 2) - np.exp(z / 2))
        assert ratio == pytest.approx(64.0, rel=0.1)


def oscillator_growth(zeta, h_omega, n_steps=3000):
    """Amplitude ratio after ``n_steps`` fixed steps of the tableau on ``x'' + 2 zeta x' + x = 0`` (w = 1)."""
    a = np.pad(dopri.A, ((0, 0), (0, 1)))
    jac = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    y = np.array([1.0, 0.0])
    start = np.linalg.norm(y)
    for _ in range(n_steps):
        k = np.zeros((6, 2))
        for s in range(6):
            k[s] = jac @ (y + h_omega * a[s] @ k)
        y = y + h_omega * dopri.B @ k
        if np.linalg.norm(y) > 1e3 * start:                 # grown: no need to go on
            break
    return np.linalg.norm(y) / start


@pytest.mark.parametrize("zeta", [0.06, 0.3, 3.0])
def test_stability_bound_against_time_stepping(zeta):
    """Below the bound (0.97 x) the mode decays under the steps; above it (1.03 x) it grows."""
    bound = dopri.stability_bound(zeta)
    assert oscillator_growth(zeta, 0.97 * bound) < 1.0
    assert oscillator_growth(zeta, 1.03 * bound) > 10.0


def test_stability_bound_values():
    """The real-axis bound of DOPRI5 (about 3.31 = |h lambda| on a real root) and the lightly damped case
    lie where the bound of the scanned ray says: ``|R|`` is 1 there to the bisection's accuracy."""
    overdamped = dopri.stability_bound(1.0)
    assert abs(dopri.stability_function(-overdamped)) == pytest.approx(1.0, abs=1e-9)
    light = dopri.stability_bound(0.06)
    z = light * complex(-0.06, math.sqrt(1 - 0.06**2))
    assert abs(dopri.stability_function(z)) == pytest.approx(1.0, abs=1e-9)
    assert 2.0 < light < overdamped
