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

__all__ = []


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
    (``None`` and string fields, such as an unused damping or the contact law, are left out).

    A later object's field overwrites an earlier one of the same name.

    Parameters
    ----------
    *objs : dataclass
        Model objects (:class:`~screening.core.model.Block`, :class:`~screening.core.model.Foundation`, an
        excitation, ...), each field a float or an array in its SI unit.

    Returns
    -------
    dict
        ``{field name: value}``, the values as stored (floats or arrays, SI units).

    References
    ----------
    .. [1] screening documentation, "Models", docs/models.md.
    """
    out = {}
    for obj in objs:
        out.update(_numeric_fields(obj))
        for sub in _nested(obj).values():
            out.update(numeric_fields(sub))
    return out


def broadcast_shape(*objs):
    """The broadcast shape of every numeric field of the model objects ``objs``.

    Parameters
    ----------
    *objs : dataclass
        Model objects whose fields are floats or arrays (nested model objects included).

    Returns
    -------
    tuple of int
        The numpy broadcast shape of all their fields (``()`` when every field is a scalar).

    References
    ----------
    .. [1] C. R. Harris et al., "Array programming with NumPy", Nature 585 (2020) 357-362
       (broadcasting).
    .. [2] screening documentation, "Models", docs/models.md.
    """
    return np.broadcast_shapes(*(a.shape for obj in objs for a in _all_arrays(obj)))


def flatten(*objs):
    """``(flat_objs, shape)``: copies of ``objs`` whose fields are 1-d arrays over the broadcast points.

    Every numeric field is broadcast to :func:`broadcast_shape` and raveled (C order), so point ``i``
    of every field belongs together; ``shape`` restores the grid (``values.reshape(shape)``).  The
    copies are not validated again (their values were checked when the objects were made).

    Parameters
    ----------
    *objs : dataclass
        Model objects whose fields are floats or arrays.

    Returns
    -------
    flat_objs : tuple of dataclass
        One copy per object, every numeric field a contiguous 1-d float array of ``prod(shape)``
        points (units unchanged, SI).
    shape : tuple of int
        The broadcast shape of the points.

    References
    ----------
    .. [1] C. R. Harris et al., "Array programming with NumPy", Nature 585 (2020) 357-362
       (broadcasting).
    .. [2] screening documentation, "Models", docs/models.md.
    """
    shape = broadcast_shape(*objs)
    flat = tuple(_map(obj, lambda a: np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1)) for obj in objs)
    return flat, shape


def select(obj, index):
    """``obj`` (flat fields) at ``index``: a slice gives a chunk, an integer a scalar point.

    Parameters
    ----------
    obj : dataclass
        A model object with 1-d fields (:func:`flatten`).
    index : int or slice or array_like of int
        The point(s) to take [-].

    Returns
    -------
    dataclass
        A copy of ``obj``: fields of Python floats for an integer ``index``, arrays otherwise
        (units unchanged, SI).

    References
    ----------
    .. [1] screening documentation, "Models", docs/models.md.
    """
    if isinstance(index, (int, np.integer)):
        return _map(obj, lambda a: float(a[index]))
    return _map(obj, lambda a: a[index])


def point_key(*objs):
    """Hashable key of scalar model objects (equal keys: the same parameter point).

    The key holds each object's class name and its numeric fields sorted by name, as floats
    (nested objects in turn), so objects made with ``0.21`` and ``np.float64(0.21)`` share a key.

    Parameters
    ----------
    *objs : dataclass
        Model objects with scalar fields (:func:`select` with an integer).

    Returns
    -------
    tuple
        ``(class name, (field, value), ..., <nested keys>)`` per object, values in SI units.

    References
    ----------
    .. [1] screening documentation, "Models", docs/models.md.
    """
    key = []
    for obj in objs:
        key.append(type(obj).__name__)
        key += [(name, float(v)) for name, v in sorted(_numeric_fields(obj).items())]
        key += [point_key(sub) for sub in _nested(obj).values()]
    return tuple(key)
