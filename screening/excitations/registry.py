"""The registry of excitations: a ``kind`` is turned into its class at set-up (study parsing, result
readers); the solvers use the excitation object's filter and PSD, never its kind."""

from __future__ import annotations

from screening.excitations.base import Excitation
from screening.registry import Registry

__all__ = ["register", "unregister", "names", "get", "parameters", "build"]

_REGISTRY = Registry("kind")


def register(cls):
    """Add an :class:`Excitation` subclass under its ``kind`` (usable as a class decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, Excitation)) or not cls.kind:
        raise TypeError(f"register() takes an Excitation subclass with a kind (got {cls!r})")
    return _REGISTRY.add(cls.kind, cls)


#: Remove a registered excitation (tests that register their own).
unregister = _REGISTRY.remove
#: Registered kinds, in registration order.
names = _REGISTRY.names
#: The excitation class of a registered ``kind``; ``ValueError`` naming the registered kinds otherwise.
get = _REGISTRY.get


def parameters():
    """``{name: Parameter}`` of every registered excitation's parameters (first declaration wins)."""
    out = {}
    for cls in _REGISTRY.values():
        for name, p in cls.parameters.items():
            out.setdefault(name, p)
    return out


def build(kind, S0, params, envelope):
    """An excitation of ``kind`` with intensity ``S0`` [m2 s-3], its parameters taken from the mapping
    ``params`` and ``envelope``."""
    cls = get(kind)
    return cls(S0, *(params[name] for name in cls.parameters), envelope=envelope)
