"""Energy-consistent quasi-static condensation (``"virtual_work"``): the rocking damping is the
dissipation of the contact law along the quasi-static path, not its moment about the base centre.

Why (``docs/heavy_uplift.md``).  The paper's condensation (and ``"cubic"``) slaves the base
indentation to ``z_cb(theta)`` and takes the damping moment of eq. (16) about the base centre with
``zdot_cb = z_cb'(theta) theta'``.  That moment is not the generalised force of the damping on the
one remaining coordinate: the damping *force* ``F_d`` also works through ``zdot_cb``, and its power
``F_d zdot_cb`` is left out (the vertical equation is dropped).  In uplift the two differ by a
factor ``sqrt(|theta| / theta_ul)`` (eps = 0), and free rocking of the coupled model released
at 30 ``theta_ul`` loses 7.5 % of its amplitude per half cycle where the condensed model loses 13 %.

Here ``z_cb = z_cb(theta)`` is treated as a holonomic constraint (principle of virtual work).  The
generalised damping force is ``-dD/dtheta'`` of the Rayleigh function of the bed along the
constraint, ``D = (1/2) int lam z zdot^2`` (Hunt–Crossley) or ``(1/2) int c zdot^2`` (Winkler), with
``zdot(u) = (z_cb'(theta) + u) theta'`` (small angles, ``u`` towards the compressed edge).  So

    C(theta) theta'^2 = power dissipated in the bed.

The restoring moment is unchanged: on the static path the vertical balance holds, so the extra
virtual work ``(F_k - m g) delta z_cb`` vanishes and ``K`` is that of ``"cubic"`` (with ``eps = 0``
the paper's eq. 25).  The quasi-static ``z_cb(theta)`` is the cubic condensation's (eqs. Q1, Q2 of
:mod:`screening.core.condensation.cubic`, ``eps = 0``: eqs. 17–18).

Symbols and units (SI): ``a = |theta|`` [rad], ``z = z_cb`` [m], ``zp = dz_cb/da`` [m/rad],
``v = z + b a`` the compressed-edge indentation [m], ``V = zp + b = dv/da`` [m/rad], ``b`` [m],
``lam`` [N s/m^3], ``c`` [N s/m^2].

Equations (contact zone: ``u`` from ``-b`` to ``b`` without uplift; the length ``L = v / a``
from the compressed edge with uplift, ``s`` the distance from it, ``z(s) = v - a s``,
``zdot(s) = (V - s) a'``)::

    Hunt–Crossley, no uplift:  C = lam int_{-b}^{b} (z + a u) (zp + u)^2 du
                                 = lam [2 b z zp^2 + (2/3) b^3 z + (4/3) b^3 a zp]
    Hunt–Crossley, uplift:     C = lam int_0^L (v - a s) (V - s)^2 ds
                                 = lam [V^2 v^2 / (2 a) - V v^3 / (3 a^2) + v^4 / (12 a^3)]
    Winkler, no uplift:        C = c [2 b zp^2 + (2/3) b^3]
    Winkler, uplift:           C = c [V^2 L - V L^2 + L^3 / 3]

``C`` is continuous at the threshold (there ``v = 2 b a`` and the two zones coincide) and
positive (a Rayleigh function).  With ``eps = 0`` (``zp = 0`` without uplift, ``V = v / (2 a)``,
``v^2 = 2 m g a / k`` with it) the Hunt–Crossley ``C`` is simply

    C = C1 min(1, theta_ul / |theta|),   C1 = lam b^2 m g / (3 k)   (the paper's no-uplift value)

against the paper's ``C1 (theta_ul / |theta|)^(1/2)`` (eq. 24): ``sqrt(|theta| / theta_ul)`` times
less damping in uplift.

What is still dropped: the vertical inertia (``m z_cb''``; the constrained inertia ``m zp^2``
and its rate terms would change ``M``, which the condensation interface keeps at ``I_cm + m h^2``),
and the lag of ``z_cb`` behind its static value.  Method and checks: ``docs/heavy_uplift.md``.
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

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``C(theta)`` [N m s/rad], broadcast over ``theta`` and the model's fields.

    Notes
    -----
    ``C theta'^2`` is the power dissipated in the bed, ``2 D`` of the Rayleigh function
    ``D = (1/2) int zdot (w_rate + w_indentation z) zdot`` over the contact zone with
    ``zdot(u) = (z_cb'(theta) + u) theta'`` along the quasi-static path of the cubic condensation: the
    generalised force of the law of eqs. (3)-(4) in [1] on the one remaining coordinate (the paper's
    eq. (24) takes the moment about the base centre instead; module docstring).

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
    """Compiled twin of :func:`rocking_damping` and of the cubic ``K``.

    Parameters
    ----------
    p : numpy.void
        A :data:`screening.core.condensation.cubic.SDOF_RECORD`.
    theta : float
        Rotation [rad].

    Returns
    -------
    C : float
        Rocking damping [N m s/rad].
    K : float
        Secant rocking stiffness [N m/rad] (that of the cubic condensation, eqs. (14) and (16) in [1]).

    Notes
    -----
    The dissipation-consistent damping of :func:`rocking_damping` from one indentation solve.

    """
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
