"""Contact laws of the bed behind one interface (:class:`ContactLaw`) and a registry.

A law is one module that defines a :class:`ContactLaw` and registers it; the solvers use its
weights on the basis damping pressures (see :mod:`screening.laws.base`).
"""

from screening.laws.base import DAMPING_FIELDS, ContactLaw
from screening.laws.registry import get, names, parameters, register, unregister
from screening.laws import hunt_crossley as _hunt_crossley  # noqa: F401  (registers)
from screening.laws import winkler as _winkler  # noqa: F401  (registers)

__all__ = ["DAMPING_FIELDS", "ContactLaw", "get", "names", "parameters", "register", "unregister"]
