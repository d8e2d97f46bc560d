"""The registry of condensations: a name is turned into a :class:`~screening.condensation.base.Condensation`
once, at set-up (study parsing, ``linearize``, ``monte_carlo``); nothing downstream looks at the name."""

from __future__ import annotations

from screening.condensation.base import Condensation
from screening.registry import Registry

__all__ = ["unregister", "names", "get", "register"]

_REGISTRY = Registry("condensation", lambda item: isinstance(item, Condensation))

#: Remove a registered condensation (tests that register their own).
unregister = _REGISTRY.remove
#: Registered names, in registration order.
names = _REGISTRY.names
#: The :class:`Condensation` for a registered name (an instance is returned as it is); ``ValueError``
#: naming the parameter and the registered names otherwise.
get = _REGISTRY.get


def register(condensation):
    """Add a :class:`Condensation` instance under its ``name`` (a later one with the same name replaces it)."""
    if not isinstance(condensation, Condensation):
        raise TypeError(f"register() takes a Condensation instance (got {type(condensation).__name__})")
    return _REGISTRY.add(condensation.name, condensation)
