"""The condensed model's functions for any registered condensation, chosen by name or object.

Each function turns ``condensation`` (a registered name such as ``"paper"`` or ``"cubic"``, or a
:class:`~screening.core.condensation.Condensation`) into its object once and calls its method; the
physics lives in the condensation's own module (:mod:`~screening.core.condensation.paper`,
:mod:`~screening.core.condensation.cubic`).  SI units; ``theta`` [rad].
"""

from __future__ import annotations

import numpy as np

from screening.core.condensation.registry import DEFAULT_CONDENSATION, get
from screening.core.condensation.uplift_integrals import gaussian_uplift_integrals

__all__ = ["uplift_threshold", "rocking_damping", "rocking_stiffness", "restoring_moment", "rocking_acceleration",
           "equivalent_coefficients", "equivalent_coefficients_from_moments", "uplift_probability"]


def uplift_threshold(block, foundation, condensation=DEFAULT_CONDENSATION):
    """Uplift threshold ``theta_ul`` [rad]: the rotation at which the lifted edge leaves the bed.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m]); fields may be arrays (broadcast).
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); fields may be arrays (broadcast).
    condensation : str or screening.core.condensation.Condensation, optional
        A registered name (``"paper"``, ``"cubic"``, ``"virtual_work"``) or an object; default
        :data:`screening.core.condensation.DEFAULT_CONDENSATION`.

    Returns
    -------
    numpy.ndarray or float
        ``theta_ul`` [rad], broadcast over the model's fields.

    Notes
    -----
    ``"paper"``: ``theta_ul = m g / (2 b^2 k)``, eq. (19) in [1]; ``"cubic"``: the exact angle with the
    bed's cubic term (:func:`screening.core.physics.contact.exact_uplift_angle`).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> f"{float(uplift_threshold(block, bed)):.4e}"
    '1.2012e-03'
    """
    return get(condensation).uplift_threshold(block, foundation)


