"""Every variable on the grid of a sweep result, declared once.

One :class:`Output` per variable: its name, where it lies (``shape``: the histories on
``(grid..., t)``, the per-point values on the grid, the exceedance probabilities on
``(grid..., threshold)``), its type in the file, its CF attributes, the value a point gets when its
task failed, when a result holds it and the stage of a run that fills it.  The solvers
(:mod:`screening.solvers.moments`, :mod:`screening.solvers.datasets`), the batch task
(:mod:`screening.sweep.execution`), both result formats (:mod:`screening.io.writer`,
:mod:`screening.io.zarrfile`), :mod:`screening.solvers.schema` and ``screening info``
(:mod:`screening.report.text`) read these declarations; none keeps its own list of names.  The
compiled kernels know nothing of them: they fill arrays they are handed.

Adding a variable to every sweep result is one :class:`Output` here plus the code of its stage that
fills it (docs/architecture.md, "Adding an output variable").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from screening.core.status import PointStatus, Trust, flag_attributes

__all__ = []

#: Who fills a variable: the moment solver (``linearize``), the block's model (``model``), the trust rule
#: (:mod:`screening.analysis.trust`), the intensity measures of the input and the probability that rocking
#: starts (:mod:`screening.analysis.intensity`), the per-point inputs a study derives (``inputs``) and the
#: probabilities of overturning and exceedance (:mod:`screening.sweep.probabilities`).
STAGES = ("linearize", "model", "trust", "intensity", "rocking", "inputs", "probabilities")

#: When a result holds a variable: always; the histories the study stores (``[output]``); with
#: ``[accuracy]`` or ``[fragility]`` (``probabilities``); with ``[fragility]``; where the study derives the input.
WHEN = ("always", "histories", "probabilities", "fragility", "derived")


@dataclass(frozen=True)
class Output:
    """One variable on the grid of a sweep result.

    ``shape``: ``"history"`` (grid dimensions, then ``t``), ``"point"`` (the grid dimensions) or
    ``"threshold"`` (grid dimensions, then ``threshold``).  ``dtype``: its numpy type in the file (and in
    the batch arrays).  ``attrs``: its CF attributes.  ``failed``: the value of a point whose task failed
    (for a flag, also what a zarr chunk that was never written reads as).  ``stage``: who fills it
    (:data:`STAGES`); ``when``: which results hold it (:data:`WHEN`).  ``client``: the client keeps it
    for every point (spot selection, run summary); ``info``: ``screening info`` summarises it;
    ``linearize``: :func:`screening.linearize` returns it too.
    """

    name: str
    stage: str
    dtype: str
    attrs: dict = field(compare=False, repr=False)
    shape: str = "point"
    when: str = "always"
    failed: float = math.nan
    client: bool = False
    info: bool = False
    linearize: bool = False

    @property
    def fill(self):
        """The netCDF ``_FillValue``: NaN for floats, none (``False``) for flags and counts."""
        return np.dtype(self.dtype).type(np.nan) if np.dtype(self.dtype).kind == "f" else False

    @property
    def is_flag(self):
        return "flag_values" in self.attrs

    def failed_array(self, n, nt=0, n_thresholds=0):
        """The values of ``n`` points whose task failed (``nt`` output times, ``n_thresholds`` thresholds)."""
        trailing = {"history": (nt,), "threshold": (n_thresholds,)}.get(self.shape, ())
        return np.full((n,) + trailing, self.failed, dtype=self.dtype)

    def cast(self, value, shape):
        """``value`` (a solver array over the points ``shape``, or values that broadcast to it) flat over the
        points, in this variable's type."""
        if self.shape == "point":
            return np.broadcast_to(value, shape).reshape(-1).astype(self.dtype)
        return np.asarray(value).reshape(math.prod(shape), -1).astype(self.dtype)


def _v(units, long_name, **extra):
    return {"units": units, "long_name": long_name, **extra}


def _history(name, units, long_name):
    return Output(name, "linearize", "f4", _v(units, long_name), shape="history", when="histories", linearize=True)


_BAND = ("ground motion band-limited to the excitation's band_limit_hz (global attribute; default 25 Hz), "
         "whatever the bed")
_OPEN_BAND = ("the 90 % interval of the error atlas model (docs/error_atlas.md); -1 (low) or inf (high) where "
              "the interval reaches the range the model was fitted on: open, the point untrusted")
