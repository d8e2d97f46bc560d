"""Contact laws of the bed behind one interface (:class:`ContactLaw`) and a registry.

A law is one module that defines a :class:`ContactLaw` and registers it; the solvers use its
weights on the basis damping pressures (see :mod:`screening.core.laws.base`).
"""

from screening.core.laws.base import DAMPING_FIELDS, ContactLaw
from screening.core.laws.registry import get, names, parameters, register, unregister
from screening.core.laws import hunt_crossley as _hunt_crossley  # noqa: F401  (registers)
from screening.core.laws import winkler as _winkler  # noqa: F401  (registers)

__all__ = ["DAMPING_FIELDS", "ContactLaw", "get", "names", "parameters", "register", "unregister"]
