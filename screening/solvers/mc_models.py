"""The coupled and the condensed Monte Carlo models behind :mod:`screening.solvers.mc_registry`.

Both run on the compiled 4-state integrator of :mod:`screening.kernels.mcs_kernels` (selected
there by an integer model code, resolved here once):

* ``"coupled"``: the full model, paper eqs. 7–8 with the exact contact resultants of
  :mod:`screening.core.physics.contact` (states ``theta, theta', z_cb, z_cb'``), from static
  equilibrium;
* ``"condensed"``: the SDOF eq. 22 with a condensation's ``C(theta)``, ``K(theta)``
  (:mod:`screening.core.condensation`), from rest.

Defining them registers both; importing this module then registers the stiff-bed model
(:mod:`screening.solvers.stiff_bed`) and its exact-contact sampler (:mod:`screening.solvers.stiff_bed_fast`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from screening.core import condensation as condensations
from screening.core.condensation.paper import uplift_threshold as paper_uplift_threshold
from screening.core.physics.contact import exact_uplift_angle, law_constants, law_resultants, rest_indentation
from screening.kernels import mcs_kernels as kern
from screening.core.status import BestMethod, EscalationModel
from screening.solvers.mc_registry import KERNEL_CONDENSATION, ChunkIntegrator, get, MonteCarloModel
from screening.solvers.synthesis import rocking_frequency, vertical_frequency

__all__ = []

def state_scales(block, foundation):
    """Absolute error scales of the Monte Carlo state ``(theta, theta', z_cb, z_cb')``.

    Parameters
    ----------
    block, foundation
        One point of the model, as in :func:`screening.solvers.montecarlo.check_scalar_models`.

    Returns
    -------
    numpy.ndarray
        ``[theta_ul, theta_ul w_r, z_st, z_st w_v]``: [rad], [rad s-1], [m], [m s-1], with ``theta_ul``
        of eq. (19) in [1], ``z_st = m g / (2 b k)`` of eq. (17) and the rocking and vertical
        frequencies ``w_r``, ``w_v`` (``w_r`` at least 1 rad s-1).

    Notes
    -----
    The integrators scale their absolute tolerance by these: the state's natural sizes at the onset
    of uplift.

    """
    tu = float(paper_uplift_threshold(block, foundation))
    z_st = float(block.m * block.g / (2.0 * block.b * foundation.k))
    w_r = max(rocking_frequency(block, foundation), 1.0)
    return np.array([tu, tu * w_r, z_st, z_st * vertical_frequency(block, foundation)])


def exact_uplift_threshold(block, foundation):
    """The uplift angle that labels the coupled model's samples, with the attributes saying which.

    Parameters
    ----------
    block, foundation
        As in :func:`state_scales`.

    Returns
    -------
    theta_ul : float
        The exact static uplift angle [rad] (:func:`screening.core.physics.contact.exact_uplift_angle`, the
        ``"cubic"`` threshold), or the paper's ``m g / (2 b^2 k)`` (eq. (19) in [1]) for a softening
        bed that cannot carry the block through uplift.
    attrs : dict
        ``theta_ul_condensation`` (``"cubic"`` or ``"paper"``) and, for the fallback, ``theta_ul_note``.

    Notes
    -----
    The coupled model has no threshold of its own; the exact angle is where its static balance
    (eq. (13) in [1]) lifts the far edge.

    """
    tu = float(exact_uplift_angle(block, foundation))
    if math.isfinite(tu):
        return tu, {"theta_ul_condensation": "cubic"}
    return (float(paper_uplift_threshold(block, foundation)),
            {"theta_ul_condensation": "paper",
             "theta_ul_note": "the exact (cubic) uplift angle does not exist here (the softening bed cannot carry "
                              "the block through the onset of uplift: |eps| (m g/(2 b k))^2 >= 2/27); theta_ul is "
                              "the paper's m g / (2 b^2 k)"})


def quasi_static_indentation(block, foundation, theta0):
    """Base-centre indentation ``z_cb`` [m] carrying the weight at rest at a given rotation.

    Parameters
    ----------
    block, foundation, theta0
        The model as in :func:`state_scales`, at the rotation ``theta0`` [rad].

    Returns
    -------
    float
        ``z_cb`` [m] with ``F_cb(theta0, 0, z_cb, 0) = m g`` (exact contact resultant, eq. (5) in [1]);
        :func:`~screening.core.physics.contact.rest_indentation` at ``theta0 = 0``.

    Raises
    ------
    ValueError
        When the bed cannot carry the block at ``theta0``.

    Notes
    -----
    The initial vertical state of a coupled sample started at ``theta0``: the root in ``z_cb`` of the
    vertical balance by Brent's method, bracketed from the flight boundary ``z_cb = -b |sin theta0|``.

    """
    if theta0 == 0.0:
        return rest_indentation(block, foundation)
    b = float(block.b)
    weight = float(block.m * block.g)

    def excess(z):
        force, _ = law_resultants(theta0, 0.0, z, 0.0, b, *law_constants(foundation))
        return float(force) - weight

    lo = -b * abs(math.sin(theta0))          # flight boundary: no force
    hi = max(rest_indentation(block, foundation), 1e-12) + b * abs(math.sin(theta0))
    for _ in range(200):
        if excess(hi) > 0.0:
            break
        hi = lo + 2.0 * (hi - lo)
    else:
        raise ValueError(f"the softening bed (foundation.eps = {float(foundation.eps):.3g} m-2) cannot carry the block "
                         f"at the initial rotation theta0 = {float(theta0):.4g} rad: start from a smaller rotation")
    return float(optimize.brentq(excess, lo, hi, xtol=1e-15, rtol=1e-14))


class _KernelIntegrator(ChunkIntegrator):
    """:func:`screening.kernels.mcs_kernels.chunk_integrator` with the model code and records bound; ``rest``:
    the coupled model's rest state, from which the exact integrator's propagator is built per input grid."""

    def __init__(self, code, sdof, params, rest=None):
        self.code = code
        self.sdof = sdof
        self.params = params[None]
        self.rest = rest
        self.integrate = kern.chunk_integrator(sdof.record.dtype)
        self._propagators = {}

    def propagator(self, dt_grid):
        """The :func:`~screening.kernels.mcs_kernels.full_contact_propagator` of the grid ``dt_grid`` [s] (once
        per grid), or :data:`~screening.kernels.mcs_kernels.NO_PROPAGATOR` for another integrator."""
        if int(self.params[0]["integrator"]) != kern.INTEGRATOR_EXACT or self.rest is None:
            return kern.NO_PROPAGATOR
        if dt_grid not in self._propagators:
            self._propagators[dt_grid] = kern.full_contact_propagator(self.params[0], self.rest, float(dt_grid))
        return self._propagators[dt_grid]

    def __call__(self, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                 out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min,
                 vertical=None, census=None):
        vacc, vrate = (kern.NO_VERTICAL, kern.NO_VERTICAL) if vertical is None else vertical
        census = np.zeros((0, len(kern.CENSUS)), dtype=np.int64) if census is None else census
        self.integrate(self.code, self.sdof.damping_stiffness, self.sdof.record, (acc, vacc), (acc_dot, vrate), dt_grid,
                       t_out,
                       self.params, y_init, scale, rtol, h_max, max_steps, out_theta, out_theta_dot, out_z,
                       out_z_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min,
                       self.propagator(dt_grid), census)


class _KernelModel(MonteCarloModel):
    """A model of the 4-state kernel of :mod:`screening.kernels.mcs_kernels` (``code``: its model code)."""

    code = -1

    def state_scales(self, block, foundation):
        return state_scales(block, foundation)

    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        cond = condensations.get(condensation if self.uses_condensation else KERNEL_CONDENSATION)
        rest = self.initial_state(block, foundation) if self.code == kern.MODEL_COUPLED else None
        return _KernelIntegrator(self.code, cond.sdof_kernel(block, foundation),
                                 kern.model_record(block, foundation, cond, max_flight_time, sample_integrator), rest)


class CoupledModel(_KernelModel):
    """The full coupled rocking/vertical model (module docstring)."""

    name = "coupled"
    description = "coupled rocking and vertical motion, exact contact resultants (eqs. 7-8)"
    #: Tighter than the condensed model: near overturning its samples are sensitive to integration
    #: error (at 1e-6 about 4 % of the samples of the paper's S0 = 2.4e-3 case switch between
    #: overturned and survived against a 1e-9 reference; at 1e-7 the survivors' peak variance moves
    #: by ~0.15 standard errors).
    default_rtol = 1e-7
    vertical_state = True
    code = kern.MODEL_COUPLED
    flag_code = 0
    escalation_code = EscalationModel.coupled
    step_cost_s = 0.41e-6          # fitted with the escalation's grid terms (analysis.escalation, STEP_COST_S)

    def initial_state(self, block, foundation, theta0=0.0, theta_dot0=0.0):
        return np.array([theta0, theta_dot0, quasi_static_indentation(block, foundation, theta0), 0.0])

    def uplift_threshold(self, block, foundation, condensation):
        return exact_uplift_threshold(block, foundation)


class CondensedModel(_KernelModel):
    """The condensed SDOF with a condensation's ``C(theta)``, ``K(theta)`` (module docstring)."""

    name = "condensed"
    description = "condensed SDOF (eq. 22) with a condensation's C(theta), K(theta)"
    default_rtol = 1e-6
    uses_condensation = True
    code = kern.MODEL_CONDENSED
    flag_code = 1
    escalation_code = EscalationModel.condensed
    step_cost_s = 0.14e-6
    best_method = BestMethod.condensed_monte_carlo

    def check(self, block, foundation, condensation):
        condensations.get(condensation).check(block, foundation)

    def initial_state(self, block, foundation, theta0=0.0, theta_dot0=0.0):
        return np.array([theta0, theta_dot0, 0.0, 0.0])

    def uplift_threshold(self, block, foundation, condensation):
        return float(condensations.get(condensation).uplift_threshold(block, foundation)), {}

    def dataset_attributes(self, block, foundation, condensation):
        cond = condensations.get(condensation)
        attrs = dict(condensation=cond.name, m_sdof=float(block.m_sdof),
                     C1=float(cond.damping_at_rest(block, foundation)))
        if type(cond).capacity_angle is not condensations.Condensation.capacity_angle:
            attrs["theta_capacity"] = float(cond.capacity_angle(block, foundation))
        return attrs


COUPLED = get("coupled")
CONDENSED = get("condensed")

from screening.solvers import stiff_bed  # noqa: E402,F401  (registers "stiff_bed")
from screening.solvers import stiff_bed_fast  # noqa: E402,F401  (registers "stiff_bed_fast")