_PROBABILITY_SE = ("(Monte Carlo: binomial, Agresti-Coull, or the two-fidelity estimate's where esc_estimator "
                   "says multifidelity; Gaussian: from the band of the moments; NaN where p_source is unreliable)")

#: The variables on the grid of a sweep result, in file order.
GRID_OUTPUTS = (
    # the moment solver: histories (float32) and summaries
    _history("var_theta", "rad2", "variance of the rocking rotation"),
    _history("var_theta_dot", "rad2 s-2", "variance of the rocking angular velocity"),
    _history("cov_theta_theta_dot", "rad2 s-1", "covariance of rocking rotation and angular velocity"),
    _history("c_eq", "N m s rad-1", "equivalent linear rocking damping"),
    _history("k_eq", "N m rad-1", "equivalent linear rocking stiffness"),
    _history("p_uplift", "1", "probability of uplift (|theta| > theta_ul)"),
    Output("status", "linearize", "i1", flag_attributes(PointStatus, "solver status of the point"),
           failed=PointStatus.task_failed, client=True, linearize=True),
    Output("sl_trust", "trust", "i1", flag_attributes(Trust, "trust in the linearized peak var_theta "
                                                             "(docs/trust.md)"),
           failed=Trust.untrusted, client=True),
    Output("t_stop", "linearize", "f8", _v("s", "time at which the integration of the point stopped"), linearize=True),
    Output("peak_var_theta", "linearize", "f8", _v("rad2", "peak variance of the rocking rotation"), info=True,
           linearize=True),
    Output("t_peak_var_theta", "linearize", "f8", _v("s", "time of the peak rotation variance"), info=True,
           linearize=True),
    Output("peak_p_uplift", "linearize", "f8", _v("1", "peak probability of uplift"), client=True, info=True,
           linearize=True),
    Output("min_k_eq", "linearize", "f8", _v("N m rad-1", "minimum equivalent linear rocking stiffness"), info=True,
           linearize=True),
    # the block and its condensation
    Output("theta_ul", "model", "f8", _v("rad", "static uplift threshold angle of the condensation")),
    Output("slenderness", "model", "f8", _v("rad", "slenderness angle atan(b/h), the rigid-block overturning angle")),
    # the trust rule's predicted error band
    Output("sl_error_low", "trust", "f8", _v("1", "lower end of the predicted relative error of SL's peak var_theta "
                                                  "against the coupled model (SL / MCS - 1)", note=_OPEN_BAND)),
    Output("sl_error_high", "trust", "f8", _v("1", "upper end of the predicted relative error of SL's peak var_theta "
                                                   "against the coupled model (SL / MCS - 1)", note=_OPEN_BAND)),
    # intensity measures of each point's input
    Output("pga_median", "intensity", "f8", _v("m s-2", "median peak ground acceleration of the modulated input "
                                                        "(2000 records synthesised per excitation shape)", note=_BAND)),
    Output("rms_acceleration", "intensity", "f8", _v("m s-2", "root mean square ground acceleration over the record",
                                                     note=_BAND)),
    Output("arias_intensity", "intensity", "f8", _v("m s-1", "Arias intensity pi/(2 g) int a2 dt (expected value for "
                                                             "stochastic inputs)", note=_BAND)),
    Output("uplift_acceleration", "rocking", "f8", _v("m s-2", "quasi-static ground acceleration at which the block "
                                                               "starts to rock (g b/(3 h) on a linear Winkler bed)")),
    Output("p_rocking_start", "rocking", "f8", _v("1", "probability that the ground acceleration exceeds the bed's "
                                                       "uplift acceleration at least once during the record "
                                                       "(random-vibration theory, closed form)")),
    # inputs the study derives per point (S0 from a target PGA)
    Output("S0", "inputs", "f8", _v("m2 s-3", "two-sided PSD level of the driving white noise, E[xi xi] = 2 pi S0 "
                                              "delta", note="from the target median PGA of the grid point "
                                                            "(excitation.pga)"), when="derived"),
    # solver step counts
    Output("n_steps", "linearize", "i4", _v("1", "number of solver steps (accepted and rejected)"), failed=0,
           linearize=True),
    Output("n_rejected", "linearize", "i4", _v("1", "number of rejected solver steps"), failed=0),
    # probabilities (the linearization's, replaced where Monte Carlo ran: screening.sweep.probabilities)
    Output("p_exceed", "probabilities", "f8", _v("1", "probability that |theta| exceeds the threshold during the "
                                                      "record"), shape="threshold", when="fragility"),
    Output("p_exceed_se", "probabilities", "f8", _v("1", f"standard error of p_exceed {_PROBABILITY_SE}"),
           shape="threshold", when="fragility"),
    Output("p_overturn", "probabilities", "f8", _v("1", "probability that the block overturns during the record "
                                                        "(|theta| > atan(b/h)), from the model named by p_source"),
           when="probabilities"),
    Output("p_overturn_se", "probabilities", "f8", _v("1", f"standard error of p_overturn {_PROBABILITY_SE}"),
           when="probabilities"),
)

