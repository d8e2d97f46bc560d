"""The Winkler contact law with a linear dashpot: damping pressure ``c zdot``.

``c`` [N s m-2] is the dashpot per unit base length and per unit indentation rate; with ``eps = 0``
the law is the classical Winkler bed.
"""

from __future__ import annotations

import numpy as np

from screening.laws.base import ContactLaw
from screening.laws.registry import register

__all__ = ["winkler_damping", "Winkler", "WINKLER"]


def winkler_damping(z, z_dot, c):
    """Winkler (linear dashpot) damping pressure ``c zdot`` [N/m].

    Parameters
    ----------
    z : indentation [m] (> 0 in contact; the pressure does not depend on it).
    z_dot : indentation rate [m/s].
    c : dashpot coefficient [N s m-2], >= 0.
    """
    return c * np.asarray(z_dot, dtype=float) + 0.0 * np.asarray(z, dtype=float)


class Winkler(ContactLaw):
    name = "winkler"
    description = "Winkler linear dashpot c zdot"
    parameter = "c"
    attributes = {"units": "N s m-2", "long_name": "Winkler distributed viscous damping"}

    pressure = staticmethod(winkler_damping)

    def damping_weights(self, coefficient):
        return coefficient, 0.0 * coefficient


WINKLER = register(Winkler())
