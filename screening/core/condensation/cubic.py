"""Quasi-static condensation with the cubic term in the static vertical balance (``"cubic"``).

The paper's condensation (:mod:`screening.core.condensation.paper`) slaves the base-centre indentation to
the *linear* static balance (eqs. 17–18 of [mitseas2026]); here ``z_cb(theta)`` is the root of the full
balance with the ``eps`` term in both regimes (eqs. 13 and 15), and ``C(theta)``, ``K(theta)`` follow
from eqs. (14) and (16) with it, the quasi-static rate ``zdot_cb = z_cb'(theta) theta'`` kept in ``C``.
``eps = 0`` reproduces the paper.  A softening bed has a capacity angle beyond which no quasi-static
equilibrium exists (:func:`capacity_angle`); there the compressed edge is held at its peak load with no
rate, so ``K`` and ``C`` stay finite.  Symbols [SI], the derivation, the uplift threshold and the
softening limits: ``docs/method.md#cubic-condensation`` and ``#softening-beds-and-the-capacity-angle``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.core.condensation.base import Condensation, SdofKernel
from screening.core.physics import contact
from screening.core.physics.contact import (UPLIFT_BEARING_LIMIT, bearing_load, exact_uplift_angle,
                                            linear_indentation, rising_root)
from screening.core.condensation.registry import register
from screening.core.signatures import sdof_coefficients_signature

__all__ = []

#: Largest ``|eps| z_lin^2`` of a softening bed for which the uplift threshold exists
#: (:data:`screening.core.physics.contact.UPLIFT_BEARING_LIMIT`).
SOFTENING_LIMIT = UPLIFT_BEARING_LIMIT


def check_bearing(block, foundation):
    """Refuse a softening bed that cannot carry the block through the onset of uplift.

    Notes
    -----
    Raises ``ValueError`` naming ``foundation.eps`` unless ``|eps| z_lin^2 < 2/27`` (:data:`SOFTENING_LIMIT`,
    :func:`bearing_load`; ``z_lin`` of eq. (17) of [mitseas2026]) at every point; ``eps >= 0`` passes.
    Every public function here calls it.
    """
    eps = np.asarray(foundation.eps, dtype=float)
    load = bearing_load(block, foundation)
    if np.any(load >= SOFTENING_LIMIT):
        bad = float(np.broadcast_to(eps, np.broadcast(eps, load).shape)[load >= SOFTENING_LIMIT].flat[0])
        raise ValueError(
            f"parameter 'foundation.eps' = {bad!r} 1/m^2: the softening bed cannot carry the block "
            f"through the onset of uplift under condensation='cubic' (need |eps| (m g/(2 b k))^2 < 2/27)")


def rest_indentation(block, foundation):
    """Static indentation at rest ``z0`` [m] (eq. (13) of [mitseas2026], cubic term included), after :func:`check_bearing`."""
    check_bearing(block, foundation)
    return contact.rest_indentation(block, foundation)


def uplift_threshold(block, foundation):
    """Uplift threshold ``theta_ul`` [rad]: the exact static uplift angle (:func:`screening.core.physics.contact.exact_uplift_angle`).

    Notes
    -----
    ``y = b theta_ul`` solves ``2 eps y^3 + y = z_lin``: where the quasi-static ``z_cb(theta)`` reaches
    ``b theta`` (eq. (19) of [mitseas2026] generalised).  Raises ``ValueError`` naming ``foundation.eps`` where :func:`check_bearing` refuses the bed.
    """
    check_bearing(block, foundation)
    return exact_uplift_angle(block, foundation)


def capacity_angle(block, foundation):
    """Capacity angle ``theta_cap = k / (4 |eps| m g)`` [rad] of a softening bed; ``inf`` for ``eps >= 0``.

    Notes
    -----
    Beyond it the uplift balance ``(k/(2a)) v^2 + (eps k/(4a)) v^4 = m g`` (eq. (15) of [mitseas2026])
    has no root.
    """
    eps = np.asarray(foundation.eps, dtype=float)
    with np.errstate(divide="ignore"):
        cap = np.where(eps < 0.0, foundation.k / (4.0 * np.abs(eps) * block.m * block.g), np.inf)
    return cap[()]


def in_equilibrium(theta, block, foundation):
    """Boolean: where a quasi-static vertical equilibrium exists, ``|theta| <= theta_cap`` (:func:`capacity_angle`)."""
    return np.abs(np.asarray(theta, dtype=float)) <= capacity_angle(block, foundation)


def quasi_static_indentation(theta, block, foundation):
    """Quasi-static base-centre indentation ``z_cb`` [m] (even in ``theta``) and its slope ``dz_cb/d|theta|`` [m/rad].

    Notes
    -----
    Below ``theta_ul`` the balance ``eps z^3 + (1 + eps b^2 theta^2) z = z_lin`` (eq. (13) of [mitseas2026]),
    above it the uplift balance (eq. (15)); beyond the capacity angle the contact is held at its peak load
    with slope 0.
    """
    return indentation_state(theta, block, foundation)[:2]


def indentation_state(theta, block, foundation):
    """The quasi-static contact state at ``theta`` [rad]: ``(z, slope, v, a, uplift)``.

    Notes
    -----
    ``z``, ``slope`` of :func:`quasi_static_indentation`; ``v = b |theta| + z`` [m] the compressed-edge
    indentation; ``a = |theta|`` broadcast with the fields; ``uplift`` where ``|theta| > theta_ul``.
    """
    check_bearing(block, foundation)
    a = np.abs(np.asarray(theta, dtype=float))
    b, k, eps, mg = block.b, foundation.k, np.asarray(foundation.eps, dtype=float), block.m * block.g
    z_lin = linear_indentation(block, foundation)
    a, b, k, eps, mg, z_lin = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (a, b, k, eps, mg, z_lin)))
    uplift = a > uplift_threshold(block, foundation)
    # no uplift: eq. (13) balance (Q1)
    beta = 1.0 + eps * b * b * a * a
    z_in = rising_root(eps, beta, z_lin)
    dz_in = -2.0 * eps * b * b * a * z_in / (beta + 3.0 * eps * z_in * z_in)
    # uplift: eq. (15) balance (Q2), held at the peak load beyond the capacity angle
    A = 2.0 * mg * a / k
    s2 = 1.0 + 2.0 * eps * A
    beyond = s2 <= 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        S = np.sqrt(np.where(beyond, 1.0, s2))
        w = np.where(beyond, 1.0 / np.abs(np.where(eps != 0.0, eps, 1.0)), 2.0 * A / (1.0 + S))
        v_up = np.sqrt(w)
        dz_up = np.where(beyond, 0.0, mg / (k * S * v_up) - b)       # (dw/da) / (2 v) - b
    z_up = v_up - b * a
    z = np.where(uplift, z_up, z_in)
    dz = np.where(uplift, dz_up, dz_in)
    v = np.where(uplift, v_up, z_in + b * a)
    return z, dz, v, a, uplift


def rocking_damping(theta, block, foundation):
    """Rocking damping ``C(theta)`` [N m s/rad] of the cubic condensation.

    Notes
    -----
    Eqs. (14) and (16) of [mitseas2026] with the quasi-static rate ``zdot_cb = (dz/dtheta) theta'`` and the
    law's damping pressure; ``eps = 0`` gives eq. (24).  Raises ``ValueError`` naming ``foundation.eps`` where :func:`check_bearing` refuses the bed.
    """
    z, dz, v, a, uplift = indentation_state(theta, block, foundation)
    b = block.b
    w_rate, w_ind = foundation.damping_weights          # zdot (w_rate + w_ind z)
    c_in = (2.0 / 3.0 * w_rate * b**3 + 0.0 * a) + 2.0 / 3.0 * w_ind * b**3 * (z + a * dz)
    with np.errstate(divide="ignore", invalid="ignore"):
        c_up = (w_rate / (a * a) * (0.5 * dz * v * (b * a - z) + (b**3 * a**3 + z**3) / (3.0 * a))
                + w_ind / (12.0 * a**3) * (3.0 * b**4 * a**4 + 4.0 * b**3 * z * a**3 + z**4
                                           + 2.0 * a * dz * v * v * (2.0 * b * a - z)))
    return np.where(uplift, c_up, c_in)[()]


def rocking_stiffness(theta, block, foundation):
    """Secant rocking stiffness ``K(theta)`` [N m/rad] (restoring moment ``K theta``), the same for both laws.

    Notes
    -----
    ``K_in = (2/3) b^3 k - m g h + eps k (2 b^3 z^2 + (2/5) b^5 a^2)`` (eq. (14) of [mitseas2026]) and ``K_up``
    of eq. (16) at the quasi-static ``z``; ``eps = 0`` gives eq. (25).  Raises ``ValueError`` naming ``foundation.eps`` where :func:`check_bearing` refuses the bed.
    """
    z, _, v, a, uplift = indentation_state(theta, block, foundation)
    b, k, eps = block.b, foundation.k, foundation.eps
    mgh = block.m * block.g * block.h
    k_in = 2.0 / 3.0 * b**3 * k - mgh + eps * k * (2.0 * b**3 * z * z + 0.4 * b**5 * a * a)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_up = (k * v * v * (2.0 * b * a - z) / 6.0 + eps * k * v**4 * (4.0 * b * a - z) / 20.0) / a**3 - mgh
    return np.where(uplift, k_up, k_in)[()]


def restoring_moment(theta, block, foundation):
    """Restoring moment ``K(theta) theta`` [N m], odd in ``theta`` (eq. (22) of [mitseas2026])."""
    theta = np.asarray(theta, dtype=float)
    return (rocking_stiffness(theta, block, foundation) * theta)[()]


def damping_at_rest(block, foundation):
    """Rocking damping at rest ``C(0) = (2/3) b^3 (w_rate + w_indentation z0)`` [N m s/rad] (eq. (14) of [mitseas2026])."""
    check_bearing(block, foundation)
    w_rate, w_ind = foundation.damping_weights
    return 2.0 / 3.0 * w_rate * block.b**3 + 2.0 / 3.0 * w_ind * block.b**3 * rest_indentation(block, foundation)


def stiffness_at_rest(block, foundation):
    """Rocking stiffness at rest ``K(0) = (2/3) b^3 k - m g h + 2 eps k b^3 z0^2`` [N m/rad] (eq. (14) of [mitseas2026])."""
    z0 = rest_indentation(block, foundation)
    b, k = block.b, foundation.k
    return contact.linear_rocking_stiffness(block, foundation) + 2.0 * foundation.eps * k * b**3 * z0 * z0


#: Per-point parameters of the compiled twins (SI units): block, bed (the law's damping weights),
#: threshold, ``z_lin`` (eq. 17), rest indentation ``z_rest`` and ``z_curv = dz/d(theta^2)`` at rest
#: (the Newton start of the no-uplift balance).
SDOF_RECORD = np.dtype([("theta_ul", "f8"), ("m", "f8"), ("g", "f8"), ("h", "f8"), ("b", "f8"), ("k", "f8"),
                        ("eps", "f8"), ("w_rate", "f8"), ("w_indentation", "f8"), ("z_lin", "f8"), ("z_rest", "f8"),
                        ("z_curv", "f8")])


def sdof_record(block, foundation):
    """The 1-element :data:`SDOF_RECORD` [SI] of scalar model objects, for the compiled twins.

    Notes
    -----
    The block, the bed, the threshold, ``z_lin`` and the rest indentation with its curvature (the Newton
    start of the balance of eq. (13) of [mitseas2026]).
    """
    b, eps = float(block.b), float(foundation.eps)
    z0 = float(rest_indentation(block, foundation))
    rec = np.zeros(1, dtype=SDOF_RECORD)
    values = dict(theta_ul=float(uplift_threshold(block, foundation)), m=float(block.m), g=float(block.g),
                  h=float(block.h), b=b, k=float(foundation.k), eps=eps, w_rate=float(foundation.damping_weights[0]),
                  w_indentation=float(foundation.damping_weights[1]),
                  z_lin=float(linear_indentation(block, foundation)), z_rest=z0,
                  z_curv=-eps * b * b * z0 / (1.0 + 3.0 * eps * z0 * z0))
    for name, value in values.items():
        rec[name] = value
    return rec


@numba.njit(cache=True)
def quasi_static_indentation_jit(p, a):
    """Compiled twin of :func:`quasi_static_indentation` at ``a = |theta|`` (record ``p``), also returning ``v``."""
    b, eps = p.b, p.eps
    if a <= p.theta_ul:
        # eps z^3 + beta z = z_lin, beta = 1 + eps b^2 a^2: Newton from the Taylor start
        # z0 + (dz/d a^2) a^2 (error O(a^4); monotone like the start z_lin / beta)
        beta = 1.0 + eps * b * b * a * a
        z = p.z_rest + p.z_curv * a * a
        for _ in range(100):
            step = (eps * z * z * z + beta * z - p.z_lin) / (3.0 * eps * z * z + beta)
            z -= step
            if abs(step) <= 1e-15 * z:
                break
        return z, -2.0 * eps * b * b * a * z / (beta + 3.0 * eps * z * z), z + b * a
    mg = p.m * p.g
    big_a = 2.0 * mg * a / p.k
    s2 = 1.0 + 2.0 * eps * big_a
    if s2 <= 0.0:                               # beyond the capacity angle: peak load, no rate
        v = 1.0 / math.sqrt(-eps)
        return v - b * a, 0.0, v
    S = math.sqrt(s2)
    v = math.sqrt(2.0 * big_a / (1.0 + S))
    return v - b * a, mg / (p.k * S * v) - b, v


@numba.njit(sdof_coefficients_signature(SDOF_RECORD), cache=True)
def damping_stiffness_jit(p, theta):
    """Compiled twin of :func:`rocking_damping` and :func:`rocking_stiffness`: ``(C, K)`` from one indentation solve."""
    a = abs(theta)
    z, dz, v = quasi_static_indentation_jit(p, a)
    b, k, eps, w_rate, w_ind = p.b, p.k, p.eps, p.w_rate, p.w_indentation
    mgh = p.m * p.g * p.h
    b3 = b * b * b
    if a <= p.theta_ul:
        stiffness = 2.0 / 3.0 * b3 * k - mgh + eps * k * (2.0 * b3 * z * z + 0.4 * b3 * b * b * a * a)
        return 2.0 / 3.0 * w_rate * b3 + 2.0 / 3.0 * w_ind * b3 * (z + a * dz), stiffness
    ba = b * a
    a3 = a * a * a
    v2 = v * v
    stiffness = (k * v2 * (2.0 * ba - z) / 6.0 + eps * k * v2 * v2 * (4.0 * ba - z) / 20.0) / a3 - mgh
    ba2 = ba * ba
    z2 = z * z
    return (w_rate / (a * a) * (0.5 * dz * v * (ba - z) + (ba * ba * ba + z * z * z) / (3.0 * a))
            + w_ind / (12.0 * a3) * (3.0 * ba2 * ba2 + 4.0 * ba2 * ba * z + z2 * z2 + 2.0 * a * dz * v2 * (2.0 * ba - z)),
            stiffness)


class CubicCondensation(Condensation):
    """Static vertical balance including the cubic term, in both regimes (module docstring)."""

    name = "cubic"
    description = ("quasi-static z_cb from the static vertical balance with the cubic term (eqs. 13, 15); "
                   "C, K from eqs. 14, 16 with zdot_cb = z_cb'(theta) theta'")

    def check(self, block, foundation):
        check_bearing(block, foundation)

    uplift_threshold = staticmethod(uplift_threshold)
    capacity_angle = staticmethod(capacity_angle)
    rocking_damping = staticmethod(rocking_damping)
    rocking_stiffness = staticmethod(rocking_stiffness)
    damping_at_rest = staticmethod(damping_at_rest)
    stiffness_at_rest = staticmethod(stiffness_at_rest)

    def sdof_kernel(self, block, foundation):
        return SdofKernel(damping_stiffness_jit, sdof_record(block, foundation))


CUBIC = register(CubicCondensation())
