"""Contact resultants of the full coupled model (paper eqs. 1–6), exact in every regime.

The resultant force ``F_cb`` [N] and the moment about the base centre ``M_cb`` [N m] are
the integrals (5)–(6) of the contact law (3)–(4) over the part of the base that is in
contact.  They are evaluated here in closed form, for any ``theta`` (both signs), any
``z_cb`` and both bed laws, without small-angle approximations.

Derivation
----------
Measure the base by ``u = b - eta`` in ``[-b, b]`` (signed distance from the base centre
towards edge ``B``).  Eqs. (1)–(2) give a field that is *linear* in ``u``::

    z(u)    = z_cb + u sin(theta),          zdot(u) = zdot_cb + u theta_dot cos(theta),
    lever arm (b - eta) cos(theta) = u cos(theta).

The compressed edge is ``B`` (``u = +b``) for ``theta >= 0`` and ``A`` (``u = -b``) for
``theta < 0``; with ``sigma = sign(theta)`` (``+1`` at ``theta = 0``) and ``p`` the distance
from the compressed edge into the base, ``u = sigma (b - p)`` and ``z`` decreases linearly
in ``p`` from the compressed-edge indentation ``z_c = z_cb + b |sin(theta)|``.  The contact
zone is ``0 <= p <= P``:

* full contact (``z_cb - b |sin theta| >= 0``): ``P = 2 b``;
* uplift (``z_cb - b |sin theta| < 0 < z_c``): ``P = z_c / |sin theta|`` (eq. 6 text:
  ``eta_U = z_cb / sin(theta) + b`` for ``theta > 0``; the mirror image for ``theta < 0``);
* flight (``z_c <= 0``): no contact, ``F_cb = M_cb = 0``.

Every integrand is a product of one to four functions that are linear in ``p`` (``z``,
``zdot`` and the lever ``r = b - p``), so each integral is exact from the end values
``f1 = f(0)``, ``f2 = f(P)`` (Beta integrals ``int_0^1 (1-t)^i t^j dt = i! j!/(i+j+1)!``)::

    int z            = P (z1 + z2) / 2
    int z^3          = P (z1 + z2)(z1^2 + z2^2) / 4
    int z r          = P (2 z1 r1 + z1 r2 + z2 r1 + 2 z2 r2) / 6        (same for zdot r, z zdot)
    int z^3 r        = P [(z1^3 r1 + z2^3 r2)/5 + (z1^3 r2 + z2^3 r1)/20
                          + 3 (z1^2 z2 r1 + z1 z2^2 r2)/20 + (z1^2 z2 r2 + z1 z2^2 r1)/10]
    int z zdot r     = P [(z1 v1 r1 + z2 v2 r2)/4 + (mixed triple products)/12]

and ``F_cb = k int z + eps k int z^3 + lam int z zdot`` (Winkler: ``c int zdot``),
``M_cb = sigma cos(theta) (k int z r + eps k int z^3 r + lam int z zdot r)``
(Winkler: ``c int zdot r``).  The end-value form has no division by ``sin(theta)`` and no
cancellation between large terms, so it is accurate at ``theta = 0`` and at the flight
boundary alike.

Written out for the regimes of the paper (``s = sin theta``, ``c = cos theta``,
``z_B = z_cb + b s``, ``zdot_B = zdot_cb + b theta_dot c``):

* full contact (agrees with eq. 9; eq. 10 with ``2/5`` instead of the printed ``2/3``)::

    F = 2 b k z_cb + 2 b eps k z_cb (z_cb^2 + b^2 s^2) + lam b (2 z_cb zdot_cb + (2/3) b^2 s c theta_dot)
    M = (2/3) b^3 k s c + eps k c (2 b^3 z_cb^2 s + (2/5) b^5 s^3)
        + (2/3) lam b^3 c (z_cb c theta_dot + zdot_cb s)

* uplift, ``theta > 0`` (stiffness terms agree with eqs. 11–12, damping terms differ)::

    F = k z_B^2/(2 s) + eps k z_B^4/(4 s) + lam z_B^2 (3 s zdot_cb + 2 b s c theta_dot - z_cb c theta_dot)/(6 s^2)
    M = c [k z_B^2 (2 b s - z_cb)/(6 s^2) + eps k z_B^4 (4 b s - z_cb)/(20 s^2)
           + lam (c theta_dot (3 b^4 s^4 + 4 b^3 z_cb s^3 + z_cb^4)
                  + 2 s zdot_cb z_B^2 (2 b s - z_cb))/(12 s^3)]

  Eq. (11) has ``- zdot_cb cos(theta)`` where the integral gives ``- z_cb theta_dot cos(theta)``;
  eq. (12) lacks one factor ``cos(theta)`` on its ``theta_dot`` term (``zdot = ... - eta
  theta_dot cos(theta)``), an ``O(1 - cos theta)`` difference.

* uplift, ``theta < 0``: mirror image, ``F(theta, theta_dot) = F(-theta, -theta_dot)`` and
  ``M(theta, theta_dot) = -M(-theta, -theta_dot)`` at the same ``z_cb, zdot_cb``;
* flight: ``F = M = 0``.

Winkler beds (``c zdot``): ``F = c int zdot``, ``M = sigma cos(theta) c int zdot r``, e.g.
full contact ``F = 2 b c zdot_cb``, ``M = (2/3) c b^3 c^2 theta_dot``.

Units: ``theta`` [rad], ``theta_dot`` [rad/s], ``z_cb`` [m] (indentation of the base centre,
positive into the bed), ``zdot_cb`` [m/s], ``b`` [m], ``k`` [N/m^2], ``eps`` [1/m^2],
``damping`` = ``lam`` [N s/m^3] (Hunt–Crossley) or ``c`` [N s/m^2] (Winkler).

Method and how it is checked: ``docs/method.md#contact-regimes-and-resultants``.
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
    """The constants of a Hunt–Crossley or Winkler bed as plain numbers.

    Parameters
    ----------
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    k : float
        Bed stiffness [N m-2].
    eps : float
        Cubic stiffness parameter [m-2].
    damping : float
        ``lam`` [N s m-3] (Hunt–Crossley) or ``c`` [N s m-2] (Winkler).
    winkler : bool
        True for a Winkler bed.

    Notes
    -----
    The arguments of :func:`contact_resultants` after ``b``, for the laws of eqs. (3)-(4) in [1]; see
    :func:`law_constants` for any registered law.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    return float(foundation.k), float(foundation.eps), float(foundation.damping), foundation.law == "winkler"


