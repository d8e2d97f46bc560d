"""screening: stochastic screening of rigid blocks rocking on flexible nonlinear foundations."""

__version__ = "0.1.0"

from .condensed import rocking_damping, rocking_stiffness, uplift_threshold
from . import fragility  # noqa: F401 - registers the ``ds.rocking`` accessor
from .excitation import ConstantEnvelope, Envelope, KanaiTajimi, WhiteNoise
from .linearization import equivalent_coefficients, uplift_probability
from .model import Block, Foundation, WinklerFoundation
from .response import linearize

__all__ = [
    "Block", "Foundation", "WinklerFoundation", "Envelope", "ConstantEnvelope", "WhiteNoise",
    "KanaiTajimi", "uplift_threshold", "rocking_damping", "rocking_stiffness",
    "equivalent_coefficients", "uplift_probability", "linearize", "__version__",
]
