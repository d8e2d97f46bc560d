"""Equivalent linear coefficients of the condensed rocking equation (paper section 2.4).

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
"""

from __future__ import annotations


import numba
import numpy as np

from screening.condensation.paper import damping_inner_parts, uplift_threshold
from screening.condensation.uplift_integrals import gaussian_uplift_integrals, uplift_integrals_q
from screening.kernels.signatures import FMA, moment_coefficients_signature

def coefficient_constants(block, foundation):
    """Parameter-only constants of the closed forms (SI): ``C1`` (and its parts ``C1_rate``,
    ``C1_indentation`` of the law's two basis pressures), ``K0, mgh, E0, theta_ul``."""
    m, g, b, h, k = block.m, block.g, block.b, block.h, foundation.k
    c1_rate, c1_indentation = damping_inner_parts(block, foundation)
    return {
        "C1": c1_rate + c1_indentation,
        "C1_rate": c1_rate,
        "C1_indentation": c1_indentation,
        "K0": 2.0 / 3.0 * b**3 * k,
        "mgh": m * g * h,
        "E0": (m * g) ** 2 * b / k,
        "theta_ul": uplift_threshold(block, foundation),
    }


def equivalent_coefficients(sigma_theta, cov_over_sigma, block, foundation):
    """Closed-form ``(c_eq [N m s/rad], k_eq [N m/rad])`` of the paper's condensation (eqs. 35–36 corrected).

    ``sigma_theta`` [rad] >= 0 and ``cov_over_sigma = cov(theta, theta') / sigma_theta`` [rad/s]
    (``rho sigma_theta_dot``); broadcast with array model parameters.  The module docstring
    gives the formulas; :func:`equivalent_coefficients_jit` is the compiled twin the moment
    solver uses (same formulas, the Gaussian integrals read from :mod:`~screening.condensation.uplift_integrals`).
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
    """One :data:`RECORD` per point of the (flat, 1-d) model fields."""
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
    """Compiled twin of :func:`equivalent_coefficients` from the moments ``var_theta`` [rad2], ``cov`` [rad2/s].

    ``p``: a :data:`RECORD`; ``table``: the universal table of
    :func:`screening.condensation.uplift_integrals.coefficient_table`.  Finite at ``var_theta = 0``.
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
