"""An excitation's shape as the random-vibration intensity measures cache it (screening.analysis._excitation_shape):
the time grid, the cache key (the same for two levels of one shape, different for another shape or length) and the
unit excitation rebuilt from a key's parameters (its PSD that of the original divided by its level)."""

import numpy as np
import pytest

from screening.analysis import _excitation_shape as shape
from screening.core.excitations.kanai_tajimi import KanaiTajimi, kanai_tajimi_psd
from screening.core.excitations.white import WhiteNoise
from screening.core.model.excitation import ConstantEnvelope, Envelope


def test_the_time_grid_spans_the_record_evenly():
    t = shape.times(8.0)
    assert (t.size, t[0], t[-1]) == (shape.N_TIMES, 0.0, 8.0)
    np.testing.assert_allclose(np.diff(t), 8.0 / (shape.N_TIMES - 1), rtol=1e-12)
    assert shape.times(2.0, 5).tolist() == [0.0, 0.5, 1.0, 1.5, 2.0]


def test_the_key_holds_the_shape_and_length_not_the_level():
    env = Envelope(4.0, 2.0)
    low, high = KanaiTajimi(1e-4, 15.0, 0.6, env), KanaiTajimi(3e-3, 15.0, 0.6, env)
    assert shape.shape_key(low, 20.0) == shape.shape_key(high, 20.0) == ("kanai_tajimi", "exponential", 4.0, 2.0, 20.0)
    assert shape.shape_key(low, 10.0) != shape.shape_key(low, 20.0)
    assert shape.shape_key(KanaiTajimi(1e-4, 15.0, 0.6, Envelope(5.0, 2.0)), 20.0) != shape.shape_key(low, 20.0)
    assert shape.shape_key(WhiteNoise(1e-4, ConstantEnvelope()), 20.0) == ("white", "constant", 20.0)


@pytest.mark.parametrize("envelope_kind", ["exponential", "constant"])
def test_the_rebuilt_excitation_has_unit_level_and_the_same_shape(envelope_kind):
    p = {"omega_g": 15.0, "zeta_g": 0.6, "T1": 4.0, "T2": 2.0}
    exc = shape.scalar_excitation("kanai_tajimi", envelope_kind, p)
    omega = np.linspace(0.0, 100.0, 11)
    np.testing.assert_allclose(exc.psd(omega), kanai_tajimi_psd(omega, 1.0, 15.0, 0.6), rtol=1e-14)
    assert exc.envelope.kind == envelope_kind
    if envelope_kind == "exponential":
        assert (exc.envelope.T1, exc.envelope.T2) == (4.0, 2.0)
