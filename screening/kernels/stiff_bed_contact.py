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

from screening.core.condensation import cubic
from screening.kernels.mcs_equations import GRAVITY_RATIO_MIN

__all__ = []


# ----------------------------------------------------------------------------- numpy reference
def housner_restitution(block):
    """Housner's coefficient of restitution of a rectangular block [1].

    The ratio of the angular velocity after an impact on the opposite corner to the one before, for a
    uniform rectangular block rocking on a rigid base; its square is the energy ratio per impact.  The
    stiff-bed model's ``transfer="housner"`` option uses it in place of the bed-derived loss.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.

    Returns
    -------
    float
        ``r`` [1], in ``(-0.5, 1]``.

    Notes
    -----
    Angular momentum about the new corner is conserved through an instantaneous, perfectly plastic
    impact: ``I_O theta'_+ = (I_O - 2 m b^2) theta'_-`` with ``I_O = (4/3) m R^2``, ``b = R sin(alpha)``
    (uniform block, ``I_cm = m (b^2 + h^2) / 3``), so

    ``r = 1 - (3/2) sin^2(alpha)``,  ``alpha = atan(b / h)``.

    The energy ratio per impact is ``r^2`` (``docs/stiff_bed.md``).

    References
    ----------
    .. [1] [housner1963] in the bibliography, ``docs/bibliography.md``.
    """
    return 1.0 - 1.5 * math.sin(math.atan2(float(block.b), float(block.h))) ** 2


