"""Former home of :mod:`screening.limits` (moved below the solvers, which use it): the same module object."""

import sys

from screening import limits as _moved

__all__ = _moved.__all__
sys.modules[__name__] = _moved
