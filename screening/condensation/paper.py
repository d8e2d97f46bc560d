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

The functions below are the paper's condensation alone; :mod:`screening.condensation.api` has
the same functions for any registered condensation (``condensation=`` a name or object).

Method and how it is checked: ``docs/method.md#paper-condensation``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.condensation.base import Condensation, MomentKernel, SdofKernel
from screening.kernels.signatures import sdof_coefficients_signature
from screening.condensation.registry import register


def uplift_threshold(block, foundation):
    """Static uplift angle ``theta_ul = m g / (2 b^2 k)`` [rad] (eq. 19)."""
    return block.m * block.g / (2.0 * block.b**2 * foundation.k)


def static_indentation(theta, block, foundation):
    """Quasi-static vertical displacement of the base centre ``z_st(theta)`` [m] (eqs. 17–18)."""
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    inner = mg / (2.0 * b * k) + 0.0 * theta
    outer = np.sqrt(2.0 * mg * theta / k) - b * theta
    return np.where(theta <= uplift_threshold(block, foundation), inner, outer)


def damping_inner_parts(block, foundation):
    """No-uplift rocking damping of the two basis pressures of the law [N m s/rad]:
    ``(2/3) w_rate b^3`` (``zdot``, Winkler) and ``w_indentation b^2 m g / (3 k)`` (``z zdot``, eq. 24)."""
    w_rate, w_ind = foundation.damping_weights
    return 2.0 / 3.0 * w_rate * block.b**3, w_ind * block.b**2 * block.m * block.g / (3.0 * foundation.k)


def damping_inner(block, foundation):
    """No-uplift rocking damping ``C_1`` [N m s/rad] (eq. 24; Winkler: ``(2/3) c b^3``)."""
    rate, indentation = damping_inner_parts(block, foundation)
    return rate + indentation


def rocking_damping(theta, block, foundation):
    """Piecewise rocking damping ``C(theta)`` [N m s/rad] (eq. 24; Winkler: module doc).

    ``theta`` [rad]; vectorised over theta and parameter arrays.
    """
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    tu = uplift_threshold(block, foundation)
    c1 = damping_inner(block, foundation) + 0.0 * theta
    w_rate, w_ind = foundation.damping_weights
    with np.errstate(divide="ignore", invalid="ignore"):
        c2 = (w_rate / 12.0 * (2.0 * mg / k) ** 1.5 * theta**-1.5
              + w_ind * b / 12.0 * (2.0 * mg / k) ** 1.5 * theta**-0.5)
    return np.where(theta <= tu, c1, c2)


def rocking_stiffness(theta, block, foundation):
    """Piecewise secant rocking stiffness ``K(theta)`` [N m/rad] (eq. 25).

    ``theta`` [rad]; the restoring moment is ``K(theta) theta``.  Same for both beds.
    """
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


def restoring_moment(theta, block, foundation):
    """Restoring moment ``K(theta) theta`` [N m] of the condensed model (eq. 22)."""
    theta = np.asarray(theta, dtype=float)
    return rocking_stiffness(theta, block, foundation) * theta


#: Per-point parameters of :func:`damping_stiffness_jit` (SI units): ``C = C1`` inside the threshold,
#: ``C2_rate |theta|^-3/2 + C2_indentation |theta|^-1/2`` outside (the law's two basis pressures); ``K = K1_0 + K1_2 theta^2`` inside,
#: ``MGB/|theta| - K2_32 |theta|^-3/2 - K2_12 |theta|^-1/2 + K2_0`` outside (eqs. 24–25).
SDOF_RECORD = np.dtype([("theta_ul", "f8"), ("C1", "f8"), ("C2_rate", "f8"), ("C2_indentation", "f8"), ("K1_0", "f8"),
                        ("K1_2", "f8"), ("MGB", "f8"), ("K2_32", "f8"), ("K2_12", "f8"), ("K2_0", "f8")])


def sdof_record(block, foundation):
    """The :data:`SDOF_RECORD` of scalar model objects (a 1-element array)."""
    m, g, h, b = float(block.m), float(block.g), float(block.h), float(block.b)
    k, eps = float(foundation.k), float(foundation.eps)
    w_rate, w_ind = (float(w) for w in foundation.damping_weights)
    mg = m * g
    rec = np.zeros(1, dtype=SDOF_RECORD)
    rec["theta_ul"] = uplift_threshold(block, foundation)
    rec["C1"] = 2.0 / 3.0 * w_rate * b**3 + w_ind * b * b * mg / (3.0 * k)
    rec["C2_rate"] = w_rate / 12.0 * (2.0 * mg / k) ** 1.5            # x |theta|^-3/2
    rec["C2_indentation"] = w_ind * b / 12.0 * (2.0 * mg / k) ** 1.5  # x |theta|^-1/2
    rec["K1_0"] = 2.0 / 3.0 * b**3 * k - mg * h + eps * mg * mg * b / (2.0 * k)
    rec["K1_2"] = eps * 0.4 * k * b**5
    rec["MGB"] = mg * b
    rec["K2_32"] = mg * math.sqrt(2.0 * mg * k) / (3.0 * k)
    rec["K2_12"] = eps * mg * mg / (5.0 * k) * math.sqrt(2.0 * mg / k)
    rec["K2_0"] = -mg * h + eps * mg * mg * b / k
    return rec


@numba.njit(sdof_coefficients_signature(SDOF_RECORD), cache=True)
def damping_stiffness_jit(p, theta):
    """Compiled twin of :func:`rocking_damping` and :func:`rocking_stiffness`: ``(C [N m s/rad], K [N m/rad])``
    at ``theta`` [rad], ``p`` an :data:`SDOF_RECORD`."""
    a = abs(theta)
    if a <= p.theta_ul:
        return p.C1, p.K1_0 + p.K1_2 * theta * theta
    r = 1.0 / math.sqrt(a)
    stiffness = p.MGB * r * r - p.K2_32 * r * r * r - p.K2_12 * r + p.K2_0
    return p.C2_rate * r * r * r + p.C2_indentation * r, stiffness


class PaperCondensation(Condensation):
    """The paper's condensation, eqs. (17)–(25): static indentation from the linear vertical balance."""

    name = "paper"
    description = "quasi-static z_cb from the linear static balance (eqs. 17-25)"

    uplift_threshold = staticmethod(uplift_threshold)
    rocking_damping = staticmethod(rocking_damping)
    rocking_stiffness = staticmethod(rocking_stiffness)

    def damping_at_rest(self, block, foundation):
        return damping_inner(block, foundation)

    def stiffness_at_rest(self, block, foundation):
        e0 = (block.m * block.g) ** 2 * block.b / foundation.k
        return 2.0 / 3.0 * block.b**3 * foundation.k - block.m * block.g * block.h + 0.5 * foundation.eps * e0

    def equivalent_coefficients(self, sigma_theta, cov_over_sigma, block, foundation):
        from screening.condensation.paper_coefficients import equivalent_coefficients

        return equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation)

    def sdof_kernel(self, block, foundation):
        return SdofKernel(damping_stiffness_jit, sdof_record(block, foundation))

    def moment_kernel(self, block, foundation):
        from screening.condensation.paper_coefficients import equivalent_coefficients_jit, records
        from screening.condensation.uplift_integrals import coefficient_table

        rec = records(block, foundation)
        return MomentKernel(equivalent_coefficients_jit, rec, coefficient_table()[None],
                            np.zeros(rec.size, dtype=np.int64))


PAPER = register(PaperCondensation())
