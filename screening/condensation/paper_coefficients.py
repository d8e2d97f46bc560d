"""Equivalent linear coefficients of the condensed rocking equation (paper section 2.4).

``c_eq = E[dg/dtheta']`` and ``k_eq = E[dg/dtheta]`` (eq. 31) for
``g = C(theta) theta' + K(theta) theta`` with ``(theta, theta')`` zero-mean Gaussian.

Closed forms (eq. 35 and eq. 36 as corrected in ERRATA.md).  With ``r = sigma_theta /
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

``condensation="cubic"`` (:mod:`screening.condensation.cubic`) has no closed form; the public
functions below then evaluate eq. (31) by quadrature (:mod:`screening.condensation.quadrature`).
"""

from __future__ import annotations

import numpy as np
from scipy import special

from screening.condensation import quadrature as cubic_linearization
from screening.condensation.paper import check_condensation, damping_inner, uplift_threshold

#: Beyond this x = theta_ul^2/(2 sigma_theta^2) every tail is below 1e-300: use the limits.
X_LIMIT = 700.0

_C12 = 2.0**-0.25 / np.sqrt(np.pi)
_C32 = 2.0**-0.75 / np.sqrt(np.pi)


def _upper_gamma(a, x):
    """Non-regularised upper incomplete gamma ``Gamma(a, x)`` for ``a > 0``."""
    return special.gammaincc(a, x) * special.gamma(a)


def gaussian_uplift_integrals(r):
    """The dimensionless Gaussian integrals of the module table at ``r = sigma_theta/theta_ul``.

    Returns a dict of arrays ``p_in, p_out, tail_m12, tail_m32, inner_m2`` and the
    velocity-coupling versions ``tail_m12_r = tail_m12 / r`` and ``tail_m32_r = tail_m32 / r``
    (finite, and zero, at ``r = 0``).  Exact limits are used where ``x > X_LIMIT``.
    """
    r = np.asarray(r, dtype=float)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        x = 0.5 / r**2
        tiny = ~(x <= X_LIMIT)  # includes r = 0 (x = inf)
        rs = np.where(tiny, 1.0, r)
        xs = np.where(tiny, 0.5, x)
        sx = np.sqrt(xs)
        g14 = _upper_gamma(0.25, xs)
        gm14 = 4.0 * (xs**-0.25 * np.exp(-xs) - _upper_gamma(0.75, xs))
        out = {
            "p_in": special.erf(sx),
            "p_out": special.erfc(sx),
            "tail_m12": _C12 * rs**-0.5 * g14,
            "tail_m32": _C32 * rs**-1.5 * gm14,
            "inner_m2": rs**2 * special.gammainc(1.5, xs),
            "tail_m12_r": _C12 * rs**-1.5 * g14,
            "tail_m32_r": _C32 * rs**-2.5 * gm14,
        }
    limits = {"p_in": 1.0, "p_out": 0.0, "tail_m12": 0.0, "tail_m32": 0.0,
              "tail_m12_r": 0.0, "tail_m32_r": 0.0}
    for name, value in limits.items():
        out[name] = np.where(tiny, value, out[name])
    out["inner_m2"] = np.where(tiny, np.where(np.isfinite(r), r, 0.0) ** 2, out["inner_m2"])
    return out


def uplift_probability(sigma_theta, block, foundation, condensation="paper"):
    """Uplift occupancy ``P(|theta| > theta_ul) = erfc(theta_ul / (sqrt(2) sigma_theta))`` [1] (eq. 58).

    ``theta_ul`` of the chosen ``condensation`` (``"paper"``: eq. 19, or ``"cubic"``).
    """
    r = np.asarray(sigma_theta, dtype=float) / uplift_threshold(block, foundation, condensation)
    return gaussian_uplift_integrals(r)["p_out"]


def coefficient_constants(block, foundation):
    """Parameter-only constants of the closed forms (SI): ``C1, K0, mgh, E0, theta_ul``."""
    m, g, b, h, k = block.m, block.g, block.b, block.h, foundation.k
    return {
        "C1": damping_inner(block, foundation),
        "K0": 2.0 / 3.0 * b**3 * k,
        "mgh": m * g * h,
        "E0": (m * g) ** 2 * b / k,
        "theta_ul": uplift_threshold(block, foundation),
    }


def equivalent_coefficients_from_moments(var_theta, cov_theta_theta_dot, block, foundation,
                                          condensation="paper"):
    """``(c_eq [N m s/rad], k_eq [N m/rad])`` from ``var_theta`` [rad^2] and ``cov`` [rad^2/s].

    The form used by the moment equations: it needs only ``cov / sigma_theta`` and is
    finite at zero covariance (the start of every Lyapunov integration).
    ``condensation``: ``"paper"`` (closed forms) or ``"cubic"`` (quadrature).
    """
    check_condensation(condensation)
    var_theta = np.asarray(var_theta, dtype=float)
    cov = np.asarray(cov_theta_theta_dot, dtype=float)
    s = np.sqrt(np.maximum(var_theta, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        cov_over_s = np.where(s > 0.0, cov / s, 0.0)
    if condensation == "cubic":
        return cubic_linearization.equivalent_coefficients(s, cov_over_s, block, foundation)
    return _coefficients(s, cov_over_s, block, foundation)


def equivalent_coefficients(sigma_theta, sigma_theta_dot, rho, block, foundation, condensation="paper"):
    """Closed-form equivalent damping and stiffness (eqs. 35–36, corrected).

    Parameters
    ----------
    sigma_theta : standard deviation of the rotation [rad], >= 0.
    sigma_theta_dot : standard deviation of the rotational velocity [rad/s], >= 0.
    rho : correlation coefficient of ``theta`` and ``theta'`` [1], in [-1, 1].
    block, foundation : :class:`~screening.model.Block` and a foundation model.
    condensation : ``"paper"`` (closed forms, eqs. 35–36) or ``"cubic"`` (eq. 31 by
        quadrature, :mod:`screening.condensation.quadrature`).

    Returns
    -------
    (c_eq, k_eq) : [N m s/rad], [N m/rad], broadcast over all array arguments.
    """
    check_condensation(condensation)
    s = np.asarray(sigma_theta, dtype=float)
    cov_over_s = np.asarray(rho, dtype=float) * np.asarray(sigma_theta_dot, dtype=float)
    if condensation == "cubic":
        return cubic_linearization.equivalent_coefficients(s, cov_over_s, block, foundation)
    return _coefficients(s, cov_over_s, block, foundation)


def _coefficients(s, cov_over_s, block, foundation):
    const = coefficient_constants(block, foundation)
    tu = const["theta_ul"]
    G = gaussian_uplift_integrals(s / tu)
    hunt_crossley = foundation.contact == "hunt_crossley"
    c_shape = G["tail_m12"] if hunt_crossley else G["tail_m32"]
    coupling = 0.5 * G["tail_m12_r"] if hunt_crossley else 1.5 * G["tail_m32_r"]
    c_eq = const["C1"] * (G["p_in"] + c_shape)
    k_eq = (const["K0"] * (G["p_in"] + G["tail_m32"]) - const["mgh"]
            - const["C1"] * coupling * cov_over_s / tu
            + foundation.eps * const["E0"] * (0.5 * G["p_in"] + G["p_out"]
                                              + 0.3 * G["inner_m2"] - 0.2 * G["tail_m12"]))
    c_eq, k_eq = np.broadcast_arrays(c_eq, k_eq)
    return c_eq.copy(), k_eq.copy()
