"""Energy-consistent quasi-static condensation (``"virtual_work"``): the rocking damping is the
dissipation of the contact law along the quasi-static path, not its moment about the base centre.

``z_cb(theta)`` of the cubic condensation is treated as a holonomic constraint: the damping is
``-dD/dtheta'`` of the bed's Rayleigh function along it, ``C(theta) theta'^2`` = the power dissipated in
the bed, while ``K`` is that of ``"cubic"``.  With ``eps = 0`` (Hunt–Crossley) ``C = C1 min(1, theta_ul / |theta|)``
against the paper's ``C1 (theta_ul / |theta|)^(1/2)`` (eq. 24 of [mitseas2026]).  Why, the equations of
each regime, and what is still dropped: ``docs/heavy_uplift.md``.
"""

from __future__ import annotations

import numba
import numpy as np

from screening.core.condensation import cubic
from screening.core.condensation.base import Condensation, SdofKernel
from screening.core.condensation.registry import register
from screening.core.signatures import sdof_coefficients_signature

__all__ = []


def rocking_damping(theta, block, foundation):
    """Energy-consistent rocking damping ``C(theta)`` [N m s/rad] of the ``"virtual_work"`` condensation.

    Notes
    -----
    ``C theta'^2 = 2 D``, ``D = (1/2) int zdot (w_rate + w_indentation z) zdot`` over the contact zone with
    ``zdot(u) = (z_cb'(theta) + u) theta'`` along the cubic condensation's path: the generalised force of
    the law of eqs. (3)-(4) of [mitseas2026] on the one remaining coordinate.
    """
    z, zp = cubic.quasi_static_indentation(theta, block, foundation)
    b = block.b
    a = np.abs(np.asarray(theta, dtype=float))
    v = z + b * a
    uplift = a > cubic.uplift_threshold(block, foundation)
    V = zp + b
    w_rate, w_ind = foundation.damping_weights          # zdot (w_rate + w_ind z)
    with np.errstate(divide="ignore", invalid="ignore"):
        length = v / a
        c_in = (w_rate * (2.0 * b * zp * zp + 2.0 / 3.0 * b**3)
                + w_ind * (2.0 * b * z * zp * zp + 2.0 / 3.0 * b**3 * z + 4.0 / 3.0 * b**3 * a * zp))
        c_up = (w_rate * (V * V * length - V * length * length + length**3 / 3.0)
                + w_ind * (V * V * v * v / (2.0 * a) - V * v**3 / (3.0 * a * a) + v**4 / (12.0 * a**3)))
    return np.where(uplift, c_up, c_in)[()]


@numba.njit(sdof_coefficients_signature(cubic.SDOF_RECORD), cache=True)
def damping_stiffness_jit(p, theta):
    """Compiled twin of :func:`rocking_damping` and of the cubic ``K``: ``(C, K)`` from one indentation solve."""
    a = abs(theta)
    z, zp, v = cubic.quasi_static_indentation_jit(p, a)
    _, stiffness = cubic.damping_stiffness_jit(p, theta)
    b, w_rate, w_ind = p.b, p.w_rate, p.w_indentation
    b3 = b * b * b
    if a <= p.theta_ul:
        return (w_rate * (2.0 * b * zp * zp + 2.0 / 3.0 * b3)
                + w_ind * (2.0 * b * z * zp * zp + 2.0 / 3.0 * b3 * z + 4.0 / 3.0 * b3 * a * zp)), stiffness
    V = zp + b
    length = v / a
    v2 = v * v
    return (w_rate * (V * V * length - V * length * length + length * length * length / 3.0)
            + w_ind * (V * V * v2 / (2.0 * a) - V * v2 * v / (3.0 * a * a) + v2 * v2 / (12.0 * a * a * a))), stiffness


class VirtualWorkCondensation(Condensation):
    """Quasi-static path of ``"cubic"``; damping from the bed's dissipation along it (module docstring)."""

    name = "virtual_work"
    description = ("quasi-static z_cb of 'cubic'; C(theta) theta'^2 = power dissipated in the bed along the "
                   "quasi-static path (generalised force of the constrained coordinate), K of 'cubic'")

    def check(self, block, foundation):
        cubic.check_bearing(block, foundation)

    def uplift_threshold(self, block, foundation):
        return cubic.uplift_threshold(block, foundation)

    def capacity_angle(self, block, foundation):
        return cubic.capacity_angle(block, foundation)

    def rocking_damping(self, theta, block, foundation):
        return rocking_damping(theta, block, foundation)

    def rocking_stiffness(self, theta, block, foundation):
        return cubic.rocking_stiffness(theta, block, foundation)

    def stiffness_at_rest(self, block, foundation):
        return cubic.stiffness_at_rest(block, foundation)

    def sdof_kernel(self, block, foundation):
        return SdofKernel(damping_stiffness_jit, cubic.sdof_record(block, foundation))


VIRTUAL_WORK = register(VirtualWorkCondensation())
