"""Bed parameters from materials: the ``k``, ``lam`` or ``c`` and ``eps`` of a :class:`~screening.core.model.Foundation`.

For a layer of thickness ``t`` [m] under a base of out-of-plane depth ``d`` [m], ``k = E_c d / t``
[N m-2] with ``E_c`` the layer's confined modulus (:func:`oedometric_modulus`, or a pad's with its shape
factor); ``eps`` [m-2] from a backbone test (:func:`fit_backbone`); the damping from a coefficient of
restitution or a vertical damping ratio.  :func:`bed_summary` gives what an engineer checks (``screening
info`` prints it).  The contact law: ``docs/method.md#contact-law``; typical ranges and references:
``docs/beds.md``.
"""

from __future__ import annotations

import math

import numpy as np
from screening.core import condensation as condensations
from screening.core.physics.contact import (exact_uplift_angle, linear_rocking_stiffness, rest_indentation,
                                            vertical_damping_ratio)
from screening.solvers.synthesis import rocking_frequency, vertical_frequency

__all__ = ["TYPICAL", "oedometric_modulus", "pad_compression_modulus", "layer_stiffness", "hunt_crossley_lambda",
           "c_from_vertical_damping", "lam_from_vertical_damping", "restitution_from_damping_ratio",
           "fit_backbone", "bed_summary", "format_bed_summary"]

#: Indicative material ranges (SI), see docs/beds.md for the sources and caveats.
TYPICAL = {
    "lime mortar": {"E": (0.5e9, 5e9), "nu": (0.15, 0.25), "zeta_v": (0.02, 0.05)},
    "cement mortar": {"E": (5e9, 25e9), "nu": (0.15, 0.25), "zeta_v": (0.02, 0.05)},
    "elastomeric pad (natural rubber / neoprene)": {"E": (1.5e6, 6e6), "nu": (0.49, 0.5), "zeta_v": (0.02, 0.15)},
    "soft clay": {"E": (2e6, 15e6), "nu": (0.4, 0.5), "zeta_v": (0.02, 0.10)},
    "stiff clay": {"E": (10e6, 100e6), "nu": (0.2, 0.4), "zeta_v": (0.02, 0.10)},
    "loose sand": {"E": (10e6, 25e6), "nu": (0.2, 0.4), "zeta_v": (0.02, 0.10)},
    "dense sand": {"E": (50e6, 80e6), "nu": (0.3, 0.45), "zeta_v": (0.02, 0.10)},
    "dense sand and gravel": {"E": (100e6, 200e6), "nu": (0.15, 0.35), "zeta_v": (0.02, 0.10)},
    "timber (across the grain)": {"E": (0.23e9, 1.6e9), "nu": (0.3, 0.45), "zeta_v": (0.01, 0.05)},
}


def oedometric_modulus(E, nu):
    """Constrained (oedometric) modulus of a thin bonded layer [Pa].

    Parameters
    ----------
    E : array_like
        Young's modulus of the layer [Pa].
    nu : array_like
        Poisson's ratio [1], in (-1, 0.5).

    Returns
    -------
    numpy.ndarray
        ``E_c = E (1 - nu) / ((1 + nu)(1 - 2 nu))`` [Pa].

    Raises
    ------
    ValueError
        Naming ``nu`` when it is outside (-1, 0.5).

    Notes
    -----
    The modulus of a layer compressed without lateral strain; the bed stiffness is then
    :func:`layer_stiffness` ``k = E_c d / t``, the ``k`` of the contact law eq. (3) in [1].

    References
    ----------
    [1] [mitseas2026]; [2] J. E. Bowles, Foundation Analysis and Design, 5th ed., McGraw-Hill (1996).

    Examples
    --------
    >>> f"{float(oedometric_modulus(1e9, 0.2)):.4g}"
    '1.111e+09'
    """
    E, nu = np.asarray(E, dtype=float), np.asarray(nu, dtype=float)
    if np.any(nu >= 0.5) or np.any(nu <= -1.0):
        raise ValueError(f"parameter 'nu' must be in (-1, 0.5) for a confined layer (got {nu!r})")
    return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def pad_compression_modulus(E, shape_factor, kappa=0.75, bulk_modulus=2.0e9):
    """Compression modulus of a bonded elastomeric pad [Pa], in series with the bulk modulus.

    Parameters
    ----------
    E : array_like
        Young's modulus of the rubber [Pa].
    shape_factor : array_like
        Loaded area over the free bulging area ``S`` [1].
    kappa : float, optional
        Hardness factor [1], 0.5 to 1 (default 0.75).
    bulk_modulus : float, optional
        Bulk modulus of the rubber ``K`` [Pa] (default 2e9).

    Returns
    -------
    numpy.ndarray
        ``E_c`` [Pa] with ``1/E_c = 1/(E (1 + 2 kappa S^2)) + 1/K``.

    Notes
    -----
    The confined modulus of [1]; ``k = E_c d / t`` (:func:`layer_stiffness`) is the bed's ``k``.

    References
    ----------
    [1] A. N. Gent and P. B. Lindley, "The compression of bonded rubber blocks", Proc. Inst. Mech. Eng. 173
    (1959) 111-122.

    Examples
    --------
    >>> f"{float(pad_compression_modulus(3e6, 5.0)):.4g}"
    '1.092e+08'
    """
    ec = np.asarray(E, dtype=float) * (1.0 + 2.0 * kappa * np.asarray(shape_factor, dtype=float) ** 2)
    return 1.0 / (1.0 / ec + 1.0 / bulk_modulus)


