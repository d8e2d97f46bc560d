"""The rigid block (paper, section 2.1).

Method and how it is checked: ``docs/method.md#block``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.core.validation import checked

__all__ = ["Block"]


#: Half-width ``b`` and height ``h`` [m] a block may have: a micrometre to a kilometre.  Far beyond, the
#: condensation's ``b^2`` and ``b^3`` leave float64 (``b <= ~1e-162``: the uplift threshold divides by
#: zero; ``b, h >= ~1e103``: ``b^3`` and ``h^2`` overflow).
LENGTH_RANGE = (1e-6, 1e3)


@dataclass(frozen=True)
class Block:
    """Rigid rectangular block of width ``2 b`` and height ``2 h``.

    Parameters
    ----------
    m : mass [kg], > 0.
    b : half-width of the base [m], in :data:`LENGTH_RANGE`.
    h : half-height, i.e. height of the centre of mass above the base [m], in :data:`LENGTH_RANGE`.
    I_cm : polar moment of inertia about the centre of mass [kg m^2], > 0.
        Defaults to ``m (b^2 + h^2) / 3`` (uniform rectangle).
    g : gravity [m/s^2], > 0.
    """

    m: float
    b: float
    h: float
    I_cm: float | None = None
    g: float = 9.81

    def __post_init__(self):
        for name in ("m", "g"):
            object.__setattr__(self, name, checked(name, getattr(self, name), lower=0.0))
        low, high = LENGTH_RANGE
        for name in ("b", "h"):
            object.__setattr__(self, name, checked(name, getattr(self, name), lower=low, lower_inclusive=True,
                                                   upper=high, upper_inclusive=True,
                                                   range_text=f"a length in {low:g}..{high:g} m"))
        if self.I_cm is None:
            object.__setattr__(self, "I_cm", self.m * (self.b**2 + self.h**2) / 3.0)
        else:
            object.__setattr__(self, "I_cm", checked("I_cm", self.I_cm, lower=0.0))

    @property
    def m_sdof(self):
        """Rotational inertia about the rocking edge, ``I_cm + m h^2`` [kg m^2] (eq. 23)."""
        return self.I_cm + self.m * self.h**2

    @property
    def slenderness(self):
        """Slenderness angle ``atan(b / h)`` [rad]: the rigid-block overturning angle."""
        return np.arctan2(self.b, self.h)

    @property
    def weight(self):
        """``m g`` [N]."""
        return self.m * self.g
