"""Model objects: the block, its bed and the ground excitation (SI units throughout)."""

from screening.model.block import Block
from screening.model.excitation import ConstantEnvelope, Envelope, KanaiTajimi, WhiteNoise
from screening.model.foundation import CONTACT_LAWS, Foundation, contact_pressure

__all__ = ["Block", "Foundation", "contact_pressure", "CONTACT_LAWS", "Envelope",
           "ConstantEnvelope", "WhiteNoise", "KanaiTajimi"]
