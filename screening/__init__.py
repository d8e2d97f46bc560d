"""screening: stochastic screening of rigid blocks rocking on flexible nonlinear foundations."""

from screening._version import __version__

from screening.kernels.cache import clear_stale_cache as _clear_stale_cache

_clear_stale_cache()   # numba's cache does not follow changes of other modules: drop it when any source changed

from screening.analysis import beds  # noqa: F401 - ``from screening import beds``: bed parameters from materials
from screening.analysis import fragility  # noqa: F401 - registers the ``ds.rocking`` accessor
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.condensation.api import (equivalent_coefficients, rocking_damping, rocking_stiffness,
                                             uplift_probability, uplift_threshold)
from screening.core.model import Block, Foundation
from screening.analysis.linearization import linearize
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.simulate import simulate
from screening.solvers.tail import tail_probability

__all__ = [
    "Block", "Foundation", "Envelope", "ConstantEnvelope", "WhiteNoise",
    "KanaiTajimi", "uplift_threshold", "rocking_damping", "rocking_stiffness",
    "equivalent_coefficients", "uplift_probability", "linearize", "monte_carlo", "simulate", "tail_probability",
    "__version__",
]
