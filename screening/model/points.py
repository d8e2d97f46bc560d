"""Parameter points: model objects whose fields are broadcast together, flattened and indexed.

The batched solvers take model objects whose fields may be arrays; these helpers turn them into
objects with flat 1-d fields (one entry per parameter point) and pick points or chunks out of
them, so that every downstream function sees ordinary model objects.
"""

from __future__ import annotations

import copy
import dataclasses
import functools

import numpy as np

__all__ = ["numeric_fields", "broadcast_shape", "flatten", "select", "point_key"]


@functools.lru_cache(maxsize=None)
def _field_names(cls):
    return tuple(f.name for f in dataclasses.fields(cls))


def _numeric_fields(obj):
    """``{name: value}`` of the numeric dataclass fields of ``obj`` (nested model objects excluded)."""
    out = {}
    for name in _field_names(type(obj)):
        value = getattr(obj, name)
        if value is None or isinstance(value, str) or dataclasses.is_dataclass(value):
            continue
        out[name] = value
    return out


def _nested(obj):
    return {name: getattr(obj, name) for name in _field_names(type(obj))
            if dataclasses.is_dataclass(getattr(obj, name))}


def _all_arrays(obj):
    arrays = [np.asarray(v, dtype=float) for v in _numeric_fields(obj).values()]
    for sub in _nested(obj).values():
        arrays += _all_arrays(sub)
    return arrays


def _map(obj, fn):
    """A copy of ``obj`` with ``fn`` applied to every numeric field (recursively).

    ``fn`` only broadcasts or indexes values that the object has already validated, so the copy
    is not validated again (that would cost more than a small solve).
    """
    out = copy.copy(obj)
    for name, value in _numeric_fields(obj).items():
        object.__setattr__(out, name, fn(np.asarray(value, dtype=float)))
    for name, sub in _nested(obj).items():
        object.__setattr__(out, name, _map(sub, fn))
    return out


def numeric_fields(*objs):
    """``{name: value}`` of every numeric field of the model objects, nested ones included
    (``None`` and string fields, such as an unused damping or the contact law, are left out)."""
    out = {}
    for obj in objs:
        out.update(_numeric_fields(obj))
        for sub in _nested(obj).values():
            out.update(numeric_fields(sub))
    return out


def broadcast_shape(*objs):
    """The broadcast shape of every numeric field of the model objects ``objs``."""
    return np.broadcast_shapes(*(a.shape for obj in objs for a in _all_arrays(obj)))


def flatten(*objs):
    """``(flat_objs, shape)``: copies of ``objs`` whose fields are 1-d arrays over the broadcast points."""
    shape = broadcast_shape(*objs)
    flat = tuple(_map(obj, lambda a: np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1)) for obj in objs)
    return flat, shape


def select(obj, index):
    """``obj`` (flat fields) at ``index``: a slice gives a chunk, an integer a scalar point."""
    if isinstance(index, (int, np.integer)):
        return _map(obj, lambda a: float(a[index]))
    return _map(obj, lambda a: a[index])


def point_key(*objs):
    """Hashable key of scalar model objects (equal keys: the same parameter point)."""
    key = []
    for obj in objs:
        key.append(type(obj).__name__)
        key += [(name, float(v)) for name, v in sorted(_numeric_fields(obj).items())]
        key += [point_key(sub) for sub in _nested(obj).values()]
    return tuple(key)
