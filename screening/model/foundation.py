"""Foundation (bed) models and the distributed contact law (paper, section 2.1, eqs. 3–4).

Every parameter may be a Python float or a numpy array; arrays broadcast against each
other so that the physics functions downstream are vectorised over parameter points.
All quantities are SI.  The contact law gives a force per unit base length [N/m], so
``k`` is in N/m^2, the Hunt–Crossley ``lam`` in N s/m^4, the Winkler dashpot ``c`` in
N s/m^2 and ``eps`` in 1/m^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.validation import checked

CONTACT_LAWS = ("hunt_crossley", "winkler")


@dataclass(frozen=True)
class Foundation:
    """Generalised Hunt–Crossley bed, ``F_n = k z + eps k z^3 + lam z zdot`` (eqs. 3–4).

    Parameters
    ----------
    k : distributed stiffness [N/m^2] (force per unit base length per unit indentation), > 0.
    lam : Hunt–Crossley damping [N s/m^4] (per unit length, per unit indentation and
        per unit indentation rate), >= 0.
    eps : cubic stiffness parameter [1/m^2]; any finite sign (``eps = 0`` is plain
        Hunt–Crossley, ``eps > 0`` hardening, ``eps < 0`` softening).
    """

    k: float
    lam: float
    eps: float = 0.0

    contact = "hunt_crossley"

    def __post_init__(self):
        object.__setattr__(self, "k", checked("k", self.k, lower=0.0))
        object.__setattr__(self, "lam", checked("lam", self.lam, lower=0.0, lower_inclusive=True))
        object.__setattr__(self, "eps", checked("eps", self.eps))

    @property
    def damping(self):
        """The damping coefficient of the bed (``lam`` here) [N s/m^4]."""
        return self.lam


@dataclass(frozen=True)
class WinklerFoundation:
    """Winkler bed with a linear dashpot, ``F_n = k z + eps k z^3 + c zdot`` (eq. 3 note).

    ``eps = 0`` (the default) is the classical linear Winkler foundation model.

    Parameters
    ----------
    k : distributed stiffness [N/m^2], > 0.
    c : distributed viscous damping [N s/m^2] (per unit length per unit rate), >= 0.
    eps : cubic stiffness parameter [1/m^2], any finite sign.
    """

    k: float
    c: float
    eps: float = 0.0

    contact = "winkler"

    def __post_init__(self):
        object.__setattr__(self, "k", checked("k", self.k, lower=0.0))
        object.__setattr__(self, "c", checked("c", self.c, lower=0.0, lower_inclusive=True))
        object.__setattr__(self, "eps", checked("eps", self.eps))

    @property
    def damping(self):
        """The damping coefficient of the bed (``c`` here) [N s/m^2]."""
        return self.c


def contact_pressure(z, z_dot, foundation):
    """Normal contact force per unit base length, eqs. (3)–(4) [N/m].

    ``z`` [m] is the local indentation (positive into the bed), ``z_dot`` [m/s] its rate.
    Hunt–Crossley: ``k z + eps k z^3 + lam z z_dot``; Winkler: ``k z + eps k z^3 + c z_dot``.
    Zero where ``z < 0`` (no tension, no contact).  The dashpot may pull
    (``F_n < 0``) while ``z > 0``, as in the paper's law.
    """
    z = np.asarray(z, dtype=float)
    z_dot = np.asarray(z_dot, dtype=float)
    k, eps = foundation.k, foundation.eps
    if foundation.contact == "hunt_crossley":
        damping = foundation.lam * z * z_dot
    else:
        damping = foundation.c * z_dot
    force = k * z + eps * k * z**3 + damping
    return np.where(z > 0.0, force, 0.0)
