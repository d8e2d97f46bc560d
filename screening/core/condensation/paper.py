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

Equivalent linear coefficients (paper section 2.4)
--------------------------------------------------
``c_eq = E[dg/dtheta']`` and ``k_eq = E[dg/dtheta]`` (eq. 31) for
``g = C(theta) theta' + K(theta) theta`` with ``(theta, theta')`` zero-mean Gaussian.

Closed forms (eq. 35 and eq. 36 as corrected: docs/method.md#eq-36-equivalent-stiffness).  With ``r = sigma_theta /
theta_ul`` and ``x = theta_ul^2 / (2 sigma_theta^2) = 1 / (2 r^2)`` every sigma-dependent
part is one of these dimensionless Gaussian integrals (``1_in``: ``|theta| <= theta_ul``):

=====================  =====================================  ==========================================
name                   definition                              closed form
=====================  =====================================  ==========================================
``p_in``               ``P(|theta| <= theta_ul)``              ``erf(sqrt(x))``
``p_out``              ``P(|theta| > theta_ul)`` (eq. 58)      ``erfc(sqrt(x))``
``tail_m12``           ``E[|theta/theta_ul|^-1/2 1_out]``      ``2^-1/4 / sqrt(pi) r^-1/2 Gamma(1/4, x)``
``tail_m32``           ``E[|theta/theta_ul|^-3/2 1_out]``      ``2^-3/4 / sqrt(pi) r^-3/2 Gamma(-1/4, x)``
``inner_m2``           ``E[(theta/theta_ul)^2 1_in]``          ``r^2 P(3/2, x)`` (regularised lower)
=====================  =====================================  ==========================================

with ``Gamma(-1/4, x) = 4 (x^-1/4 e^-x - Gamma(3/4, x))``.  Writing ``K0 = (2/3) b^3 k``,
``E0 = m^2 g^2 b / k`` and ``C1`` the no-uplift damping, the coefficients are

* Hunt–Crossley: ``c_eq = C1 (p_in + tail_m12)`` — eq. (35);
* Winkler:       ``c_eq = C1 (p_in + tail_m32)``;
* ``k_eq = K0 (p_in + tail_m32) - m g h - D + eps E0 (p_in/2 + p_out + 0.3 inner_m2 - tail_m12/5)``

where the velocity-coupling term ``D = -E[C'(theta) theta']`` is
``(C1/2) cov / sigma_theta^2 * tail_m12`` (Hunt–Crossley) or
``(3/2) C1 cov / sigma_theta^2 * tail_m32`` (Winkler).  Expanding the tails recovers the
printed eq. (36) term by term, including its three corrections: the ``Gamma(1/4)`` rho-term
carries ``sigma_theta_dot / sigma_theta^(3/2)``, there is no jump term (``C`` is
continuous), and the eps bracket is ``E[d(K_eps theta)/d theta]`` (coefficient 6/5 on
``b^5``, halved ``Gamma(1/4)`` term).

Limits: ``sigma_theta -> 0`` gives the no-uplift values ``c_eq = C1``,
``k_eq = K0 - m g h + eps (E0/2 + (6/5) k b^5 sigma_theta^2)``; ``sigma_theta -> inf`` gives
``c_eq -> 0`` and ``k_eq -> -m g h + eps E0``.


Method and how it is checked: ``docs/method.md#closed-forms-for-the-paper-condensation``.

The functions below are the paper's condensation alone; :mod:`screening.core.condensation.api` has
the same functions for any registered condensation (``condensation=`` a name or object).

Method and how it is checked: ``docs/method.md#paper-condensation``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from screening.core.condensation.base import Condensation, MomentKernel, SdofKernel
from screening.core.condensation.registry import register
from screening.core.condensation.uplift_integrals import (coefficient_table, gaussian_uplift_integrals,
                                                          uplift_integrals_q)
from screening.core.signatures import FMA, moment_coefficients_signature, sdof_coefficients_signature
from screening.core.physics.contact import bed_rocking_stiffness, linear_rocking_stiffness

__all__ = []


def uplift_threshold(block, foundation):
    """Static uplift angle ``theta_ul`` [rad] of the paper's condensation.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``theta_ul = m g / (2 b^2 k)`` [rad].

    Notes
    -----
    Eq. (19) in [1]: the rotation at which the linear static indentation ``m g / (2 b k)`` (eq. (17))
    equals ``b theta``.

    """
    return block.m * block.g / (2.0 * block.b**2 * foundation.k)


def static_indentation(theta, block, foundation):
    """Quasi-static vertical displacement of the base centre ``z_st(theta)`` [m].

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
        ``m g / (2 b k)`` for ``|theta| <= theta_ul`` (eq. (17) in [1]) and
        ``sqrt(2 m g |theta| / k) - b |theta|`` beyond (eq. (18)).

    Notes
    -----
    The linear static balance in full contact and in uplift; continuous at ``theta_ul`` (eq. (19)).

    """
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    inner = mg / (2.0 * b * k) + 0.0 * theta
    outer = np.sqrt(2.0 * mg * theta / k) - b * theta
    return np.where(theta <= uplift_threshold(block, foundation), inner, outer)


def damping_inner_parts(block, foundation):
    """No-uplift rocking damping of the law's two basis pressures [N m s/rad].

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    rate : numpy.ndarray or float
        ``(2/3) w_rate b^3`` (the ``zdot`` pressure, Winkler).
    indentation : numpy.ndarray or float
        ``w_indentation b^2 m g / (3 k)`` (the ``z zdot`` pressure, Hunt–Crossley).

    Notes
    -----
    The no-uplift branch of eq. (24) in [1] is the ``z zdot`` part; the Winkler dashpot adds the ``zdot``
    part.

    """
    w_rate, w_ind = foundation.damping_weights
    return 2.0 / 3.0 * w_rate * block.b**3, w_ind * block.b**2 * block.m * block.g / (3.0 * foundation.k)


def damping_inner(block, foundation):
    """No-uplift rocking damping ``C_1`` [N m s/rad].

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``C_1`` [N m s/rad]: the sum of :func:`damping_inner_parts`.

    Notes
    -----
    ``lam b^2 m g / (3 k)`` for Hunt–Crossley, eq. (24) in [1]; ``(2/3) c b^3`` for Winkler.

    """
    rate, indentation = damping_inner_parts(block, foundation)
    return rate + indentation


def stiffness_at_rest(block, foundation):
    """Rocking stiffness at rest ``K(0)`` [N m/rad] of the paper's condensation.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2]); fields may be arrays.

    Returns
    -------
    numpy.ndarray or float
        ``K(0) = (2/3) b^3 k - m g h + eps m^2 g^2 b / (2 k)`` [N m/rad].

    Notes
    -----
    Eq. (25) in [1] at ``theta = 0``: :func:`screening.core.physics.contact.linear_rocking_stiffness` plus the
    cubic term's share about the static indentation ``m g / (2 b k)``.

    """
    e0 = (block.m * block.g) ** 2 * block.b / foundation.k
    return linear_rocking_stiffness(block, foundation) + 0.5 * foundation.eps * e0


def rocking_damping(theta, block, foundation):
    """Piecewise rocking damping ``C(theta)`` [N m s/rad] of the paper's condensation.

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

    Notes
    -----
    ``C_1`` (:func:`damping_inner`) for ``|theta| <= theta_ul``; beyond,
    ``w_rate (2 m g / k)^(3/2) |theta|^(-3/2) / 12 + w_indentation b (2 m g / k)^(3/2) |theta|^(-1/2) / 12``:
    eq. (24) in [1] for Hunt–Crossley, its Winkler form from the module docstring.

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
    """Piecewise secant rocking stiffness ``K(theta)`` [N m/rad] of the paper's condensation.

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

    Notes
    -----
    Eq. (25) in [1]: ``(2/3) b^3 k - m g h + eps (m^2 g^2 b / (2 k) + (2/5) k b^5 theta^2)`` for
    ``|theta| <= theta_ul``, ``m g (b/|theta| - sqrt(2 m g k) |theta|^(-3/2) / (3 k) - h) +
    eps (m^2 g^2 b / k - m^2 g^2 sqrt(2 m g / k) |theta|^(-1/2) / (5 k))`` beyond.

    """
    theta = np.asarray(theta, dtype=float)
    a = np.abs(theta)
    m, g, b, h, k, eps = block.m, block.g, block.b, block.h, foundation.k, foundation.eps
    mg = m * g
    tu = uplift_threshold(block, foundation)
    k1 = linear_rocking_stiffness(block, foundation) + eps * (mg**2 * b / (2.0 * k) + 0.4 * k * b**5 * theta**2)
    with np.errstate(divide="ignore", invalid="ignore"):
        k2 = (mg * (b / a - np.sqrt(2.0 * mg * k) / (3.0 * k) * a**-1.5 - h)
              + eps * (mg**2 * b / k - mg**2 / (5.0 * k) * np.sqrt(2.0 * mg / k) * a**-0.5))
    return np.where(a <= tu, k1, k2)


def restoring_moment(theta, block, foundation):
    """Restoring moment ``K(theta) theta`` [N m] of the paper's condensation.

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

    Notes
    -----
    The conservative term of eq. (22) in [1] with ``K`` of eq. (25).

    """
    theta = np.asarray(theta, dtype=float)
    return rocking_stiffness(theta, block, foundation) * theta


#: Per-point parameters of :func:`damping_stiffness_jit` (SI units): ``C = C1`` inside the threshold,
#: ``C2_rate |theta|^-3/2 + C2_indentation |theta|^-1/2`` outside (the law's two basis pressures); ``K = K1_0 + K1_2 theta^2`` inside,
#: ``MGB/|theta| - K2_32 |theta|^-3/2 - K2_12 |theta|^-1/2 + K2_0`` outside (eqs. 24–25).
SDOF_RECORD = np.dtype([("theta_ul", "f8"), ("C1", "f8"), ("C2_rate", "f8"), ("C2_indentation", "f8"), ("K1_0", "f8"),
                        ("K1_2", "f8"), ("MGB", "f8"), ("K2_32", "f8"), ("K2_12", "f8"), ("K2_0", "f8")])


def sdof_record(block, foundation):
    """The :data:`SDOF_RECORD` of scalar model objects: the constants of ``C`` and ``K``.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    numpy.ndarray
        A 1-element :data:`SDOF_RECORD` (SI units) for :func:`damping_stiffness_jit`.

    Notes
    -----
    The parameter-only factors of eqs. (24)-(25) in [1], so that the compiled twin evaluates ``C`` and
    ``K`` with one square root.

    """
    m, g, h, b = float(block.m), float(block.g), float(block.h), float(block.b)
    k, eps = float(foundation.k), float(foundation.eps)
    w_rate, w_ind = (float(w) for w in foundation.damping_weights)
    mg = m * g
    rec = np.zeros(1, dtype=SDOF_RECORD)
    rec["theta_ul"] = uplift_threshold(block, foundation)
    rec["C1"] = damping_inner(block, foundation)
    rec["C2_rate"] = w_rate / 12.0 * (2.0 * mg / k) ** 1.5            # x |theta|^-3/2
    rec["C2_indentation"] = w_ind * b / 12.0 * (2.0 * mg / k) ** 1.5  # x |theta|^-1/2
    rec["K1_0"] = stiffness_at_rest(block, foundation)
    rec["K1_2"] = eps * 0.4 * k * b**5
    rec["MGB"] = mg * b
    rec["K2_32"] = mg * math.sqrt(2.0 * mg * k) / (3.0 * k)
    rec["K2_12"] = eps * mg * mg / (5.0 * k) * math.sqrt(2.0 * mg / k)
    rec["K2_0"] = -mg * h + eps * mg * mg * b / k
    return rec


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
    Eqs. (24)-(25) in [1] from the record's constants; the condensed Monte Carlo's ``C``, ``K``.

    """
    a = abs(theta)
    if a <= p.theta_ul:
        return p.C1, p.K1_0 + p.K1_2 * theta * theta
    r = 1.0 / math.sqrt(a)
    stiffness = p.MGB * r * r - p.K2_32 * r * r * r - p.K2_12 * r + p.K2_0
    return p.C2_rate * r * r * r + p.C2_indentation * r, stiffness


# ---------------------------------------------------------------- equivalent linear coefficients (section 2.4)

def coefficient_constants(block, foundation):
    """Parameter-only constants of the closed-form equivalent coefficients (SI).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    dict
        ``C1`` [N m s/rad] (and its parts ``C1_rate``, ``C1_indentation``), ``K0 = (2/3) b^3 k`` [N m/rad],
        ``mgh`` [N m], ``E0 = (m g)^2 b / k`` [N m] and ``theta_ul`` [rad].

    Notes
    -----
    The factors of eqs. (35)-(36) in [1] that do not depend on the moments.

    """
    m, g, b, h, k = block.m, block.g, block.b, block.h, foundation.k
    c1_rate, c1_indentation = damping_inner_parts(block, foundation)
    return {
        "C1": c1_rate + c1_indentation,
        "C1_rate": c1_rate,
        "C1_indentation": c1_indentation,
        "K0": bed_rocking_stiffness(block, foundation),
        "mgh": m * g * h,
        "E0": (m * g) ** 2 * b / k,
        "theta_ul": uplift_threshold(block, foundation),
    }


def equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation):
    """Closed-form equivalent damping and stiffness of the paper's condensation.

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    cov_over_sigma : array_like
        ``cov(theta, theta') / sigma_theta = rho sigma_theta_dot`` [rad s-1].
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); fields may be arrays.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays.

    Returns
    -------
    c_eq : numpy.ndarray
        [N m s/rad], broadcast with the model's fields.
    k_eq : numpy.ndarray
        [N m/rad].

    Notes
    -----
    Eqs. (35)-(36) in [1], with the corrections of ``docs/method.md`` (module docstring): the Gaussian
    expectations of eq. (31) of the piecewise ``C``, ``K`` (eqs. (24)-(25)) through the universal uplift
    integrals of :mod:`~screening.core.condensation.uplift_integrals`; :func:`equivalent_coefficients_jit` is the
    compiled twin.

    """
    s = np.asarray(sigma_theta, dtype=float)
    cov_over_s = np.asarray(cov_over_sigma, dtype=float)
    const = coefficient_constants(block, foundation)
    tu = const["theta_ul"]
    G = gaussian_uplift_integrals(s / tu)
    c1_rate, c1_ind = const["C1_rate"], const["C1_indentation"]
    c_eq = c1_rate * (G["p_in"] + G["tail_m32"]) + c1_ind * (G["p_in"] + G["tail_m12"])
    coupling = c1_rate * (1.5 * G["tail_m32_r"]) + c1_ind * (0.5 * G["tail_m12_r"])
    k_eq = (const["K0"] * (G["p_in"] + G["tail_m32"]) - const["mgh"]
            - coupling * cov_over_s / tu
            + foundation.eps * const["E0"] * (0.5 * G["p_in"] + G["p_out"]
                                              + 0.3 * G["inner_m2"] - 0.2 * G["tail_m12"]))
    c_eq, k_eq = np.broadcast_arrays(c_eq, k_eq)
    return c_eq.copy(), k_eq.copy()


