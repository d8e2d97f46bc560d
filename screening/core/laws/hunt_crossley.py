"""The (generalised) Hunt–Crossley contact law: damping pressure ``lam z zdot`` (paper eq. 4).

``lam`` [N s m-3] is the damping per unit base length, per unit indentation and per unit
indentation rate; with ``eps = 0`` the law is the plain Hunt–Crossley law.
"""

from __future__ import annotations

import numpy as np

from screening.core.laws.base import ContactLaw
from screening.core.laws.registry import register

__all__ = ["HuntCrossley"]


def hunt_crossley_damping(z, z_dot, lam):
    """Hunt–Crossley damping pressure ``lam z zdot`` [N/m] (eq. 4).

    Parameters
    ----------
    z : float or array_like
        Indentation [m] (> 0 in contact).
    z_dot : float or array_like
        Indentation rate [m/s].
    lam : float
        Damping coefficient [N s m-3], >= 0.

    Returns
    -------
    numpy.ndarray
        Damping pressure per unit base length [N/m], broadcast over ``z`` and ``z_dot``.

    Notes
    -----
    The damping part of the contact law, eq. (4) in [1]:

    .. math:: p_d = \\lambda\\, z\\, \\dot z

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] K. H. Hunt and F. R. E. Crossley, "Coefficient of restitution interpreted as damping in
       vibroimpact", J. Appl. Mech. 42(2) (1975) 440-445.
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
