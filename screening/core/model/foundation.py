"""Foundation (bed) models and the distributed contact law (paper, section 2.1, eqs. 3–4).

Every parameter may be a Python float or a numpy array; arrays broadcast against each
other so that the physics functions downstream are vectorised over parameter points.
All quantities are SI.  The contact law gives a force per unit base length [N/m], so
``k`` is in N/m^2, the Hunt–Crossley ``lam`` in N s/m^3, the Winkler dashpot ``c`` in
N s/m^2 and ``eps`` in 1/m^2.

Method and how it is checked: ``docs/method.md#contact-law``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.core import laws
from screening.core.laws.base import DAMPING_FIELDS
from screening.core.validation import checked

__all__ = ["Foundation"]


def __getattr__(name):
    if name == "CONTACT_LAWS":                       # the registered laws, at the time of asking
        return laws.names()
    raise AttributeError(name)


@dataclass(frozen=True)
class Foundation:
    """A distributed bed under the block's base: contact law ``F_n = k z + eps k z^3 + damping``
    per unit base length (eqs. 3–4).

    ``law = "hunt_crossley"``: damping ``lam z zdot`` (generalised Hunt–Crossley; ``eps = 0`` is
    plain Hunt–Crossley).  ``law = "winkler"``: damping ``c zdot`` (``eps = 0`` is the classical
    Winkler bed with a linear dashpot).  Give ``lam`` or ``c``; ``law`` follows from which one
    unless stated.

    Parameters
    ----------
    k : distributed stiffness [N/m^2] (force per unit base length per unit indentation), > 0.
    lam : Hunt–Crossley damping [N s/m^3] (per unit length, per unit indentation and
        per unit indentation rate), >= 0.
    eps : cubic stiffness parameter [1/m^2]; any finite sign (``> 0`` hardening, ``< 0`` softening).
    c : Winkler dashpot [N s/m^2] (per unit length per unit rate), >= 0.
    law : a registered contact law (:func:`screening.core.laws.names`: ``"hunt_crossley"``, ``"winkler"``);
        the law names the field (``lam`` or ``c``) that holds its damping coefficient.
    """

    k: float
    lam: float | None = None
    eps: float = 0.0
    c: float | None = None
    law: str | None = None

    def __post_init__(self):
        law = self.law
        if law is None:
            law = "winkler" if self.c is not None and self.lam is None else "hunt_crossley"
        own = laws.get(law).parameter
        for other in DAMPING_FIELDS:
            if other != own and getattr(self, other) is not None:
                raise ValueError(f"parameter '{other}' does not apply to law={law!r} (give '{own}')")
        if getattr(self, own) is None:
            raise ValueError(f"parameter '{own}' is required for law={law!r} (a finite number >= 0)")
        object.__setattr__(self, "law", law)
        object.__setattr__(self, "k", checked("k", self.k, lower=0.0))
        object.__setattr__(self, own, checked(own, getattr(self, own), lower=0.0, lower_inclusive=True))
        object.__setattr__(self, "eps", checked("eps", self.eps))

    @property
    def contact_law(self):
        """The registered :class:`~screening.core.laws.ContactLaw` of :attr:`law`."""
        return laws.get(self.law)

    @property
    def damping(self):
        """The damping coefficient of the law: ``lam`` [N s/m^3], ``c`` [N s/m^2], ... (its ``parameter``)."""
        return getattr(self, self.contact_law.parameter)

    @property
    def damping_weights(self):
        """``(w_rate [N s m-2], w_indentation [N s m-3])``: the damping pressure is
        ``zdot (w_rate + w_indentation z)`` (:meth:`screening.core.laws.ContactLaw.damping_weights`)."""
        return self.contact_law.weights(self)

    @property
    def winkler(self):
        """True for the Winkler law (kept for callers outside the package; the solvers use
        :attr:`damping_weights`)."""
        return self.law == "winkler"


def contact_pressure(z, z_dot, foundation):
    """Normal contact force per unit base length, eqs. (3)–(4) [N/m].

    ``z`` [m] is the local indentation (positive into the bed), ``z_dot`` [m/s] its rate.
    ``k z + eps k z^3`` plus the damping pressure of the law (Hunt–Crossley ``lam z z_dot``,
    Winkler ``c z_dot``, :meth:`screening.core.laws.ContactLaw.damping_pressure`).
    Zero where ``z < 0`` (no tension, no contact).  The dashpot may pull
    (``F_n < 0``) while ``z > 0``, as in the paper's law.

    Parameters
    ----------
    z : array_like
        Local indentation [m], positive into the bed.
    z_dot : array_like
        Its rate [m/s]; broadcasts against ``z``.
    foundation : Foundation
        The bed: ``k`` [N/m^2], ``eps`` [1/m^2] and the damping of its law (``lam`` [N s/m^3] or
        ``c`` [N s/m^2]).

    Returns
    -------
    numpy.ndarray
        The normal force per unit base length ``F_n`` [N/m], the broadcast shape of the inputs.

    Notes
    -----
    Eq. (3) in [1]_, with the Hunt-Crossley damping of [2]_, and eq. (4), no tension:

    .. math::

        F_n = k z + \\varepsilon k z^3 + \\lambda z \\dot z \\quad (z > 0), \\qquad F_n = 0 \\quad (z \\le 0)

    The Winkler law [3]_ replaces :math:`\\lambda z \\dot z` by :math:`c \\dot z`.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] K. H. Hunt and F. R. E. Crossley, "Coefficient of restitution interpreted as damping in
       vibroimpact", J. Appl. Mech. 42(2) (1975) 440-445.
    .. [3] E. Winkler, Die Lehre von der Elasticitaet und Festigkeit, Dominicus, Prague (1867).

    Examples
    --------
    >>> bed = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    >>> z = 1e-4                                                     # 0.1 mm into the bed
    >>> float(contact_pressure(z, 0.0, bed)) == 2.89e7 * z * (1 + 6e7 * z**2)
    True
    >>> contact_pressure([-1e-4, 1e-4], [0.01, 0.01], bed).tolist()   # no tension; 2890 + 1734 + 895 [N/m]
    [0.0, 5519.0]
    """
    z = np.asarray(z, dtype=float)
    z_dot = np.asarray(z_dot, dtype=float)
    k, eps = foundation.k, foundation.eps
    damping = foundation.contact_law.damping_pressure(z, z_dot, foundation.damping)
    force = k * z + eps * k * z**3 + damping
    return np.where(z > 0.0, force, 0.0)
