"""The interface every quasi-static condensation implements (see ``docs/method.md``).

A condensation turns the coupled rocking/vertical model into one rocking equation
``m_sdof theta'' + C(theta) theta' + K(theta) theta = m h a_g`` by slaving the vertical motion of
the base to the rotation.  It provides the numpy functions below (vectorised over ``theta`` and
array model parameters, SI units) and, for the compiled solvers, its kernels (:attr:`moment_kernel`,
:attr:`sdof_kernel`).  Register an instance with :func:`screening.core.condensation.register`.

Method and how it is checked: ``docs/method.md#quasi-static-condensation``.
"""

from __future__ import annotations

import abc

import numpy as np

from screening.core.condensation import quadrature
from screening.core.registry import NamedModel
from screening.core.signatures import MomentKernel, SdofKernel

__all__ = ["Condensation", "MomentKernel", "SdofKernel"]


class Condensation(NamedModel, abc.ABC):
    """A quasi-static condensation of the coupled model.  Subclasses set :attr:`name`."""

    axis = "condensation"

    #: registry name (the value of ``condensation`` in studies and function arguments)
    name: str = ""
    #: one line for attributes and reports
    description: str = ""

    def check(self, block, foundation):
        """Raise ``ValueError`` naming the parameter if the bed cannot be condensed (default: accept)."""

    @abc.abstractmethod
    def uplift_threshold(self, block, foundation):
        """Uplift threshold ``theta_ul`` [rad]."""

    def capacity_angle(self, block, foundation):
        """Rotation [rad] beyond which no quasi-static equilibrium exists (default ``inf``)."""
        return np.broadcast_to(np.inf, np.shape(self.uplift_threshold(block, foundation)))[()]

    @abc.abstractmethod
    def rocking_damping(self, theta, block, foundation):
        """Rocking damping ``C(theta)`` [N m s/rad]."""

    @abc.abstractmethod
    def rocking_stiffness(self, theta, block, foundation):
        """Secant rocking stiffness ``K(theta)`` [N m/rad]; the restoring moment is ``K(theta) theta``."""

    def restoring_moment(self, theta, block, foundation):
        """Restoring moment ``K(theta) theta`` [N m]."""
        theta = np.asarray(theta, dtype=float)
        return (self.rocking_stiffness(theta, block, foundation) * theta)[()]

    def damping_at_rest(self, block, foundation):
        """``C(0)`` [N m s/rad]."""
        return self.rocking_damping(0.0, block, foundation)

    def stiffness_at_rest(self, block, foundation):
        """``K(0)`` [N m/rad]."""
        return self.rocking_stiffness(0.0, block, foundation)

    def equivalent_coefficients(self, sigma_theta, cov_over_sigma, block, foundation):
        """``(c_eq [N m s/rad], k_eq [N m/rad])`` at ``sigma_theta`` [rad] and ``cov / sigma_theta`` [rad/s].

        Default: Gaussian quadrature of ``C``, ``K`` (:mod:`screening.core.condensation.quadrature`).
        """
        return quadrature.equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation, self)

    def moment_kernel(self, block, foundation):
        """:class:`MomentKernel` for model objects with flat (1-d) fields (default: quadrature tables)."""
        return quadrature.moment_kernel(block, foundation, self)

    def sdof_kernel(self, block, foundation):
        """:class:`SdofKernel` for scalar model objects: the compiled ``C``, ``K`` of the condensed
        Monte Carlo.  A condensation without one cannot run ``monte_carlo(model="condensed")``."""
        raise NotImplementedError(f"condensation {self.name!r} has no compiled C(theta), K(theta) "
                                  "(Condensation.sdof_kernel) for the condensed Monte Carlo")
