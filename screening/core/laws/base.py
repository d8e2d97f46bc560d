"""The interface every contact law implements (see ``docs/architecture_models.md``).

The bed presses on the base with ``F_n = k z + eps k z^3 + F_d(z, zdot)`` per unit base length
[N/m] where the indentation ``z > 0`` (paper eqs. 3-4).  The stiffness part is common to every law;
a law is its damping pressure ``F_d``.  The solvers integrate ``F_d`` over the contact zone (the
coupled resultants) and along the quasi-static path (the condensations) in closed form for the two
rate-linear basis pressures ``zdot`` and ``z zdot``, so a law hands the compiled code its damping
as the pair of weights ``(w_rate, w_indentation)`` of

    F_d(z, zdot) = zdot (w_rate + w_indentation z)

(a record of two numbers, never its name).  :func:`screening.core.laws.register` checks that a law's
numpy :meth:`ContactLaw.damping_pressure` is that combination of its weights before accepting it.
"""

from __future__ import annotations

import abc

import numpy as np

from screening.core.registry import NamedModel

__all__ = ["DAMPING_FIELDS", "ContactLaw"]

#: Damping fields of :class:`screening.core.model.Foundation` a law may take its coefficient from.
DAMPING_FIELDS = ("lam", "c")


class ContactLaw(NamedModel, abc.ABC):
    """A contact law: its damping pressure, its weights on the basis pressures, its parameter.

    Subclasses set :attr:`name`, :attr:`parameter` (the :class:`~screening.core.model.Foundation` field
    that holds the damping coefficient, one of :data:`DAMPING_FIELDS`) and :attr:`attributes`
    (the CF attributes of that coefficient: ``units``, ``long_name``).
    """

    axis = "contact law"
    #: registry name (``Foundation(law=...)``, ``contact = ...`` in studies)
    name: str = ""
    #: one line for attributes and reports
    description: str = ""
    #: the Foundation field (and study key) holding the damping coefficient
    parameter: str = ""
    #: CF attributes of the damping coefficient
    attributes: dict = {}

    #: the law's numpy function ``(z [m], z_dot [m/s], coefficient) -> F_d [N/m]`` (a staticmethod)
    pressure = None

    def damping_pressure(self, z, z_dot, coefficient):
        """Damping part of the contact pressure ``F_d`` [N/m] at indentation ``z`` [m] (> 0) and rate
        ``z_dot`` [m/s], for the damping ``coefficient`` in :attr:`attributes` ``units`` (:attr:`pressure`)."""
        return type(self).pressure(z, z_dot, coefficient)

    @abc.abstractmethod
    def damping_weights(self, coefficient):
        """``(w_rate [N s m-2], w_indentation [N s m-3])`` with ``F_d = zdot (w_rate + w_indentation z)``."""

    def weights(self, foundation):
        """:meth:`damping_weights` of a foundation's coefficient, as float arrays broadcast together."""
        w_rate, w_ind = self.damping_weights(np.asarray(getattr(foundation, self.parameter), dtype=float))
        w_rate, w_ind = np.broadcast_arrays(np.asarray(w_rate, dtype=float), np.asarray(w_ind, dtype=float))
        return w_rate[()], w_ind[()]
