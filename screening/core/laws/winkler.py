"""The Winkler contact law with a linear dashpot: damping pressure ``c zdot``.

``c`` [N s m-2] is the dashpot per unit base length and per unit indentation rate; with ``eps = 0``
the law is the classical Winkler bed.
"""

from __future__ import annotations

import numpy as np

from screening.core.laws.base import ContactLaw
from screening.core.laws.registry import register

__all__ = ["Winkler"]


def winkler_damping(z, z_dot, c):
    """Winkler (linear dashpot) damping pressure ``c zdot`` [N/m].

    Parameters
    ----------
    z : float or array_like
        Indentation [m] (> 0 in contact; the pressure does not depend on it, only its shape).
    z_dot : float or array_like
        Indentation rate [m/s].
    c : float
        Dashpot coefficient [N s m-2], >= 0.

    Returns
    -------
    numpy.ndarray
        Damping pressure per unit base length [N/m], broadcast over ``z`` and ``z_dot``.

    Notes
    -----
    .. math:: p_d = c\\, \\dot z

    the Winkler counterpart of the Hunt–Crossley term ``lam z zdot`` of eq. (4) in [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] E. Winkler, Die Lehre von der Elasticitaet und Festigkeit, Dominicus, Prague (1867).
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
