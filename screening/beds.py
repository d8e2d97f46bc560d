"""Bed parameters from materials: the ``k``, ``lam`` or ``c`` and ``eps`` of a :class:`~screening.model.Foundation`.

The contact law is a force per unit base length (docs/method.md, "Contact law"):
``F_n = k z + eps k z^3 + lam z z'`` (Hunt-Crossley) or ``k z + eps k z^3 + c z'`` (Winkler).
For a layer of thickness ``t`` [m] under a base of out-of-plane depth ``d`` [m] (the block's
dimension perpendicular to the rocking plane), each strip of the base compresses the layer
like a column, so

    k = E_c d / t                                   [N m-2]

with ``E_c`` the layer's modulus in confined compression: the oedometric modulus
``E (1 - nu) / ((1 + nu)(1 - 2 nu))`` for a thin bonded layer of mortar or soil, or for an
elastomeric pad ``E (1 + 2 kappa S^2)`` (Gent & Lindley 1959; ``S`` the shape factor, loaded
area over the free bulging area, ``kappa`` 0.5..1 from the rubber hardness) capped by the bulk
modulus.  ``eps`` [m-2] comes from a backbone (force-indentation) test by
:func:`fit_backbone`; the damping from a coefficient of restitution (:func:`hunt_crossley_lambda`)
or a vertical damping ratio (:func:`lam_from_vertical_damping`, :func:`c_from_vertical_damping`).

:func:`bed_summary` gives the quantities an engineer checks (static indentation, uplift angle,
slenderness, rocking and vertical frequencies, vertical damping ratio); ``screening info`` prints
them.  Typical ranges and references: docs/beds.md.
"""

from __future__ import annotations

import math

import numpy as np

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
}


def oedometric_modulus(E, nu):
    """Constrained (oedometric) modulus ``E (1 - nu) / ((1 + nu)(1 - 2 nu))`` [Pa]; ``nu < 0.5``."""
    E, nu = np.asarray(E, dtype=float), np.asarray(nu, dtype=float)
    if np.any(nu >= 0.5) or np.any(nu <= -1.0):
        raise ValueError(f"parameter 'nu' must be in (-1, 0.5) for a confined layer (got {nu!r})")
    return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def pad_compression_modulus(E, shape_factor, kappa=0.75, bulk_modulus=2.0e9):
    """Compression modulus of a bonded elastomeric pad ``E (1 + 2 kappa S^2)`` [Pa] (Gent & Lindley 1959),
    in series with the bulk modulus ``K`` (``1/E_c = 1/(E (1 + 2 kappa S^2)) + 1/K``)."""
    ec = np.asarray(E, dtype=float) * (1.0 + 2.0 * kappa * np.asarray(shape_factor, dtype=float) ** 2)
    return 1.0 / (1.0 / ec + 1.0 / bulk_modulus)


def layer_stiffness(modulus, thickness, depth):
    """Distributed stiffness ``k = E_c d / t`` [N m-2] of a layer of modulus ``E_c`` [Pa] (confined: see
    :func:`oedometric_modulus`, :func:`pad_compression_modulus`), thickness ``t`` [m] and out-of-plane depth ``d`` [m]."""
    return np.asarray(modulus, dtype=float) * np.asarray(depth, dtype=float) / np.asarray(thickness, dtype=float)


