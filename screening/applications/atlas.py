"""The error atlas: a space-filling design in the dimensionless groups that govern the linearization's error.

A design point is a vector of numbers in the unit cube (:data:`GROUPS` names its axes); :func:`design`
draws a scrambled Sobol sequence of them, :func:`groups_of` turns each into the dimensionless groups and
:func:`physical_point` into one physical block, bed and excitation shape that has exactly those groups
(:func:`measured_groups` recomputes them from the physical objects: the tests hold the two together).

Why these groups (for a uniform rectangular block on a Hunt–Crossley bed ``k z + eps k z^3 + lam z zdot``;
Buckingham: mass and size scale out once every frequency is measured against one frequency of the block
and every acceleration against the uplift acceleration ``g tan(alpha)``):

* ``alpha = atan(b/h)`` [rad] -- slenderness: the rigid-block toppling angle and the shape of the
  block's inertia (``I_O = m (b^2 + 4 h^2) / 3``).
* ``r_ul = theta_ul / alpha`` [1] with ``theta_ul = m g / (2 b^2 k)`` -- how far into the bed the block
  must rock before uplift, against how far it can rock at all: soft beds (``r_ul`` ~ 0.2, nearly the
  standing limit ``tan(alpha) / (3 alpha)``) to stiff ones (statues on stone, ``r_ul`` ~ 3e-5).  For a
  uniform block it also fixes the two frequency ratios: ``(w_r / p)^2 = (sin(alpha) / (3 theta_ul) -
  cos(alpha)) (4/3) / (1/3 + cos(alpha)^2)`` and ``(w_v / p)^2 = 4 R / (3 b theta_ul)`` (derived, reported by :func:`derived_groups`),
  with ``p = sqrt(3 g / (4 R))`` Housner's frequency parameter, ``R = sqrt(b^2 + h^2)``,
  ``w_r`` the rocking frequency on the bed and ``w_v`` the vertical one.
* ``zeta_v`` [1] -- damping ratio of the vertical mode at rest, ``c_v / (2 m w_v)`` with ``c_v = 2 b lam
  z0`` (:func:`screening.core.physics.contact.vertical_damping_ratio`); for Hunt–Crossley it also fixes
  the rocking damping ratio at rest (derived ``zeta_r``).
* ``e = eps z0^2`` [1] with ``z0 = m g / (2 b k)`` -- the cubic term against the linear one at the
  static indentation: hardening (``e > 0``), linear (``0``), softening (``e < 0``).
* excitation kind (white noise or Kanai–Tajimi), with ``omega_g / p`` [1] and ``zeta_g`` [1] for the filter.
* ``tau = T1 p`` [1] -- the envelope ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` with ``T2 = T1 / 2`` against
  the block's time scale; the record is ``RECORD_T1`` x ``T1`` long.
* intensity -- the peak uplift probability ``p_target`` the paper-condensation linearization reaches
  (``S0`` found by bisection), times ``factor`` >= 1 on ``S0`` past toppling.  Reported besides as the
  dimensionless ``I_S = sqrt(2 pi S0 p) / (g tan(alpha))`` (:func:`derived_groups`).

Rocking frequency ``p`` (not ``w_r``) is the time scale: in uplift, where the error lives, the block
rocks at a fraction of ``p`` whatever the bed.

Families (:func:`family_of`): a coarse partition of the design by slenderness (2 bins), ``r_ul`` (3), bed
law (3) and excitation kind (2) -- every physical system belongs to exactly one, and a cross-validation
that holds out a family holds out a whole neighbourhood of systems, not a single point.

All functions are pure and vectorised over points unless stated.  Units SI.
"""

from __future__ import annotations

import math

import numpy as np
from screening.core.condensation import paper
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation
from screening.core.model.excitation import Envelope
from screening.core.physics.contact import rest_indentation, vertical_damping_ratio
from screening.solvers.synthesis import rocking_frequency, vertical_frequency

__all__ = []

#: Axes of the unit-cube design, in order.
GROUPS = ("alpha", "log10_r_ul", "log10_zeta_v", "u_bed", "u_kind", "log10_omega_g_p", "zeta_g", "log10_tau",
          "u_intensity")
