"""The registry of condensations: a name is turned into a :class:`~screening.condensation.base.Condensation`
once, at set-up (study parsing, ``linearize``, ``monte_carlo``); nothing downstream looks at the name."""

from __future__ import annotations

from screening.condensation.base import Condensation

_REGISTRY: dict[str, Condensation] = {}


def register(condensation):
    """Add a :class:`Condensation` instance under its ``name`` (a later one with the same name replaces it)."""
    if not isinstance(condensation, Condensation):
        raise TypeError(f"register() takes a Condensation instance (got {type(condensation).__name__})")
    _REGISTRY[condensation.name] = condensation
    return condensation


def unregister(name):
    """Remove a registered condensation (tests that register their own)."""
    _REGISTRY.pop(name, None)


def names():
    """Registered names, in registration order."""
    return tuple(_REGISTRY)


def get(condensation):
    """The :class:`Condensation` for a registered name (an instance is returned as it is).

    Raises ``ValueError`` naming the parameter and the registered names otherwise.
    """
    if isinstance(condensation, Condensation):
        return condensation
    if isinstance(condensation, str) and condensation in _REGISTRY:
        return _REGISTRY[condensation]
    raise ValueError(f"parameter 'condensation' must be one of {names()} (got {condensation!r})")
