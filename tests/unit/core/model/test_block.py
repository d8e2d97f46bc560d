"""The rigid block (screening.core.model.block): its inertia, slenderness and bounded, checked fields."""

import math

import numpy as np
import pytest

from screening.core.model import Block


def test_block_default_inertia_is_uniform_rectangle():
    blk = Block(m=2.0, b=0.1, h=0.3)
    # rectangle 2b x 2h: m ((2b)^2 + (2h)^2) / 12
    assert blk.I_cm == pytest.approx(2.0 * (0.2**2 + 0.6**2) / 12.0, rel=1e-14)
    assert blk.m_sdof == pytest.approx(blk.I_cm + 2.0 * 0.3**2, rel=1e-14)
    assert blk.slenderness == pytest.approx(math.atan(0.1 / 0.3), rel=1e-14)


@pytest.mark.parametrize("kwargs, name", [
    (dict(m=0.0, b=0.1, h=0.3), "'m'"),
    (dict(m=-1.0, b=0.1, h=0.3), "'m'"),
    (dict(m=1.0, b=np.nan, h=0.3), "'b'"),
    (dict(m=1.0, b=0.1, h=np.inf), "'h'"),
    (dict(m=1.0, b=0.1, h=0.3, I_cm=-1.0), "'I_cm'"),
    (dict(m="heavy", b=0.1, h=0.3), "'m'"),
    (dict(m=1.0, b=0.1, h=0.3, g=0.0), "'g'"),
    # lengths beyond float64 in the condensation: ZeroDivisionError / OverflowError before the bounds
    (dict(m=1.0, b=1e-171, h=0.3), "'b'"),
    (dict(m=1.0, b=1e150, h=0.3), "'b'"),
    (dict(m=1.0, b=0.1, h=1e150), "'h'"),
    (dict(m=1.0, b=np.array([0.1, 2e3]), h=0.3), "'b'"),
])
def test_block_rejects_bad_values_naming_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name) as err:
        Block(**kwargs)
    assert "must be" in str(err.value)


def test_block_lengths_are_bounded_with_the_range_in_the_message():
    from screening.core.model.block import LENGTH_RANGE

    with pytest.raises(ValueError, match=r"parameter 'b' must be a length in 1e-06\.\.1000 m \(got 1e-171\)"):
        Block(m=1.0, b=1e-171, h=0.3)
    low, high = LENGTH_RANGE
    for b, h in ((low, 0.3), (high, 0.3), (0.1, low), (0.1, high)):     # the ends are valid
        assert Block(m=1.0, b=b, h=h).b == b
