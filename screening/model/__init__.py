"""Model objects: the block, its bed and the ground excitation (SI units throughout)."""

from screening.model.block import Block
from screening.model.excitation import ConstantEnvelope, Envelope
from screening.model.foundation import CONTACT_LAWS, Foundation, contact_pressure

__all__ = ["Block", "Foundation", "contact_pressure", "CONTACT_LAWS", "Envelope",
           "ConstantEnvelope", "WhiteNoise", "KanaiTajimi"]


def __getattr__(name):
    """The excitations live in :mod:`screening.excitations` (imported on first use: they import this package)."""
    if name in ("WhiteNoise", "KanaiTajimi"):
        from screening import excitations

        return getattr(excitations, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
