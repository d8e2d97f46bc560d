"""Quasi-static condensation with the cubic term in the static vertical balance (``"cubic"``).

The paper's condensation (section 2.3, :mod:`screening.core.condensation.paper`) slaves the base-centre
indentation to the *linear* static balance, ``z_st = m g / (2 b k)`` (eq. 17) and
``(k / (2|theta|)) (b|theta| + z_cb)^2 = m g`` (eq. 18), although the moment equations
(14), (16) it feeds keep the ``eps`` terms.  For a hardening bed the true rest indentation
is smaller (``z0 = 0.92 z_st`` for the paper's block with ``eps = 6e7``), which lowers the
no-uplift damping ``(2/3) lam b^3 z`` and the stiffness term ``2 eps k b^3 z^2``.
Here ``z_cb(theta)`` is the root of the full static vertical balance instead, in both
regimes, and ``C(theta)``, ``K(theta)`` follow from eqs. (14) and (16) with it.

Symbols and units (SI): ``m`` [kg], ``g`` [m/s^2], ``b`` half-width [m], ``h`` height of the
centre of mass [m], ``k`` [N/m^2], ``eps`` [1/m^2], ``lam`` [N s/m^3] (Hunt–Crossley) or ``c``
[N s/m^2] (Winkler), ``theta`` [rad], ``a = |theta|``, ``z = z_cb`` [m] (positive into the
bed), ``z_lin = m g / (2 b k)`` [m] (eq. 17).  Everything is even in ``theta`` (``C``, ``K``,
``z_cb``) by the mirror symmetry of the base, so the formulas are written for ``a``.

Derivation (small angles, as eqs. 13–16)
----------------------------------------
With ``u = b - eta`` the indentation field is ``z(u) = z + u theta`` (eqs. 1–2), in contact
where it is positive.  Quasi-static condensation drops ``m z''`` and the damping force from
the vertical balance (eqs. 13, 15), leaving ``F_k(theta, z) = m g`` with ``F_k`` the
stiffness part of the resultant:

* no uplift (``z >= b a``), eq. (13)::

      2 b k z + 2 b eps k z (z^2 + b^2 a^2) = m g
      <=>  eps z^3 + (1 + eps b^2 a^2) z = z_lin                                  (Q1)

  At ``theta = 0`` this is the rest indentation ``z0``: ``eps z0^3 + z0 = z_lin``.
  ``z`` depends on ``theta`` through ``eps b^2 a^2``; implicit differentiation gives
  ``dz/da = -2 eps b^2 a z / (1 + eps b^2 a^2 + 3 eps z^2)``.

* uplift (``-b a < z < b a``), eq. (15) with the compressed-edge indentation
  ``v = b a + z`` (contact length ``v / a``)::

      (k / (2a)) v^2 + (eps k / (4a)) v^4 = m g

  a quadratic in ``w = v^2``: ``(eps/2) w^2 + w = A`` with ``A = 2 m g a / k`` [m^2], whose
  root on the rising branch (``1 + eps w > 0``) is, without cancellation,
  ``w = 2 A / (1 + S)``, ``S = sqrt(1 + 2 eps A)``,  so ``z = sqrt(w) - b a``   (Q2)
  and ``dw/da = 2 m g / (k S)`` (from ``w' (1 + eps w) = A / a`` and ``1 + eps w = S``),
  ``dz/da = (dw/da) / (2 v) - b``.  ``eps = 0`` gives eq. (18).

* uplift threshold: the regimes meet where ``z = b a`` (``v = 2 b a``); both (Q1) and (Q2)
  then read ``2 eps y^3 + y = z_lin`` with ``y = b theta_ul``, so
  ``theta_ul = y / b``  (eq. 19 is the ``eps = 0`` case).  ``z_cb(theta)`` and ``dz/da`` are
  continuous there (the pressure vanishes at the lifting edge).  The threshold is *not*
  ``z0 / b``: with ``theta_ul = z0 / b`` the uplift root (Q2) would not meet ``z0`` and
  ``z_cb``, ``C``, ``K theta`` would jump at the threshold (``z_cb`` by 7 % for the paper's
  hardening bed).

Moments about the base centre (eqs. 14 and 16, re-derived by integrating the law over
the contact zone with ``zdot(u) = zdot_cb + u theta'``), minus the gravity term
``m g h theta``:

* stiffness, ``K(theta) = restoring moment / theta``::

      K_in = (2/3) b^3 k - m g h + eps k (2 b^3 z^2 + (2/5) b^5 a^2)               (eq. 14)
      K_up = [k v^2 (2 b a - z) / 6 + eps k v^4 (4 b a - z) / 20] / a^3 - m g h    (eq. 16)

* damping, with the quasi-static rate ``zdot_cb = (dz/dtheta) theta'``::

      Hunt–Crossley:  C_in = (2/3) lam b^3 (z + a dz/da)                           (eq. 14)
                      C_up = lam / (12 a^3) [3 b^4 a^4 + 4 b^3 z a^3 + z^4
                                             + 2 a (dz/da) v^2 (2 b a - z)]        (eq. 16)
      Winkler:        C_in = (2/3) c b^3
                      C_up = (c / a^2) [(dz/da) v (b a - z) / 2 + (b^3 a^3 + z^3) / (3 a)]

  With the linear balance (``z = z_lin``, eq. 18) these are exactly eqs. (24)–(25) and the
  Winkler forms of :mod:`screening.core.condensation.paper`; so ``eps = 0`` reproduces the paper.

Rate terms.  ``zdot_cb = z_cb'(theta) theta'`` is kept in ``C``: it is what the paper does
in the uplift branch (eq. 24 is eq. 16 with ``zdot_cb = z_st'(theta) theta'``), and without
it the ``eps = 0`` limit would not be the paper's model.  In the no-uplift regime it is new
(``z_st`` is constant in the paper): for ``eps > 0`` the block rises as it rotates
(``dz/da < 0``), which lowers ``C_in`` towards the threshold (by 17 % at ``theta_ul`` for
the paper's hardening bed).  ``C`` is continuous at ``theta_ul``.

Softening beds (``eps < 0``)
----------------------------
* The threshold exists only while ``2 eps y^3 + y`` reaches ``z_lin`` on its rising branch:
  ``|eps| z_lin^2 < 2/27``.  Otherwise the bed cannot carry the block through the onset of
  uplift and :func:`check_bearing` raises ``ValueError`` (every public function calls it).
  This is stricter than carrying it at rest (``|eps| z_lin^2 < 4/27``).
* In uplift the quartic has a root only while ``1 + 2 eps A >= 0``, i.e. up to the
  *capacity angle* ``theta_cap = k / (4 |eps| m g)`` (:func:`capacity_angle`; 0.142 rad for
  the paper's softening bed, below its slenderness 0.165 rad).  Beyond it no quasi-static
  equilibrium exists (the narrowing contact zone cannot carry ``m g``).  The functions here
  then hold the compressed edge at the peak load (``w = 1/|eps|``, ``z = |eps|^(-1/2) - b a``)
  and, there being no equilibrium to follow, carry no quasi-static rate (``dz/da`` is
  reported as 0), so that ``K`` stays finite and continuous and ``C`` finite and positive
  (``3 b^4 a^4 + 4 b^3 z a^3 + z^4 = v^2 ((z - b a)^2 + 2 b^2 a^2) > 0``) for the Gaussian
  expectations.  :func:`in_equilibrium` flags those angles, the condensed Monte Carlo stops
  such samples as diverged, and the moment solver records ``theta_capacity``.  Just below
  ``theta_cap``, ``dz/da ~ (theta_cap - a)^(-1/2)`` (the block sinks ever faster), an
  integrable singularity of ``C``.

Method and how it is checked: ``docs/method.md#cubic-condensation``.
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

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    None
        Returns only when every point passes.

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    The condition is ``|eps| z_lin^2 < 2/27`` (:data:`SOFTENING_LIMIT`, :func:`bearing_load`; ``z_lin`` of
    eq. (17) in [1]); any element of array parameters failing it raises.  ``eps >= 0`` always passes.

    """
    eps = np.asarray(foundation.eps, dtype=float)
    load = bearing_load(block, foundation)
    if np.any(load >= SOFTENING_LIMIT):
        bad = float(np.broadcast_to(eps, np.broadcast(eps, load).shape)[load >= SOFTENING_LIMIT].flat[0])
        raise ValueError(
            f"parameter 'foundation.eps' = {bad!r} 1/m^2: the softening bed cannot carry the block "
            f"through the onset of uplift under condensation='cubic' (need |eps| (m g/(2 b k))^2 < 2/27)")