def law_constants(foundation):
    """The constants of a bed of any contact law as plain numbers.

    Parameters
    ----------
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    k : float
        Bed stiffness [N m-2].
    eps : float
        Cubic stiffness parameter [m-2].
    w_rate : float
        Weight of the rate in the damping pressure [N s m-2].
    w_indentation : float
        Weight of the rate times the indentation [N s m-3].

    Notes
    -----
    The arguments of :func:`law_resultants` after ``b``: the damping pressure of the law is
    ``zdot (w_rate + w_indentation z)`` (Winkler ``(c, 0)``, Hunt–Crossley ``(0, lam)``, eq. (3) in [1]).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    w_rate, w_indentation = foundation.damping_weights
    return float(foundation.k), float(foundation.eps), float(w_rate), float(w_indentation)


def corner_indentations(theta, z_cb, b):
    """Indentations of the compressed and of the lifted base edge [m].

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    z_cb : array_like
        Indentation of the base centre [m], positive into the bed.
    b : float or array_like
        Half-width of the base [m].

    Returns
    -------
    z_c : numpy.ndarray
        Indentation of the compressed edge [m] (edge B for ``theta >= 0``, A otherwise).
    z_f : numpy.ndarray
        Indentation of the lifted edge [m]; negative in uplift.

    Notes
    -----
    ``z_c = z_cb + b |sin theta|``, ``z_f = z_cb - b |sin theta|``: the linear indentation field of
    eqs. (1)-(2) in [1] at the two edges.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    a = np.abs(np.sin(np.asarray(theta, dtype=float)))
    z_cb = np.asarray(z_cb, dtype=float)
    return z_cb + b * a, z_cb - b * a