#: Ranges of the axes (uniform between the bounds, in the units of the name: log10 where it says so).
RANGES = {
    "alpha": (0.10, 0.45),                       # [rad]: a slender statue to a squat cabinet
    "log10_r_ul": (math.log10(3e-5), math.log10(0.25)),
    "log10_zeta_v": (math.log10(0.02), math.log10(1.0)),
    "log10_omega_g_p": (math.log10(0.5), math.log10(20.0)),
    "zeta_g": (0.2, 0.8),
    "log10_tau": (math.log10(5.0), math.log10(30.0)),
}
#: Bed law from ``u_bed``: softening below the first edge, linear up to the second, hardening above.
BED_EDGES = (0.3, 0.4)
#: ``|e|`` ranges (log-uniform) of softening and hardening beds.
SOFTENING_E = (1e-5, 3e-3)
HARDENING_E = (1e-3, 1.0)
#: ``u_kind`` below this: white noise; above: Kanai–Tajimi.
WHITE_FRACTION = 1.0 / 3.0
#: Intensity: ``u_intensity`` below ``BEYOND_EDGE`` maps logit-uniformly to ``p_target`` in ``P_TARGET``;
#: above, ``p_target = P_BEYOND`` and ``S0`` is multiplied by a factor log-uniform in ``BEYOND_FACTOR``.
P_TARGET = (0.002, 0.97)
BEYOND_EDGE = 0.85
P_BEYOND = 0.9
BEYOND_FACTOR = (1.0, 3.0)
#: Record length in units of T1, and output instants per record.
RECORD_T1 = 4.0
N_OUTPUT = 400
#: The physical scale the design is realised at: half-diagonal R [m] and mass m [kg] (both scale out).
SCALE_R = 0.5
SCALE_M = 100.0
G = 9.81
#: Family bins: slenderness edges [rad], r_ul edges [1].
FAMILY_ALPHA_EDGES = (0.275,)
FAMILY_R_EDGES = (1e-3, 2e-2)
BED_LAWS = ("softening", "linear", "hardening")
KINDS = ("white", "kanai_tajimi")


def design(n_points, seed=0):
    """The atlas design: scrambled Sobol points in the unit cube, one coordinate per axis of :data:`GROUPS`.

    Drawn with :class:`scipy.stats.qmc.Sobol` (Owen scrambling); the same ``seed`` gives the same points.

    Parameters
    ----------
    n_points : int
        Number of points, >= 1 (a power of two keeps the balance properties of the sequence).
    seed : int, default 0
        Scrambling seed, >= 0.

    Returns
    -------
    numpy.ndarray
        ``(n_points, len(GROUPS))`` coordinates in ``[0, 1)`` [1].

    """
    from scipy.stats import qmc

    if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)) or n_points < 1:
        raise ValueError(f"parameter 'n_points' must be an integer >= 1 (got {n_points!r})")
    sampler = qmc.Sobol(d=len(GROUPS), scramble=True, seed=seed)
    return sampler.random(int(n_points))


def _lerp(u, bounds):
    lo, hi = bounds
    return lo + (hi - lo) * np.asarray(u, dtype=float)