def rest_indentation(block, foundation):
    """Static indentation at rest ``z0`` [m] of a bed the cubic condensation can carry.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``z0`` [m] (:func:`screening.core.physics.contact.rest_indentation`).

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    Eq. (13) in [1] at rest, cubic term included, after :func:`check_bearing`.

    """
    check_bearing(block, foundation)
    return contact.rest_indentation(block, foundation)


def uplift_threshold(block, foundation):
    """Uplift threshold ``theta_ul`` [rad] of the cubic condensation: the exact static uplift angle.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``theta_ul`` [rad] (:func:`screening.core.physics.contact.exact_uplift_angle`).

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    ``y = b theta_ul`` solves ``2 eps y^3 + y = z_lin``: the rotation at which the quasi-static ``z_cb(theta)``
    of eq. (13) in [1] reaches ``b theta`` (eq. (19) generalised; ``eps = 0`` gives ``m g / (2 b^2 k)``).

    """
    check_bearing(block, foundation)
    return exact_uplift_angle(block, foundation)


def capacity_angle(block, foundation):
    """Capacity angle ``theta_cap`` [rad] of a softening bed; ``inf`` for ``eps >= 0``.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``theta_cap = k / (4 |eps| m g)`` [rad].

    Notes
    -----
    Beyond it the uplift balance ``(k/(2a)) v^2 + (eps k/(4a)) v^4 = m g`` (eq. (15) in [1], ``a = |theta|``)
    has no root: no quasi-static equilibrium exists.

    """
    eps = np.asarray(foundation.eps, dtype=float)
    with np.errstate(divide="ignore"):
        cap = np.where(eps < 0.0, foundation.k / (4.0 * np.abs(eps) * block.m * block.g), np.inf)
    return cap[()]


