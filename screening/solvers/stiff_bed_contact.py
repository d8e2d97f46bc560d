"""The contact law of the stiff-bed model (:mod:`screening.solvers.stiff_bed`): the rigid block on the
bed's quasi-static contact, its inertia, restoring moment and damping, the stored energy, Housner's
restitution, and the compiled twins of the rocking acceleration and indentation curvature.

The equations are those of the stiff-bed model's module docstring; method and checks:
``docs/stiff_bed.md``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.condensation import cubic
from screening.solvers.mcs_equations import GRAVITY_RATIO_MIN

__all__ = ["housner_restitution", "indentation_curvature", "constraint_damping", "gravity_ratio", "rocking_coefficients",
           "rocking_acceleration", "potential", "STIFF", "stiff_record", "indentation_curvature_jit",
           "constraint_damping_jit", "rocking_acceleration_jit"]


# ----------------------------------------------------------------------------- numpy reference
def housner_restitution(block):
    """Housner's coefficient of restitution ``r = 1 - (3/2) sin^2(alpha)`` [1] of a rectangular block.

    Notes
    -----
    Angular momentum about the new corner is conserved through an instantaneous, perfectly plastic
    impact: ``I_O theta'_+ = (I_O - 2 m b^2) theta'_-`` with ``I_O = (4/3) m R^2``, ``b = R sin(alpha)``
    (uniform block, ``I_cm = m (b^2 + h^2) / 3``).  The energy ratio per impact is ``r^2``.
    """
    return 1.0 - 1.5 * math.sin(math.atan2(float(block.b), float(block.h))) ** 2


def indentation_curvature(theta, block, foundation):
    """``d^2 z_cb / da^2`` [m/rad^2] of the quasi-static indentation of the ``"cubic"`` condensation at
    ``a = |theta|`` (vectorised).

    Notes
    -----
    Full contact (``eps z^3 + beta z = z_lin``, ``beta = 1 + eps b^2 a^2``): ``z' = N / D`` with
    ``N = -2 eps b^2 a z``, ``D = beta + 3 eps z^2``, so ``z'' = (N' D - N D') / D^2``,
    ``N' = -2 eps b^2 (z + a z')``, ``D' = 2 eps b^2 a + 6 eps z z'``.  Uplift
    (``z = v - b a``, ``v^2 = 2 A / (1 + S)``, ``S = sqrt(1 + 2 eps A)``, ``A = 2 m g a / k``):
    ``z' = m g / (k S v) - b``, so ``z'' = -(m g / k) (S' v + S v') / (S v)^2`` with
    ``S' = 2 eps m g / (k S)``, ``v' = z' + b``.  Beyond the capacity angle of a softening bed: 0.
    """
    a = np.abs(np.asarray(theta, dtype=float))
    z, dz = cubic.quasi_static_indentation(a, block, foundation)
    b, k, eps, mg = float(block.b), float(foundation.k), float(foundation.eps), float(block.m * block.g)
    up = a > cubic.uplift_threshold(block, foundation)
    n = -2.0 * eps * b * b * a * z
    d = 1.0 + eps * b * b * a * a + 3.0 * eps * z * z
    dn = -2.0 * eps * b * b * (z + a * dz)
    dd = 2.0 * eps * b * b * a + 6.0 * eps * z * dz
    curv_in = (dn * d - n * dd) / (d * d)
    s2 = 1.0 + 4.0 * eps * mg * a / k
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):       # unused branch beyond capacity
        S = np.sqrt(np.maximum(s2, 1e-300))
        v = z + b * a
        curv_up = np.where(s2 > 0.0, -(mg / k) * (2.0 * eps * mg / (k * S) * v + S * (dz + b)) / (S * v) ** 2, 0.0)
    return np.where(up, curv_up, curv_in)[()]


def constraint_damping(theta, block, foundation):
    """Rocking damping ``C_D(a)`` [N m s/rad] of the bed's damping pressure on the quasi-static contact, at
    ``a = |theta|`` (vectorised): the dissipated power is ``C_D(a) theta'^2`` (times ``cos^2 theta`` in the
    model, where ``a = |sin theta|``).

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    block : screening.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    numpy.ndarray
        ``C_D`` [N m s/rad].

    Notes
    -----
    With the base centre slaved to ``z = Z(a)`` (``w = dZ/da``), the indentation field is ``z(u) = z + a u``
    and its rate ``(w + u) theta'`` at the signed distance ``u`` from the base centre (the compressed edge at
    ``u = b``).  The damping pressure ``(w_rate + w_ind z(u)) zdot(u)`` dissipates

    ``C_D = int (w_rate + w_ind z(u)) (w + u)^2 du``

    over the contact: in full contact (``u`` in ``[-b, b]``)
    ``C_D = w_rate (2 b w^2 + 2 b^3 / 3) + w_ind (z (2 b w^2 + 2 b^3 / 3) + 4 a w b^3 / 3)``; in uplift (contact
    length ``L = v / a`` from the corner, ``v = z + b a``, ``q = w + b``)
    ``C_D = w_rate L ((q - L/2)^2 + L^2/12) + w_ind v L ((q - L/3)^2 / 2 + L^2/36)``; continuous at
    ``theta_ul``.  It is the condensation's damping moment coefficient ``C`` plus the work of the vertical
    damping force along the constraint, ``w (w_rate + w_ind) int ... (w + u)``: ``C`` alone counts the
    moment's work only, and in uplift, where the base centre rises at ``w ~ -b``, overstates the dissipation
    by ``2 b / L`` (for ``eps = 0``: ``C = lam b v^3 / (12 a^2)`` against ``C_D = lam v^4 / (24 a^3)``).

    References
    ----------
    Rayleigh's dissipation function of the contact pressure (eqs. 3-6 of the coupled model,
    :mod:`screening.physics.contact`) on the constraint ``z_cb = Z(theta)`` (``docs/stiff_bed.md``).
    """
    z, dz, v, a, up = cubic._indentation_state(theta, block, foundation)
    w_rate, w_ind = (float(x) for x in foundation.damping_weights)
    b = float(block.b)
    full = (w_rate + w_ind * z) * (2.0 * b * dz * dz + 2.0 / 3.0 * b ** 3) + w_ind * 4.0 / 3.0 * a * dz * b ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        length = v / a
        q = dz + b
        lifted = (w_rate * length * ((q - 0.5 * length) ** 2 + length * length / 12.0)
                  + w_ind * v * length * (0.5 * (q - length / 3.0) ** 2 + length * length / 36.0))
    return np.where(up, lifted, full)[()]


def gravity_ratio(a_v, g):
    """``lam = (g + a_v) / g`` [1]: the weight under a vertical ground acceleration ``a_v`` [m/s2]
    (positive up), held at :data:`~screening.solvers.mcs_equations.GRAVITY_RATIO_MIN` or above (below 0
    the block lifts off, which the model stops)."""
    return np.maximum(1.0 + np.asarray(a_v, dtype=float) / g, GRAVITY_RATIO_MIN)


def rocking_coefficients(theta, block, foundation, a_v=0.0):
    """``(m_eff [kg m2], dm_eff/dtheta [kg m2/rad], Q [N m], C_eff [N m s/rad])`` of the stiff-bed model.

    ``m_eff`` the inertia on the quasi-static contact, ``Q`` the restoring generalized moment
    (bed moment minus gravity), ``C_eff = cos^2(theta) C_D(|sin theta|)`` the damping
    (:func:`constraint_damping`; module docstring).  ``theta`` [rad], vectorised; ``a_v`` [m/s2] the vertical ground acceleration.

    Notes
    -----
    Under ``a_v`` the weight is ``lam m g``, ``lam = (g + a_v) / g``.  On the linear Winkler bed the
    contact law is similar in the weight: ``Z(a; lam) = lam Z(a / lam)``, the bed moment
    ``B(a; lam) = lam B(a / lam)`` (``B = (K + m g h) a``), the rate damping ``C(a; lam) = C(a / lam)``;
    so the laws are read at ``a / lam``, ``Z''`` divided by ``lam``, and gravity's moment is
    ``lam m g h sin(theta)`` (docs/stiff_bed.md, "Vertical ground acceleration").
    """
    theta = np.asarray(theta, dtype=float)
    lam = gravity_ratio(a_v, float(block.g))
    s, c = np.sin(theta), np.cos(theta)
    sigma = np.where(theta >= 0.0, 1.0, -1.0)
    a = np.abs(s)
    al = a / lam
    z, dz = cubic.quasi_static_indentation(al, block, foundation)
    d2z = indentation_curvature(al, block, foundation) / lam
    m, h = float(block.m), float(block.h)
    mgh = m * float(block.g) * h
    z_t = sigma * c * dz
    z_tt = c * c * d2z - a * dz
    u = z_t + h * s
    m_eff = float(block.I_cm) + m * (h * h * c * c + u * u)
    dm_eff = m * (-2.0 * h * h * c * s + 2.0 * u * (z_tt + h * c))
    q = sigma * c * (cubic.rocking_stiffness(al, block, foundation) * a + mgh * a) - lam * mgh * s
    c_eff = c * c * constraint_damping(al, block, foundation)
    return m_eff, dm_eff, q, c_eff


def rocking_acceleration(theta, theta_dot, x_g_ddot, block, foundation, a_v=0.0):
    """``theta''`` [rad/s2] of the stiff-bed model (module docstring), without the transfer loss.

    ``theta`` [rad], ``theta_dot`` [rad/s], ``x_g_ddot`` inertial ground acceleration [m/s2]
    (the kernels' convention, :mod:`screening.solvers.simulate`), ``a_v`` vertical ground
    acceleration [m/s2] (positive up; :func:`rocking_coefficients`); vectorised.
    """
    m_eff, dm_eff, q, c_eff = rocking_coefficients(theta, block, foundation, a_v)
    theta_dot = np.asarray(theta_dot, dtype=float)
    return ((block.m * block.h * np.cos(theta) * x_g_ddot - q - c_eff * theta_dot - 0.5 * dm_eff * theta_dot ** 2)
            / m_eff)


def potential(theta, block, foundation, n_pieces=64, order=8):
    """``V(theta) = int_0^|theta| Q`` [J]: the energy stored at rest at ``theta`` [rad] (scalar).

    Gauss–Legendre quadrature of ``order`` points on ``[0, theta_ul]`` and on ``n_pieces``
    geometrically growing pieces of ``[theta_ul, |theta|]`` (the contact length varies like
    ``theta^(-1/2)`` just past uplift); relative error below 1e-9 for the beds of the tests.
    """
    a = abs(float(theta))
    tu = float(cubic.uplift_threshold(block, foundation))
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.array([0.0, min(a, tu)])
    if a > tu:
        edges = np.concatenate((edges, np.geomspace(tu, a, n_pieces + 1)[1:]))
    lo, hi = edges[:-1, None], edges[1:, None]
    nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x
    q = rocking_coefficients(nodes.ravel(), block, foundation)[2].reshape(nodes.shape)
    return float(np.sum(0.5 * (hi - lo) * w * q))


# ----------------------------------------------------------------------------- compiled twins
#: Per-run parameters of the compiled stiff-bed kernel (SI), built by :func:`stiff_record`.
STIFF = np.dtype([("m", "f8"), ("g", "f8"), ("h", "f8"), ("I_cm", "f8"), ("theta_ul", "f8"),
                  ("theta_over", "f8"), ("theta_cap", "f8"), ("rate_max", "f8"), ("locate", "f8")])


def stiff_record(block, foundation, locate=True):
    """The :data:`STIFF` record (1-element array) of scalar model objects; ``locate``: shorten a step
    that crosses zero into uplift on the other side to the crossing (:class:`StiffBedModel`)."""
    rec = np.zeros(1, dtype=STIFF)
    values = dict(m=float(block.m), g=float(block.g), h=float(block.h), I_cm=float(block.I_cm),
                  theta_ul=float(cubic.uplift_threshold(block, foundation)), theta_over=float(block.slenderness),
                  theta_cap=float(cubic.capacity_angle(block, foundation)),
                  rate_max=1e3 * math.sqrt(float(block.g) / float(block.h)), locate=1.0 if locate else 0.0)
    for name, value in values.items():
        rec[name] = value
    return rec


@numba.njit(cache=True)
def indentation_curvature_jit(cp, a, z, dz, v):
    """Compiled :func:`indentation_curvature` from the indentation state ``(z, dz/da, v)`` at ``a``
    (``cp`` a :data:`screening.condensation.cubic.SDOF_RECORD`)."""
    eps, b = cp.eps, cp.b
    if a <= cp.theta_ul:
        n = -2.0 * eps * b * b * a * z
        d = 1.0 + eps * b * b * a * a + 3.0 * eps * z * z
        dn = -2.0 * eps * b * b * (z + a * dz)
        dd = 2.0 * eps * b * b * a + 6.0 * eps * z * dz
        return (dn * d - n * dd) / (d * d)
    mg = cp.m * cp.g
    s2 = 1.0 + 4.0 * eps * mg * a / cp.k
    if s2 <= 0.0:
        return 0.0
    S = math.sqrt(s2)
    sv = S * v
    return -(mg / cp.k) * (2.0 * eps * mg / (cp.k * S) * v + S * (dz + b)) / (sv * sv)


@numba.njit(cache=True)
def constraint_damping_jit(cp, a, z, dz, v):
    """Compiled :func:`constraint_damping` from the indentation state ``(z, dz/da, v)`` at ``a``
    (``cp`` a :data:`screening.condensation.cubic.SDOF_RECORD`)."""
    b, w_rate, w_ind = cp.b, cp.w_rate, cp.w_indentation
    if a <= cp.theta_ul:
        return (w_rate + w_ind * z) * (2.0 * b * dz * dz + 2.0 / 3.0 * b * b * b) + w_ind * 4.0 / 3.0 * a * dz * b * b * b
    length = v / a
    q = dz + b
    r = q - 0.5 * length
    s = q - length / 3.0
    return (w_rate * length * (r * r + length * length / 12.0)
            + w_ind * v * length * (0.5 * s * s + length * length / 36.0))


@numba.njit(cache=True)
def rocking_acceleration_jit(sp, cp, theta, theta_dot, x_g_ddot, a_v=0.0):
    """Compiled :func:`rocking_acceleration` (``sp`` a :data:`STIFF` record, ``cp`` the cubic condensation's)."""
    s = math.sin(theta)
    c = math.cos(theta)
    sigma = 1.0 if theta >= 0.0 else -1.0
    a = sigma * s
    lam = max(1.0 + a_v / sp.g, GRAVITY_RATIO_MIN)
    al = a / lam
    z, dz, v = cubic.quasi_static_indentation_jit(cp, al)
    d2z = indentation_curvature_jit(cp, al, z, dz, v) / lam
    stiffness = cubic.damping_stiffness_jit(cp, al)[1]
    damping = constraint_damping_jit(cp, al, z, dz, v)
    m, h = sp.m, sp.h
    mgh = m * sp.g * h
    u = sigma * c * dz + h * s
    m_eff = sp.I_cm + m * (h * h * c * c + u * u)
    dm_eff = m * (-2.0 * h * h * c * s + 2.0 * u * (c * c * d2z - a * dz + h * c))
    q = sigma * c * (stiffness * a + mgh * a) - lam * mgh * s
    return (m * h * c * x_g_ddot - q - c * c * damping * theta_dot - 0.5 * dm_eff * theta_dot * theta_dot) / m_eff
