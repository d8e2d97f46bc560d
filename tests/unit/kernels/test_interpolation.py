"""Piecewise-cubic tables: per-interval coefficients and the octave grid's bit-level lookup."""

import numba
import numpy as np
import pytest

from screening.kernels.interpolation import (cubic, cubic_coefficients, octave_first, octave_grid, octave_position,
                                             octave_position_jit)

E_LO, E_HI, BITS = -7, 5, 4


@numba.njit
def _positions(x, first, bits):
    j = np.empty(x.size, dtype=np.int64)
    s = np.empty(x.size)
    for i in range(x.size):
        j[i], s[i] = octave_position_jit(x[i], first, bits)
    return j, s


@numba.njit
def _lookup(table, j, s):
    return cubic(table, j, 0, s)


def test_octave_grid_spacing_is_a_fixed_fraction_of_each_octave():
    x = octave_grid(E_LO, E_HI, BITS)
    assert x.size == (E_HI - E_LO) * 2**BITS + 1
    assert x[0] == 2.0**E_LO and x[-1] == 2.0**E_HI
    rel = np.diff(x) / x[:-1]
    assert rel.min() == pytest.approx(2.0 ** -(BITS + 1), rel=0.07) and rel.max() == 2.0**-BITS


def test_compiled_octave_position_matches_the_numpy_reference():
    rng = np.random.default_rng(0)
    x = np.concatenate([2.0 ** rng.uniform(E_LO - 3, E_HI + 3, 5000), octave_grid(E_LO, E_HI, BITS)])
    j_ref, s_ref = octave_position(x, E_LO, BITS)
    j, s = _positions(x, octave_first(E_LO, BITS), BITS)
    np.testing.assert_array_equal(j, j_ref)
    np.testing.assert_array_equal(s, s_ref)
    nodes = octave_grid(E_LO, E_HI, BITS)
    inside = (j >= 0) & (j < nodes.size - 1)
    np.testing.assert_allclose(nodes[j[inside]] + s[inside] * (nodes[j[inside] + 1] - nodes[j[inside]]), x[inside],
                               rtol=1e-15)
    assert np.all((j < 0) == (x < 2.0**E_LO))


def test_nonpositive_and_non_finite_arguments_fall_outside_the_grid():
    j, _ = _positions(np.array([0.0, -0.0, -1.0, -np.inf, np.inf, np.nan]), octave_first(E_LO, BITS), BITS)
    n = (E_HI - E_LO) * 2**BITS
    assert np.all(j[:4] < 0) and np.all(j[4:] >= n)


def test_cubic_coefficients_on_an_octave_grid_reproduce_a_smooth_function():
    x = octave_grid(E_LO, E_HI, BITS)
    table = cubic_coefficients(np.log(x)[:, None], (1.0 / x)[:, None], np.diff(x))
    probe = 2.0 ** np.linspace(E_LO + 0.01, E_HI - 0.01, 777)
    j, s = octave_position(probe, E_LO, BITS)
    got = np.array([_lookup(table, jj, ss) for jj, ss in zip(j, s)])
    # cubic Hermite error h^4 max|f''''| / 384 with h = 2^-BITS x, f'''' = -6 / x^4
    np.testing.assert_allclose(got, np.log(probe), rtol=0, atol=6.0 / 384.0 * 2.0 ** (-4 * BITS) * 1.01)
    assert np.max(np.abs(got - np.log(probe))) > 1e-9          # the check could fail
