"""What the compiled sample integrators share (screening.kernels._sample_steps).

The ground input of a sample between grid points against scipy's cubic Hermite spline of the same
values and rates: each channel, its rate, the rows a sample reads (its own horizontal row; its own,
the one shared, or no vertical row), the grid's ends.  The error-norm term against its formula
written out, and the outcome store."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from screening.kernels import _sample_steps as steps

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
        v, r = steps.NO_VERTICAL, steps.NO_VERTICAL
    acc, acc_dot = (H_VAL, v), (H_RATE, r)
    for row in range(3):
        horizontal = _spline(H_VAL[row], H_RATE[row])
        vrow = {"per sample": row, "shared": 0, "none": None}[vertical]
        for t in TIMES:
            x, a_v = steps.ground_input(row, acc, acc_dot, DT, t)
            dx, da_v = steps.ground_input_rate(row, acc, acc_dot, DT, t)
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
        assert steps.ground_input(1, acc, acc_dot, DT, t) == pytest.approx((H_VAL[1, j], V_VAL[1, j]), rel=1e-12,
                                                                           abs=1e-12)
        assert steps.ground_input_rate(1, acc, acc_dot, DT, t) == pytest.approx((H_RATE[1, j], V_RATE[1, j]),
                                                                                rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("e, y, ynew, scale, rtol", [(1e-6, 0.01, -0.02, 1e-5, 1e-3), (-3.0, 0.0, 0.0, 2.0, 0.5),
                                                      (2e-9, -4.0, 1.0, 0.0, 1e-6)])
def test_the_error_term_is_the_squared_error_over_its_mixed_tolerance(e, y, ynew, scale, rtol):
    """``(e / (atol + rtol max(|y|, |ynew|)))^2``: the larger of the old and new state sets the relative part."""
    tolerance = scale + rtol * max(abs(y), abs(ynew))
    assert steps.err_term(e, y, ynew, scale, rtol) == pytest.approx((e / tolerance) ** 2, rel=1e-15)


def test_a_sample_outcome_is_stored_in_its_row_of_the_chunk_outputs():
    """The compiled helper the chunk integrators share writes the six fields of one outcome to their arrays at
    that row, keeping their dtypes, and no other row."""
    n = 3
    outs = (np.zeros(n, np.int64), np.zeros(n, np.int64), np.full(n, -1.0), np.zeros(n, np.int64),
            np.zeros(n, np.int64), np.full(n, -1.0))
    steps.store_outcome(1, (2, 5, 0.25, 17, 3, 1e-6), *outs)
    assert [a[1].item() for a in outs] == [2, 5, 0.25, 17, 3, 1e-6]
    assert [a[[0, 2]].tolist() for a in outs] == [[0, 0], [0, 0], [-1.0, -1.0], [0, 0], [0, 0], [-1.0, -1.0]]