#: The declarations by name.
OUTPUTS = {o.name: o for o in GRID_OUTPUTS}

#: The histories the moment solver can return, in file order.
HISTORY_VARIABLES = tuple(o.name for o in GRID_OUTPUTS if o.shape == "history")


def of_stage(*stages):
    """The declarations filled by ``stages``, in file order.

    Each stage of a run (:data:`STAGES`) fills its own variables; the batch task asks here which.

    Parameters
    ----------
    *stages : str
        Names from :data:`STAGES` (``"linearize"``, ``"model"``, ``"trust"``, ...).

    Returns
    -------
    tuple of Output
        The :class:`Output` declarations of those stages, in file order.

    """
    return tuple(o for o in GRID_OUTPUTS if o.stage in stages)


def selected(histories=HISTORY_VARIABLES, derived=(), probabilities=False, fragility=False):
    """The declarations a result holds: the ``histories`` it stores, the ``derived`` inputs, the probabilities
    (``probabilities``: with ``[accuracy]`` or ``[fragility]``) and the exceedance ones (``fragility``), in
    file order (the histories in the order of ``histories``).

    Parameters
    ----------
    histories : sequence of str, optional
        The histories the study stores (``[output]``), from :data:`HISTORY_VARIABLES`; default all.
    derived : sequence of str, optional
        The inputs the study derives per point (e.g. ``("S0",)`` from a target PGA).
    probabilities : bool, optional
        Whether the result holds ``p_overturn`` and its error (``[accuracy]`` or ``[fragility]``).
    fragility : bool, optional
        Whether it also holds ``p_exceed`` on ``threshold`` (``[fragility]``; implies ``probabilities``).

    Returns
    -------
    tuple of Output
        The declarations, histories first in the order asked, then the others in file order.

    """
    wanted = {"always": True, "probabilities": probabilities or fragility, "fragility": fragility}
    chosen = [OUTPUTS[name] for name in histories]
    chosen += [o for o in GRID_OUTPUTS if o.when not in ("histories", "derived") and wanted[o.when]
               or o.when == "derived" and o.name in derived]
    return tuple(chosen)


def client_variables():
    """Names the client keeps for every point (a worker that writes its batch itself returns only these).

    Returns
    -------
    tuple of str
        The variables declared with ``client=True``, in file order (spot selection and run summary
        read them).

    """
    return tuple(o.name for o in GRID_OUTPUTS if o.client)


def info_variables():
    """Names ``screening info`` summarises over the status-ok points.

    Returns
    -------
    tuple of str
        The variables declared with ``info=True``, in file order.

    """
    return tuple(o.name for o in GRID_OUTPUTS if o.info)


def solver_summaries():
    """Per-point names the moment solver returns besides its histories.

    Returns
    -------
    tuple of str
        The ``"point"``-shaped variables of the ``linearize`` stage, in file order.

    """
    return tuple(o.name for o in of_stage("linearize") if o.shape == "point")


def linearize_variables():
    """Per-point names :func:`screening.linearize` returns besides the histories and the model quantities.

    Returns
    -------
    tuple of str
        The solver summaries declared with ``linearize=True`` (``n_rejected`` is a sweep's only).

    """
    return tuple(o.name for o in of_stage("linearize") if o.shape == "point" and o.linearize)


def failed_value(name):
    """The value of ``name`` at a point whose task failed.

    NaN for a float, the flag ``task_failed`` for ``status``, 0 for step counts: a failed point is
    marked, never silently a number.

    Parameters
    ----------
    name : str
        A declared variable (a key of :data:`OUTPUTS`).

    Returns
    -------
    float or int
        Its value at a failed point (in the variable's units).

    """
    return OUTPUTS[name].failed
