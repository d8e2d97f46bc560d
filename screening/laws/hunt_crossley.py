"""The (generalised) Hunt–Crossley contact law: damping pressure ``lam z zdot`` (paper eq. 4).

``lam`` [N s m-3] is the damping per unit base length, per unit indentation and per unit
indentation rate; with ``eps = 0`` the law is the plain Hunt–Crossley law.
"""

from __future__ import annotations

import numpy as np

from screening.laws.base import ContactLaw
from screening.laws.registry import register

__all__ = ["hunt_crossley_damping", "HuntCrossley", "HUNT_CROSSLEY"]


def hunt_crossley_damping(z, z_dot, lam):
    """Hunt–Crossley damping pressure ``lam z zdot`` [N/m] (eq. 4).

    Parameters
    ----------
    z : indentation [m] (> 0 in contact).
    z_dot : indentation rate [m/s].
    lam : damping coefficient [N s m-3], >= 0.
    """
    return lam * np.asarray(z, dtype=float) * np.asarray(z_dot, dtype=float)


class HuntCrossley(ContactLaw):
    name = "hunt_crossley"
    description = "Hunt-Crossley damping lam z zdot"
    parameter = "lam"
    attributes = {"units": "N s m-3", "long_name": "Hunt-Crossley distributed damping"}

    pressure = staticmethod(hunt_crossley_damping)

    def damping_weights(self, coefficient):
        return 0.0 * coefficient, coefficient


HUNT_CROSSLEY = register(HuntCrossley())
