"""Every status code the package stores or returns: one enum per code space.

Compiled kernels read the members as integer constants (numba supports ``IntEnum``); files store
the integer with CF ``flag_values`` / ``flag_meanings`` made by :func:`flag_attributes`.
Nothing else in the package spells a status number.

Method and how it is checked: ``docs/method.md#status-flags``.
"""

from __future__ import annotations

import enum

import numpy as np


class PointStatus(enum.IntEnum):
    """Outcome of the linearized moment integration of one parameter point."""

    #: the sweep task holding the point failed even after its retries (no solver result)
    task_failed = -1
    #: integrated to the end of the record
    ok = 0
    #: the equivalent stiffness reached zero: the linearized model topples
    k_eq_negative = 1
    #: sigma_theta passed the slenderness angle: near-toppling, the Gaussian closure is meaningless
    sigma_theta_beyond_slenderness = 2
    #: the step budget (max_steps) ran out
    step_budget_exhausted = 3
    #: the moments could not be kept finite
    non_finite_moments = 4
    #: the point's scales (uplift angle squared, filter frequency cubed, ...) under- or overflow
    #: float64: not integrated
    beyond_float_range = 5


class SampleStatus(enum.IntEnum):
    """Outcome of one Monte Carlo sample."""

    ok = 0
    overturned = 1
    diverged = 2


class DivergenceReason(enum.IntEnum):
    """Why a Monte Carlo sample was stopped as diverged."""

    none = 0
    non_finite_state = 1
    long_flight = 2
    out_of_bounds = 3
    step_underflow = 4
    step_budget = 5
    no_equilibrium = 6


#: Plain-language text of the divergence reasons (messages to users).
DIVERGENCE_TEXT = {
    DivergenceReason.none: "none",
    DivergenceReason.non_finite_state: "non-finite state",
    DivergenceReason.long_flight: "flight longer than max_flight_time",
    DivergenceReason.out_of_bounds: "state out of physical bounds",
    DivergenceReason.step_underflow: "step size underflow",
    DivergenceReason.step_budget: "step budget exhausted",
    DivergenceReason.no_equilibrium: "|theta| beyond the capacity angle (no quasi-static equilibrium)",
}


class SampleState(enum.IntEnum):
    """State of a stored Monte Carlo sample at the end of the record (spot checks)."""

    standing = 0
    overturned = 1
    diverged_or_failed = 2


class SpotStatus(enum.IntEnum):
    """Outcome of a Monte Carlo spot check of a sweep."""

    ok = 0
    task_failed = 1


class Trust(enum.IntEnum):
    """How far to trust a linearized point (:mod:`screening.analysis.trust`, docs/method.md#trusting-a-point)."""

    #: the calibration shows SL within 10 % of the coupled model in this regime (band within 25 %)
    trusted = 0
    #: no evidence either way, or errors between 10 % and 50 %: check with coupled Monte Carlo
    check = 1
    #: SL stopped, locks in, is near toppling, or the calibration shows errors beyond 50 % / overturning
    untrusted = 2


class BestMethod(enum.IntEnum):
    """Where a point's best estimate comes from (``[accuracy]``, :mod:`screening.analysis.correction`)."""

    #: the linearization itself: the trust rule promises the target accuracy there
    linearization = 0
    #: the linearization times the correction learned from the escalated Monte Carlo points
    corrected_linearization = 1
    #: condensed Monte Carlo at the point (only the linearization was in doubt)
    condensed_monte_carlo = 2
    #: coupled Monte Carlo at the point
    coupled_monte_carlo = 3
    #: no estimate can be vouched for: the correction does not reach the point (or failed its leave-one-out
    #: check) and no Monte Carlo ran there; the value is the linearization's, with a NaN standard error
    unreliable = 4


class EscalationModel(enum.IntEnum):
    """Monte Carlo model run at an escalated point."""

    condensed = 0
    coupled = 1


class TargetMet(enum.IntEnum):
    """Whether an escalated point's Monte Carlo reached the target's standard error (``target / 2`` of its peak)."""

    #: the budget ran out (or a run failed) before the standard error came down to ``target / 2``
    short_of_target = 0
    target_met = 1


class ContactRegime(enum.IntEnum):
    """Contact regime of the coupled model's base."""

    #: no regime (after overturning or divergence)
    none = -1
    full_contact = 0
    uplift_positive = 1
    uplift_negative = 2
    flight = 3


def flag_attributes(code_space, long_name, dtype=np.int8):
    """CF flag attributes ``{long_name, flag_values, flag_meanings}`` of an enum or a list of its members
    (sorted by value)."""
    members = sorted(code_space, key=int)
    return {"long_name": long_name,
            "flag_values": np.array([int(m) for m in members], dtype=dtype),
            "flag_meanings": " ".join(m.name for m in members)}
