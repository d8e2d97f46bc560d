"""A name -> model registry, one per model axis (condensations, contact laws, excitations).

A model is looked up by name once, at set-up; the registry refuses an unknown name with the
registered ones (``parameter '<axis>' must be one of (...) (got ...)``).
"""

from __future__ import annotations

import collections.abc

__all__ = []


class NamedModel:
    """Mixin of the registered model objects (condensations, contact laws, Monte Carlo models): equal when
    of the same class with the same state (a copy sent to a worker equals the original), hashed by class and
    ``name``, shown as ``<{axis} {name!r}>`` with the class attribute ``axis``."""

    axis = "model"
    name = ""

    def __eq__(self, other):
        return type(other) is type(self) and other.__dict__ == self.__dict__

    def __hash__(self):
        return hash((type(self), self.name))

    def __repr__(self):
        return f"<{self.axis} {self.name!r}>"


class Registry:
    """Registered models of one axis, in registration order.

    ``parameter``: the name of the argument that selects a model (in error messages);
    ``is_model``: ``is_model(x)`` true for an object :meth:`get` hands back unchanged (an instance).
    """

    def __init__(self, parameter, is_model=lambda item: False):
        self.parameter = parameter
        self._is_model = is_model
        self._items = {}

    def add(self, name, item):
        """Register ``item`` under ``name`` (a later one with the same name replaces it); returns it."""
        self._items[name] = item
        return item

    def remove(self, name):
        """Remove a registered name (tests that register their own)."""
        self._items.pop(name, None)

    def names(self):
        """Registered names, in registration order."""
        return tuple(self._items)

    def values(self):
        """Registered models, in registration order."""
        return tuple(self._items.values())

    def get(self, key):
        """The model registered as ``key`` (a model object is returned as it is); ``ValueError`` otherwise."""
        if self._is_model(key):
            return key
        if isinstance(key, str) and key in self._items:
            return self._items[key]
        raise ValueError(f"parameter '{self.parameter}' must be one of {self.names()} (got {key!r})")


class Live(collections.abc.Mapping):
    """A mapping read from ``build()`` each time it is used: a table derived from registries, never a snapshot."""

    def __init__(self, build):
        self._build = build

    def __getitem__(self, key):
        return self._build()[key]

    def __iter__(self):
        return iter(self._build())

    def __len__(self):
        return len(self._build())

    def __repr__(self):
        return repr(self._build())


class LiveTuple(collections.abc.Sequence):
    """A tuple read from ``build()`` each time it is used (the names of a registry and the like)."""

    def __init__(self, build):
        self._build = build

    def __getitem__(self, index):
        return tuple(self._build())[index]

    def __len__(self):
        return len(tuple(self._build()))

    def __eq__(self, other):
        return tuple(self._build()) == (tuple(other) if isinstance(other, (tuple, LiveTuple)) else other)

    __hash__ = None

    def __add__(self, other):
        return tuple(self._build()) + tuple(other)

    def __repr__(self):
        return repr(tuple(self._build()))
