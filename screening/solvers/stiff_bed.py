"""The stiff-bed rocking model (``model="stiff_bed"``): a rigid block on the bed's quasi-static contact,
with the energy lost at each corner-to-corner transfer derived from the bed.

On a stiff bed the vertical mode of the coupled model (``sqrt(2 b k / m)``, thousands of rad/s) sets
its step size but adds little to the rocking; what matters is how rocking starts on the compliant
contact and how much energy each transfer of the pivot from one corner to the other takes.  This
model keeps those two and drops the vertical dynamics:

* **Quasi-static contact.**  The base-centre indentation is slaved to the exact static vertical
  balance, ``z_cb = Z(theta)``: the indentation law of the ``"cubic"`` condensation
  (:func:`screening.core.condensation.cubic.quasi_static_indentation`, eqs. 13 and 15 with the cubic
  term) evaluated at ``a = |sin theta|``; the bed's moment is that condensation's moment law at
  ``a`` times ``cos theta``, which is the exact contact moment of :mod:`screening.core.physics.contact` at
  that indentation (the condensation's small-angle formulas are exact in ``sin theta`` except for
  the lever ``cos theta``).  Linear in full contact (``K(0)``), uplift from ``theta_ul``
  (:func:`screening.core.condensation.cubic.uplift_threshold`, ``m g / (2 b^2 k)`` for ``eps = 0``: a
  ground acceleration of ``g b / (3 h)``), the contact then shrinking towards the corner.
* **Rigid-block inertia on that constraint.**  With ``z_cb = Z(theta)`` and the base centre held
  horizontally (the kinematics of the coupled model), the kinetic energy is
  ``T = m_eff(theta) theta'^2 / 2`` with
  ``m_eff = I_cm + m (h^2 cos^2 theta + (Z'(theta) + h sin theta)^2)``, and Lagrange's equation is::

      m_eff theta'' + m_eff'(theta) theta'^2 / 2 = m h cos(theta) x_g'' - Q(theta) - cos^2(theta) C_D(a) theta'
      Q(theta) = sign(theta) cos(theta) (K(a) a + m g h a) - m g h sin(theta),   a = |sin theta|

  ``K``: the ``"cubic"`` condensation's secant stiffness (so ``K(a) a + m g h a`` is the bed moment);
  ``C_D``: the damping of the bed's damping pressure on the constraint, whose power is the coupled
  model's contact dissipation at ``z_cb = Z(theta)``
  (:func:`screening.kernels.stiff_bed_contact.constraint_damping`: the condensation's damping moment
  plus the work of the vertical damping force along the constraint; the moment alone overstates the
  dissipation in uplift by ``2 b / L``, ``L`` the contact length).
  On an infinitely stiff bed ``Z = -b |sin theta|``, ``Q = m g (b cos theta - h |sin theta|)`` and
  ``m_eff = I_cm + m (h^2 + b^2 cos^2 theta - 2 b h cos theta |sin theta|)``: exactly the coupled
  model's rigid limit, and Housner's block about its corner (``I_O = I_cm + m (b^2 + h^2)``) to first
  order in ``theta``.  Near rest ``m_eff = I_cm + m h^2``, the condensed model's inertia.
* **Transfer loss from the bed.**  Each time ``theta`` changes sign after the block has rocked
  (its amplitude ``A`` since the last sign change above ``theta_ul``), ``theta'`` is multiplied by
  ``sqrt(eta(A))`` (``transfer="bed"``; the default ``"impact"`` reads the same table at the amplitude whose
  loss-free crossing rate is the rate at the crossing, :func:`impact_table`).  ``eta(A)`` is computed once per
  bed (:func:`transfer_table`): the coupled model rocks freely from rest at ``A`` through one transfer to the
  next extreme ``A_1``; with the potential ``V(theta) = int_0^theta Q`` its energy ratio is ``V(A_1) / V(A)``;
  this model, run the same way without transfer loss, keeps ``V(A_1') / V(A)`` (its own contact damping);
  ``eta`` is the ratio of the two (at most 1).  It is tabulated over ``log A`` and read by linear interpolation,
  ``eta = 1`` at ``A = theta_ul`` (no uplift, no transfer).  Never fitted to Monte Carlo.  With
  ``transfer="housner"`` the ratio is Housner's ``r^2``, ``r = 1 - (3/2) sin^2(alpha)``, the limit
  of a perfectly plastic impact on a rigid bed.

Numerics.  Full contact (``|theta| <= theta_ul``) is the linear oscillator
``m0 theta'' + C0 theta' + K0 theta = m h x_g''`` (``m0 = I_cm + m h^2``, ``C0 = C(0)``,
``K0 = K(0)``); there the state is advanced exactly from one input grid point to the next
(:func:`linear_propagator`: the matrix exponential with the cubic Hermite input), so the bed's
stiff small-rotation frequency never sets the step.  Everywhere else (uplift, and intervals that
contain an output instant or leave full contact) the adaptive Dormand–Prince 5(4) pair of the
other models integrates the nonlinear equation; steps in full contact land on grid points to hand
back to the exact propagator.  A step that crosses zero after the block has rocked and would end in
uplift on the other side is shortened to the crossing, so the transfer's velocity ratio is applied
in full contact (the rotation past zero scaled by the same ratio) (``StiffBedModel(locate=False)``: at the end of the step that crossed zero).  A sample is overturned when ``|theta| > atan(b/h)``, diverged when
its state stops being finite or its rate exceeds ``1000 sqrt(g/h)``, when it passes the capacity
angle of a softening bed, or when the step budget runs out.

Validity.  The model assumes the vertical mode is fast and the uplift angle small against the
slenderness: :func:`validity` names the rule, :meth:`StiffBedModel.check` warns when it fails.

Method and how it is checked: ``docs/stiff_bed.md``.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during earthquakes.
Bulletin of the Seismological Society of America 53(2), 403-417.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from screening.core import laws
from screening.core.condensation import cubic
from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, ground_cutoff
from screening.core.model import Block, Foundation
from screening.core.status import BestMethod, EscalationModel
from screening.kernels import mcs_kernels as kern
from screening.kernels.stiff_bed_contact import (housner_restitution, indentation_curvature,
                                                 indentation_curvature_jit, potential, rocking_acceleration,
                                                 rocking_acceleration_jit, rocking_coefficients, stiff_record)
from screening.kernels.stiff_bed_kernels import integrate_chunk, integrate_sample, linear_propagator, transfer_ratio_jit
from screening.solvers.mc_registry import ChunkIntegrator, get as get_model, MonteCarloModel, register
from screening.solvers.model_choice import RULE_FILE, rule_of, vouches
from screening.solvers.synthesis import rocking_frequency

__all__ = []

#: Amplitudes of the transfer table: this many, log-spaced from ``TABLE_LOW theta_ul`` to
#: ``TABLE_HIGH atan(b/h)``.
TABLE_POINTS = 10
TABLE_LOW = 2.0
TABLE_HIGH = 0.7
#: Relative tolerance of this model's free-rocking runs that build the transfer table (the coupled
#: model's runs use its own default): fixed, so the table does not move with the Monte Carlo tolerance.
TABLE_RTOL = 1e-7


# ----------------------------------------------------------------------------- validity
def validity_limit():
    """Largest ``theta_ul / atan(b/h)`` of the stiff-bed model's measured validity.

    The upper bound of the shipped rule of ``model = "auto"`` (``screening/data/model_choice.toml``): the
    model holds where the uplift angle is small against the slenderness.

    Returns
    -------
    float
        The bound on ``theta_ul / atan(b/h)`` [1].

    Notes
    -----
    The rule is ``theta_ul / atan(b/h) <= validity_limit()``: the bed's vertical mode is then fast against
    the rocking, so the quasi-static contact holds (``docs/stiff_bed.md``, "Validity").

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` (section "Validity") and
       ``docs/model_choice.md`` (the shipped rules of ``model = "auto"``).
    """
    return rule_of("stiff_bed").bound("theta_ul_over_slenderness")[1]


def validity(block, foundation):
    """The stiff-bed model's validity indicator at a block and bed, and its rule.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    ratio : float
        ``theta_ul / atan(b/h)`` [1]: the ``"cubic"`` condensation's uplift angle over the slenderness.
    rule : str
        The rule the model is used under, ``theta_ul / atan(b/h) <= validity_limit()``.

    Notes
    -----
    ``theta_ul`` is the rotation at which the indentation of the lifting edge reaches zero (uplift starts)
    on the compression-only contact law of eq. (3) in [2]; small against
    ``atan(b/h)``, the bed's vertical mode is fast against the rocking (``docs/stiff_bed.md``, "Validity").

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` (section "Validity") and
       ``docs/model_choice.md`` (the shipped rules of ``model = "auto"``).
    .. [2] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    ratio = float(cubic.uplift_threshold(block, foundation)) / float(block.slenderness)
    return ratio, f"theta_ul / atan(b/h) <= {validity_limit():g}"