#: Per-point parameters of :func:`equivalent_coefficients_jit` (SI units).
RECORD = np.dtype([("theta_ul", "f8"), ("inv_theta_ul2", "f8"), ("C1_rate", "f8"), ("C1_indentation", "f8"),
                   ("K0", "f8"), ("mgh", "f8"), ("E0", "f8"), ("eps", "f8")])


def records(block, foundation):
    """One :data:`RECORD` per point: the constants of the compiled closed forms.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); flat (1-d) or scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); flat (1-d) or scalar fields.

    Returns
    -------
    numpy.ndarray
        Structured array of :data:`RECORD` (SI units), one per point.

    Notes
    -----
    :func:`coefficient_constants` laid out for :func:`equivalent_coefficients_jit` (eqs. (35)-(36) in [1]).

    """
    const = coefficient_constants(block, foundation)
    fields = {"theta_ul": const["theta_ul"], "inv_theta_ul2": 1.0 / const["theta_ul"] ** 2,
              "C1_rate": const["C1_rate"], "C1_indentation": const["C1_indentation"],
              "K0": const["K0"], "mgh": const["mgh"], "E0": const["E0"], "eps": foundation.eps}
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in fields.values()))
    out = np.empty(arrays[0].size, dtype=RECORD)
    for name, a in zip(fields, arrays):
        out[name] = a.reshape(-1)
    return out