def layer_stiffness(modulus, thickness, depth):
    """Distributed stiffness ``k`` [N m-2] of a confined layer under the base.

    Parameters
    ----------
    modulus : array_like
        Confined modulus ``E_c`` [Pa] (:func:`oedometric_modulus`, :func:`pad_compression_modulus`).
    thickness : array_like
        Layer thickness ``t`` [m].
    depth : array_like
        Out-of-plane depth of the base ``d`` [m].

    Returns
    -------
    numpy.ndarray
        ``k = E_c d / t`` [N m-2], the stiffness per unit base length and unit indentation.

    Notes
    -----
    Each strip of the base compresses the layer like a column; ``k`` is the stiffness of the
    distributed contact law, eq. (3) in [1].

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    A 1 cm mortar joint (``E_c`` = 1.111 GPa) under a base 26 cm deep:

    >>> f"{float(layer_stiffness(1.111e9, 0.01, 0.26)):.4g}"
    '2.889e+10'
    """
    return np.asarray(modulus, dtype=float) * np.asarray(depth, dtype=float) / np.asarray(thickness, dtype=float)


def hunt_crossley_lambda(k, restitution, impact_velocity, model="hunt_crossley"):
    """Hunt–Crossley damping ``lam`` [N s m-3] from a coefficient of restitution.

    Parameters
    ----------
    k : array_like
        Bed stiffness [N m-2].
    restitution : array_like
        Coefficient of restitution ``e`` [1], in (0, 1].
    impact_velocity : array_like
        Impact velocity ``v`` at which ``e`` was measured [m s-1].
    model : {"hunt_crossley", "lankarani_nikravesh", "flores"}, optional
        The relation between ``e`` and the damping (default ``"hunt_crossley"``).

    Returns
    -------
    numpy.ndarray
        ``lam = alpha k`` [N s m-3].

    Raises
    ------
    ValueError
        Naming ``restitution`` or ``model`` when out of range.

    Notes
    -----
    ``alpha`` [s m-1] is ``3 (1 - e) / (2 v)`` [2] (good for ``e`` near 1), ``3 (1 - e^2) / (4 v)`` [3] or
    ``8 (1 - e) / (5 e v)`` [4] (also for low ``e``); ``lam`` is the damping of the law eq. (3) in [1].

    References
    ----------
    [1] [mitseas2026]; [2] K. H. Hunt and F. R. E. Crossley, "Coefficient of restitution interpreted as
    damping in vibroimpact", J. Appl. Mech. 42 (1975) 440-445; [3] H. M. Lankarani and P. E. Nikravesh, "A
    contact force model with hysteresis damping for impact analysis of multibody systems", J. Mech. Des. 112
    (1990) 369-376; [4] P. Flores, M. Machado, M. T. Silva and J. M. Martins, "On the continuous contact
    force models for soft materials in multibody dynamics", Multibody Syst. Dyn. 25 (2011) 357-375.

    Examples
    --------
    >>> f"{float(hunt_crossley_lambda(2.89e7, 0.8, 0.1)):.4g}"
    '8.67e+07'
    """
    e = np.asarray(restitution, dtype=float)
    v = np.asarray(impact_velocity, dtype=float)
    if np.any((e <= 0.0) | (e > 1.0)):
        raise ValueError(f"parameter 'restitution' must be in (0, 1] (got {restitution!r})")
    if model == "hunt_crossley":
        alpha = 1.5 * (1.0 - e) / v
    elif model == "lankarani_nikravesh":
        alpha = 0.75 * (1.0 - e * e) / v
    elif model == "flores":
        alpha = 1.6 * (1.0 - e) / (e * v)
    else:
        raise ValueError(f"parameter 'model' must be 'hunt_crossley', 'lankarani_nikravesh' or 'flores' (got {model!r})")
    return alpha * np.asarray(k, dtype=float)


