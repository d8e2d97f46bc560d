"""Model objects: the block, its bed and the excitation's envelope (SI units throughout; the excitations are in
:mod:`screening.core.excitations`)."""

from screening.core.model.block import Block
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.model.foundation import CONTACT_LAWS, Foundation, contact_pressure

__all__ = ["Block", "Foundation", "contact_pressure", "CONTACT_LAWS", "Envelope", "ConstantEnvelope"]
