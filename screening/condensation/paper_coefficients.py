"""Former home of the closed-form ``c_eq``, ``k_eq`` of the paper's condensation, now in
:mod:`screening.condensation.paper` beside the ``C``, ``K`` they integrate: the same module object."""

import sys

from screening.condensation import paper as _moved

__all__ = _moved.__all__
sys.modules[__name__] = _moved