def c_from_vertical_damping(k, m, b, zeta_v):
    """Winkler dashpot ``c`` [N s m-2] giving a vertical damping ratio of the block on its bed.

    Parameters
    ----------
    k, m, b : array_like
        Bed stiffness [N m-2], block mass [kg] and half-width of the base [m].
    zeta_v : array_like
        Vertical damping ratio [1].

    Returns
    -------
    numpy.ndarray or float
        ``c = zeta_v sqrt(2 b k m) / b`` [N s m-2].

    Notes
    -----
    The block bouncing on the bed in full contact is an oscillator of stiffness ``2 b k`` and damping
    ``2 b c`` (eq. (9) in [1] with the Winkler law): ``2 b c = 2 zeta_v sqrt(2 b k m)``.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    The paper's block at 5 % vertical damping:

    >>> f"{float(c_from_vertical_damping(2.89e7, 8.67, 0.035, 0.05)):.4g}"
    '5983'
    """
    return zeta_v * np.sqrt(2.0 * b * k * m) / b


def lam_from_vertical_damping(k, m, b, zeta_v, g=9.81):
    """Hunt–Crossley ``lam`` [N s m-3] giving a vertical damping ratio about the static indentation.

    Parameters
    ----------
    k, m, b, zeta_v
        As in :func:`c_from_vertical_damping`.
    g : float, optional
        Gravitational acceleration [m s-2] (default 9.81).

    Returns
    -------
    numpy.ndarray or float
        ``lam = c / z_st`` [N s m-3] with ``c`` of :func:`c_from_vertical_damping`.

    Notes
    -----
    The Hunt–Crossley dashpot ``lam z`` per unit length is ``lam z_st`` about the static indentation
    ``z_st = m g / (2 b k)`` (eq. (17) in [1]).

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    The same, as a Hunt-Crossley ``lam``:

    >>> f"{float(lam_from_vertical_damping(2.89e7, 8.67, 0.035, 0.05)):.4g}"
    '1.423e+08'
    """
    z_st = m * g / (2.0 * b * k)
    return c_from_vertical_damping(k, m, b, zeta_v) / z_st


def restitution_from_damping_ratio(zeta):
    """Coefficient of restitution [1] of a linear spring-dashpot contact.

    Parameters
    ----------
    zeta : array_like
        Damping ratio of the contact [1], in [0, 1).

    Returns
    -------
    numpy.ndarray
        ``e = exp(-pi zeta / sqrt(1 - zeta^2))`` [1].

    Notes
    -----
    The velocity ratio after and before a half period of the damped oscillation; with
    :func:`hunt_crossley_lambda` it turns a damping ratio into the ``lam`` of eq. (3) in [1].

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    A contact at 5 % damping returns 85 % of the approach velocity:

    >>> f"{float(restitution_from_damping_ratio(0.05)):.4f}"
    '0.8545'
    """
    z = np.asarray(zeta, dtype=float)
    return np.exp(-np.pi * z / np.sqrt(1.0 - z * z))


def fit_backbone(indentation, force_per_length, k=None):
    """Bed stiffness and cubic parameter fitted to a backbone (force-indentation) test.

    Parameters
    ----------
    indentation : array_like
        Indentations ``z`` [m] of the test.
    force_per_length : array_like
        Force per unit base length ``F`` [N m-1] at each indentation.
    k : float, optional
        Bed stiffness [N m-2] to hold fixed (default: fitted too).

    Returns
    -------
    k : float
        Bed stiffness [N m-2].
    eps : float
        Cubic stiffness parameter [m-2].

    Raises
    ------
    ValueError
        With fewer than two points.

    Notes
    -----
    Least squares of ``F = k z (1 + eps z^2)``, the restoring part of the contact law eq. (3) in [1].

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> z = np.linspace(1e-5, 1e-4, 5)
    >>> k, eps = fit_backbone(z, 2.89e7 * z * (1 + 6e7 * z**2))
    >>> f"{k:.4g} {eps:.4g}"
    '2.89e+07 6e+07'
    """
    z = np.asarray(indentation, dtype=float).ravel()
    f = np.asarray(force_per_length, dtype=float).ravel()
    if z.size < 2:
        raise ValueError("a backbone fit needs at least two points")
    if k is None:
        coef, *_ = np.linalg.lstsq(np.column_stack([z, z**3]), f, rcond=None)
        return float(coef[0]), float(coef[1] / coef[0])
    r = f - k * z
    return float(k), float(np.dot(z**3, r) / (k * np.dot(z**3, z**3)))