def validity_problem(block, foundation, excitation=None):
    """Why the stiff-bed model is outside its measured validity at a point, or ``None``.

    Checks the point against the model's shipped rule (:func:`screening.solvers.model_choice.vouches`):
    ``None`` where it holds, else one line naming the rule, the indicator outside it and what to use instead.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    excitation : object, optional
        The point's excitation (its ``kind`` is checked), or ``None`` (records: not checked).

    Returns
    -------
    str or None
        The message, or ``None`` inside the validity.

    Notes
    -----
    The rule bounds dimensionless indicators of the point (``theta_ul / atan(b/h)``, the bed's vertical
    damping ratio, ...) to the ranges the model was measured on against coupled Monte Carlo
    (``docs/stiff_bed.md``, "Validity"; ``docs/model_choice.md``).

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` (section "Validity") and
       ``docs/model_choice.md`` (the shipped rules of ``model = "auto"``).
    """
    rule = rule_of("stiff_bed")
    kind = getattr(excitation, "kind", None)
    ok, why = vouches(rule, block, foundation, kind, check_excitation=excitation is not None)
    if ok:
        return None
    return (f"model 'stiff_bed' outside its measured validity: {why} (rule: screening/data/{RULE_FILE}, "
            f"from {rule.benchmark}); use model = 'coupled' or 'auto'")