@numba.njit(moment_coefficients_signature(RECORD), cache=True, fastmath=FMA)
def equivalent_coefficients_jit(p, table, var_theta, cov):
    """Compiled twin of :func:`equivalent_coefficients` from the moments.

    Parameters
    ----------
    p : numpy.void
        A :data:`RECORD` (:func:`records`).
    table : numpy.ndarray
        The universal table of :func:`screening.core.condensation.uplift_integrals.coefficient_table`.
    var_theta : float
        Variance of the rotation [rad2].
    cov : float
        Covariance of the rotation and its rate [rad2 s-1].

    Returns
    -------
    c_eq : float
        [N m s/rad].
    k_eq : float
        [N m/rad].

    Notes
    -----
    Eqs. (35)-(36) in [1] (corrected) with the Gaussian integrals read from the table; finite at
    ``var_theta = 0``, the start of every integration of eq. (45).

    """
    q = var_theta * p.inv_theta_ul2                 # (sigma_theta / theta_ul)^2
    p_in, tail_m12, tail_m32, p32 = uplift_integrals_q(q, table)
    # the law's two basis pressures: zdot (tails |theta|^-3/2) and z zdot (|theta|^-1/2)
    coupling = p.C1_rate * (1.5 * tail_m32) + p.C1_indentation * (0.5 * tail_m12)
    # D = coupling * cov / sigma^2, finite at sigma = 0 (the tails vanish first)
    d_term = coupling * cov / var_theta if tail_m12 > 0.0 or tail_m32 > 0.0 else 0.0
    c_eq = p.C1_rate * (p_in + tail_m32) + p.C1_indentation * (p_in + tail_m12)
    k_eq = (p.K0 * (p_in + tail_m32) - p.mgh - d_term
            + p.eps * p.E0 * (1.0 - 0.5 * p_in + 0.3 * q * p32 - 0.2 * tail_m12))
    return c_eq, k_eq


class PaperCondensation(Condensation):
    """The paper's condensation, eqs. (17)–(25): static indentation from the linear vertical balance."""

    name = "paper"
    description = "quasi-static z_cb from the linear static balance (eqs. 17-25)"

    uplift_threshold = staticmethod(uplift_threshold)
    rocking_damping = staticmethod(rocking_damping)
    rocking_stiffness = staticmethod(rocking_stiffness)

    def damping_at_rest(self, block, foundation):
        return damping_inner(block, foundation)

    stiffness_at_rest = staticmethod(stiffness_at_rest)

    def equivalent_coefficients(self, sigma_theta, cov_over_sigma, block, foundation):
        return equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation)

    def sdof_kernel(self, block, foundation):
        return SdofKernel(damping_stiffness_jit, sdof_record(block, foundation))

    def moment_kernel(self, block, foundation):
        rec = records(block, foundation)
        return MomentKernel(equivalent_coefficients_jit, rec, coefficient_table()[None],
                            np.zeros(rec.size, dtype=np.int64))


PAPER = register(PaperCondensation())