def contact_regime(theta, z_cb, b):
    """Contact regime code (``REGIME_*``) of a rotated, indented base.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    z_cb : array_like
        Indentation of the base centre [m], positive into the bed.
    b : float or array_like
        Half-width of the base [m].

    Returns
    -------
    numpy.ndarray
        :data:`REGIME_FULL_CONTACT`, :data:`REGIME_UPLIFT_POSITIVE`, :data:`REGIME_UPLIFT_NEGATIVE` or
        :data:`REGIME_FLIGHT` (integer codes of :class:`screening.core.status.ContactRegime`).

    Notes
    -----
    Full contact while the lifted edge is indented (``z_f >= 0``), flight once the compressed edge is
    not (``z_c <= 0``), uplift between (:func:`corner_indentations`; the regimes of eqs. (9)-(12) in [1]).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    theta = np.asarray(theta, dtype=float)
    z_c, z_f = corner_indentations(theta, z_cb, b)
    uplift = np.where(theta >= 0.0, REGIME_UPLIFT_POSITIVE, REGIME_UPLIFT_NEGATIVE)
    return np.where(z_c <= 0.0, REGIME_FLIGHT, np.where(z_f >= 0.0, REGIME_FULL_CONTACT, uplift))


def contact_length(theta, z_cb, b):
    """Length of the contact zone [m], measured from the compressed edge.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    z_cb : array_like
        Indentation of the base centre [m], positive into the bed.
    b : float or array_like
        Half-width of the base [m].

    Returns
    -------
    numpy.ndarray
        ``P`` [m]: ``2 b`` in full contact, ``z_c / |sin theta|`` in uplift, 0 in flight.

    Notes
    -----
    In uplift the contact ends where the indentation field reaches zero, ``eta_U = z_cb / sin(theta) + b``
    (text of eq. (6) in [1]).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
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
    """Resultant contact force ``F_cb`` [N] and moment ``M_cb`` [N m] of any contact law, exact.

    Vectorised over all array arguments (broadcast).  See the module docstring for the
    derivation and the regime-by-regime formulas.

    Parameters
    ----------
    theta : array_like
        Rotation [rad] (positive clockwise, edge B compressed).
    theta_dot : array_like
        Rotation rate [rad s-1].
    z_cb : array_like
        Indentation of the base centre [m], positive into the bed.
    z_cb_dot : array_like
        Its rate [m s-1].
    b : float or array_like
        Half-width of the base [m].
    k : float or array_like
        Bed stiffness [N m-2].
    eps : float or array_like
        Cubic stiffness parameter [m-2].
    w_rate : float or array_like
        Weight [N s m-2] of the rate in the law's damping pressure ``zdot (w_rate + w_indentation z)``.
    w_indentation : float or array_like
        Weight [N s m-3] of the rate times the indentation (:attr:`screening.core.model.Foundation.damping_weights`:
        Winkler ``(c, 0)``, Hunt–Crossley ``(0, lam)``).

    Returns
    -------
    F_cb : numpy.ndarray
        Resultant contact force [N]; zero in flight.
    M_cb : numpy.ndarray
        Resultant moment about the base centre [N m]; zero in flight.

    Notes
    -----
    ``F_cb = k int z + eps k int z^3 + w_rate int zdot + w_indentation int z zdot`` and
    ``M_cb = sigma cos(theta) (k int z r + eps k int z^3 r + w_rate int zdot r + w_indentation int z zdot r)``
    over the contact zone, each integral exact from its end values (module docstring): eqs. (5)-(6)
    in [1] with the law of eqs. (3)-(4), without small-angle approximations.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
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
    """Static indentation of the base centre by the linear law alone, ``z_lin`` [m].

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``z_lin = m g / (2 b k)`` [m].

    Notes
    -----
    Eq. (17) in [1]: the weight carried by the uniform pressure ``k z`` over the base ``2 b``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    return block.m * block.g / (2.0 * block.b * foundation.k)


def bed_rocking_stiffness(block, foundation):
    """Rocking stiffness of the linear bed under the base in full contact, ``(2/3) b^3 k`` [N m/rad].

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``b`` [m]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2]); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``(2/3) b^3 k`` [N m/rad].

    Notes
    -----
    The restoring moment of the linear part of the contact pressure (eq. (3) in [1]) over the whole
    base ``-b <= x <= b`` rotated by a small ``theta``: ``int k (x theta) x dx = (2/3) b^3 k theta``.
    ``K0`` of the paper's closed-form coefficients (eqs. (35)-(36) in [1]) and the bed's part of
    :func:`linear_rocking_stiffness`.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    return 2.0 / 3.0 * block.b**3 * foundation.k


def linear_rocking_stiffness(block, foundation):
    """Rocking stiffness at rest without the cubic term, ``K0 - m g h = (2/3) b^3 k - m g h`` [N m/rad]
    (``K0``: :func:`bed_rocking_stiffness`).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``(2/3) b^3 k - m g h`` [N m/rad].

    Notes
    -----
    ``K(0)`` of every condensation at ``eps = 0`` (eqs. (22) and (25) in [1] at ``theta = 0``): the bed's
    restoring moment ``(2/3) b^3 k theta`` in full contact less the overturning moment of the
    weight ``m g h theta``.  A condensation adds its own ``eps`` term; the block rocks about its
    rest position only where this is positive.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    return bed_rocking_stiffness(block, foundation) - block.m * block.g * block.h