def check_standing(block, foundation):
    """Raise ``ValueError`` if the block cannot stand on the bed.

    Parameters
    ----------
    block : screening.core.model.Block
        The block.
    foundation : screening.core.model.Foundation
        The bed.

    Returns
    -------
    None
        Raises ``ValueError`` (naming ``foundation.k``) where ``K(0) = (2/3) b^3 k - m g h + ... <= 0``.

    References
    ----------
    .. [1] screening documentation, "The stiff-bed model", docs/stiff_bed.md.
    """
    cubic.check_bearing(block, foundation)
    k0 = float(cubic.stiffness_at_rest(block, foundation))
    if not k0 > 0.0:
        raise ValueError(f"parameter 'foundation.k' = {float(foundation.k)!r} N/m2: the block cannot stand on this "
                         f"bed (rocking stiffness at rest K(0) = {k0:.4g} N m/rad; need (2/3) b^3 k > m g h)")



# ----------------------------------------------------------------------------- transfer table
def _free_rocking_extreme(integrator, y_init, scale, rtol, t_end, n_out=4000):
    """``|theta|`` at the first extreme after the first sign change of ``theta`` in free rocking
    from ``y_init`` (no ground motion), NaN if there is none within ``t_end`` [s] or it overturned."""
    t_out = np.linspace(0.0, t_end, n_out)
    n_grid = 17
    acc = np.zeros((1, n_grid))
    out = [np.empty((1, n_out)) for _ in range(4)]
    uplift = np.zeros((1, n_out), dtype=np.bool_)
    peak, h_min = np.zeros(1), np.zeros(1)
    status, reason, n_acc, n_rej = (np.zeros(1, dtype=np.int64) for _ in range(4))
    integrator(acc, acc.copy(), t_end / (n_grid - 1), t_out, np.ascontiguousarray(y_init, dtype=float), scale, rtol,
               0.005, 50_000_000, *out, uplift, peak, status, reason, n_acc, n_rej, h_min)
    theta, theta_dot = out[0][0], out[1][0]
    if status[0] != kern.STATUS_OK:
        return math.nan
    side = np.sign(y_init[0])
    crossed = np.flatnonzero(np.sign(theta) == -side)
    if not crossed.size:
        return math.nan
    i = crossed[0]
    turn = np.flatnonzero(np.sign(theta_dot[i:]) == side)       # the rate turns back towards the start side
    if not turn.size or i + turn[0] + 1 >= n_out:
        return math.nan
    j = i + turn[0]
    # the extreme lies between j - 1 and j: cubic Hermite of theta with rates theta_dot, its rate root
    dt = t_out[1] - t_out[0]
    v0, v1 = theta_dot[j - 1], theta_dot[j]
    s = v0 / (v0 - v1) if v0 != v1 else 0.5
    s = min(max(s, 0.0), 1.0)
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    return abs(h00 * theta[j - 1] + h01 * theta[j] + dt * (h10 * v0 + h11 * v1))


