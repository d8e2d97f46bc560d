"""Quasi-static condensations of the coupled model to one rocking equation, behind one interface.

``get(name)`` turns a registered name into a :class:`Condensation`; ``register`` adds one (a
third-party condensation needs only the numpy functions of :class:`Condensation`);
``DEFAULT_CONDENSATION`` names the one used wherever none is chosen.
"""

from screening.core.condensation.base import Condensation
from screening.core.condensation.registry import DEFAULT_CONDENSATION, get, names, register, unregister

__all__ = ["Condensation", "DEFAULT_CONDENSATION", "get", "names", "register", "unregister"]

# the built-in condensations register themselves
from screening.core.condensation import paper as _paper, cubic as _cubic, virtual_work as _virtual_work  # noqa: E402,F401,I001