def groups_of(u):
    """The dimensionless groups of unit-cube design points.

    Each coordinate maps onto its group over :data:`RANGES` (log-uniformly where the axis name says
    ``log10``); ``u_bed`` picks the bed law and ``|e|``, ``u_kind`` the excitation kind, ``u_intensity``
    the target uplift probability and the factor past toppling.

    Parameters
    ----------
    u : array_like
        Design points ``(..., len(GROUPS))`` in the unit cube [1] (:func:`design`); ``ValueError`` for
        another last dimension or a coordinate outside ``[0, 1]``.

    Returns
    -------
    dict of str to numpy.ndarray
        Arrays over the points: ``alpha`` [rad], ``r_ul`` [1], ``zeta_v`` [1], ``e`` [1], ``bed_law``
        (str), ``kind`` (str), ``omega_g_p`` [1] (NaN for white noise), ``zeta_g`` [1] (NaN for white
        noise), ``tau`` [1], ``p_target`` [1], ``factor`` [1].

    Notes
    -----
    ``p_target = 1 / (1 + exp(-x))`` with ``x`` uniform between the logits of :data:`P_TARGET` as
    ``u_intensity`` runs over ``[0, BEYOND_EDGE)``; above, ``p_target = P_BEYOND`` and
    ``log factor`` is uniform over ``log BEYOND_FACTOR``.  The groups follow from Buckingham's theorem
    [3] with Housner's frequency parameter as the time scale [2]; the bed and the filter are those of
    [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [housner1963] in the bibliography, ``docs/bibliography.md``.
    .. [3] E. Buckingham, "On physically similar systems; illustrations of the use of dimensional
       equations", Physical Review 4(4) (1914) 345-376.
    """
    u = np.atleast_2d(np.asarray(u, dtype=float))
    if u.shape[-1] != len(GROUPS) or np.any((u < 0) | (u > 1)):
        raise ValueError(f"parameter 'u' must hold points of the unit cube with {len(GROUPS)} coordinates")
    c = {name: u[..., i] for i, name in enumerate(GROUPS)}
    out = {"alpha": _lerp(c["alpha"], RANGES["alpha"]),
           "r_ul": 10.0 ** _lerp(c["log10_r_ul"], RANGES["log10_r_ul"]),
           "zeta_v": 10.0 ** _lerp(c["log10_zeta_v"], RANGES["log10_zeta_v"]),
           "tau": 10.0 ** _lerp(c["log10_tau"], RANGES["log10_tau"])}
    ub = c["u_bed"]
    soft, hard = ub < BED_EDGES[0], ub >= BED_EDGES[1]
    ls, lh = np.log10(SOFTENING_E), np.log10(HARDENING_E)
    e_soft = -10.0 ** _lerp(np.clip(ub / BED_EDGES[0], 0, 1), ls)
    e_hard = 10.0 ** _lerp(np.clip((ub - BED_EDGES[1]) / (1.0 - BED_EDGES[1]), 0, 1), lh)
    out["e"] = np.where(soft, e_soft, np.where(hard, e_hard, 0.0))
    out["bed_law"] = np.where(soft, "softening", np.where(hard, "hardening", "linear"))
    white = c["u_kind"] < WHITE_FRACTION
    out["kind"] = np.where(white, "white", "kanai_tajimi")
    out["omega_g_p"] = np.where(white, np.nan, 10.0 ** _lerp(c["log10_omega_g_p"], RANGES["log10_omega_g_p"]))
    out["zeta_g"] = np.where(white, np.nan, _lerp(c["zeta_g"], RANGES["zeta_g"]))
    ui = c["u_intensity"]
    logit = np.log(np.asarray(P_TARGET) / (1.0 - np.asarray(P_TARGET)))
    x = _lerp(np.clip(ui / BEYOND_EDGE, 0, 1), logit)
    beyond = ui >= BEYOND_EDGE
    out["p_target"] = np.where(beyond, P_BEYOND, 1.0 / (1.0 + np.exp(-x)))
    lf = np.log(BEYOND_FACTOR)
    out["factor"] = np.where(beyond, np.exp(_lerp((ui - BEYOND_EDGE) / (1.0 - BEYOND_EDGE), lf)), 1.0)
    return out


def housner_frequency(block):
    """Housner's frequency parameter ``p`` of a rigid block [rad s-1].

    Parameters
    ----------
    block : screening.core.model.Block
        The block: ``m`` [kg], half-width ``b`` [m], half-height ``h`` [m], ``I_cm`` [kg m2], ``g``
        [m s-2] (scalars).

    Returns
    -------
    float
        ``p`` [rad s-1].

    Notes
    -----
    ``p = sqrt(m g R / I_O)`` with ``I_O = I_cm + m R^2`` and ``R = sqrt(b^2 + h^2)`` [2]; for a uniform
    rectangular block ``I_O = 4 m R^2 / 3`` and ``p = sqrt(3 g / (4 R))``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [housner1963] in the bibliography, ``docs/bibliography.md``.
    """
    R = math.hypot(float(block.b), float(block.h))
    return math.sqrt(float(block.m) * float(block.g) * R / (float(block.I_cm) + float(block.m) * R * R))


