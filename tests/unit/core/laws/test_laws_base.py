"""The contact-law interface (screening.core.laws.base): a law's damping is ``zdot (w_rate + w_indentation z)``."""

import numpy as np
import pytest

from screening.core.laws import registry
from screening.core.laws.base import DAMPING_FIELDS, ContactLaw
from screening.core.model import Foundation


@pytest.mark.parametrize("name", ["hunt_crossley", "winkler"])
def test_every_registered_law_is_its_weighted_sum_of_the_basis_pressures(name):
    law = registry.get(name)
    assert isinstance(law, ContactLaw) and law.parameter in DAMPING_FIELDS
    rng = np.random.default_rng(3)
    z, z_dot, coefficient = rng.uniform(1e-6, 1e-3, 20), rng.normal(0, 0.1, 20), 7.5e8
    w_rate, w_ind = law.damping_weights(coefficient)
    np.testing.assert_allclose(law.damping_pressure(z, z_dot, coefficient), z_dot * (w_rate + w_ind * z), rtol=1e-14)


def test_the_weights_of_a_foundation_come_from_the_field_its_law_names():
    bed = Foundation(k=2.89e7, lam=np.array([1e8, 2e8]))
    w_rate, w_ind = registry.get(bed.law).weights(bed)
    np.testing.assert_array_equal(w_ind, [1e8, 2e8])
    np.testing.assert_array_equal(w_rate, [0.0, 0.0])
