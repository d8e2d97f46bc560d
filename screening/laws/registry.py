"""The registry of contact laws: a name is turned into a :class:`~screening.laws.base.ContactLaw` at
set-up (``Foundation(law=...)``, study parsing); the solvers read the law's weights, never its name."""

from __future__ import annotations

import numpy as np

from screening.laws.base import DAMPING_FIELDS, ContactLaw
from screening.registry import Registry

__all__ = ["register", "unregister", "names", "get", "parameters"]

_REGISTRY = Registry("law", lambda item: isinstance(item, ContactLaw))


def _check_weights(law):
    """Refuse a law whose damping pressure is not ``zdot (w_rate + w_indentation z)`` of its weights."""
    rng = np.random.default_rng(0)
    z = rng.uniform(1e-6, 1e-2, 16)
    z_dot = rng.uniform(-1.0, 1.0, 16)
    coefficient = 1.0 + rng.uniform(0.0, 1.0)
    w_rate, w_ind = law.damping_weights(coefficient)
    expected = z_dot * (w_rate + w_ind * z)
    got = np.asarray(law.damping_pressure(z, z_dot, coefficient), dtype=float)
    if not np.allclose(got, expected, rtol=1e-12, atol=0.0):
        raise ValueError(f"contact law {law.name!r}: damping_pressure is not zdot (w_rate + w_indentation z) "
                         "of its damping_weights (the only damping the solvers integrate)")


def register(law):
    """Add a :class:`ContactLaw` instance under its ``name`` (a later one with the same name replaces it).

    Raises ``TypeError`` for anything else and ``ValueError`` when its :attr:`~ContactLaw.parameter` is
    not a Foundation damping field or its pressure does not match its weights.
    """
    if not isinstance(law, ContactLaw):
        raise TypeError(f"register() takes a ContactLaw instance (got {type(law).__name__})")
    if law.parameter not in DAMPING_FIELDS:
        raise ValueError(f"contact law {law.name!r}: parameter must be one of {DAMPING_FIELDS} "
                         f"(got {law.parameter!r})")
    _check_weights(law)
    return _REGISTRY.add(law.name, law)


#: Remove a registered law (tests that register their own).
unregister = _REGISTRY.remove
#: Registered names, in registration order.
names = _REGISTRY.names
#: The :class:`ContactLaw` for a registered name (an instance is returned as it is); ``ValueError`` naming
#: the parameter and the registered names otherwise.
get = _REGISTRY.get


def parameters():
    """``{damping field: CF attributes}`` of the registered laws."""
    return {law.parameter: dict(law.attributes) for law in _REGISTRY.values()}
