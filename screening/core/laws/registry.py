"""The registry of contact laws: a name is turned into a :class:`~screening.core.laws.base.ContactLaw` at
set-up (``Foundation(law=...)``, study parsing); the solvers read the law's weights, never its name."""

from __future__ import annotations

import numpy as np

from screening.core.laws.base import DAMPING_FIELDS, ContactLaw
from screening.core.registry import Registry

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

    Parameters
    ----------
    law : ContactLaw
        The law; its ``parameter`` must be a Foundation damping field (``lam`` [N s m-3] or ``c``
        [N s m-2]) and its ``damping_pressure`` [N m-1] must equal ``zdot (w_rate + w_indentation z)``
        of its ``damping_weights`` (checked at 16 random points to 1e-12).

    Returns
    -------
    ContactLaw
        ``law`` itself.

    Raises
    ------
    TypeError
        For anything that is not a ``ContactLaw`` instance.
    ValueError
        When its parameter is not a damping field or its pressure does not match its weights.

    Notes
    -----
    The solvers integrate one damping pressure only, linear in the indentation rate and at most
    linear in the indentation: ``p_d = zdot (w_rate + w_indentation z)``; Hunt–Crossley (eq. (4) in
    [mitseas2026]) has ``w_rate = 0, w_indentation = lam``, Winkler ``w_rate = c, w_indentation = 0``.

    Examples
    --------
    >>> from screening.core.laws.winkler import WINKLER
    >>> register(WINKLER) is WINKLER
    True
    >>> register("winkler")
    Traceback (most recent call last):
    ...
    TypeError: register() takes a ContactLaw instance (got str)
    """
    if not isinstance(law, ContactLaw):
        raise TypeError(f"register() takes a ContactLaw instance (got {type(law).__name__})")
    if law.parameter not in DAMPING_FIELDS:
        raise ValueError(f"contact law {law.name!r}: parameter must be one of {DAMPING_FIELDS} "
                         f"(got {law.parameter!r})")
    _check_weights(law)
    return _REGISTRY.add(law.name, law)


#: Remove a registered law (tests that register their own); the registered names, in registration order; the
#: :class:`ContactLaw` for a registered name (an instance is returned as it is), ``ValueError`` naming the
#: parameter and the registered names otherwise.
unregister, names, get = _REGISTRY.remove, _REGISTRY.names, _REGISTRY.get


def parameters():
    """The CF attributes of the damping field of every registered law.

    Returns
    -------
    dict of str to dict
        ``{damping field: {"units": ..., "long_name": ...}}``, e.g. ``lam`` in [N s m-3] and ``c`` in
        [N s m-2], in registration order.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md`` (the Hunt–Crossley law, eq. 4).

    Examples
    --------
    >>> {field: attrs["units"] for field, attrs in parameters().items()}
    {'lam': 'N s m-3', 'c': 'N s m-2'}
    """
    return {law.parameter: dict(law.attributes) for law in _REGISTRY.values()}
