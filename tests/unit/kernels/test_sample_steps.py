"""The ground input of a Monte Carlo sample between grid points (screening.solvers.mcs_inputs) against
scipy's cubic Hermite spline of the same values and rates: each channel, its rate, the rows a sample
reads (its own horizontal row; its own, the one shared, or no vertical row), the grid's ends."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from screening.solvers import mcs_inputs

DT = 0.01
N_GRID = 9
RNG = np.random.default_rng(7)
H_VAL, H_RATE = RNG.normal(size=(3, N_GRID)), 50.0 * RNG.normal(size=(3, N_GRID))     # three samples
V_VAL, V_RATE = RNG.normal(size=(3, N_GRID)), 50.0 * RNG.normal(size=(3, N_GRID))
GRID = DT * np.arange(N_GRID)
#: inside intervals, on grid points (the first and last included) and a little past the last one
TIMES = np.concatenate([RNG.uniform(0.0, GRID[-1], 25), GRID, [GRID[-1] + 0.3 * DT]])


def _spline(values, rates):
    return CubicHermiteSpline(GRID, values, rates, extrapolate=True)


@pytest.mark.parametrize("vertical", ["per sample", "shared", "none"])
def test_input_and_its_rate_are_scipys_cubic_hermite_spline_of_each_channel(vertical):
    if vertical == "per sample":
        v, r = V_VAL, V_RATE
    elif vertical == "shared":
        v, r = V_VAL[:1].copy(), V_RATE[:1].copy()
    else:
        v, r = mcs_inputs.NO_VERTICAL, mcs_inputs.NO_VERTICAL
    acc, acc_dot = (H_VAL, v), (H_RATE, r)
    for row in range(3):
        horizontal = _spline(H_VAL[row], H_RATE[row])
        vrow = {"per sample": row, "shared": 0, "none": None}[vertical]
        for t in TIMES:
            x, a_v = mcs_inputs._hermite(row, acc, acc_dot, DT, t)
            dx, da_v = mcs_inputs._hermite_rate(row, acc, acc_dot, DT, t)
            assert x == pytest.approx(float(horizontal(t)), rel=1e-12, abs=1e-12)
            assert dx == pytest.approx(float(horizontal(t, 1)), rel=1e-10, abs=1e-9)
            if vrow is None:
                assert (a_v, da_v) == (0.0, 0.0)
            else:
                upright = _spline(V_VAL[vrow], V_RATE[vrow])
                assert a_v == pytest.approx(float(upright(t)), rel=1e-12, abs=1e-12)
                assert da_v == pytest.approx(float(upright(t, 1)), rel=1e-10, abs=1e-9)


def test_grid_points_give_the_grid_values_and_rates():
    acc, acc_dot = (H_VAL, V_VAL), (H_RATE, V_RATE)
    for j, t in enumerate(GRID):
        assert mcs_inputs._hermite(1, acc, acc_dot, DT, t) == pytest.approx((H_VAL[1, j], V_VAL[1, j]), rel=1e-12,
                                                                            abs=1e-12)
        assert mcs_inputs._hermite_rate(1, acc, acc_dot, DT, t) == pytest.approx((H_RATE[1, j], V_RATE[1, j]),
                                                                                 rel=1e-9, abs=1e-9)
