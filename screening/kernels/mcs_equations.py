"""The equations a Monte Carlo sample integrates (:mod:`screening.kernels.mcs_kernels` runs them): the
per-run model record, the compiled right-hand sides of the coupled eqs. (7)–(8) and the condensed eq. (22)
under horizontal and vertical ground acceleration, their input gains, and the uplift test.

Method: ``docs/method.md#coupled-and-condensed-models``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.linalg import expm

from screening.core.physics.contact import law_resultants_trig_jit

__all__ = []

#: Which equations a sample integrates.
MODEL_COUPLED = 0
MODEL_CONDENSED = 1

#: Smallest gravity ratio ``(g + a_v) / g`` the condensed laws are evaluated at (a sample whose ratio
#: falls below zero is stopped as lifted off at the end of the step).
GRAVITY_RATIO_MIN = 1e-3

#: Per-sample-run parameters of the compiled kernels (SI units), built by :func:`model_record`.
MODEL = np.dtype([
    ("m", "f8"), ("g", "f8"), ("h", "f8"), ("I_cm", "f8"), ("b", "f8"),      # block
    ("k", "f8"), ("eps", "f8"), ("w_rate", "f8"), ("w_indentation", "f8"),  # bed (law's weights)
    ("m_sdof", "f8"),                                                        # I_cm + m h^2 [kg m2]
    ("theta_over", "f8"),        # overturning angle atan(b/h) [rad]
    ("theta_ul", "f8"),          # uplift threshold of the condensation [rad] (condensed uplift flag)
    ("theta_cap", "f8"),         # capacity angle of the condensation [rad] (inf: none)
    ("max_flight", "f8"),        # longest flight before a sample is called diverged [s]
    ("z_max", "f8"), ("z_min", "f8"), ("rate_max", "f8"),   # physical bounds of the coupled state
    ("integrator", "i8"),        # INTEGRATOR_DOPRI or INTEGRATOR_RODAS
])

#: Integrators of a sample (the ``integrator`` field of :data:`MODEL`), by the name of the
#: ``integrator`` numerics option.
INTEGRATOR_DOPRI = 0
INTEGRATOR_RODAS = 1
#: The explicit pair, but exact (exponential) steps over the input's grid intervals in quiet full contact
#: (:func:`full_contact_propagator`; coupled model only).
INTEGRATOR_EXACT = 2
INTEGRATORS = {"dopri": INTEGRATOR_DOPRI, "rodas": INTEGRATOR_RODAS, "exact": INTEGRATOR_EXACT}

#: An exact full-contact step needs the state's amplitude bound ``A_z + b A_theta`` (energy of each linear
#: mode) within this fraction of the static indentation at its start, middle and end: far from uplift.
CONTACT_MARGIN = 0.5

#: "No propagator": what integrators other than ``"exact"`` are given.
NO_PROPAGATOR = np.zeros((0, 4))


def model_record(block, foundation, cond, max_flight_time=0.5, integrator="dopri"):
    """The :data:`MODEL` record of scalar model objects: every number a compiled sample integration reads.

    Built once per run; the kernels read the block, the bed's law weights, ``m_sdof``, the
    overturning, uplift and capacity angles, the flight limit, the physical bounds of the coupled
    state and the integrator from it.

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields: ``m`` [kg], ``b``, ``h`` [m], ``I_cm`` [kg m^2], ``g`` [m/s^2]).
    foundation : screening.Foundation
        The bed (scalar fields: ``k`` [N/m^2], ``eps`` [1/m^2], its damping weights).
    cond : screening.core.condensation.Condensation
        The condensation of condensed runs (its uplift threshold and capacity angle are stored).
    max_flight_time : float, optional
        Longest flight [s] before a sample is called diverged.
    integrator : str, optional
        A key of :data:`INTEGRATORS` (``"dopri"``, ``"rodas"`` or ``"exact"``).

    Returns
    -------
    numpy.ndarray
        A 0-d record of dtype :data:`MODEL` (SI units).

    Notes
    -----
    ``m_sdof = I_cm + m h^2`` (eq. (22) in [1]_), ``theta_over = atan(b / h)``, ``theta_ul`` of the
    condensation (eq. (19) for the paper's); the bounds ``z_max = b``, ``z_min = -2 h`` and
    ``rate_max = 1000 sqrt(g / h)`` flag a blown-up coupled state.

    """
    m, g, h, b = float(block.m), float(block.g), float(block.h), float(block.b)
    rec = np.zeros((), dtype=MODEL)
    values = dict(m=m, g=g, h=h, I_cm=float(block.I_cm), b=b, k=float(foundation.k), eps=float(foundation.eps),
                  w_rate=float(foundation.damping_weights[0]), w_indentation=float(foundation.damping_weights[1]),
                  m_sdof=float(block.m_sdof), theta_over=float(block.slenderness),
                  theta_ul=float(cond.uplift_threshold(block, foundation)),
                  theta_cap=float(cond.capacity_angle(block, foundation)), max_flight=float(max_flight_time),
                  z_max=b,                              # sinking half the base width into the bed: blown up
                  z_min=-2.0 * h,                       # jumping a block height off the bed: blown up
                  rate_max=1e3 * math.sqrt(g / h),      # ~1000 x the free-fall rocking rate: blown up
                  integrator=INTEGRATORS[integrator])
    for name, value in values.items():
        rec[name] = value
    return rec


# ----------------------------------------------------------------------------- right-hand sides
@numba.njit(cache=True)
def coupled_accelerations(theta, theta_dot, z_cb, z_cb_dot, x_g_ddot, p, a_v=0.0):
    """``(theta'', z_cb'')`` [rad/s^2, m/s^2] of the coupled eqs. (7)–(8).

    The right-hand side of the coupled Monte Carlo model: the block's rocking and vertical motion
    on the bed, contact resultants integrated in closed form over the actual contact zone
    (:func:`screening.core.physics.contact.law_resultants_trig_jit`).

    Parameters
    ----------
    theta : float
        Rotation [rad].
    theta_dot : float
        Angular velocity [rad/s].
    z_cb : float
        Indentation of the base centre [m] (positive down, relative to the ground).
    z_cb_dot : float
        Its rate [m/s].
    x_g_ddot : float
        Horizontal ground acceleration [m/s^2].
    p : numpy.record
        The :data:`MODEL` record (:func:`model_record`).
    a_v : float, optional
        Vertical ground acceleration [m/s^2], positive up.

    Returns
    -------
    theta_ddot : float
        Angular acceleration [rad/s^2].
    z_ddot : float
        Vertical acceleration of the base centre [m/s^2].

    Notes
    -----
    Eliminating ``z_cb''`` from eq. (8) in [1]_ with eq. (7):
    ``(I_cm + m h^2 cos^2) theta'' = m h x_g'' cos - M_cb + h F_cb sin + m h^2 theta'^2 sin cos``,
    ``z_cb'' = g + a_v - F_cb/m - h (theta'^2 cos + theta'' sin)``, with ``a_v`` the vertical
    ground acceleration (positive up): in the ground's frame it adds to gravity, and ``z_cb`` (down) is
    relative to the ground, so it enters the vertical equation only (docs/method.md).  The printed
    resultants of eqs. (10)-(12) are corrected (docs/method.md, "Corrections to the printed equations").

    """
    return coupled_accelerations_trig(math.sin(theta), math.cos(theta), theta_dot, z_cb, z_cb_dot, x_g_ddot, p, a_v)


@numba.njit(cache=True, inline="always")
def coupled_accelerations_trig(s, c, theta_dot, z_cb, z_cb_dot, x_g_ddot, p, a_v):
    """:func:`coupled_accelerations` from ``s = sin(theta)``, ``c = cos(theta)`` (a caller with its own ``sin``, ``cos``).

    Parameters
    ----------
    s, c : float
        ``sin(theta)``, ``cos(theta)`` [1] of the rotation.
    theta_dot, z_cb, z_cb_dot, x_g_ddot, p, a_v : float or numpy.record
        As :func:`coupled_accelerations`.

    Returns
    -------
    tuple of float
        ``(theta'' [rad/s^2], z_cb'' [m/s^2])``.

    """
    m, g, h = p.m, p.g, p.h
    force, moment = law_resultants_trig_jit(s, c, theta_dot, z_cb, z_cb_dot, p.b, p.k, p.eps, p.w_rate,
                                            p.w_indentation)
    mh = m * h
    theta_ddot = ((mh * x_g_ddot * c - moment + h * force * s + mh * h * theta_dot * theta_dot * s * c)
                  / (p.I_cm + mh * h * c * c))
    z_ddot = (g + a_v) - force / m - h * (theta_dot * theta_dot * c + theta_ddot * s)
    return theta_ddot, z_ddot


@numba.njit(cache=True)
def condensed_acceleration(damping_stiffness, cond, theta, theta_dot, x_g_ddot, p, a_v=0.0):
    """``theta''`` [rad/s^2] of the condensed SDOF, eq. (22): ``(m h x_g'' - C theta' - K theta) / m_sdof``.

    Parameters
    ----------
    damping_stiffness : numba function
        The condensation's compiled ``(cond, theta) -> (C, K)`` (:class:`~screening.core.signatures.SdofKernel`).
    cond : numpy.record
        Its record.
    theta, theta_dot, x_g_ddot, p, a_v
        As in :func:`coupled_accelerations`.

    Returns
    -------
    float
        ``theta''`` [rad/s^2].

    Notes
    -----
    Eq. (22) in [1]_ with ``C(theta)``, ``K(theta)`` of eqs. (24)-(25) (or the chosen condensation's).
    A vertical ground acceleration scales the weight by ``lam = (g + a_v) / g``; the laws are read at
    ``theta / lam`` and the weight's moment gains ``m h a_v theta`` (docs/method.md, "Vertical ground
    acceleration")::

        m_sdof theta'' = m h x_g'' - C(theta / lam) theta' - K(theta / lam) theta + m h a_v theta

    """
    if a_v == 0.0:                                  # the horizontal-only path: no divisions
        damping, stiffness = damping_stiffness(cond, theta)
        return (p.m * p.h * x_g_ddot - damping * theta_dot - stiffness * theta) / p.m_sdof
    lam = max(1.0 + a_v / p.g, GRAVITY_RATIO_MIN)
    damping, stiffness = damping_stiffness(cond, theta / lam)
    return (p.m * p.h * x_g_ddot - damping * theta_dot - stiffness * theta + p.m * p.h * a_v * theta) / p.m_sdof


@numba.njit(cache=True)
def input_gain(model, theta, p):
    """``d(theta'', z_cb'')/d x_g''`` [rad/m, 1]: the right-hand side is linear in the input.

    The linearly implicit integrator reads the exact time derivative of the right-hand side as this
    gain times the input's rate.

    Parameters
    ----------
    model : int
        :data:`MODEL_COUPLED` or :data:`MODEL_CONDENSED`.
    theta : float
        Rotation [rad].
    p : numpy.record
        The :data:`MODEL` record (:func:`model_record`).

    Returns
    -------
    tuple of float
        ``(d theta''/d x_g'' [rad/m], d z_cb''/d x_g'' [1])``.

    Notes
    -----
    Coupled (eqs. (7)-(8) in [1]_ as in :func:`coupled_accelerations`): ``m h cos / (I_cm + m h^2 cos^2)``
    and ``-h sin`` times that; condensed (eq. (22)): ``m h / m_sdof`` and 0.

    """
    if model == MODEL_COUPLED:
        s = math.sin(theta)
        c = math.cos(theta)
        mh = p.m * p.h
        g1 = mh * c / (p.I_cm + mh * p.h * c * c)
        return g1, -p.h * s * g1
    return p.m * p.h / p.m_sdof, 0.0


@numba.njit(cache=True)
def vertical_gain(model, theta, p):
    """``d(theta'', z_cb'')/d a_v`` [rad/m, 1]: coupled ``(0, 1)``; condensed ``m h theta / m_sdof`` and 0
    (the weight's moment; the law's dependence through ``theta / lam`` is left out of this rate).

    Parameters
    ----------
    model, theta, p : int, float, numpy.record
        As :func:`input_gain`: the model code, the rotation [rad] and the :data:`MODEL` record.

    Returns
    -------
    tuple of float
        ``(d theta''/d a_v [rad/m], d z_cb''/d a_v [1])``.

    Notes
    -----
    From :func:`coupled_accelerations` (``a_v`` enters ``z_cb''`` only) and the condensed equation of
    :func:`condensed_acceleration` (eq. (22) in [1]_ with the weight's moment ``m h a_v theta``).

    """
    if model == MODEL_COUPLED:
        return 0.0, 1.0
    return p.m * p.h * theta / p.m_sdof, 0.0


def _jacobian_at_rest(p, y_star):
    """``(L, B)``: the coupled right-hand side's Jacobian at the rest state ``y_star`` (central differences,
    exact for its quadratic terms) and its input gain there."""
    z_st = float(y_star[2])
    theta_step = 1e-3 * z_st / float(p["b"])
    steps = np.array([theta_step, 1e3 * theta_step, 1e-3 * z_st, 1e3 * 1e-3 * z_st])
    L = np.zeros((4, 4))
    L[0, 1] = L[2, 3] = 1.0
    for j in range(4):
        up, down = np.array(y_star, float), np.array(y_star, float)
        up[j] += steps[j]
        down[j] -= steps[j]
        a_up = coupled_accelerations(up[0], up[1], up[2], up[3], 0.0, p)
        a_down = coupled_accelerations(down[0], down[1], down[2], down[3], 0.0, p)
        L[1, j] = (a_up[0] - a_down[0]) / (2.0 * steps[j])
        L[3, j] = (a_up[1] - a_down[1]) / (2.0 * steps[j])
    g1, g3 = input_gain(MODEL_COUPLED, 0.0, p)
    return L, np.array([0.0, g1, 0.0, g3])


def _phi_functions(a):
    """``(exp(a), phi_1(a), ..., phi_4(a))`` of a 4 x 4 matrix from one exponential of a 20 x 20 block matrix."""
    big = np.zeros((20, 20))
    big[:4, :4] = a
    for i in range(4):
        big[4 * i:4 * i + 4, 4 * i + 4:4 * i + 8] = np.eye(4)
    e = expm(big)
    return [e[:4, 4 * i:4 * i + 4] for i in range(5)]


def _step_matrices(a, h, fraction):
    """``(Phi, W, Psi1, Psi2)`` of a step over ``fraction`` (1 or 1/2) of a grid interval ``h``: ``a = L h
    fraction``; ``W`` the responses to the cubic Hermite basis of the interval (before the input gain)."""
    phi = _phi_functions(a)
    hs = h * fraction
    # response to sigma^k (sigma = s / h on the interval) for s in [0, h fraction]: hs k! fraction^k phi_{k+1}
    mono = [hs * math.factorial(k) * fraction ** k * phi[k + 1] for k in range(4)]
    hermite = [2.0 * mono[3] - 3.0 * mono[2] + mono[0], mono[3] - 2.0 * mono[2] + mono[1],
               -2.0 * mono[3] + 3.0 * mono[2], mono[3] - mono[2]]
    return phi[0], hermite, hs * phi[1], hs * fraction * phi[2]


def full_contact_propagator(p, y_star, dt):
    """The exact propagator of the coupled model linearized in full contact, over one input grid interval.

    Parameters
    ----------
    p : numpy.ndarray or numpy.record
        The :data:`MODEL` record (:func:`model_record`).
    y_star : array_like
        The rest state ``(0, 0, z_st, 0)`` [rad, rad/s, m, m/s].
    dt : float
        The input grid's step [s].

    Returns
    -------
    numpy.ndarray
        ``(45, 4)``: rows 0-15 ``Phi = exp(L dt)``, ``W`` (column ``c``: the response to the ``c``-th cubic
        Hermite basis function of the input through its gain ``B``), ``Psi1``, ``Psi2`` (responses to a
        constant and to a ramp ``s/dt`` of the remainder); rows 16-31 the same at ``dt/2``; row 32
        ``y_star``; rows 33-34 rows 1 and 3 of ``L``; row 35 ``(dt, K_theta, K_z, B_1)``; row 36
        ``(CONTACT_MARGIN z_st, 0, 0, 0)``.  :data:`NO_PROPAGATOR` where a full-contact mode is not a
        stable oscillator (``K_theta`` or ``K_z`` <= 0).

    Notes
    -----
    With ``x = y - y_star`` the coupled eqs. (7)-(8) in [1]_ read ``x' = L x + B u(t) + N(x, u)``.  Over an
    interval of the cubic Hermite input ``u`` the linear part is propagated exactly (variation of
    constants, ``phi`` functions from one matrix exponential [2]_); the remainder ``N`` (Hunt-Crossley
    damping, cubic bed term, geometry) enters as a linear function of time (ETD2 of [2]_).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hochbruck2010] in the bibliography, ``docs/bibliography.md``.
    """
    rec = p[()] if isinstance(p, np.ndarray) and p.ndim == 0 else p
    L, B = _jacobian_at_rest(rec, y_star)
    k_theta, k_z = -L[1, 0], -L[3, 2]
    if not (k_theta > 0.0 and k_z > 0.0):
        return NO_PROPAGATOR
    rows = []
    for fraction in (1.0, 0.5):
        phi, hermite, psi1, psi2 = _step_matrices(L * dt * fraction, dt, fraction)
        rows += [phi, np.column_stack([w @ B for w in hermite]), psi1, psi2]
    rows.append(np.array(y_star, float)[None])
    rows.append(L[[1, 3]])
    rows.append(np.array([[dt, k_theta, k_z, B[1]]]))
    rows.append(np.array([[CONTACT_MARGIN * float(y_star[2]), 0.0, 0.0, 0.0]]))
    _, _, psi1, psi2 = _step_matrices(L * 2.0 * dt, 2.0 * dt, 1.0)       # a step over two intervals
    rows += [psi1, psi2]
    return np.ascontiguousarray(np.vstack(rows))
