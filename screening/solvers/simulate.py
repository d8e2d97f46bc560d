"""Deterministic response of a block on its bed to one ground-motion record.

:func:`simulate` integrates the coupled model (eqs. 7–8 with the exact contact resultants)
or the condensed SDOF (eq. 22) for a given, uniformly sampled horizontal ground
acceleration, with the same compiled adaptive Dormand–Prince 5(4) integrator as the Monte
Carlo engine (:func:`screening.kernels.mcs_kernels.integrate_sample`): one "sample" whose input
row is the record.

Sign convention
---------------
The record is taken in the usual convention: ``a_g(t) > 0`` accelerates the ground towards
``+x``, so the block feels the inertial (d'Alembert) force ``-m a_g`` towards ``-x``.  The axis
``+x`` points from edge ``A`` to edge ``B`` of the base, and ``theta > 0`` presses edge ``B``
(``+x`` side) into the bed and lifts edge ``A`` (docs/method.md, "Coupled equations of
motion").  Eq. (8) as implemented has ``+ m h x_g'' cos(theta)`` on its right-hand side, so
its ``x_g''`` is the *inertial* acceleration of the block's frame: the kernel's input is

    x_g''(t) = -a_g(t),

converted once here.  A positive ground-acceleration pulse therefore first tips the block
towards ``-x`` (``theta < 0``, edge ``A`` pressed), as a block on a braking truck tips forward.
The response to ``-a_g`` is the mirror image: ``theta``, ``theta'`` change sign and ``z_cb`` is
unchanged (the model is symmetric about the block's axis).

A record's vertical component ``a_v(t)`` (positive up, :attr:`screening.core.records.Record.vertical`)
enters the models as a change of gravity, ``g -> g + a_v(t)`` in the block's frame
(docs/method.md, "Vertical ground acceleration"); ``vertical=False`` leaves it out.  Where
``g + a_v < 0`` the ground pulls away faster than the block falls: the coupled model flies and
lands; the condensed and stiff-bed models stop (diverged, reason ``lift_off``).

Between samples the input is the cubic Hermite interpolant of the record with slopes from
second-order finite differences (``numpy.gradient``); after the end of the record (if
``t_end`` is longer) the ground is at rest.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from screening.core import condensation as condensations
from screening.core.physics.contact import (REGIME_FULL_CONTACT, REGIME_UPLIFT_NEGATIVE, REGIME_UPLIFT_POSITIVE,
                                            contact_regime)
from screening.core.records import Record
from screening.solvers import mc_registry
from screening.kernels import mcs_kernels as kern
from screening.solvers.datasets import finish
from screening.solvers.mc_models import quasi_static_indentation  # noqa: F401  (its former home)
from screening.solvers.model_choice import resolve as resolve_model
from screening.solvers.montecarlo import check_scalar_models
from screening.core.status import ContactRegime, DIVERGENCE_TEXT, DivergenceReason, flag_attributes
from screening.solvers.schema import cf, declare
from screening.core.validation import check_integer, check_scalar
from screening.core import limits

__all__ = ["simulate"]

#: The variables of a deterministic simulation of one record (:func:`simulate`), declared here.
SIMULATION = declare("simulation", {
    "theta": cf("rad", "rocking rotation (theta > 0 presses edge B, the +x side, into the bed)"),
    "theta_dot": cf("rad s-1", "rocking angular velocity"),
    "z_cb": cf("m", "indentation of the base centre into the bed (coupled model; 0 condensed)"),
    "z_cb_dot": cf("m s-1", "indentation rate of the base centre (coupled model; 0 condensed)"),
    "contact_regime": {**flag_attributes(ContactRegime, "contact regime"), "units": "1"},
    "ground_acceleration": cf("m s-2", "horizontal ground acceleration (usual convention: > 0 towards +x)"),
    "vertical_ground_acceleration": cf("m s-2", "vertical ground acceleration that entered the model (> 0 up: "
                                                "g + a_v acts on the block)"),
    "lift_off": cf("1", "g + a_v < 0 somewhere in the record: the ground pulls away from the block (coupled: "
                        "flight; condensed and stiff-bed: stopped, diverged with reason lift_off)"),
    "peak_abs_theta": cf("rad", "peak |theta| over the record (up to overturning or divergence)"),
    "overturned": cf("1", "the block overturned (|theta| > atan(b/h))"),
    "diverged": cf("1", "the integration diverged"),
    "overturning_time": cf("s", "time at which |theta| first exceeded atan(b/h) (NaN if it did not)"),
})

#: Most sub-intervals on which the overturning time is located.
MAX_OVERTURN_RESOLUTION = 100_000

#: Code of ``contact_regime`` after overturning or divergence (no state).
REGIME_NONE = int(ContactRegime.none)

SIGN_CONVENTION = ("ground_acceleration > 0 accelerates the ground towards +x (edge A -> edge B); theta > 0 "
                   "presses edge B (+x side) into the bed; the kernel's x_g'' of eq. (8) is -ground_acceleration")


def simulation_times(record, t_end=None, output_dt=None, t_end_name="t_end"):
    """The time grid of :func:`simulate` on a record, checked before anything is allocated.

    Parameters
    ----------
    record : screening.core.records.Record
        The ground-acceleration record (its ``dt`` [s] and ``duration`` [s]).
    t_end : float, optional
        End time [s] > 0 (default the record's duration).
    output_dt : float, optional
        Output step [s] > 0 (default the record's ``dt``).
    t_end_name : str, optional
        How ``t_end`` is spelled in messages (``"--t-end"`` for the command line).

    Returns
    -------
    t_end : float
        [s].
    output_dt : float
        [s].
    n_out : int
        Number of output instants, at most :data:`~screening.core.limits.MAX_RECORD_SAMPLES`.

    Raises
    ------
    ValueError
        One line naming the parameter when a value or the number of steps is out of range.

    Notes
    -----
    The outputs are ``0, output_dt, ...`` up to ``t_end``; the record is read as the ground acceleration
    of eq. (8) in [1] and is zero after its end.

    """
    t_end = check_scalar(t_end_name, record.duration if t_end is None else t_end, lower=0.0)
    output_dt = record.dt if output_dt is None else check_scalar("output_dt", output_dt, lower=0.0)
    top = limits.MAX_RECORD_SAMPLES
    for name, step in ((t_end_name, record.dt), ("output_dt", output_dt)):
        steps = limits.output_steps(t_end, step)
        if not steps < top:
            raise ValueError(f"parameter '{name}': t_end / {'dt' if step is record.dt else 'output_dt'} = "
                             f"{steps:.3g} steps; at most {top - 1} (t_end = {t_end:g} s)")
    return t_end, output_dt, int(math.floor(t_end / output_dt + 1e-9)) + 1


def vertical_text(record, used):
    """What became of ``record``'s vertical component (the ``vertical_ground_motion`` attribute)."""
    if record.vertical is None:
        return "none (the record has no vertical component)"
    if not used:
        return "left out (vertical = false): the models took the horizontal component only"
    return "used: g + a_v(t) acts on the block and its bed (docs/method.md, 'Vertical ground acceleration')"


def _input(ground_acceleration, dt):
    if isinstance(ground_acceleration, Record):
        if dt is not None and not math.isclose(float(dt), ground_acceleration.dt, rel_tol=1e-9):
            raise ValueError(f"parameter 'dt' ({dt!r}) differs from the record's time step ({ground_acceleration.dt!r})")
        return ground_acceleration
    if dt is None:
        raise ValueError("parameter 'dt' [s] is required when 'ground_acceleration' is an array")
    arr = np.asarray(ground_acceleration, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"parameter 'ground_acceleration' must be one-dimensional (got shape {arr.shape})")
    return Record(arr, dt, name="record")


def simulate(block, foundation, ground_acceleration, dt=None, model="coupled", theta0=0.0, theta_dot0=0.0,
             condensation=condensations.DEFAULT_CONDENSATION, t_end=None, output_dt=None, rtol=None, h_max=None,
             max_steps=20_000_000, max_flight_time=0.5, overturn_resolution=200, vertical=True):
    """Response of a block on a flexible bed to one ground-acceleration record.

    Parameters
    ----------
    block : :class:`~screening.core.model.Block` with scalar fields (SI).
    foundation : :class:`~screening.core.model.Foundation` with scalar fields (SI).
    ground_acceleration : :class:`~screening.core.records.Record` or 1-d array [m/s2], horizontal ground
        acceleration in the usual convention (positive: ground accelerates towards ``+x``; see
        the module docstring), sampled at ``dt``.
    dt : time step of the samples [s] (required for an array; taken from a Record).
    model : a registered Monte Carlo model or its name (:mod:`screening.solvers.mc_registry`):
        ``"coupled"`` (eqs. 7–8, exact contact), ``"condensed"`` (eq. 22 with ``condensation``) or
        ``"stiff_bed"`` (:mod:`screening.solvers.stiff_bed`).
    theta0 : initial rotation [rad], ``|theta0| <`` slenderness.
    theta_dot0 : initial angular velocity [rad/s].
    condensation : condensation of the condensed model (default
        :data:`screening.core.condensation.DEFAULT_CONDENSATION`; ``"paper"``, ``"cubic"``, ``"virtual_work"``);
        a model that does not read it accepts the default or ``"paper"`` only, as in :func:`screening.monte_carlo`
        (:meth:`~screening.solvers.mc_registry.MonteCarloModel.check`).
    t_end : end time [s] (default: the record's duration; longer: ground at rest afterwards).
    output_dt : output step [s] (default ``dt``).
    rtol : relative tolerance (default :data:`screening.solvers.montecarlo.DEFAULT_RTOL` of the model).
    h_max : largest integration step [s] (default ``min(0.005 s, dt)``).
    max_steps, max_flight_time : as for :func:`screening.monte_carlo`.
    overturn_resolution : after overturning, the last output interval is integrated again on this
        many sub-intervals to locate the overturning time.
    vertical : use the record's vertical component when it has one (True, default), or leave it out.

    Returns
    -------
    xarray.Dataset on ``t`` [s] with ``theta`` [rad], ``theta_dot`` [rad s-1], ``z_cb`` [m] and
    ``z_cb_dot`` [m s-1] (the coupled model's vertical state; zero for the condensed model),
    ``contact_regime`` (flags: full contact, uplift theta > 0, uplift theta < 0, flight; -1 after
    overturning; condensed: uplift when ``|theta| > theta_ul``), the input ``ground_acceleration``
    [m s-2], and scalars ``peak_abs_theta`` [rad], ``overturned``, ``diverged``,
    ``overturning_time`` [s] (NaN if it did not overturn), ``theta_ul``, ``slenderness``.  After
    overturning or divergence the states are NaN.  ``attrs["status"]``: ``"ok"``,
    ``"overturned"`` or ``"diverged: <reason>"``; ``attrs["sign_convention"]`` states the convention.
    ``attrs["vertical_ground_motion"]`` says whether a vertical component was used; when it was,
    ``vertical_ground_acceleration`` [m s-2] holds it and ``lift_off`` whether ``g + a_v < 0`` anywhere.

    Notes
    -----
    ``"coupled"``: the equations of motion of the block on its bed, eqs. (7)-(8) in [1] with the exact
    contact resultants of eqs. (5)-(6) (:func:`screening.core.physics.contact.law_resultants`);
    ``"condensed"``: eq. (22) with the condensation's ``C(theta)``, ``K(theta)``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import numpy as np
    >>> from screening import Block, Foundation, simulate
    >>> t = np.arange(0.0, 2.0, 0.01)
    >>> ds = simulate(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...               2.0 * np.sin(2 * np.pi * 2.0 * t), dt=0.01, model="condensed", condensation="paper")
    >>> ds.attrs["status"], f"{float(ds['peak_abs_theta']):.3e}"
    ('overturned', '1.669e-01')
    """
    record = _input(ground_acceleration, dt)
    check_scalar_models(block, foundation, purpose="simulate")
    mc = resolve_model(model, block, foundation)        # "auto": no rule is measured on records (the fallback)
    model = mc.name
    cond = condensations.get(condensation)
    dt = record.dt
    theta0 = check_scalar("theta0", theta0)
    theta_dot0 = check_scalar("theta_dot0", theta_dot0)
    slender = float(block.slenderness)
    if abs(theta0) >= slender:
        raise ValueError(f"parameter 'theta0' must be smaller in magnitude than the slenderness angle "
                         f"{slender:.6g} rad (got {theta0!r})")
    t_end, output_dt, n_out = simulation_times(record, t_end, output_dt)
    rtol = mc.default_rtol if rtol is None else check_scalar("rtol", rtol, lower=0.0, upper=limits.MAX_RTOL,
                                                              upper_inclusive=True)
    h_max = min(0.005, dt) if h_max is None else check_scalar("h_max", h_max, lower=0.0)
    max_steps = check_integer("max_steps", max_steps, 1)
    max_flight_time = check_scalar("max_flight_time", max_flight_time, lower=0.0)
    overturn_resolution = check_integer("overturn_resolution", overturn_resolution, 1, MAX_OVERTURN_RESOLUTION)
    mc.check(block, foundation, cond)                 # what the model cannot use: its own check, as monte_carlo
    mc_registry.check_validity(mc, block, foundation)

    # input on the record grid, padded with rest to cover t_end (plus two samples for the interpolant)
    times = output_dt * np.arange(n_out)
    n_grid = max(record.acceleration.size, int(math.ceil(times[-1] / dt)) + 2)
    a_g = np.zeros(n_grid)
    a_g[:record.acceleration.size] = record.acceleration
    kernel_acc = np.ascontiguousarray(-a_g[None, :])                        # the one sign conversion
    kernel_rate = np.ascontiguousarray(np.gradient(kernel_acc[0], dt, edge_order=2)[None, :])
    use_vertical = bool(vertical) and record.vertical is not None
    vertical_input = None
    if use_vertical:
        a_v = np.zeros(n_grid)
        a_v[:record.vertical.size] = record.vertical                         # positive up, no sign change
        vertical_input = (np.ascontiguousarray(a_v[None, :]),
                          np.ascontiguousarray(np.gradient(a_v, dt, edge_order=2)[None, :]))

    y0 = mc.initial_state(block, foundation, theta0, theta_dot0)
    integrate = mc.integrator(block, foundation, cond, max_flight_time)
    scales = rtol * mc.state_scales(block, foundation)

    def run(t_out, y_init):
        out = [np.empty((1, t_out.size)) for _ in range(4)]
        uplift = np.zeros((1, t_out.size), dtype=np.bool_)
        peak, h_min = np.zeros(1), np.zeros(1)
        status, reason, n_acc, n_rej = (np.zeros(1, dtype=np.int64) for _ in range(4))
        integrate(kernel_acc, kernel_rate, dt, np.ascontiguousarray(t_out), np.ascontiguousarray(y_init, dtype=float),
                  scales, rtol, h_max, int(max_steps), *out, uplift, peak, status, reason, n_acc, n_rej, h_min,
                  **({} if vertical_input is None else {"vertical": vertical_input}))
        return [o[0] for o in out], int(status[0]), int(reason[0]), float(peak[0]), int(n_acc[0] + n_rej[0])

    (theta, theta_dot, z_cb, z_cb_dot), status, reason, peak, n_steps = run(times, y0)
    overturned = status == kern.STATUS_OVERTURNED
    diverged = status == kern.STATUS_DIVERGED
    t_over = math.nan
    if overturned:
        i = int(np.flatnonzero(np.isfinite(theta))[-1])
        fine = times[i] + np.linspace(0.0, output_dt, int(overturn_resolution) + 1)
        state = np.array([theta[i], theta_dot[i], z_cb[i], z_cb_dot[i]])
        (f_theta, *_), _, _, _, _ = run(fine, state)
        bad = np.flatnonzero(~np.isfinite(f_theta))
        t_over = float(fine[bad[0]]) if bad.size else float(times[min(i + 1, n_out - 1)])

    finite = np.isfinite(theta)
    theta_ul = mc.uplift_threshold(block, foundation, cond)[0]
    if mc.vertical_state:
        regime = np.where(finite, contact_regime(np.nan_to_num(theta), np.nan_to_num(z_cb), float(block.b)),
                          REGIME_NONE)
    else:
        up = np.where(theta >= 0.0, REGIME_UPLIFT_POSITIVE, REGIME_UPLIFT_NEGATIVE)
        regime = np.where(finite, np.where(np.abs(np.nan_to_num(theta)) > theta_ul, up, REGIME_FULL_CONTACT),
                          REGIME_NONE)
    acc_out = np.interp(times, dt * np.arange(n_grid), a_g)

    status_text = "ok"
    if overturned:
        status_text = "overturned"
    elif diverged:
        status_text = f"diverged: {DIVERGENCE_TEXT[DivergenceReason(reason)]}"
    coords = {"t": ("t", times)}
    for name in ("m", "b", "h", "I_cm", "g"):
        coords[name] = ((), float(getattr(block, name)))
    coords["k"] = ((), float(foundation.k))
    coords[foundation.contact_law.parameter] = ((), float(foundation.damping))
    coords["eps"] = ((), float(foundation.eps))
    data = {
        "theta": ("t", theta), "theta_dot": ("t", theta_dot), "z_cb": ("t", z_cb), "z_cb_dot": ("t", z_cb_dot),
        "contact_regime": ("t", regime.astype(np.int8)), "ground_acceleration": ("t", acc_out),
        "peak_abs_theta": ((), peak), "overturned": ((), bool(overturned)), "diverged": ((), bool(diverged)),
        "overturning_time": ((), t_over), "theta_ul": ((), theta_ul), "slenderness": ((), slender),
    }
    attrs = {
        "title": f"rocking response to record {record.name!r} ({model} model)",
        "status": status_text, "model": model, "contact": foundation.law, "record": record.name,
        "record_source": record.source, "record_units_in": record.units_in, "record_dt": dt,
        "sign_convention": SIGN_CONVENTION, "theta0": theta0, "theta_dot0": theta_dot0,
        "initial_z_cb": float(y0[2]), "rtol": rtol, "h_max": h_max, "n_steps": n_steps,
        "integrator": "adaptive Dormand-Prince 5(4) (screening.kernels.mcs_kernels), steps land on output times; "
                      "input: cubic Hermite of the record with finite-difference slopes",
        "overturning_time_resolution": output_dt / int(overturn_resolution) if overturned else math.nan,
    }
    if mc.uses_condensation:
        attrs["condensation"] = cond.name
    attrs["vertical_ground_motion"] = vertical_text(record, use_vertical)
    if use_vertical:
        data["vertical_ground_acceleration"] = ("t", np.interp(times, dt * np.arange(n_grid), vertical_input[0][0]))
        data["lift_off"] = ((), bool(np.any(float(block.g) + record.vertical < 0.0)))
    return finish(xr.Dataset(data, coords=coords, attrs=attrs), table=SIMULATION)