def in_equilibrium(theta, block, foundation):
    """Where a quasi-static vertical equilibrium exists, ``|theta| <= theta_cap``.

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
    numpy.ndarray
        Boolean, broadcast over ``theta`` and the model's fields.

    Notes
    -----
    :func:`capacity_angle` from the uplift balance eq. (15) in [1].

    """
    return np.abs(np.asarray(theta, dtype=float)) <= capacity_angle(block, foundation)


def quasi_static_indentation(theta, block, foundation):
    """Quasi-static base-centre indentation and its slope in the cubic condensation.

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
    z_cb : numpy.ndarray
        Indentation of the base centre [m], even in ``theta``.
    slope : numpy.ndarray
        ``dz_cb/d|theta|`` [m/rad]; ``dz_cb/dtheta = sign(theta) * slope``.

    Notes
    -----
    ``z_cb`` solves the static vertical balance with the cubic term: ``eps z^3 + (1 + eps b^2 theta^2) z =
    z_lin`` below ``theta_ul`` (eq. (13) in [1]) and the uplift balance eq. (15) above it; beyond the
    capacity angle of a softening bed the contact is held at its peak load and the slope reported is 0
    (module docstring).

    """
    return indentation_state(theta, block, foundation)[:2]


def indentation_state(theta, block, foundation):
    """The quasi-static contact state at the rocking angle ``theta``: what the damping, the stiffness
    and the stiff-bed model's contact read.

    Parameters
    ----------
    theta : array_like
        Rocking angle [rad]; only ``|theta|`` matters.
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2]); fields may be arrays.

    Returns
    -------
    z : numpy.ndarray
        Indentation of the base centre ``z_cb`` [m] (:func:`quasi_static_indentation`).
    slope : numpy.ndarray
        ``dz_cb/d|theta|`` [m/rad].
    v : numpy.ndarray
        Indentation of the compressed edge ``v = b |theta| + z_cb`` [m].
    a : numpy.ndarray
        ``|theta|`` [rad], broadcast with the fields.
    uplift : numpy.ndarray of bool
        Whether the far edge has lifted (``|theta| > theta_ul``).

    Notes
    -----
    Below ``theta_ul`` the balance with the cubic term, ``eps z^3 + (1 + eps b^2 theta^2) z = z_lin``
    (eq. (13) in [1]); above it the uplift balance eq. (15) in [1], held at the peak load beyond the
    capacity angle of a softening bed (slope 0 there).

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
    numpy.ndarray
        ``C(theta)`` [N m s/rad], broadcast over ``theta`` and the model's fields.

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    Eqs. (14) and (16) in [1] re-derived with the quasi-static rate ``zdot_cb = (dz/dtheta) theta'`` and the
    law's damping pressure (module docstring); with ``eps = 0`` it is eq. (24).

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
    """Secant rocking stiffness ``K(theta)`` [N m/rad] of the cubic condensation.

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
    numpy.ndarray
        ``K(theta)`` [N m/rad]; the restoring moment is ``K(theta) theta``.  Same for both laws.

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    ``K_in = (2/3) b^3 k - m g h + eps k (2 b^3 z^2 + (2/5) b^5 a^2)`` (eq. (14) in [1]) and ``K_up`` of
    eq. (16), at the quasi-static ``z`` of :func:`quasi_static_indentation`; with ``eps = 0`` it is eq. (25).

    """
    z, _, v, a, uplift = indentation_state(theta, block, foundation)
    b, k, eps = block.b, foundation.k, foundation.eps
    mgh = block.m * block.g * block.h
    k_in = 2.0 / 3.0 * b**3 * k - mgh + eps * k * (2.0 * b**3 * z * z + 0.4 * b**5 * a * a)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_up = (k * v * v * (2.0 * b * a - z) / 6.0 + eps * k * v**4 * (4.0 * b * a - z) / 20.0) / a**3 - mgh
    return np.where(uplift, k_up, k_in)[()]


def restoring_moment(theta, block, foundation):
    """Restoring moment ``K(theta) theta`` [N m] of the cubic condensation.

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
    numpy.ndarray
        ``K(theta) theta`` [N m], odd in ``theta``.

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    The conservative term of eq. (22) in [1] with ``K`` of :func:`rocking_stiffness`.

    """
    theta = np.asarray(theta, dtype=float)
    return (rocking_stiffness(theta, block, foundation) * theta)[()]


def damping_at_rest(block, foundation):
    """Rocking damping at rest ``C(0)`` [N m s/rad] of the cubic condensation.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``(2/3) b^3 (w_rate + w_indentation z0)`` (Hunt–Crossley ``(2/3) lam b^3 z0``, Winkler ``(2/3) c b^3``).

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    Eq. (14) in [1] at ``theta = 0`` with the rest indentation ``z0`` (eq. (13)).

    """
    check_bearing(block, foundation)
    w_rate, w_ind = foundation.damping_weights
    return 2.0 / 3.0 * w_rate * block.b**3 + 2.0 / 3.0 * w_ind * block.b**3 * rest_indentation(block, foundation)


def stiffness_at_rest(block, foundation):
    """Rocking stiffness at rest ``K(0)`` [N m/rad] of the cubic condensation.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``(2/3) b^3 k - m g h + 2 eps k b^3 z0^2`` [N m/rad].

    Raises
    ------
    ValueError
        Naming ``foundation.eps`` for a softening bed that cannot carry the block through the onset of
        uplift (:func:`check_bearing`).

    Notes
    -----
    Eq. (14) in [1] at ``theta = 0`` with the rest indentation ``z0`` (eq. (13)); its ``eps = 0`` part is
    :func:`screening.core.physics.contact.linear_rocking_stiffness`.

    """
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
    """The :data:`SDOF_RECORD` of scalar model objects, for the compiled twins.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    numpy.ndarray
        A 1-element :data:`SDOF_RECORD` (SI units).

    Notes
    -----
    The block, the bed, the threshold, ``z_lin`` (eq. (17) in [1]) and the rest indentation with its
    curvature (the Newton start of the balance of eq. (13)).

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
    """Compiled twin of :func:`quasi_static_indentation` at ``a = |theta|``.

    Parameters
    ----------
    p : numpy.void
        An :data:`SDOF_RECORD` (:func:`sdof_record`).
    a : float
        Absolute rotation [rad].

    Returns
    -------
    z_cb : float
        [m].
    slope : float
        ``dz_cb/da`` [m/rad].
    v : float
        Compressed-edge indentation ``b a + z_cb`` [m].

    Notes
    -----
    Newton on the balance of eq. (13) in [1] below ``theta_ul``, the closed-form root of eq. (15) above.

    """
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
    """Compiled twin of :func:`rocking_damping` and :func:`rocking_stiffness`.

    Parameters
    ----------
    p : numpy.void
        An :data:`SDOF_RECORD` (:func:`sdof_record`).
    theta : float
        Rotation [rad].

    Returns
    -------
    C : float
        Rocking damping [N m s/rad].
    K : float
        Secant rocking stiffness [N m/rad].

    Notes
    -----
    Eqs. (14) and (16) in [1] with one indentation solve for both (:func:`quasi_static_indentation_jit`).

    """
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