def indentation_curvature(theta, block, foundation):
    """Curvature ``d^2 Z / da^2`` of the quasi-static base-centre indentation.

    The second derivative of the ``"cubic"`` condensation's static indentation ``Z(a)`` at ``a = |theta|``
    (vectorised): it enters the stiff-bed model's inertia derivative ``dm_eff/dtheta``.  In full contact on a
    linear bed (``eps = 0``) it is zero; past uplift it is negative.

    Parameters
    ----------
    theta : array_like
        Rotation [rad] (its magnitude is used).
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    float or numpy.ndarray
        ``d^2 Z / da^2`` [m/rad^2], the shape of ``theta``.

    Notes
    -----
    Full contact (``eps z^3 + beta z = z_lin``, ``beta = 1 + eps b^2 a^2``): ``z' = N / D`` with
    ``N = -2 eps b^2 a z``, ``D = beta + 3 eps z^2``, so ``z'' = (N' D - N D') / D^2``,
    ``N' = -2 eps b^2 (z + a z')``, ``D' = 2 eps b^2 a + 6 eps z z'``.  Uplift
    (``z = v - b a``, ``v^2 = 2 A / (1 + S)``, ``S = sqrt(1 + 2 eps A)``, ``A = 2 m g a / k``):
    ``z' = m g / (k S v) - b``, so ``z'' = -(m g / k) (S' v + S v') / (S v)^2`` with
    ``S' = 2 eps m g / (k S)``, ``v' = z' + b``.  Beyond the capacity angle of a softening bed: 0.
    The static balance is that of the contact law, eq. (3) in [1], on the quasi-static contact of
    ``docs/stiff_bed.md``.

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
    """Rocking damping ``C_D(a)`` of the bed's damping pressure on the quasi-static contact.

    Evaluated at ``a = |theta|`` (vectorised): the dissipated power is ``C_D(a) theta'^2`` (times
    ``cos^2 theta`` in the model, where ``a = |sin theta|``).

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    float or numpy.ndarray
        ``C_D`` [N m s/rad], the shape of ``theta``.

    Notes
    -----
    With the base centre slaved to ``z = Z(a)`` (``w = dZ/da``), the indentation field is ``z(u) = z + a u``
    and its rate ``(w + u) theta'`` at the signed distance ``u`` from the base centre (the compressed edge at
    ``u = b``).  The damping pressure ``(w_rate + w_ind z(u)) zdot(u)`` (the damping term of the contact
    law, eq. (3) in [1]) dissipates

    ``C_D = int (w_rate + w_ind z(u)) (w + u)^2 du``

    over the contact: in full contact (``u`` in ``[-b, b]``)
    ``C_D = w_rate (2 b w^2 + 2 b^3 / 3) + w_ind (z (2 b w^2 + 2 b^3 / 3) + 4 a w b^3 / 3)``; in uplift (contact
    length ``L = v / a`` from the corner, ``v = z + b a``, ``q = w + b``)
    ``C_D = w_rate L ((q - L/2)^2 + L^2/12) + w_ind v L ((q - L/3)^2 / 2 + L^2/36)``; continuous at
    ``theta_ul``.  It is the condensation's damping moment coefficient ``C`` plus the work of the vertical
    damping force along the constraint, ``w (w_rate + w_ind) int ... (w + u)``: ``C`` alone counts the
    moment's work only, and in uplift, where the base centre rises at ``w ~ -b``, overstates the dissipation
    by ``2 b / L`` (for ``eps = 0``: ``C = lam b v^3 / (12 a^2)`` against ``C_D = lam v^4 / (24 a^3)``).
    This is Rayleigh's dissipation function of the contact pressure on the constraint ``z_cb = Z(theta)``
    (``docs/stiff_bed.md``).

    """
    z, dz, v, a, up = cubic.indentation_state(theta, block, foundation)
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
    """The weight ratio ``lam = (g + a_v) / g`` under a vertical ground acceleration.

    The block's apparent weight over its weight when the ground accelerates upward at ``a_v``, held at
    :data:`~screening.kernels.mcs_equations.GRAVITY_RATIO_MIN` or above (below 0 the block lifts off,
    which the model stops).

    Parameters
    ----------
    a_v : array_like
        Vertical ground acceleration [m s-2], positive up.
    g : float
        Gravitational acceleration [m s-2].

    Returns
    -------
    numpy.ndarray
        ``lam`` [1], the shape of ``a_v``.

    Notes
    -----
    ``lam = max((g + a_v) / g, GRAVITY_RATIO_MIN)``: in the frame of the ground, gravity becomes
    ``g + a_v`` (``docs/stiff_bed.md``, "Vertical ground acceleration").

    References
    ----------
    .. [1] ``docs/stiff_bed.md``, section "Vertical ground acceleration".
    """
    return np.maximum(1.0 + np.asarray(a_v, dtype=float) / g, GRAVITY_RATIO_MIN)


def rocking_coefficients(theta, block, foundation, a_v=0.0):
    """Inertia, its slope, restoring moment and damping of the stiff-bed model at ``theta``.

    ``m_eff`` is the inertia of the rigid block on the quasi-static contact, ``Q`` the restoring generalized
    moment (bed moment minus gravity), ``C_eff = cos^2(theta) C_D(|sin theta|)`` the damping
    (:func:`constraint_damping`); vectorised in ``theta``.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    a_v : float or array_like, optional
        Vertical ground acceleration [m s-2], positive up (default 0).

    Returns
    -------
    m_eff : numpy.ndarray
        Generalized inertia [kg m2].
    dm_eff : numpy.ndarray
        ``d m_eff / d theta`` [kg m2/rad].
    q : numpy.ndarray
        Restoring generalized moment ``Q`` [N m].
    c_eff : numpy.ndarray
        Damping ``C_eff`` [N m s/rad].

    Notes
    -----
    With ``a = |sin theta|``, ``sigma = sign(theta)`` and ``u = sigma cos(theta) Z'(a) + h sin(theta)``:

    ``m_eff = I_cm + m (h^2 cos^2 theta + u^2)``,
    ``Q = sigma cos(theta) (K(a) + m g h) a - lam m g h sin(theta)``

    with ``K`` the bed's rocking stiffness of the contact law, eq. (3) in [1] (the ``"cubic"``
    condensation).  Under ``a_v`` the weight is ``lam m g``, ``lam = (g + a_v) / g``.  On the linear
    Winkler bed the contact law is similar in the weight: ``Z(a; lam) = lam Z(a / lam)``, the bed moment
    ``B(a; lam) = lam B(a / lam)`` (``B = (K + m g h) a``), the rate damping ``C(a; lam) = C(a / lam)``;
    so the laws are read at ``a / lam``, ``Z''`` divided by ``lam``, and gravity's moment is
    ``lam m g h sin(theta)`` (``docs/stiff_bed.md``, "Vertical ground acceleration").

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
    """Angular acceleration ``theta''`` of the stiff-bed model, without the transfer loss.

    The equation of motion of the rigid block on the quasi-static contact (:func:`rocking_coefficients`),
    solved for ``theta''``; vectorised.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    theta_dot : array_like
        Angular velocity [rad s-1].
    x_g_ddot : array_like
        Inertial ground acceleration [m s-2] (the kernels' convention, ``-a_g``; :mod:`screening.solvers.simulate`).
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    a_v : float or array_like, optional
        Vertical ground acceleration [m s-2], positive up (default 0).

    Returns
    -------
    numpy.ndarray
        ``theta''`` [rad s-2].

    Notes
    -----
    Lagrange's equation with ``T = m_eff theta'^2 / 2``:

    ``m_eff theta'' + (1/2) dm_eff theta'^2 + C_eff theta' + Q = m h cos(theta) x_g''``

    (``docs/stiff_bed.md``, "Rigid block on that constraint"; the contact law is eq. (3) in [1]).

    """
    m_eff, dm_eff, q, c_eff = rocking_coefficients(theta, block, foundation, a_v)
    theta_dot = np.asarray(theta_dot, dtype=float)
    return ((block.m * block.h * np.cos(theta) * x_g_ddot - q - c_eff * theta_dot - 0.5 * dm_eff * theta_dot ** 2)
            / m_eff)