def _half_period_estimate(amplitude, block, foundation):
    """A time [s] past the first return of free rocking from rest at ``amplitude`` (a generous bound)."""
    alpha = float(block.slenderness)
    radius = math.hypot(float(block.b), float(block.h))
    i_o = float(block.I_cm) + float(block.m) * radius**2
    p = math.sqrt(float(block.m * block.g) * radius / i_o)
    quarter = math.acosh(1.0 / max(1.0 - amplitude / alpha, 1e-9)) / p
    w_r = max(rocking_frequency(block, foundation), 1e-3)
    return 4.0 * max(quarter, 2.0 * math.pi / w_r)


def _bed_key(block, foundation):
    return (float(block.m), float(block.g), float(block.h), float(block.b), float(block.I_cm), float(foundation.k),
            float(foundation.eps), float(foundation.damping), str(foundation.law))


@functools.lru_cache(maxsize=64)
def _transfer_table_cached(key):
    m, g, h, b, i_cm, k, eps, damping, law = key
    block = Block(m=m, b=b, h=h, I_cm=i_cm, g=g)
    foundation = Foundation(k=k, eps=eps, law=law, **{laws.get(law).parameter: damping})
    return _compute_transfer_table(block, foundation)


def _compute_transfer_table(block, foundation):
    tu = float(cubic.uplift_threshold(block, foundation))
    alpha = float(block.slenderness)
    lo, hi = TABLE_LOW * tu, TABLE_HIGH * alpha
    if lo >= hi:
        return np.array([math.log(tu)]), np.zeros(1), np.ones(1), np.ones(1), np.array([tu])
    amps = np.geomspace(lo, hi, TABLE_POINTS)
    coupled = get_model("coupled")
    c_int = coupled.integrator(block, foundation, "paper", 0.5)
    c_scale = coupled.default_rtol * coupled.state_scales(block, foundation)
    no_loss = StiffBedModel(transfer="none", locate=False)
    s_int = no_loss.integrator(block, foundation, "paper", 0.5)
    s_scale = TABLE_RTOL * no_loss.state_scales(block, foundation)
    eta_c = np.empty(amps.size)
    eta_m = np.empty(amps.size)
    for i, amp in enumerate(amps):
        t_end = _half_period_estimate(amp, block, foundation)
        v0 = potential(amp, block, foundation)
        try:
            start = coupled.initial_state(block, foundation, amp)
        except ValueError:
            raise ValueError(
                f"model 'stiff_bed': the softening bed (foundation.eps = {float(foundation.eps):.3g} m-2) cannot carry "
                f"the block rocked to {amp / alpha:.2f} of its slenderness angle, where this model measures its "
                "rocking losses; use model = \"coupled\" (or \"auto\"), or a bed that softens less (smaller "
                "|foundation.eps|)") from None
        a_c = _free_rocking_extreme(c_int, start, c_scale, coupled.default_rtol, t_end)
        a_m = _free_rocking_extreme(s_int, no_loss.initial_state(block, foundation, amp), s_scale, TABLE_RTOL,
                                    t_end)
        eta_c[i] = potential(a_c, block, foundation) / v0 if math.isfinite(a_c) else math.nan
        eta_m[i] = potential(a_m, block, foundation) / v0 if math.isfinite(a_m) else math.nan
    eta = np.clip(eta_c / eta_m, 1e-12, 1.0)
    ok = np.isfinite(eta)
    log_amp = np.concatenate(([math.log(tu)], np.log(amps[ok])))
    log_eta = np.concatenate(([0.0], np.log(eta[ok])))
    return log_amp, log_eta, eta_c, eta_m, amps


