"""The condensed model's functions for any registered condensation, chosen by name or object.

Each function turns ``condensation`` (a registered name such as ``"paper"`` or ``"cubic"``, or a
:class:`~screening.condensation.Condensation`) into its object once and calls its method; the
physics lives in the condensation's own module (:mod:`~screening.condensation.paper`,
:mod:`~screening.condensation.cubic`).  SI units; ``theta`` [rad].
"""

from __future__ import annotations

import numpy as np

from screening.condensation.registry import get
from screening.condensation.uplift_integrals import gaussian_uplift_integrals

__all__ = ["uplift_threshold", "rocking_damping", "rocking_stiffness", "restoring_moment", "rocking_acceleration",
           "equivalent_coefficients", "equivalent_coefficients_from_moments", "uplift_probability"]


def uplift_threshold(block, foundation, condensation="paper"):
    """Uplift threshold ``theta_ul`` [rad] (eq. 19 for ``"paper"``)."""
    return get(condensation).uplift_threshold(block, foundation)


def rocking_damping(theta, block, foundation, condensation="paper"):
    """Rocking damping ``C(theta)`` [N m s/rad] (eq. 24 for ``"paper"``)."""
    return get(condensation).rocking_damping(theta, block, foundation)


def rocking_stiffness(theta, block, foundation, condensation="paper"):
    """Secant rocking stiffness ``K(theta)`` [N m/rad] (eq. 25 for ``"paper"``)."""
    return get(condensation).rocking_stiffness(theta, block, foundation)


def restoring_moment(theta, block, foundation, condensation="paper"):
    """Restoring moment ``K(theta) theta`` [N m] (eq. 22)."""
    return get(condensation).restoring_moment(theta, block, foundation)


def rocking_acceleration(theta, theta_dot, ground_acceleration, block, foundation, condensation="paper"):
    """``theta''`` [rad/s^2] of the condensed SDOF, eq. (22), for the ground acceleration [m/s^2]:
    ``(m h a_g - C(theta) theta' - K(theta) theta) / m_sdof``."""
    cond = get(condensation)
    force = (block.m * block.h * np.asarray(ground_acceleration, dtype=float)
             - cond.rocking_damping(theta, block, foundation) * theta_dot
             - cond.restoring_moment(theta, block, foundation))
    return force / block.m_sdof


def equivalent_coefficients(sigma_theta, sigma_theta_dot, rho, block, foundation, condensation="paper"):
    """Equivalent damping and stiffness of the Gaussian closure (eq. 31; paper: eqs. 35–36 corrected).

    Parameters
    ----------
    sigma_theta : standard deviation of the rotation [rad], >= 0.
    sigma_theta_dot : standard deviation of the rotational velocity [rad/s], >= 0.
    rho : correlation coefficient of ``theta`` and ``theta'`` [1], in [-1, 1].
    block, foundation : :class:`~screening.model.Block` and :class:`~screening.model.Foundation`.
    condensation : a registered name or a :class:`~screening.condensation.Condensation`.

    Returns
    -------
    (c_eq, k_eq) : [N m s/rad], [N m/rad], broadcast over all array arguments; NaN where a
        moment is not finite (never the finite ``sigma = 0`` values).
    """
    s = np.asarray(sigma_theta, dtype=float)
    cov_over_s = np.asarray(rho, dtype=float) * np.asarray(sigma_theta_dot, dtype=float)
    return _finite_only(get(condensation).equivalent_coefficients, s, cov_over_s, block, foundation)


def _finite_only(coefficients, s, cov_over_s, block, foundation):
    """``coefficients(s, cov_over_s, ...)`` evaluated where both are finite, NaN elsewhere (NaN
    moments must not come back as the coefficients of the block at rest)."""
    bad = ~(np.isfinite(s) & np.isfinite(cov_over_s))
    if not np.any(bad):
        return coefficients(s, cov_over_s, block, foundation)
    c_eq, k_eq = coefficients(np.where(bad, 0.0, s), np.where(bad, 0.0, cov_over_s), block, foundation)
    c_eq, k_eq = np.array(c_eq, dtype=float), np.array(k_eq, dtype=float)
    bad = np.broadcast_to(bad, c_eq.shape)
    c_eq[bad] = np.nan
    k_eq[bad] = np.nan
    return c_eq[()], k_eq[()]


def equivalent_coefficients_from_moments(var_theta, cov_theta_theta_dot, block, foundation, condensation="paper"):
    """``(c_eq [N m s/rad], k_eq [N m/rad])`` from ``var_theta`` [rad^2] and ``cov`` [rad^2/s].

    The form of the moment equations: it needs only ``cov / sigma_theta`` and is finite at zero
    covariance (the start of every Lyapunov integration).
    """
    var_theta = np.asarray(var_theta, dtype=float)
    cov = np.asarray(cov_theta_theta_dot, dtype=float)
    s = np.sqrt(np.maximum(var_theta, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        cov_over_s = np.where(s > 0.0, cov / s, np.where(np.isfinite(cov), 0.0, np.nan))
    return _finite_only(get(condensation).equivalent_coefficients, s, cov_over_s, block, foundation)


def uplift_probability(sigma_theta, block, foundation, condensation="paper"):
    """Uplift occupancy ``P(|theta| > theta_ul) = erfc(theta_ul / (sqrt(2) sigma_theta))`` [1] (eq. 58)."""
    r = np.asarray(sigma_theta, dtype=float) / get(condensation).uplift_threshold(block, foundation)
    return gaussian_uplift_integrals(r)["p_out"]