def rising_root(alpha, beta, rhs, max_iter=100):
    """Root of ``alpha z^3 + beta z = rhs`` on the rising branch (``beta + 3 alpha z^2 > 0``).

    Parameters
    ----------
    alpha : array_like
        Cubic coefficient [m-2] (caller's units: ``z`` and ``rhs`` [m]).
    beta : array_like
        Linear coefficient [1], positive.
    rhs : array_like
        Right-hand side [m].
    max_iter : int, optional
        Largest number of Newton steps (default 100).

    Returns
    -------
    numpy.ndarray
        The root [m], broadcast over the arguments.

    Notes
    -----
    Newton from ``z = rhs / beta``: for ``alpha >= 0`` the cubic is convex and the start lies right of
    the root, for ``alpha < 0`` concave with the start left of it, so the iterates converge
    monotonically (no overshoot onto the falling branch).  It solves the static balances of eq. (13)
    in [1] (:func:`rest_indentation`, :func:`exact_uplift_angle`).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
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

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``z0`` [m], the root of ``eps z0^3 + z0 = z_lin`` on the rising (stable) branch.

    Raises
    ------
    ValueError
        When a softening bed cannot carry the weight at all: ``|eps| z_lin^2 >= 4/27``.

    Notes
    -----
    Eq. (13) in [1] at rest (``theta = 0``): ``2 b k (z + eps z^3) = m g``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
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
    """Damping ratio ``zeta_v`` [1] of the block's vertical vibration on the bed about its rest indentation.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2] and ``damping_weights``, the law's damping
        ``zdot (w_rate [N s m-2] + w_indentation [N s m-3] z)``); fields may be arrays.
    z_rest : array_like, optional
        The indentation ``z0`` [m] the dashpot is taken at, where already known (None: the rest indentation,
        :func:`rest_indentation`, which raises where the bed cannot carry the block).

    Returns
    -------
    numpy.ndarray or float
        ``zeta_v`` [1]; above 1 the vertical mode is overdamped.

    Notes
    -----
    About the rest indentation ``z0`` (eq. (13) in [1] at rest) the law's damping pressure (eqs. (3)-(4)
    in [1]) integrated over the base ``2 b`` is the dashpot ``c_v = 2 b (w_rate + w_indentation z0)``
    (Hunt-Crossley [2]: ``2 b lam z0``; Winkler: ``2 b c``), on the linear bed's vertical spring
    ``k_v = 2 b k``; the viscous damping ratio of that oscillator [3] is

        zeta_v = c_v / (2 sqrt(k_v m)) = b (w_rate + w_indentation z0) / sqrt(2 b k m)

    The spring leaves out the tangent stiffness ``6 b k eps z0^2`` of the cubic term (``eps = 0``: exact).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] K. H. Hunt and F. R. E. Crossley, "Coefficient of restitution interpreted as damping in
       vibroimpact", J. Appl. Mech. 42 (1975) 440-445.
    .. [3] [clough1975] in the bibliography, ``docs/bibliography.md``.
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

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2]); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``-eps (m g / (2 b k))^2`` [1], broadcast over the model's fields: positive for a softening
        bed, which carries the block through the onset of uplift only below :data:`UPLIFT_BEARING_LIMIT`.

    Notes
    -----
    The cubic balance ``2 eps y^3 + y = z_lin`` of :func:`exact_uplift_angle` has a root on its rising
    branch only while ``-2 eps z_lin^2 < 4/27``, i.e. ``-eps z_lin^2 < 2/27``; ``z_lin`` is eq. (17) in [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    eps = np.asarray(foundation.eps, dtype=float)
    return -eps * np.asarray(linear_indentation(block, foundation), dtype=float) ** 2


def exact_uplift_angle(block, foundation):
    """Exact static uplift angle ``theta_ul`` [rad] of a block on a bed with a cubic term.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2]); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``theta_ul`` [rad], broadcast over the model's fields; NaN where a softening bed cannot carry
        the block through the onset of uplift (:func:`bearing_load` at or above
        :data:`UPLIFT_BEARING_LIMIT`).

    Notes
    -----
    The rotation at which the lifted edge of the base reaches the bed surface in static equilibrium:
    with ``y = b theta_ul`` the base-centre indentation, the static vertical balance of eq. (13) in [1],
    ``2 b k z_cb + 2 b eps k z_cb (z_cb^2 + b^2 theta^2) = m g`` at ``z_cb = b theta``, gives
    ``2 eps y^3 + y = z_lin``, ``z_lin = m g / (2 b k)`` (eq. (17) in [1]), solved on its rising branch.  For ``eps = 0``
    it is eq. (19) in [1], ``m g / (2 b^2 k)``.  The ``"cubic"`` condensation uses it as its threshold;
    the coupled Monte Carlo labels uplift with it.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
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
