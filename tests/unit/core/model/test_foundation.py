"""The bed (screening.core.model.foundation): its checks, array fields, the distributed contact law of each damping."""

import numpy as np
import pytest

from screening.core.model import Foundation, contact_pressure


@pytest.mark.parametrize("make, name", [
    (lambda: Foundation(k=0.0, lam=1.0), "'k'"),
    (lambda: Foundation(k=1.0, lam=-1.0), "'lam'"),
    (lambda: Foundation(k=1.0, lam=1.0, eps=np.nan), "'eps'"),
    (lambda: Foundation(k=1.0, c=-2.0), "'c'"),
    (lambda: Foundation(k=np.array([1.0, -1.0]), lam=1.0), "'k'"),
])
def test_foundation_rejects_bad_values(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_parameters_may_be_arrays_that_broadcast():
    fnd = Foundation(k=2.0e7, lam=1e8, eps=np.array([-1e5, 0.0, 1e7]))
    assert fnd.eps.shape == (3,)
    assert isinstance(fnd.k, float)


def test_contact_pressure_hunt_crossley_law_and_no_tension():
    fnd = Foundation(k=2.0e7, lam=3.0e8, eps=5e6)
    z = np.array([-1e-4, 0.0, 1e-4, 2e-4])
    zd = np.array([0.3, 0.3, -0.01, 0.02])
    F = contact_pressure(z, zd, fnd)
    expected = 2.0e7 * z + 5e6 * 2.0e7 * z**3 + 3.0e8 * z * zd
    np.testing.assert_allclose(F[2:], expected[2:], rtol=1e-14)
    assert F[0] == 0.0 and F[1] == 0.0


def test_contact_pressure_winkler_uses_linear_dashpot():
    fnd = Foundation(k=2.0e7, c=1.5e3)
    F = contact_pressure(np.array([1e-4, -1e-4]), np.array([0.02, 0.02]), fnd)
    assert F[0] == pytest.approx(2.0e7 * 1e-4 + 1.5e3 * 0.02, rel=1e-14)
    assert F[1] == 0.0


def test_one_bed_type_whose_law_follows_the_damping_given():
    hc, wk = Foundation(k=2.0e7, lam=1e8), Foundation(k=2.0e7, c=1.5e3)
    assert (hc.law, wk.law) == ("hunt_crossley", "winkler") and (hc.winkler, wk.winkler) == (False, True)
    assert hc.damping == 1e8 and wk.damping == 1.5e3 and hc.c is None and wk.lam is None
    assert Foundation(k=2.0e7, c=0.0, law="winkler").damping == 0.0
    for kwargs, name in ((dict(lam=1.0, c=1.0), "'c'"), (dict(lam=1.0, law="winkler"), "'lam'"),
                         (dict(law="winkler"), "'c'"), (dict(), "'lam'"), (dict(lam=1.0, law="kelvin"), "'law'")):
        with pytest.raises(ValueError, match=name):
            Foundation(k=2.0e7, **kwargs)
