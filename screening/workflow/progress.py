"""Former home of :mod:`screening.progress` (moved below the solvers, which use it): the same module object."""

import sys

from screening import progress as _moved

__all__ = _moved.__all__
sys.modules[__name__] = _moved
