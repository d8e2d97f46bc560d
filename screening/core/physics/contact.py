"""Contact resultants of the full coupled model ([mitseas2026] eqs. 1–6), exact in every regime.

``F_cb`` [N] and the moment about the base centre ``M_cb`` [N m] are the integrals (5)–(6) of the
contact law (3)–(4) over the part of the base in contact, in closed form for any ``theta``, any
``z_cb`` and both bed laws, without small-angle approximations: each integrand is a product of
functions linear along the base, so each integral is exact from its end values (no division by
``sin theta``).  Symbols, units, the derivation and the regime-by-regime formulas (and where they
differ from the printed eqs. 10–12): ``docs/method.md#contact-regimes-and-resultants``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.core.status import ContactRegime

__all__ = []

#: Integer codes of the contact regimes returned by :func:`contact_regime`.
REGIME_FULL_CONTACT = int(ContactRegime.full_contact)
REGIME_UPLIFT_POSITIVE = int(ContactRegime.uplift_positive)
REGIME_UPLIFT_NEGATIVE = int(ContactRegime.uplift_negative)
REGIME_FLIGHT = int(ContactRegime.flight)
REGIME_NAMES = {REGIME_FULL_CONTACT: "full contact", REGIME_UPLIFT_POSITIVE: "uplift, theta > 0",
                REGIME_UPLIFT_NEGATIVE: "uplift, theta < 0", REGIME_FLIGHT: "flight"}


def foundation_constants(foundation):
    """``(k [N m-2], eps [m-2], damping, winkler)`` of a Hunt–Crossley or Winkler bed as plain numbers.

    Notes
    -----
    ``damping`` is ``lam`` [N s m-3] (Hunt–Crossley) or ``c`` [N s m-2] (Winkler, ``winkler`` true): the
    arguments of :func:`contact_resultants` after ``b`` (eqs. (3)-(4) of [mitseas2026]).
    """
    return float(foundation.k), float(foundation.eps), float(foundation.damping), foundation.law == "winkler"


def law_constants(foundation):
    """``(k [N m-2], eps [m-2], w_rate [N s m-2], w_indentation [N s m-3])`` of a bed of any contact law.

    Notes
    -----
    The arguments of :func:`law_resultants` after ``b``: the law's damping pressure is
    ``zdot (w_rate + w_indentation z)`` (Winkler ``(c, 0)``, Hunt–Crossley ``(0, lam)``, eq. (3) of [mitseas2026]).
    """
    w_rate, w_indentation = foundation.damping_weights
    return float(foundation.k), float(foundation.eps), float(w_rate), float(w_indentation)


def corner_indentations(theta, z_cb, b):
    """Indentations ``(z_c, z_f)`` [m] of the compressed and of the lifted base edge.

    Notes
    -----
    ``z_c = z_cb + b |sin theta|``, ``z_f = z_cb - b |sin theta|`` (negative in uplift): the linear
    indentation field of eqs. (1)-(2) of [mitseas2026] at the edges (``theta`` [rad], ``z_cb`` the
    base-centre indentation [m], positive into the bed, ``b`` the half-width [m]).
    """
    a = np.abs(np.sin(np.asarray(theta, dtype=float)))
    z_cb = np.asarray(z_cb, dtype=float)
    return z_cb + b * a, z_cb - b * a


def contact_regime(theta, z_cb, b):
    """Contact regime code (:class:`screening.core.status.ContactRegime`) of a rotated, indented base.

    Notes
    -----
    Full contact while the lifted edge is indented (``z_f >= 0``), flight once the compressed edge is not
    (``z_c <= 0``), uplift between (:func:`corner_indentations`; eqs. (9)-(12) of [mitseas2026]).
    """
    theta = np.asarray(theta, dtype=float)
    z_c, z_f = corner_indentations(theta, z_cb, b)
    uplift = np.where(theta >= 0.0, REGIME_UPLIFT_POSITIVE, REGIME_UPLIFT_NEGATIVE)
    return np.where(z_c <= 0.0, REGIME_FLIGHT, np.where(z_f >= 0.0, REGIME_FULL_CONTACT, uplift))


def contact_length(theta, z_cb, b):
    """Length ``P`` [m] of the contact zone from the compressed edge: ``2 b`` in full contact, ``z_c / |sin theta|`` in uplift, 0 in flight."""
    a = np.abs(np.sin(np.asarray(theta, dtype=float)))
    z_c, z_f = corner_indentations(theta, z_cb, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        partial = np.minimum(z_c / a, 2.0 * b)
    return np.where(z_c <= 0.0, 0.0, np.where(z_f >= 0.0, 2.0 * b, partial))


def contact_resultants(theta, theta_dot, z_cb, z_cb_dot, b, k, eps, damping, winkler=False):
    """Like :func:`law_resultants`, with one ``damping`` and a flag in place of the two weights.

    ``damping`` is ``lam`` [N s m-3] of a Hunt–Crossley bed (weights ``(0, lam)``) or, with ``winkler``
    true, ``c`` [N s m-2] of a Winkler bed (weights ``(c, 0)``); eqs. (5)-(6) of [mitseas2026], exact.
    Kept for callers that hold a damping and a flag; the solvers pass the law's weights.
    """
    w_rate, w_indentation = (damping, 0.0) if winkler else (0.0, damping)
    return law_resultants(theta, theta_dot, z_cb, z_cb_dot, b, k, eps, w_rate, w_indentation)


def law_resultants(theta, theta_dot, z_cb, z_cb_dot, b, k, eps, w_rate, w_indentation):
    """Resultant contact force ``F_cb`` [N] and moment ``M_cb`` [N m] of any contact law, exact; zero in flight.

    Notes
    -----
    Broadcast over the arguments (``theta`` [rad], positive with edge B compressed; ``theta_dot``
    [rad s-1]; ``z_cb`` [m], ``z_cb_dot`` [m s-1]; ``b`` [m]; ``k``, ``eps``, ``w_rate``, ``w_indentation``:
    :func:`law_constants`).  Over the contact zone, each integral exact from its end values::

        F_cb = k int z + eps k int z^3 + w_rate int zdot + w_indentation int z zdot
        M_cb = sigma cos(theta) (k int z r + eps k int z^3 r + w_rate int zdot r + w_indentation int z zdot r)

    eqs. (5)-(6) of [mitseas2026] with the law of eqs. (3)-(4), without small-angle approximations.
    """
    theta = np.asarray(theta, dtype=float)
    theta_dot = np.asarray(theta_dot, dtype=float)
    z_cb = np.asarray(z_cb, dtype=float)
    z_cb_dot = np.asarray(z_cb_dot, dtype=float)
    s, c = np.sin(theta), np.cos(theta)
    sigma = np.where(theta >= 0.0, 1.0, -1.0)
    a = sigma * s                                   # |sin theta|
    w = sigma * theta_dot * c                       # rate of the slope, seen from the compressed edge
    z1 = z_cb + b * a                               # compressed edge
    v1 = z_cb_dot + b * w
    full = z_cb - b * a >= 0.0
    in_contact = z1 > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        length = np.where(full, 2.0 * b, np.where(in_contact, z1 / np.where(a > 0.0, a, 1.0), 0.0))
    z2 = np.where(full, z_cb - b * a, 0.0)          # far end of the contact zone
    v2 = v1 - w * length
    r1, r2 = b, b - length                          # lever arm / cos(theta), towards the compressed edge
    P = length

    int_z = P * (z1 + z2) / 2.0
    int_z3 = P * (z1 + z2) * (z1 * z1 + z2 * z2) / 4.0
    int_zr = P * (2.0 * z1 * r1 + z1 * r2 + z2 * r1 + 2.0 * z2 * r2) / 6.0
    int_z3r = P * ((z1**3 * r1 + z2**3 * r2) / 5.0 + (z1**3 * r2 + z2**3 * r1) / 20.0
                   + 3.0 * (z1 * z1 * z2 * r1 + z1 * z2 * z2 * r2) / 20.0
                   + (z1 * z1 * z2 * r2 + z1 * z2 * z2 * r1) / 10.0)
    int_v = P * (v1 + v2) / 2.0
    int_vr = P * (2.0 * v1 * r1 + v1 * r2 + v2 * r1 + 2.0 * v2 * r2) / 6.0
    int_zv = P * (2.0 * z1 * v1 + z1 * v2 + z2 * v1 + 2.0 * z2 * v2) / 6.0
    int_zvr = P * ((z1 * v1 * r1 + z2 * v2 * r2) / 4.0
                   + (z1 * v1 * r2 + z1 * v2 * r1 + z2 * v1 * r1
                      + z1 * v2 * r2 + z2 * v1 * r2 + z2 * v2 * r1) / 12.0)
    force = k * int_z + eps * k * int_z3 + (w_rate * int_v + w_indentation * int_zv)
    moment = sigma * c * (k * int_zr + eps * k * int_z3r + (w_rate * int_vr + w_indentation * int_zvr))
    force = np.where(in_contact, force, 0.0)
    moment = np.where(in_contact, moment, 0.0)
    return force, moment


def linear_indentation(block, foundation):
    """Static indentation of the base centre by the linear law alone, ``z_lin = m g / (2 b k)`` [m] (eq. (17) of [mitseas2026])."""
    return block.m * block.g / (2.0 * block.b * foundation.k)


def bed_rocking_stiffness(block, foundation):
    """Rocking stiffness ``K0 = (2/3) b^3 k`` [N m/rad] of the linear bed under the base in full contact.

    Notes
    -----
    The restoring moment of the linear pressure (eq. (3) of [mitseas2026]) over the base rotated by a
    small ``theta``: ``int k (x theta) x dx = (2/3) b^3 k theta`` (``K0`` of eqs. (35)-(36)).
    """
    return 2.0 / 3.0 * block.b**3 * foundation.k


def linear_rocking_stiffness(block, foundation):
    """Rocking stiffness at rest without the cubic term, ``K0 - m g h = (2/3) b^3 k - m g h`` [N m/rad].

    Notes
    -----
    ``K(0)`` of every condensation at ``eps = 0`` (eqs. (22) and (25) of [mitseas2026] at ``theta = 0``);
    the block rocks about its rest position only where it is positive.
    """
    return bed_rocking_stiffness(block, foundation) - block.m * block.g * block.h


def rising_root(alpha, beta, rhs, max_iter=100):
    """Root [m] of ``alpha z^3 + beta z = rhs`` on the rising branch (``beta + 3 alpha z^2 > 0``).

    Notes
    -----
    Newton (at most ``max_iter`` steps) from ``z = rhs / beta``: for ``alpha >= 0`` the cubic is convex and
    the start right of the root, for ``alpha < 0`` concave and the start left of it, so the iterates
    converge monotonically.  It solves the static balances of eq. (13) of [mitseas2026].
    """
    alpha, beta, rhs = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (alpha, beta, rhs)))
    z = rhs / beta
    for _ in range(max_iter):
        step = (alpha * z**3 + beta * z - rhs) / (3.0 * alpha * z * z + beta)
        z = z - step
        if np.all(np.abs(step) <= 1e-15 * np.abs(z)):
            break
    return z


#: Largest bearing load ``|eps| z_lin^2`` [1] under which a softening bed carries the block's weight at rest
#: (:func:`rest_indentation`; the rising branch of ``z + eps z^3 = z_lin`` ends there).
REST_BEARING_LIMIT = 4.0 / 27.0


def rest_indentation(block, foundation):
    """Static indentation of the base centre at rest ``z0`` [m], cubic term included.

    Notes
    -----
    The root of ``eps z0^3 + z0 = z_lin`` on the rising branch (eq. (13) of [mitseas2026] at rest);
    ``ValueError`` where a softening bed cannot carry the weight (``|eps| z_lin^2 >= 4/27``).
    """
    z_lin = linear_indentation(block, foundation)
    eps = np.asarray(foundation.eps, dtype=float)
    load = -eps * np.asarray(z_lin, dtype=float) ** 2
    if np.any(load >= REST_BEARING_LIMIT):
        bad = float(np.broadcast_to(eps, np.shape(load))[load >= REST_BEARING_LIMIT].flat[0])
        raise ValueError(f"parameter 'foundation.eps' = {bad!r} 1/m^2: the softening bed cannot carry the block's "
                         f"weight (need |eps| (m g/(2 b k))^2 < 4/27)")
    return rising_root(eps, 1.0, z_lin)[()]


def vertical_damping_ratio(block, foundation, z_rest=None):
    """Damping ratio ``zeta_v`` [1] of the block's vertical vibration about its rest indentation (above 1: overdamped).

    Notes
    -----
    About ``z0`` (``z_rest``; None: :func:`rest_indentation`) the law's damping pressure (eqs. (3)-(4) of
    [mitseas2026]) over the base is the dashpot ``c_v = 2 b (w_rate + w_indentation z0)`` (Hunt–Crossley
    [hunt1975]: ``2 b lam z0``; Winkler: ``2 b c``) on the spring ``k_v = 2 b k`` [clough1975]::

        zeta_v = c_v / (2 sqrt(k_v m)) = b (w_rate + w_indentation z0) / sqrt(2 b k m)

    The spring leaves out the tangent stiffness ``6 b k eps z0^2`` of the cubic term.
    """
    if z_rest is None:
        z_rest = rest_indentation(block, foundation)
    w_rate, w_indentation = foundation.damping_weights
    return block.b * (w_rate + w_indentation * z_rest) / np.sqrt(2.0 * block.b * foundation.k * block.m)


#: Largest bearing load ``|eps| z_lin^2`` [1] of a softening bed that carries the block through the onset
#: of uplift (:func:`exact_uplift_angle`); it carries the weight at rest up to ``4/27``.
UPLIFT_BEARING_LIMIT = 2.0 / 27.0


def bearing_load(block, foundation):
    """Bearing load ``-eps z_lin^2`` [1] of the bed under the block's weight.

    Notes
    -----
    Positive for a softening bed, which carries the block through the onset of uplift only below
    :data:`UPLIFT_BEARING_LIMIT` (``2/27``: where ``2 eps y^3 + y = z_lin`` of :func:`exact_uplift_angle`
    keeps a root on its rising branch).
    """
    eps = np.asarray(foundation.eps, dtype=float)
    return -eps * np.asarray(linear_indentation(block, foundation), dtype=float) ** 2


def exact_uplift_angle(block, foundation):
    """Exact static uplift angle ``theta_ul`` [rad] of a block on a bed with a cubic term.

    Notes
    -----
    Where the lifted edge reaches the bed surface in static equilibrium: the vertical balance of eq. (13)
    of [mitseas2026] at ``z_cb = y = b theta_ul`` gives ``2 eps y^3 + y = z_lin`` (eq. (17)), solved on its
    rising branch; ``eps = 0`` gives eq. (19).  NaN where :func:`bearing_load` reaches
    :data:`UPLIFT_BEARING_LIMIT`.
    """
    eps = np.asarray(foundation.eps, dtype=float)
    carried = bearing_load(block, foundation) < UPLIFT_BEARING_LIMIT
    y = rising_root(2.0 * np.where(carried, eps, 0.0), 1.0, linear_indentation(block, foundation))
    return np.where(carried, y / block.b, np.nan)[()]


# ----------------------------------------------------------------------------- compiled
@numba.njit(cache=True)
def contact_resultants_jit(theta, theta_dot, z_cb, z_cb_dot, b, k, eps, damping, winkler):
    """Compiled twin of :func:`contact_resultants` (scalars; ``winkler`` a flag), kept for callers that hold
    a flag (the solvers use :func:`law_resultants_jit`).
    """
    return contact_resultants_trig_jit(math.sin(theta), math.cos(theta), theta_dot, z_cb, z_cb_dot, b, k, eps,
                                       damping, winkler)


@numba.njit(cache=True)
def contact_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, b, k, eps, damping, winkler):
    """Compiled twin of :func:`contact_resultants_jit` from ``s = sin(theta)`` and ``c = cos(theta)``
    (``|theta| < pi/2``).
    """
    if winkler:
        return law_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, b, k, eps, damping, 0.0)
    return law_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, b, k, eps, 0.0, damping)


@numba.njit(cache=True)
def law_resultants_jit(theta, theta_dot, z_cb, z_cb_dot, b, k, eps, w_rate, w_indentation):
    """Compiled twin of :func:`law_resultants` (scalars; same arguments and units)."""
    return law_resultants_trig_jit(math.sin(theta), math.cos(theta), theta_dot, z_cb, z_cb_dot, b, k, eps,
                                   w_rate, w_indentation)


@numba.njit(cache=True)
def law_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, b, k, eps, w_rate, w_indentation):
    """Compiled twin of :func:`law_resultants_jit` from ``s = sin(theta)`` and ``c = cos(theta)``
    (``|theta| < pi/2``).
    """
    sigma = 1.0 if s >= 0.0 else -1.0
    a = sigma * s
    z1 = z_cb + b * a
    if z1 <= 0.0:
        return 0.0, 0.0                              # flight
    w = sigma * theta_dot * c
    v1 = z_cb_dot + b * w
    z2 = z_cb - b * a
    if z2 >= 0.0:
        P = 2.0 * b                                  # full contact
    else:
        z2 = 0.0
        P = z1 / a                                   # uplift (a > 0 here)
    v2 = v1 - w * P
    r1 = b
    r2 = b - P
    z1s = z1 * z1
    z2s = z2 * z2
    int_z = P * (z1 + z2) * 0.5
    int_z3 = P * (z1 + z2) * (z1s + z2s) * 0.25
    int_zr = P * (2.0 * z1 * r1 + z1 * r2 + z2 * r1 + 2.0 * z2 * r2) / 6.0
    int_z3r = P * ((z1s * z1 * r1 + z2s * z2 * r2) * 0.2 + (z1s * z1 * r2 + z2s * z2 * r1) * 0.05
                   + 0.15 * (z1s * z2 * r1 + z1 * z2s * r2) + 0.1 * (z1s * z2 * r2 + z1 * z2s * r1))
    int_v = P * (v1 + v2) * 0.5
    int_vr = P * (2.0 * v1 * r1 + v1 * r2 + v2 * r1 + 2.0 * v2 * r2) / 6.0
    int_zv = P * (2.0 * z1 * v1 + z1 * v2 + z2 * v1 + 2.0 * z2 * v2) / 6.0
    int_zvr = P * ((z1 * v1 * r1 + z2 * v2 * r2) * 0.25
                   + (z1 * v1 * r2 + z1 * v2 * r1 + z2 * v1 * r1
                      + z1 * v2 * r2 + z2 * v1 * r2 + z2 * v2 * r1) / 12.0)
    force = k * int_z + eps * k * int_z3 + (w_rate * int_v + w_indentation * int_zv)
    moment = sigma * c * (k * int_zr + eps * k * int_z3r + (w_rate * int_vr + w_indentation * int_zvr))
    return force, moment