def hunt_crossley_lambda(k, restitution, impact_velocity, model="hunt_crossley"):
    """``lam`` [N s m-4] of the law ``k z + lam z z'`` from a coefficient of restitution ``e`` measured at
    the impact velocity ``v`` [m/s]: ``lam = alpha k`` with ``alpha`` [s m-1]

    * ``"hunt_crossley"``: ``3 (1 - e) / (2 v)`` (Hunt & Crossley 1975; good for ``e`` near 1);
    * ``"lankarani_nikravesh"``: ``3 (1 - e^2) / (4 v)`` (Lankarani & Nikravesh 1990);
    * ``"flores"``: ``8 (1 - e) / (5 e v)`` (Flores et al. 2011; also for low ``e``).
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
    """Winkler dashpot ``c`` [N s m-2] giving the vertical damping ratio ``zeta_v`` of the block (mass ``m``,
    half-width ``b``) bouncing on the bed: ``2 b c = 2 zeta_v sqrt(2 b k m)``."""
    return zeta_v * np.sqrt(2.0 * b * k * m) / b


def lam_from_vertical_damping(k, m, b, zeta_v, g=9.81):
    """Hunt-Crossley ``lam`` [N s m-4] giving the vertical damping ratio ``zeta_v`` about the static
    indentation ``z_st = m g / (2 b k)`` (equivalent dashpot ``lam z_st`` per unit length)."""
    z_st = m * g / (2.0 * b * k)
    return c_from_vertical_damping(k, m, b, zeta_v) / z_st


def restitution_from_damping_ratio(zeta):
    """Coefficient of restitution of a linear spring-dashpot contact, ``exp(-pi zeta / sqrt(1 - zeta^2))``."""
    z = np.asarray(zeta, dtype=float)
    return np.exp(-np.pi * z / np.sqrt(1.0 - z * z))


def fit_backbone(indentation, force_per_length, k=None):
    """``(k [N m-2], eps [m-2])`` of ``F = k z (1 + eps z^2)`` fitted to a backbone test (force per unit base
    length [N/m] against indentation [m]) by least squares; ``k`` fixed if given."""
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
    """Quantities an engineer checks, as a dict (SI): ``static_indentation`` [m] (exact, cubic term
    included), ``uplift_angle`` [rad] (the paper's ``m g / (2 b^2 k)`` and the exact one),
    ``slenderness`` [rad], ``rocking_frequency`` and ``vertical_frequency`` [rad/s] (small amplitude,
    full contact), ``vertical_damping_ratio`` [1] and ``rocking_damping_ratio`` [1] (full contact, at
    the static indentation)."""
    from screening import condensation as condensations
    from screening.physics.contact import linear_rocking_stiffness, rest_indentation
    from screening.solvers.synthesis import rocking_frequency, vertical_frequency

    m, b = float(block.m), float(block.b)
    k = float(foundation.k)
    z_st = rest_indentation(block, foundation)
    wv = vertical_frequency(block, foundation)
    wr = rocking_frequency(block, foundation)
    w_rate, w_ind = (float(w) for w in foundation.damping_weights)
    damping_at_rest = w_rate + w_ind * z_st              # zdot (w_rate + w_ind z) at z = z_st
    c_v, c_r = 2.0 * b * damping_at_rest, 2.0 / 3.0 * damping_at_rest * b**3
    k_r = float(linear_rocking_stiffness(block, foundation))
    try:
        exact = float(condensations.get("cubic").uplift_threshold(block, foundation))
    except ValueError:
        exact = math.nan
    return {
        "static_indentation": z_st,
        "uplift_angle": float(condensations.get("paper").uplift_threshold(block, foundation)),
        "uplift_angle_exact": exact,
        "slenderness": float(block.slenderness),
        "rocking_frequency": wr,
        "vertical_frequency": wv,
        "vertical_damping_ratio": c_v / (2.0 * math.sqrt(2.0 * b * k * m)),
        "rocking_damping_ratio": c_r / (2.0 * math.sqrt(k_r * float(block.m_sdof))) if k_r > 0 else math.nan,
    }


def format_bed_summary(summary):
    """The :func:`bed_summary` as text lines with units and engineering units."""
    s = summary
    return [
        f"static indentation  {s['static_indentation'] * 1e3:.4g} mm",
        f"uplift angle        {s['uplift_angle']:.4g} rad (paper m g/(2 b^2 k))"
        + (f", {s['uplift_angle_exact']:.4g} rad exact" if np.isfinite(s['uplift_angle_exact']) else ""),
        f"slenderness         {s['slenderness']:.4g} rad ({math.degrees(s['slenderness']):.3g} deg); "
        f"uplift / slenderness {s['uplift_angle'] / s['slenderness']:.3g}",
        f"rocking frequency   {s['rocking_frequency']:.4g} rad/s ({s['rocking_frequency'] / (2 * math.pi):.3g} Hz)",
        f"vertical frequency  {s['vertical_frequency']:.4g} rad/s ({s['vertical_frequency'] / (2 * math.pi):.3g} Hz)",
        f"damping ratios      vertical {s['vertical_damping_ratio']:.3g}, rocking {s['rocking_damping_ratio']:.3g} "
        "(full contact, at the static indentation)",
    ]