def physical_point(groups, i=0):
    """The physical block, bed and excitation shape of one design point: they have exactly its groups.

    Parameters
    ----------
    groups : dict
        Output of :func:`groups_of` (arrays over points, or scalars).
    i : int, default 0
        Index of the point.

    Returns
    -------
    tuple
        ``(block, foundation, excitation_shape, timing)``: a :class:`screening.core.model.Block`, a
        :class:`screening.core.model.Foundation`, ``{"kind", "omega_g" [rad s-1], "zeta_g" [1]}`` (the
        intensity ``S0`` is set later by bisection, :func:`make_excitation`) and ``{"T1", "T2",
        "t_end", "dt"}`` [s].

    Notes
    -----
    At ``R = SCALE_R``, ``m = SCALE_M``: ``b = R sin(alpha)``, ``h = R cos(alpha)``; ``k = m g / (2 b^2
    r_ul alpha)``; ``eps = e / z0^2``, ``z0 = m g / (2 b k)``; ``lam = zeta_v m w_v / (b z_rest)`` with
    ``w_v = sqrt(2 b k / m)`` and ``z_rest`` the exact rest indentation with the cubic term
    (:func:`screening.core.physics.contact.rest_indentation`); ``omega_g = (omega_g/p) p``; ``T1 = tau / p``,
    ``T2 = T1 / 2``, ``t_end = RECORD_T1 T1``, ``dt = t_end / N_OUTPUT``.  The bed is the Hunt-Crossley
    contact law of section 2.1 in [1]; ``p`` is Housner's [2].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [housner1963] in the bibliography, ``docs/bibliography.md``.
    """
    g = {k: (v[i] if np.ndim(v) else v) for k, v in groups.items()}
    alpha = float(g["alpha"])
    block = Block(m=SCALE_M, b=SCALE_R * math.sin(alpha), h=SCALE_R * math.cos(alpha), g=G)
    b, m = float(block.b), float(block.m)
    k = m * G / (2.0 * b * b * float(g["r_ul"]) * alpha)
    z0 = m * G / (2.0 * b * k)
    eps = float(g["e"]) / z0**2
    w_v = math.sqrt(2.0 * b * k / m)
    z_rest = float(rest_indentation(block, Foundation(k=k, lam=0.0, eps=eps)))
    lam = float(g["zeta_v"]) * m * w_v / (b * z_rest)
    foundation = Foundation(k=k, lam=lam, eps=eps)
    p = housner_frequency(block)
    kind = str(g["kind"])
    shape = {"kind": kind}
    if kind == "kanai_tajimi":
        shape.update(omega_g=float(g["omega_g_p"]) * p, zeta_g=float(g["zeta_g"]))
    T1 = float(g["tau"]) / p
    t_end = RECORD_T1 * T1
    return block, foundation, shape, {"T1": T1, "T2": T1 / 2.0, "t_end": t_end, "dt": t_end / N_OUTPUT}


def make_excitation(shape, timing, S0):
    """The excitation of a design point at intensity ``S0``.

    White noise or a Kanai-Tajimi filtered noise, modulated by the envelope of ``timing``.

    Parameters
    ----------
    shape : dict
        ``{"kind": "white" | "kanai_tajimi", "omega_g" [rad s-1], "zeta_g" [1]}`` (:func:`physical_point`).
    timing : dict
        ``{"T1", "T2", ...}`` [s] (:func:`physical_point`).
    S0 : float
        Two-sided power spectral density level of the driving noise [m2 s-3].

    Returns
    -------
    screening.core.excitations.white.WhiteNoise or screening.core.excitations.kanai_tajimi.KanaiTajimi
        The excitation, with an :class:`~screening.core.model.excitation.Envelope` of ``T1``, ``T2``, without a band
        (``band_limit_hz=None``: the idealized spectra the atlas was measured with).

    Notes
    -----
    The envelope is ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` (eq. (57) in [1]); the Kanai-Tajimi filter
    has the spectrum of eq. (50) in [1] ([2], [3]).

    """
    env = Envelope(timing["T1"], timing["T2"])
    if shape["kind"] == "white":                 # the atlas measured the idealized spectra: no band
        return WhiteNoise(S0, env, band_limit_hz=None)
    return KanaiTajimi(S0, shape["omega_g"], shape["zeta_g"], env, band_limit_hz=None)


def measured_groups(block, foundation, shape, timing):
    """The dimensionless groups recomputed from physical objects (independently of the mapping).

    Parameters
    ----------
    block : screening.core.model.Block
        The block (scalars: ``m`` [kg], ``b``, ``h`` [m], ...).
    foundation : screening.core.model.Foundation
        Its bed (``k`` [N m-2], ``lam`` [N s m-3], ``eps`` [m-2]).
    shape : dict
        ``{"kind", "omega_g" [rad s-1], ...}`` (:func:`physical_point`).
    timing : dict
        ``{"T1", "t_end", ...}`` [s] (:func:`physical_point`).

    Returns
    -------
    dict of str to float
        ``{"alpha" [rad], "r_ul", "zeta_v", "e", "omega_g_p" (NaN for white noise), "tau", "record_T1"}``
        (all [1] but ``alpha``).

    Notes
    -----
    ``r_ul = theta_ul / alpha`` with the uplift angle ``theta_ul = m g / (2 b^2 k)`` of [1]; ``e = eps
    z0^2`` with the static indentation ``z0``; ``zeta_v`` from
    :func:`screening.core.physics.contact.vertical_damping_ratio`; ``omega_g_p = omega_g / p`` and
    ``tau = T1 p`` with Housner's ``p`` [2].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [housner1963] in the bibliography, ``docs/bibliography.md``.
    """
    alpha = float(block.slenderness)
    p = housner_frequency(block)
    z0 = float(paper.static_indentation(0.0, block, foundation))
    return {"alpha": alpha,
            "r_ul": float(paper.uplift_threshold(block, foundation)) / alpha,
            "zeta_v": float(vertical_damping_ratio(block, foundation)),
            "e": float(foundation.eps) * z0**2,
            "omega_g_p": shape["omega_g"] / p if shape["kind"] == "kanai_tajimi" else math.nan,
            "tau": timing["T1"] * p,
            "record_T1": timing["t_end"] / timing["T1"]}