def potential(theta, block, foundation, n_pieces=64, order=8):
    """Energy ``V(theta) = int_0^|theta| Q`` stored at rest at ``theta``.

    Gauss–Legendre quadrature of ``order`` points on ``[0, theta_ul]`` and on ``n_pieces``
    geometrically growing pieces of ``[theta_ul, |theta|]`` (the contact length varies like
    ``theta^(-1/2)`` just past uplift); relative error below 1e-9 for the beds of the tests.

    Parameters
    ----------
    theta : float
        Rotation [rad] (scalar).
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    n_pieces : int, optional
        Pieces of ``[theta_ul, |theta|]`` (default 64).
    order : int, optional
        Gauss–Legendre points per piece (default 8).

    Returns
    -------
    float
        ``V`` [J].

    Notes
    -----
    ``V(theta) = int_0^|theta| Q(s) ds`` with ``Q`` the restoring moment of :func:`rocking_coefficients`
    (no vertical acceleration); the transfer table compares ``V`` at successive amplitudes
    (``docs/stiff_bed.md``).  Gauss–Legendre quadrature: [2].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] M. Abramowitz and I. A. Stegun, Handbook of Mathematical Functions, Dover (1965), 25.4.29.
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
                  ("theta_over", "f8"), ("theta_cap", "f8"), ("rate_max", "f8"), ("locate", "f8"),
                  ("by_rate", "f8")])


def stiff_record(block, foundation, locate=True, by_rate=False):
    """The :data:`STIFF` record of the compiled stiff-bed kernel.

    A 1-element structured array of the block's and bed's scalars the kernel reads (SI), from scalar
    model objects.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    locate : bool, optional
        Shorten a step that crosses zero into uplift on the other side to the crossing
        (:class:`screening.solvers.stiff_bed.StiffBedModel`; default True).
    by_rate : bool, optional
        Read the transfer table at the rate at the zero crossing instead of the half cycle's amplitude
        (``StiffBedModel(transfer="impact")``; default False).

    Returns
    -------
    numpy.ndarray
        Shape ``(1,)``, dtype :data:`STIFF`: ``m`` [kg], ``g`` [m s-2], ``h`` [m], ``I_cm`` [kg m2],
        ``theta_ul``, ``theta_over``, ``theta_cap`` [rad], ``rate_max`` [rad s-1], ``locate``, ``by_rate`` [1 or 0].

    Notes
    -----
    ``theta_ul`` is the uplift angle of the ``"cubic"`` condensation, ``theta_over = atan(b/h)``, ``theta_cap``
    its capacity angle, ``rate_max = 1000 sqrt(g / h)`` (``docs/stiff_bed.md``).

    References
    ----------
    .. [1] ``docs/stiff_bed.md`` (the model's compiled integrator).
    """
    rec = np.zeros(1, dtype=STIFF)
    values = dict(m=float(block.m), g=float(block.g), h=float(block.h), I_cm=float(block.I_cm),
                  theta_ul=float(cubic.uplift_threshold(block, foundation)), theta_over=float(block.slenderness),
                  theta_cap=float(cubic.capacity_angle(block, foundation)),
                  rate_max=1e3 * math.sqrt(float(block.g) / float(block.h)), locate=1.0 if locate else 0.0,
                  by_rate=1.0 if by_rate else 0.0)
    for name, value in values.items():
        rec[name] = value
    return rec


@numba.njit(cache=True)
def indentation_curvature_jit(cp, a, z, dz, v):
    """Compiled :func:`indentation_curvature` from the indentation state.

    Reads ``d^2 Z / da^2`` at ``a`` from the state ``(z, dz/da, v)`` the kernel already has.

    Parameters
    ----------
    cp : numpy.record
        A :data:`screening.core.condensation.cubic.SDOF_RECORD` record (``screening.core.condensation.cubic.sdof_record(block,
        foundation)[0]``).
    a : float
        ``|sin theta|`` [rad], the rotation's magnitude at which the law is read.
    z : float
        Base-centre indentation ``Z(a)`` [m] (:func:`screening.core.condensation.cubic.quasi_static_indentation_jit`).
    dz : float
        Its slope ``dZ/da`` [m/rad].
    v : float
        Indentation of the compressed edge ``z + b a`` [m].

    Returns
    -------
    float
        ``d^2 Z / da^2`` [m/rad^2].

    Notes
    -----
    The equations of :func:`indentation_curvature` (the contact law, eq. (3) in [1]); a test holds the two
    together.

    """
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
    """Compiled :func:`constraint_damping` from the indentation state.

    Reads ``C_D`` at ``a`` from the state ``(z, dz/da, v)`` the kernel already has.

    Parameters
    ----------
    cp, a, z, dz, v : see indentation_curvature_jit
        The condensation's record [SI] and the indentation state at ``a`` [rad]: ``z`` [m], ``dz``
        [m/rad], ``v`` [m], as in :func:`indentation_curvature_jit`.

    Returns
    -------
    float
        ``C_D`` [N m s/rad].

    Notes
    -----
    The equations of :func:`constraint_damping` (the damping of the contact law, eq. (3) in [1]); a test
    holds the two together.

    """
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
    """Compiled :func:`rocking_acceleration` (scalar).

    Parameters
    ----------
    sp : numpy.record
        A :data:`STIFF` record (``stiff_record(block, foundation)[0]``).
    cp : numpy.record
        A :data:`screening.core.condensation.cubic.SDOF_RECORD` record (``screening.core.condensation.cubic.sdof_record(block,
        foundation)[0]``).
    theta : float
        Rotation [rad].
    theta_dot : float
        Angular velocity [rad s-1].
    x_g_ddot : float
        Inertial ground acceleration [m s-2] (``-a_g``).
    a_v : float, optional
        Vertical ground acceleration [m s-2], positive up (default 0).

    Returns
    -------
    float
        ``theta''`` [rad s-2].

    Notes
    -----
    The equation of motion of :func:`rocking_acceleration`,
    ``m_eff theta'' + (1/2) dm_eff theta'^2 + C_eff theta' + Q = m h cos(theta) x_g''``, on the contact law
    of eq. (3) in [1]; a test holds the two together.

    """
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