def rocking_damping(theta, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Rocking damping ``C(theta)`` [N m s/rad] of the condensed single-degree-of-freedom model.

    Parameters
    ----------
    theta, block, foundation, condensation
        The rotation [rad] and the model, as in :func:`uplift_threshold`.

    Returns
    -------
    numpy.ndarray or float
        ``C(theta)`` [N m s/rad], broadcast over ``theta`` and the model's fields.

    Notes
    -----
    ``"paper"``: ``C = lam b^2 m g / (3 k)`` for ``|theta| <= theta_ul`` and
    ``(lam b / 12) (2 m g / k)^(3/2) |theta|^(-1/2)`` beyond, eq. (24) in [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    The paper's block and bed, at rest and in uplift:

    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> [f"{c:.4g}" for c in rocking_damping([0.0, 0.01], block, bed, condensation="paper")]
    ['1.076', '0.3728']
    """
    return get(condensation).rocking_damping(theta, block, foundation)


def rocking_stiffness(theta, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Secant rocking stiffness ``K(theta)`` [N m/rad]: the restoring moment is ``K(theta) theta``.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    block, foundation, condensation
        As in :func:`uplift_threshold`.

    Returns
    -------
    numpy.ndarray or float
        ``K(theta)`` [N m/rad], broadcast over ``theta`` and the model's fields.

    Notes
    -----
    ``"paper"``: ``K = (2/3) b^3 k - m g h + eps (m^2 g^2 b / (2 k) + (2/5) k b^5 theta^2)`` in full
    contact and ``m g (b/|theta| - sqrt(2 m g k) |theta|^(-3/2) / (3 k) - h) + eps (...)`` in uplift,
    eq. (25) in [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    The secant stiffness falls once the block lifts off:

    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> [f"{k:.4g}" for k in rocking_stiffness([0.0, 0.01], block, bed)]
    ['808.2', '211']
    """
    return get(condensation).rocking_stiffness(theta, block, foundation)


def restoring_moment(theta, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Like :func:`rocking_stiffness` times ``theta``: the restoring moment ``K(theta) theta`` [N m], odd in
    ``theta``, the conservative term of eq. (22) in [mitseas2026]."""
    return get(condensation).restoring_moment(theta, block, foundation)


def rocking_acceleration(theta, theta_dot, ground_acceleration, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Rotational acceleration ``theta''`` [rad s-2] of the condensed model at the rotation ``theta`` [rad], its
    rate ``theta_dot`` [rad s-1] and the ground acceleration ``a_g`` [m s-2] (the model as in :func:`uplift_threshold`).

    Notes
    -----
    Eq. (22) in [mitseas2026] solved for the acceleration: ``theta'' = (m h a_g - C(theta) theta' - K(theta) theta)
    / m_sdof`` with ``m_sdof = I_cm + m h^2`` (eq. (23)).

    """
    cond = get(condensation)
    force = (block.m * block.h * np.asarray(ground_acceleration, dtype=float)
             - cond.rocking_damping(theta, block, foundation) * theta_dot
             - cond.restoring_moment(theta, block, foundation))
    return force / block.m_sdof


def equivalent_coefficients(sigma_theta, sigma_theta_dot, rho, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Equivalent damping and stiffness of the Gaussian closure of the condensed model.

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    sigma_theta_dot : array_like
        Standard deviation of the rotation rate [rad s-1], >= 0.
    rho : array_like
        Correlation coefficient of ``theta`` and ``theta'`` [1], in [-1, 1].
    block, foundation, condensation
        The model, as in :func:`uplift_threshold`.

    Returns
    -------
    c_eq : numpy.ndarray or float
        Equivalent damping [N m s/rad], broadcast over all array arguments; NaN where a moment is
        not finite (never the finite ``sigma = 0`` values).
    k_eq : numpy.ndarray or float
        Equivalent stiffness [N m/rad], same shape.

    Notes
    -----
    ``c_eq = E[dg/dtheta']``, ``k_eq = E[dg/dtheta]`` for ``g = C(theta) theta' + K(theta) theta`` over
    the zero-mean Gaussian density of ``(theta, theta')``, eq. (31) in [1]; for ``"paper"`` the closed
    forms eqs. (35)-(36) in [1], with the corrections of ``docs/method.md``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    A small rotation keeps the block in contact, where ``c_eq = C(0)`` and ``k_eq = K(0)``:

    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> c_eq, k_eq = equivalent_coefficients(1e-4, 1e-2, 0.0, block, bed)
    >>> f"{float(c_eq):.4g} {float(k_eq):.4g}"
    '1.076 808.2'
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


def equivalent_coefficients_from_moments(var_theta, cov_theta_theta_dot, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Like :func:`equivalent_coefficients`, from the moments the Lyapunov equations carry: the variance
    ``var_theta`` [rad2] and the covariance ``cov_theta_theta_dot`` [rad2 s-1].

    It depends on ``sigma_theta`` and ``cov / sigma_theta = rho sigma_theta_dot`` only, and is finite at zero
    covariance (the start of every integration of eq. (45) in [mitseas2026]); NaN where a moment is not finite.
    """
    var_theta = np.asarray(var_theta, dtype=float)
    cov = np.asarray(cov_theta_theta_dot, dtype=float)
    s = np.sqrt(np.maximum(var_theta, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        cov_over_s = np.where(s > 0.0, cov / s, np.where(np.isfinite(cov), 0.0, np.nan))
    return _finite_only(get(condensation).equivalent_coefficients, s, cov_over_s, block, foundation)


def uplift_probability(sigma_theta, block, foundation, condensation=DEFAULT_CONDENSATION):
    """Uplift occupancy ``P(|theta| > theta_ul)`` [1] of a zero-mean Gaussian rotation.

    Parameters
    ----------
    sigma_theta : array_like
        Standard deviation of the rotation [rad], >= 0.
    block, foundation, condensation
        The model and its condensation, as in :func:`uplift_threshold`.

    Returns
    -------
    numpy.ndarray or float
        The probability [1] that the block is in uplift, broadcast over all array arguments.

    Notes
    -----
    ``P_uplift = erfc(theta_ul / (sqrt(2) sigma_theta))``, eq. (58) in [1]; the same as
    :func:`screening.kernels.moment_kernels.uplift_occupancy` of the variance.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    At ``sigma_theta = theta_ul`` the block is in uplift a third of the time:

    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> f"{float(uplift_probability(1.2012e-3, block, bed)):.4f}"
    '0.3173'
    """
    r = np.asarray(sigma_theta, dtype=float) / get(condensation).uplift_threshold(block, foundation)
    return gaussian_uplift_integrals(r)["p_out"]
