"""The Hunt-Crossley law (screening.core.laws.hunt_crossley): damping pressure ``lam z zdot`` (eq. 4)."""

import numpy as np

from screening.core.laws.hunt_crossley import HUNT_CROSSLEY, hunt_crossley_damping


def test_the_pressure_grows_with_the_indentation_and_vanishes_without_it():
    assert hunt_crossley_damping(2e-4, 0.05, 8.95e8) == 8.95e8 * 2e-4 * 0.05
    assert hunt_crossley_damping(0.0, 0.05, 8.95e8) == 0.0
    assert np.shape(hunt_crossley_damping(np.ones(3), 0.1, 1.0)) == (3,)


def test_the_law_is_registered_with_its_parameter_and_cf_units():
    assert (HUNT_CROSSLEY.name, HUNT_CROSSLEY.parameter, HUNT_CROSSLEY.attributes["units"]) == \
        ("hunt_crossley", "lam", "N s m-3")
    assert HUNT_CROSSLEY.damping_weights(3.0) == (0.0, 3.0)