def derived_groups(block, foundation, shape, S0):
    """The groups that follow from the design's: frequency ratios and the dimensionless intensity.

    Parameters
    ----------
    block : screening.core.model.Block
        The block (scalars).
    foundation : screening.core.model.Foundation
        Its bed.
    shape : dict
        ``{"kind", "omega_g" [rad s-1], ...}`` (:func:`physical_point`).
    S0 : float
        Two-sided power spectral density level of the driving noise [m2 s-3].

    Returns
    -------
    dict of str to float
        ``w_r_p`` (rocking on the bed / ``p``), ``w_v_p`` (vertical / ``p``), ``omega_g_w_r`` (filter /
        rocking on the bed; NaN for white noise) and ``I_S`` [1].

    Notes
    -----
    ``I_S = sqrt(2 pi S0 p) / (g tan(alpha))``; for a uniform block ``(w_v / p)^2 = 4 R / (3 b
    theta_ul)`` and ``(w_r / p)^2 = (sin(alpha) / (3 theta_ul) - cos(alpha)) (4/3) / (1/3 +
    cos(alpha)^2)`` (module docstring), with Housner's ``p`` [2] and ``theta_ul`` of [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [housner1963] in the bibliography, ``docs/bibliography.md``.
    """
    p = housner_frequency(block)
    w_r, w_v = rocking_frequency(block, foundation), vertical_frequency(block, foundation)
    return {"w_r_p": w_r / p, "w_v_p": w_v / p,
            "omega_g_w_r": shape["omega_g"] / w_r if shape["kind"] == "kanai_tajimi" else math.nan,
            "I_S": math.sqrt(2.0 * math.pi * S0 * p) / (float(block.g) * float(block.b) / float(block.h))}


def family_of(groups):
    """The family of each point: the cell of (slenderness bin, ``r_ul`` bin, bed law, excitation kind).

    Parameters
    ----------
    groups : dict
        ``alpha`` [rad], ``r_ul`` [1], ``bed_law`` and ``kind`` (str) over the points
        (:func:`groups_of`).

    Returns
    -------
    numpy.ndarray of int
        The family ids [-], in ``0 .. 2 * 3 * 3 * 2 - 1`` (:func:`family_name` reads them).

    Notes
    -----
    ``id = ((a n_r + r) n_law + law) n_kind + kind`` with the bins ``a`` of
    :data:`FAMILY_ALPHA_EDGES`, ``r`` of :data:`FAMILY_R_EDGES` and the indices in :data:`BED_LAWS`
    and :data:`KINDS`.  Held-out families are the groups of the grouped cross-validation of
    ``docs/error_atlas.md``.

    """
    a = np.digitize(np.asarray(groups["alpha"], dtype=float), FAMILY_ALPHA_EDGES)
    r = np.digitize(np.asarray(groups["r_ul"], dtype=float), FAMILY_R_EDGES)
    law = np.array([BED_LAWS.index(s) for s in np.atleast_1d(groups["bed_law"])])
    kind = np.array([KINDS.index(s) for s in np.atleast_1d(groups["kind"])])
    n_r, n_law, n_kind = len(FAMILY_R_EDGES) + 1, len(BED_LAWS), len(KINDS)
    return ((a * n_r + r) * n_law + law) * n_kind + kind


def family_name(family):
    """Readable name of a family id, e.g. ``"alpha0-r1-softening-white"``.

    Parameters
    ----------
    family : int
        A family id of :func:`family_of`.

    Returns
    -------
    str
        ``"alpha<a>-r<r>-<bed law>-<kind>"``.

    """
    n_r, n_law, n_kind = len(FAMILY_R_EDGES) + 1, len(BED_LAWS), len(KINDS)
    family = int(family)
    kind = family % n_kind
    law = (family // n_kind) % n_law
    r = (family // (n_kind * n_law)) % n_r
    a = family // (n_kind * n_law * n_r)
    return f"alpha{a}-r{r}-{BED_LAWS[law]}-{KINDS[kind]}"