def bed_summary(block, foundation):
    """Quantities an engineer checks of a block on its bed.

    Parameters
    ----------
    block, foundation : screening.core.model.Block, screening.core.model.Foundation
        The block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]) and its bed (``k`` [N m-2], ``eps`` [m-2],
        its damping), scalar fields.

    Returns
    -------
    dict
        ``static_indentation`` [m] (exact, cubic term included), ``uplift_angle`` [rad] (the paper's
        ``m g / (2 b^2 k)``) and ``uplift_angle_exact`` [rad] (:func:`screening.core.physics.contact.exact_uplift_angle`,
        NaN where it does not exist), ``slenderness`` [rad], ``rocking_frequency`` and ``vertical_frequency``
        [rad s-1] (small amplitude, full contact), ``vertical_damping_ratio`` and ``rocking_damping_ratio``
        [1] (full contact, at the static indentation).

    Notes
    -----
    Static indentation from eq. (13) in [1] at rest, uplift angle eq. (19), rocking stiffness ``K(0)``
    eq. (25) at ``eps = 0``.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> s = bed_summary(block, bed)
    >>> f"{s['uplift_angle']:.4e} {s['rocking_frequency']:.4g}"
    '1.2012e-03 39.68'
    """
    b = float(block.b)
    z_st = rest_indentation(block, foundation)
    wv = vertical_frequency(block, foundation)
    wr = rocking_frequency(block, foundation)
    w_rate, w_ind = (float(w) for w in foundation.damping_weights)
    damping_at_rest = w_rate + w_ind * z_st              # zdot (w_rate + w_ind z) at z = z_st
    c_r = 2.0 / 3.0 * damping_at_rest * b**3
    k_r = float(linear_rocking_stiffness(block, foundation))
    exact = float(exact_uplift_angle(block, foundation))      # NaN where it does not exist
    return {
        "static_indentation": z_st,
        "uplift_angle": float(condensations.get("paper").uplift_threshold(block, foundation)),
        "uplift_angle_exact": exact,
        "slenderness": float(block.slenderness),
        "rocking_frequency": wr,
        "vertical_frequency": wv,
        "vertical_damping_ratio": float(vertical_damping_ratio(block, foundation, z_st)),
        "rocking_damping_ratio": c_r / (2.0 * math.sqrt(k_r * float(block.m_sdof))) if k_r > 0 else math.nan,
    }


def format_bed_summary(summary):
    """The :func:`bed_summary` as text: one line per quantity, with units and engineering units.

    Parameters
    ----------
    summary : dict
        The result of :func:`bed_summary` (SI units).

    Returns
    -------
    str
        Lines joined by newlines (no final newline), as ``screening info`` prints them.

    Notes
    -----
    The uplift angle is printed as the paper's (eq. (19) in [1]) and, where it exists, the exact one.

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    The line of the uplift angle:

    >>> from screening import Block, Foundation
    >>> block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    >>> format_bed_summary(bed_summary(block, bed)).splitlines()[1]
    'uplift angle        0.001201 rad (paper m g/(2 b^2 k)), 0.001201 rad exact'
    """
    s = summary
    return "\n".join([
        f"static indentation  {s['static_indentation'] * 1e3:.4g} mm",
        f"uplift angle        {s['uplift_angle']:.4g} rad (paper m g/(2 b^2 k))"
        + (f", {s['uplift_angle_exact']:.4g} rad exact" if np.isfinite(s['uplift_angle_exact']) else ""),
        f"slenderness         {s['slenderness']:.4g} rad ({math.degrees(s['slenderness']):.3g} deg); "
        f"uplift / slenderness {s['uplift_angle'] / s['slenderness']:.3g}",
        f"rocking frequency   {s['rocking_frequency']:.4g} rad/s ({s['rocking_frequency'] / (2 * math.pi):.3g} Hz)",
        f"vertical frequency  {s['vertical_frequency']:.4g} rad/s ({s['vertical_frequency'] / (2 * math.pi):.3g} Hz)",
        f"damping ratios      vertical {s['vertical_damping_ratio']:.3g}, rocking {s['rocking_damping_ratio']:.3g} "
        "(full contact, at the static indentation)",
    ])
