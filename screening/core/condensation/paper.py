"""The paper's quasi-static condensation ([mitseas2026] section 2.3, eqs. 17–25): ``M theta'' + C theta' + K theta = m h a_g``.

The base-centre indentation is slaved to its linear static value ``z_st(theta)`` (eqs. 17–18) and its
rate to ``z_st'(theta) theta'``, giving the piecewise ``C(theta)`` (eq. 24; its Winkler form derived
the same way) and ``K(theta)`` (eq. 25), switching at ``theta_ul = m g / (2 b^2 k)`` (eq. 19), both
continuous there.  The equivalent coefficients (eqs. 31, 35 and 36 as corrected) are closed forms in
the universal uplift integrals.  The derivations, the closed forms and the corrections:
``docs/method.md#paper-condensation``, ``#winkler-variant``, ``#closed-forms-for-the-paper-condensation``.
:mod:`screening.core.condensation.api` has the same functions for any registered condensation.
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
    """Static uplift angle ``theta_ul = m g / (2 b^2 k)`` [rad] (eq. (19) of [mitseas2026])."""
    return block.m * block.g / (2.0 * block.b**2 * foundation.k)


def static_indentation(theta, block, foundation):
    """Quasi-static base-centre indentation ``z_st(theta)`` [m] of the linear balance.

    Notes
    -----
    ``m g / (2 b k)`` for ``|theta| <= theta_ul`` (eq. (17) of [mitseas2026]), ``sqrt(2 m g |theta| / k) - b |theta|``
    beyond (eq. (18)); continuous at ``theta_ul``.
    """
    theta = np.abs(np.asarray(theta, dtype=float))
    mg, b, k = block.m * block.g, block.b, foundation.k
    inner = mg / (2.0 * b * k) + 0.0 * theta
    outer = np.sqrt(2.0 * mg * theta / k) - b * theta
    return np.where(theta <= uplift_threshold(block, foundation), inner, outer)


def damping_inner_parts(block, foundation):
    """No-uplift rocking damping [N m s/rad] of the law's two basis pressures: ``(rate, indentation)``.

    Notes
    -----
    ``rate = (2/3) w_rate b^3`` (the ``zdot`` pressure, Winkler), ``indentation = w_indentation b^2 m g / (3 k)``
    (the ``z zdot`` pressure, Hunt–Crossley: the no-uplift branch of eq. (24) of [mitseas2026]).
    """
    w_rate, w_ind = foundation.damping_weights
    return 2.0 / 3.0 * w_rate * block.b**3, w_ind * block.b**2 * block.m * block.g / (3.0 * foundation.k)


def damping_inner(block, foundation):
    """No-uplift rocking damping ``C_1`` [N m s/rad], the sum of :func:`damping_inner_parts` (eq. (24) of [mitseas2026])."""
    rate, indentation = damping_inner_parts(block, foundation)
    return rate + indentation


def stiffness_at_rest(block, foundation):
    """Rocking stiffness at rest ``K(0) = (2/3) b^3 k - m g h + eps m^2 g^2 b / (2 k)`` [N m/rad] (eq. (25) of [mitseas2026])."""
    e0 = (block.m * block.g) ** 2 * block.b / foundation.k
    return linear_rocking_stiffness(block, foundation) + 0.5 * foundation.eps * e0


def rocking_damping(theta, block, foundation):
    """Piecewise rocking damping ``C(theta)`` [N m s/rad] of the paper's condensation.

    Notes
    -----
    ``C_1`` (:func:`damping_inner`) for ``|theta| <= theta_ul``; beyond,
    ``w_rate (2 m g / k)^(3/2) |theta|^(-3/2) / 12 + w_indentation b (2 m g / k)^(3/2) |theta|^(-1/2) / 12``:
    eq. (24) of [mitseas2026] for Hunt–Crossley and its Winkler form.
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
    """Piecewise secant rocking stiffness ``K(theta)`` [N m/rad] (restoring moment ``K theta``), the same for both laws.

    Notes
    -----
    Eq. (25) of [mitseas2026]: ``(2/3) b^3 k - m g h + eps (m^2 g^2 b / (2 k) + (2/5) k b^5 theta^2)`` for
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
    """Restoring moment ``K(theta) theta`` [N m], odd in ``theta`` (eq. (22) of [mitseas2026])."""
    theta = np.asarray(theta, dtype=float)
    return rocking_stiffness(theta, block, foundation) * theta


#: Per-point parameters of :func:`damping_stiffness_jit` (SI units): ``C = C1`` inside the threshold,
#: ``C2_rate |theta|^-3/2 + C2_indentation |theta|^-1/2`` outside (the law's two basis pressures); ``K = K1_0 + K1_2 theta^2`` inside,
#: ``MGB/|theta| - K2_32 |theta|^-3/2 - K2_12 |theta|^-1/2 + K2_0`` outside (eqs. 24–25).
SDOF_RECORD = np.dtype([("theta_ul", "f8"), ("C1", "f8"), ("C2_rate", "f8"), ("C2_indentation", "f8"), ("K1_0", "f8"),
                        ("K1_2", "f8"), ("MGB", "f8"), ("K2_32", "f8"), ("K2_12", "f8"), ("K2_0", "f8")])


def sdof_record(block, foundation):
    """The 1-element :data:`SDOF_RECORD` [SI] of scalar model objects: the parameter-only factors of eqs. (24)-(25) of [mitseas2026]."""
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
    """Compiled twin of :func:`rocking_damping` and :func:`rocking_stiffness`: ``(C, K)`` from the record ``p``."""
    a = abs(theta)
    if a <= p.theta_ul:
        return p.C1, p.K1_0 + p.K1_2 * theta * theta
    r = 1.0 / math.sqrt(a)
    stiffness = p.MGB * r * r - p.K2_32 * r * r * r - p.K2_12 * r + p.K2_0
    return p.C2_rate * r * r * r + p.C2_indentation * r, stiffness


# ---------------------------------------------------------------- equivalent linear coefficients (section 2.4)

def coefficient_constants(block, foundation):
    """The moment-free factors of eqs. (35)-(36) of [mitseas2026], a dict [SI].

    Notes
    -----
    ``C1`` [N m s/rad] (and its parts ``C1_rate``, ``C1_indentation``), ``K0 = (2/3) b^3 k`` [N m/rad],
    ``mgh`` [N m], ``E0 = (m g)^2 b / k`` [N m] and ``theta_ul`` [rad].
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
    """Closed-form equivalent damping ``c_eq`` [N m s/rad] and stiffness ``k_eq`` [N m/rad] of the paper's condensation.

    Notes
    -----
    Eqs. (35)-(36) of [mitseas2026] as corrected (``docs/method.md#eq-36-equivalent-stiffness``): the Gaussian
    expectations of eq. (31) of ``C``, ``K`` through the uplift integrals of
    :mod:`~screening.core.condensation.uplift_integrals`, from ``sigma_theta`` [rad] and
    ``cov_over_sigma = rho sigma_theta_dot`` [rad s-1].
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
    """One :data:`RECORD` [SI] per point (flat or scalar fields): :func:`coefficient_constants` for :func:`equivalent_coefficients_jit`."""
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
    """Compiled twin of :func:`equivalent_coefficients` from the moments ``var_theta`` [rad2], ``cov`` [rad2 s-1] and the uplift table."""
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
