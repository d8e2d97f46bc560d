"""The solvers: the moment equations, the Monte Carlo models and drivers, the result datasets.

The built-in Monte Carlo models (``coupled``, ``condensed``, ``stiff_bed``, ``stiff_bed_fast``) register themselves on
:mod:`screening.solvers.mc_registry` here, as the condensations, contact laws and excitations do
from their package ``__init__``: the registry itself imports no model.
"""

from screening.solvers import mc_models as _mc_models  # noqa: F401  (registers the built-in Monte Carlo models)

__all__ = []
