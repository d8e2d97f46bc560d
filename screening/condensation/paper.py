"""Quasi-static condensation: the single rocking equation ``M theta'' + C theta' + K theta = m h a_g``.

Paper section 2.3, eqs. (17)–(25).  The vertical displacement of the base centre is
slaved to its static value ``z_st(theta)`` (eqs. 17–18) and its rate to
``z_st'(theta) theta'``; substituting in the small-angle rocking equation gives the
piecewise damping ``C(theta)`` and stiffness ``K(theta)`` below, switching at the uplift
threshold ``theta_ul = m g / (2 b^2 k)`` (eq. 19).  Both ``C`` and the restoring moment
``K(theta) theta`` are continuous at ``|theta| = theta_ul``.

Winkler bed (linear dashpot ``c zdot``), derived the same way
--------------------------------------------------------------
The stiffness part of the law is the same as Hunt–Crossley, so ``K(theta)`` is eq. (25).
For the damping moment about the base centre, ``M_d = int c zdot (b - eta) d eta`` over
the contact zone, with ``zdot = zdot_B - eta theta'`` (small angles):

* no uplift: ``z_cb = m g / (2 b k)`` is constant, ``zdot_B = b theta'``, so
  ``M_d = c theta' int_0^{2b} (b - eta)^2 d eta = (2/3) c b^3 theta'``;
* uplift (``theta > 0``): ``z_B = z_cb + b theta = sqrt(2 m g theta / k) = p theta`` with
  ``p = sqrt(2 m g / (k theta))`` the contact length, ``zdot_B = (p/2) theta'``, so
  ``M_d = c theta' int_0^p (p/2 - eta)(b - eta) d eta = c p^3 theta' / 12``, i.e.
  ``C_2 = (c / 12) (2 m g / k)^{3/2} |theta|^{-3/2}``, mirror-symmetric in theta.

``C_2(theta_ul) = (2/3) c b^3``: continuous, like the Hunt–Crossley case.  The same
procedure applied to ``lam z zdot`` reproduces eq. (24), which checks the route.

Selectable condensation
-----------------------
The functions below take ``condensation="paper"`` (default: eqs. 17–25 as printed, the
static indentation from the *linear* balance) or ``"cubic"`` (the static vertical balance
including the ``eps`` term, :mod:`screening.condensation.cubic`).  Any other value raises
``ValueError``.
"""

from __future__ import annotations

import numpy as np

from screening.condensation import cubic as cubic_condensation
from screening.condensation.base import Condensation
from screening.condensation.registry import register


#: Names accepted by the ``condensation`` argument throughout the package.
CONDENSATIONS = ("paper", "cubic")


def check_condensation(condensation):
    """Return ``condensation`` if it is one of :data:`CONDENSATIONS`, else raise ``ValueError``."""
    if not isinstance(condensation, str) or condensation not in CONDENSATIONS:
        raise ValueError(f"parameter 'condensation' must be one of {CONDENSATIONS} (got {condensation!r})")
    return condensation


def m_sdof(block):
    """Rotational inertia of the condensed oscillator, ``I_cm + m h^2`` [kg m^2] (eq. 23)."""
    return block.I_cm + block.m * block.h**2


def uplift_threshold(block, foundation, condensation="paper"):
    """Static uplift angle ``theta_ul = m g / (2 b^2 k)`` [rad] (eq. 19).

    ``condensation="cubic"``: :func:`screening.condensation.cubic.uplift_threshold`.
    """
    if check_condensation(condensation) == "cubic":
        return cubic_condensation.uplift_threshold(block, foundation)
    return block.m * block.g / (2.0 * block.b**2 * foundation.k)


def static_indentation(theta, block, foundation):
    """Quasi-static vertical displacement of the base centre ``z_st(theta)`` [m] (eqs. 17–18)."""
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    inner = mg / (2.0 * b * k) + 0.0 * theta
    outer = np.sqrt(2.0 * mg * theta / k) - b * theta
    return np.where(theta <= uplift_threshold(block, foundation), inner, outer)


