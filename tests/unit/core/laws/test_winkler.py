"""The Winkler law with a linear dashpot (screening.core.laws.winkler): damping pressure ``c zdot``."""

import numpy as np

from screening.core.laws.winkler import WINKLER, winkler_damping


def test_the_pressure_is_linear_in_the_rate_and_independent_of_the_indentation():
    z = np.array([1e-5, 1e-4, 1e-3])
    np.testing.assert_array_equal(winkler_damping(z, 0.2, 5e4), np.full(3, 1e4))
    assert winkler_damping(1e-4, -0.2, 5e4) == -1e4


def test_the_law_is_registered_with_its_parameter_and_cf_units():
    assert (WINKLER.name, WINKLER.parameter, WINKLER.attributes["units"]) == ("winkler", "c", "N s m-2")
    assert WINKLER.damping_weights(3.0) == (3.0, 0.0)
