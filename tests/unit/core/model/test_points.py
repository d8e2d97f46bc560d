"""Model objects whose fields are broadcast together, flattened and indexed (screening.core.model.points)."""

import numpy as np

from screening.core.model import Block, Foundation
from screening.core.model.points import broadcast_shape, flatten, numeric_fields, point_key, select


def _objects():
    block = Block(m=8.67, b=np.array([0.03, 0.035, 0.04]), h=0.21)
    bed = Foundation(k=np.array([[2.0e7], [3.0e7]]), lam=8.95e8)
    return block, bed


def test_fields_broadcast_flatten_and_select_back_to_the_same_points():
    block, bed = _objects()
    assert broadcast_shape(block, bed) == (2, 3)
    (fb, ff), shape = flatten(block, bed)
    assert shape == (2, 3) and fb.b.shape == (6,) and ff.k.shape == (6,)
    np.testing.assert_array_equal(fb.b, np.tile([0.03, 0.035, 0.04], 2))
    np.testing.assert_array_equal(ff.k, np.repeat([2.0e7, 3.0e7], 3))
    point = select(ff, 4)
    assert point.k == 3.0e7 and isinstance(point.k, float)
    chunk = select(fb, slice(1, 3))
    np.testing.assert_array_equal(chunk.b, [0.035, 0.04])


def test_numeric_fields_leave_out_strings_and_unused_values():
    block, bed = _objects()
    fields = numeric_fields(block, bed)
    assert {"m", "b", "h", "k", "lam"} <= set(fields)
    assert all(not isinstance(v, str) and v is not None for v in fields.values())


def test_point_keys_are_equal_for_equal_points_only():
    a = (Block(m=1.0, b=0.1, h=0.3), Foundation(k=1e7, lam=1e8))
    b = (Block(m=1.0, b=0.1, h=0.3), Foundation(k=1e7, lam=1e8))
    c = (Block(m=1.0, b=0.1, h=0.3), Foundation(k=2e7, lam=1e8))
    assert point_key(*a) == point_key(*b) and point_key(*a) != point_key(*c)
    assert hash(point_key(*a)) == hash(point_key(*b))