def transfer_table(block, foundation):
    """The bed-derived transfer loss of the stiff-bed model, computed once per bed.

    The energy kept through a corner-to-corner transfer, tabulated against the half-cycle amplitude: at each
    of :data:`TABLE_POINTS` amplitudes log-spaced from ``TABLE_LOW theta_ul`` to ``TABLE_HIGH atan(b/h)`` the
    coupled model rocks freely from rest through one transfer; its energy ratio over the one of this model
    without transfer loss is the transfer's ratio ``eta``.  Cached per bed (the first call on a bed runs
    the free-rocking integrations: tens of seconds).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.

    Returns
    -------
    log_amp : numpy.ndarray
        ``log`` of the table's half-cycle amplitudes [rad], the node ``theta_ul`` first (read by the kernel).
    log_eta : numpy.ndarray
        ``log`` of the transfer energy ratio [1] at those nodes, ``0`` at ``theta_ul``.
    eta_coupled : numpy.ndarray
        Per amplitude: the coupled model's free-rocking energy ratio ``V(A_1) / V(A)`` [1] through one transfer.
    eta_model : numpy.ndarray
        Per amplitude: this model's, without transfer loss [1].
    amplitudes : numpy.ndarray
        The amplitudes ``A`` [rad].

    Notes
    -----
    ``eta(A) = [V(A_1) / V(A)]_coupled / [V(A_1') / V(A)]_no loss`` with ``V`` the stored energy
    (:func:`potential`), clipped to ``(0, 1]``; ``eta = 1`` at ``A = theta_ul`` (no uplift, no transfer).
    Never fitted to Monte Carlo.  Where ``TABLE_LOW theta_ul >= TABLE_HIGH atan(b/h)`` (a bed too soft for
    the model) the table is the node ``(theta_ul, 1)`` alone (``docs/stiff_bed.md``; the coupled model's
    contact law is eq. (3) in [2]).

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` (the bed-derived transfer loss).
    .. [2] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    return _transfer_table_cached(_bed_key(block, foundation))


def impact_table(block, foundation):
    """The bed-derived transfer loss keyed by the state at the impact: the rate at the zero crossing.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (scalar fields, SI).
    foundation : screening.core.model.Foundation
        The bed (scalar fields, SI).

    Returns
    -------
    log_rate : numpy.ndarray
        ``log`` of the crossing rate [rad/s] of loss-free rocking from rest at each node of
        :func:`transfer_table`.
    log_eta : numpy.ndarray
        ``log`` of the transfer energy ratio [1] at those nodes (:func:`transfer_table`'s).

    Notes
    -----
    The corner impact sees only the state at the impact.  In free rocking from rest at ``A`` the block crosses
    zero with the energy ``V(A)`` it stored, so with the inertia ``m_0 = I_cm + m h^2`` at ``theta = 0`` its
    rate there is ``omega(A) = sqrt(2 V(A) / m_0)``: the table's node ``A`` becomes the node ``omega(A)``
    (``V``: :func:`potential`).  Under a ground motion the half cycle's amplitude and the crossing rate part
    (the ground pumps energy in or out), and the coupled model's loss follows the rate
    (``docs/stiff_bed_validity.md``, "Why the bust on mortar fails").
    """
    log_amp, log_eta, *_ = transfer_table(block, foundation)
    m0 = float(block.m_sdof)
    rates = [math.sqrt(2.0 * potential(a, block, foundation) / m0) for a in np.exp(log_amp)]
    return np.log(np.asarray(rates)), log_eta


# ----------------------------------------------------------------------------- the registered model
class StiffIntegrator(ChunkIntegrator):
    def __init__(self, block, foundation, log_amp, log_eta, locate=True, by_rate=False):
        self.sp = stiff_record(block, foundation, locate, by_rate)
        self.cp = cubic.sdof_record(block, foundation)
        self.log_amp = np.ascontiguousarray(log_amp, dtype=float)
        self.log_eta = np.ascontiguousarray(log_eta, dtype=float)
        self.m0 = float(block.m_sdof)
        self.c0 = float(cubic.damping_at_rest(block, foundation))
        self.k0 = float(cubic.stiffness_at_rest(block, foundation))
        self.mh = float(block.m * block.h)
        self._prop = {}
        #: ``(8, 2)`` step counts (``stiff_bed_kernels.COUNT_ROWS``) summed over the samples integrated since
        #: set to an array; None (the default): not counted
        self.step_counts = None

    def propagator(self, dt):
        if dt not in self._prop:
            phi, gamma = linear_propagator(self.m0, self.c0, self.k0, self.mh, dt)
            self._prop[dt] = np.ascontiguousarray(np.hstack([phi, gamma]))
        return self._prop[dt]

    def __call__(self, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                 out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min,
                 vertical=None):
        vacc, vrate = (kern.NO_VERTICAL, kern.NO_VERTICAL) if vertical is None else vertical
        counts = np.zeros((0 if self.step_counts is None else acc.shape[0], 8, 2), dtype=np.int64)
        integrate_chunk(self.sp, self.cp, self.propagator(float(dt_grid)), self.log_amp, self.log_eta, (acc, vacc),
                        (acc_dot, vrate), float(dt_grid), t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                        out_theta_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min, counts)
        if self.step_counts is not None:
            self.step_counts += counts.sum(axis=0)
        out_z[...] = 0.0
        out_z_dot[...] = 0.0


TRANSFER_LAWS = ("bed", "housner", "none", "impact")
BANDS = ("rocking", "ground", "full")
#: The ``"rocking"`` band is this many times the full-contact rocking frequency (at least the ground's band):
#: on the statue's k = 1e11 bed the ground's band alone (25 Hz) moves P(|theta| > 0.05 atan(b/h)) by 0.12
#: against the coupled model, 1.5 w_r by 0.03 (500 samples, benchmarks/stiff_bed_validity.py --band).
ROCKING_BAND_FACTOR = 1.5


class StiffBedModel(MonteCarloModel):
    """The stiff-bed model (module docstring).

    ``transfer``: ``"impact"`` (the default since 2026-11-29: the bed-derived table read at the impact, at the rate
    at the zero crossing, :func:`impact_table`), ``"bed"`` (the same table read at the half cycle's amplitude,
    :func:`transfer_table`: where the ground pumped energy in during the half cycle it keeps too much, and on the
    bust on mortar overturned too often), ``"housner"`` (Housner's ``r^2`` per transfer) or ``"none"`` (no
    transfer loss; used to build the table).  The measured validity of each: ``docs/stiff_bed_validity.md``.
    ``band``: the band of the Monte Carlo ground motions the model reads (the same samples as the
    other models, same seed and components, low-passed on a coarser grid): ``"rocking"`` (the default)
    ``max(ROCKING_BAND_FACTOR w_r, ground band)`` (``w_r`` the full-contact rocking frequency: in full
    contact the block is an oscillator at ``w_r`` and filters what lies above it, a rigid block in uplift
    responds to an input component at ``w`` like ``1/w^2``; the ground band
    :data:`screening.core.excitations.base.GROUND_BAND_LIMIT_HZ` is the band the intensity measures refer
    to); ``"ground"`` the ground band alone (cheaper, but on mortar-stiff beds it misses the input that
    starts the rocking through the full-contact resonance); ``"full"`` all of them, as the coupled model
    reads them (its band is set by the vertical frequency).  ``monte_carlo(..., band=...)`` overrides
    the band of any model.
    ``locate``: with True (the default) a step that crosses zero and would end in uplift on the other
    side is shortened to the crossing, so the velocity ratio of the transfer is applied while the
    block passes through full contact; False applies it at the end of the step that crossed zero
    (the model's first kernel: its cost and sample paths at a given tolerance, for comparisons).
    """

    flag_code = 2
    escalation_code = EscalationModel.stiff_bed
    step_cost_s = 0.2e-6           # where the full-contact share is not known (analysis.escalation)
    best_method = BestMethod.stiff_bed_monte_carlo
    name = "stiff_bed"
    description = ("rigid block on the quasi-static contact of the cubic condensation, transfer loss "
                   "derived from the coupled model's free rocking (docs/stiff_bed.md)")
    #: Default relative tolerance of the adaptive pair (absolute scales ``theta_ul`` and ``theta_ul w_r``,
    #: :meth:`state_scales`).  The model's sample paths are sensitive at every tolerance (against a 1e-9
    #: reference 14-18 % of the samples of the statue on k = 1e10 change side of 0.1 atan(b/h) at 1e-7 and
    #: at 1e-5 alike), its statistics are not: at 1e-5 they agree with the 1e-9 reference within the paired
    #: sampling error, as at 1e-7, at half the cost (docs/stiff_bed.md, "Numerics").
    default_rtol = 1e-5
    #: Default largest step [s]: free rocking on the corner runs at the largest step (2,850 of the 5,800
    #: adaptive steps per sample of the statue on k = 1e10 at 5 ms); at 10 ms the error control sets it
    #: (20 ms takes as many steps), 12 % fewer steps, and the statistics agree with a 1e-9 reference as
    #: those at 5 ms do (4,000 paired samples: docs/stiff_bed.md, "Tolerance and cost").
    default_h_max = 0.01

    def __init__(self, transfer="impact", band="rocking", locate=True):
        if transfer not in TRANSFER_LAWS:
            raise ValueError(f"parameter 'transfer' must be one of {TRANSFER_LAWS} (got {transfer!r})")
        if band not in BANDS:
            raise ValueError(f"parameter 'band' must be one of {BANDS} (got {band!r})")
        if not isinstance(locate, bool):
            raise ValueError(f"parameter 'locate' must be True or False (got {locate!r})")
        self.transfer = transfer
        self.band = band
        self.locate = locate

    def input_band(self, block, foundation):
        if self.band == "full":
            return None
        ground = ground_cutoff(GROUND_BAND_LIMIT_HZ)
        if self.band == "ground":
            return ground
        return max(ROCKING_BAND_FACTOR * rocking_frequency(block, foundation), ground)

    def check(self, block, foundation, condensation):
        super().check(block, foundation, condensation)
        check_standing(block, foundation)

    def validity_problem(self, block, foundation, excitation=None):
        return validity_problem(block, foundation, excitation)

    def initial_state(self, block, foundation, theta0=0.0, theta_dot0=0.0):
        return np.array([float(theta0), float(theta_dot0), 0.0, 0.0])

    def state_scales(self, block, foundation):
        tu = float(cubic.uplift_threshold(block, foundation))
        return np.array([tu, tu * max(rocking_frequency(block, foundation), 1.0), 0.0, 0.0])

    def table(self, block, foundation):
        """``(log_amp, log_eta)`` of this model's transfer law for a bed."""
        tu = float(cubic.uplift_threshold(block, foundation))
        if self.transfer == "none":
            return np.array([math.log(tu)]), np.zeros(1)
        if self.transfer == "housner":
            return np.array([math.log(tu), math.log(1.000001 * tu)]), \
                np.array([0.0, 2.0 * math.log(housner_restitution(block))])
        if self.transfer == "impact":
            return impact_table(block, foundation)
        log_amp, log_eta, *_ = transfer_table(block, foundation)
        return log_amp, log_eta

    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        return StiffIntegrator(block, foundation, *self.table(block, foundation), locate=self.locate,
                               by_rate=self.transfer == "impact")

    def uplift_threshold(self, block, foundation, condensation):
        return float(cubic.uplift_threshold(block, foundation)), {"theta_ul_condensation": "cubic"}

    def dataset_attributes(self, block, foundation, condensation):
        ratio, rule = validity(block, foundation)
        return {"transfer_loss": self.transfer, "validity_rule": rule, "validity_ratio": ratio,
                "m_sdof": float(block.m_sdof)}


STIFF_BED = register(StiffBedModel())