def damping_inner(block, foundation):
    """No-uplift rocking damping ``C_1`` [N m s/rad] (eq. 24; Winkler: ``(2/3) c b^3``)."""
    if foundation.contact == "hunt_crossley":
        return foundation.lam * block.b**2 * block.m * block.g / (3.0 * foundation.k)
    return 2.0 / 3.0 * foundation.c * block.b**3


def rocking_damping(theta, block, foundation, condensation="paper"):
    """Piecewise rocking damping ``C(theta)`` [N m s/rad] (eq. 24; Winkler: module doc).

    ``theta`` [rad]; vectorised over theta and parameter arrays.
    ``condensation="cubic"``: :func:`screening.condensation.cubic.rocking_damping`.
    """
    if check_condensation(condensation) == "cubic":
        return cubic_condensation.rocking_damping(theta, block, foundation)
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    tu = uplift_threshold(block, foundation)
    c1 = damping_inner(block, foundation) + 0.0 * theta
    with np.errstate(divide="ignore"):
        if foundation.contact == "hunt_crossley":
            c2 = foundation.lam * b / 12.0 * (2.0 * mg / k) ** 1.5 * theta**-0.5
        else:
            c2 = foundation.c / 12.0 * (2.0 * mg / k) ** 1.5 * theta**-1.5
    return np.where(theta <= tu, c1, c2)


def rocking_stiffness(theta, block, foundation, condensation="paper"):
    """Piecewise secant rocking stiffness ``K(theta)`` [N m/rad] (eq. 25).

    ``theta`` [rad]; the restoring moment is ``K(theta) theta``.  Same for both beds.
    ``condensation="cubic"``: :func:`screening.condensation.cubic.rocking_stiffness`.
    """
    if check_condensation(condensation) == "cubic":
        return cubic_condensation.rocking_stiffness(theta, block, foundation)
    theta = np.asarray(theta, dtype=float)
    a = np.abs(theta)
    m, g, b, h, k, eps = block.m, block.g, block.b, block.h, foundation.k, foundation.eps
    mg = m * g
    tu = uplift_threshold(block, foundation)
    k1 = 2.0 / 3.0 * b**3 * k - mg * h + eps * (mg**2 * b / (2.0 * k) + 0.4 * k * b**5 * theta**2)
    with np.errstate(divide="ignore", invalid="ignore"):
        k2 = (mg * (b / a - np.sqrt(2.0 * mg * k) / (3.0 * k) * a**-1.5 - h)
              + eps * (mg**2 * b / k - mg**2 / (5.0 * k) * np.sqrt(2.0 * mg / k) * a**-0.5))
    return np.where(a <= tu, k1, k2)


def restoring_moment(theta, block, foundation, condensation="paper"):
    """Restoring moment ``K(theta) theta`` [N m] of the condensed model (eq. 22)."""
    theta = np.asarray(theta, dtype=float)
    return rocking_stiffness(theta, block, foundation, condensation) * theta


def rocking_acceleration(theta, theta_dot, ground_acceleration, block, foundation, condensation="paper"):
    """``theta''`` [rad/s^2] of the condensed SDOF, eq. (22), for ground acceleration [m/s^2]."""
    force = (block.m * block.h * np.asarray(ground_acceleration, dtype=float)
             - rocking_damping(theta, block, foundation, condensation) * theta_dot
             - restoring_moment(theta, block, foundation, condensation))
    return force / m_sdof(block)


class PaperCondensation(Condensation):
    """The paper's condensation, eqs. (17)–(25): static indentation from the linear vertical balance."""

    name = "paper"
    description = "quasi-static z_cb from the linear static balance (eqs. 17-25)"

    def uplift_threshold(self, block, foundation):
        return uplift_threshold(block, foundation)

    def rocking_damping(self, theta, block, foundation):
        return rocking_damping(theta, block, foundation)

    def rocking_stiffness(self, theta, block, foundation):
        return rocking_stiffness(theta, block, foundation)

    def damping_at_rest(self, block, foundation):
        return damping_inner(block, foundation)

    def equivalent_coefficients(self, sigma_theta, cov_over_sigma, block, foundation):
        from screening.condensation.paper_coefficients import equivalent_coefficients

        return equivalent_coefficients(sigma_theta, cov_over_sigma, 1.0, block, foundation)


PAPER = register(PaperCondensation())
