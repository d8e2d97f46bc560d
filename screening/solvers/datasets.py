"""The datasets the solvers return, built in one place.

Every dataset follows the package's contract:

* model parameters are coordinates named as in :data:`screening.solvers.schema.PARAMETERS` (``m``, ``b``,
  ``h``, ``I_cm``, ``g``, ``k``, ``lam`` or ``c``, ``eps``, ``S0``, ``omega_g``, ``zeta_g``, ``T1``,
  ``T2`` where they apply): scalar coordinates when fixed, coordinates on dimensions when they vary;
* the string choices (``contact``, ``excitation``, ``envelope``, ``condensation``) are attributes;
* the derived ``theta_ul`` [rad] (of the condensation used) and ``slenderness`` [rad]
  (``atan(b/h)``) are data variables on the dimensions of their parameters: downstream code
  reads them and never recomputes them;
* units and long names come from :func:`screening.solvers.schema.apply_schema`, called once per dataset.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from screening.solvers import schema
from screening.solvers.schema import cf, declare
from screening.core.condensation.registry import DEFAULT_CONDENSATION
from screening.solvers import mc_registry
from screening.core.model.points import numeric_fields
from screening.solvers.estimates import sample_probabilities
from screening.solvers.outputs import HISTORY_VARIABLES, linearize_variables
from screening.core.status import DIVERGENCE_TEXT, DivergenceReason, flag_attributes, SampleState, SpotStatus

__all__ = []

#: The variables of a Monte Carlo ensemble (``monte_carlo``), declared here; in sweeps with the prefix ``mcs_``.
MONTE_CARLO = declare("monte_carlo", {
    "var_theta": cf("rad2", "Monte Carlo ensemble variance of the rocking rotation"),
    "var_theta_dot": cf("rad2 s-2", "Monte Carlo ensemble variance of the rocking angular velocity"),
    "cov_theta_theta_dot": cf("rad2 s-1", "Monte Carlo ensemble covariance of theta and theta'"),
    "var_theta_se": cf("rad2", "standard error of the Monte Carlo rotation variance"),
    "var_theta_dot_se": cf("rad2 s-2", "standard error of the Monte Carlo angular-velocity variance"),
    "p_uplift": cf("1", "fraction of Monte Carlo samples in uplift"),
    "peak_abs_theta": cf("rad", "peak |theta| of each Monte Carlo sample over the record (up to overturning "
                                "or divergence)"),
    "theta_sample": cf("rad", "rotation of each Monte Carlo sample on the output times (meaningless after the "
                              "sample overturned or diverged)"),
    "overturned": cf("1", "Monte Carlo sample overturned (|theta| > atan(b/h))"),
    "diverged": cf("1", "Monte Carlo sample diverged (excluded from the statistics)"),
    "n_steps": cf("1", "integration steps of the sample (accepted + rejected)"),
    "n_overturned": cf("1", "number of overturned Monte Carlo samples"),
    "n_diverged": cf("1", "number of diverged Monte Carlo samples"),
    "n_used": cf("1", "number of Monte Carlo samples in the statistics"),
    "peak_var_theta": cf("rad2", "peak over the output times of the Monte Carlo rotation variance"),
    "peak_var_theta_dot": cf("rad2 s-2", "peak over the output times of the Monte Carlo angular-velocity "
                                         "variance"),
    "rel_error_peak_var_theta": cf("1", "relative error of the linearization's peak var_theta against Monte "
                                        "Carlo, (max_t lin - max_t mcs) / max_t mcs on the output times"),
    "rel_error_peak_var_theta_dot": cf("1", "relative error of the linearization's peak var_theta_dot "
                                            "against Monte Carlo, (max_t lin - max_t mcs) / max_t mcs"),
    "sample_state": flag_attributes(SampleState, "state of each Monte Carlo sample at the end of the record"),
    "status": flag_attributes(SpotStatus, "status of the Monte Carlo spot check"),
    # screening.analysis.probabilities.sample_probabilities (over the samples that did not diverge)
    "p_overturn": cf("1", "fraction of the Monte Carlo samples that overturned (|theta| > atan(b/h))"),
    "p_overturn_se": cf("1", "standard error of p_overturn (binomial, Agresti-Coull)"),
    "p_exceed": cf("1", "fraction of the Monte Carlo samples whose peak |theta| exceeds the threshold "
                        "(overturned samples count)"),
    "p_exceed_se": cf("1", "standard error of p_exceed (binomial, Agresti-Coull)"),
    "threshold": cf("rad", "rotation threshold of p_exceed"),
}, prefix="mcs_")

#: Ensemble statistics of a Monte Carlo run, on ``t``.
MONTE_CARLO_STATISTICS = ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "var_theta_se", "var_theta_dot_se",
                          "p_uplift")


#: The ``integrator`` attribute of a Monte Carlo dataset, by the ``integrator`` numerics option.
INTEGRATOR_TEXT = {
    "dopri": "adaptive Dormand-Prince 5(4), PI step control, steps land on output times",
    "rodas": "adaptive Rosenbrock RODAS 4(3) (linearly implicit, L-stable), steps land on output times",
    "exact": "adaptive Dormand-Prince 5(4), exact (ETD2) steps over the input grid in quiet full contact, steps "
             "land on output times",
    "exact_contact": "closed form in full contact (the linear oscillator's exponential, cubic Hermite input), "
                     "adaptive Dormand-Prince 5(4) in uplift, outputs read from the steps' interpolants",
}


def model_fields(block, foundation, excitation):
    """The numeric fields of the model objects by parameter name, in the order of the objects.

    What a result stores as coordinates: the block's, the bed's and the excitation's numbers under
    the names of :data:`screening.solvers.schema.PARAMETERS` (``lam`` or ``c`` by contact law, ``omega_g``,
    ``zeta_g`` for Kanai-Tajimi input, ``band_limit_hz`` unless the input has no band, ``T1``, ``T2`` for the
    exponential envelope).

    Parameters
    ----------
    block : screening.Block
        The block (``m`` [kg], ``b``, ``h`` [m], ``I_cm`` [kg m^2], ``g`` [m/s^2]).
    foundation : screening.Foundation
        The bed (``k`` [N/m^2], ``lam`` [N s/m^3] or ``c`` [N s/m^2], ``eps`` [1]).
    excitation : Excitation
        The ground motion (``S0`` [m^2/s^3], filter and envelope parameters).

    Returns
    -------
    dict
        Parameter name -> value (float or array, SI as in :data:`screening.solvers.schema.PARAMETERS`).

    """
    return numeric_fields(block, foundation, excitation)


def model_labels(foundation, excitation):
    """The string choices of the model objects: ``contact``, ``excitation``, ``envelope``.

    They are global attributes of a result (a string is no coordinate).

    Parameters
    ----------
    foundation : screening.Foundation
        The bed (its contact law name, ``law``).
    excitation : Excitation
        The ground motion (its ``kind`` and its envelope's ``kind``).

    Returns
    -------
    dict of str
        ``{"contact": ..., "excitation": ..., "envelope": ...}``.

    """
    return {"contact": foundation.law, "excitation": excitation.kind, "envelope": excitation.envelope.kind}


def _coordinates(times, parameters):
    """``t`` and the parameters as coordinates, with the coordinates the parameters' DataArrays bring along."""
    coords = {"t": ("t", np.asarray(times, dtype=float))}
    for value in parameters.values():
        if isinstance(value, xr.DataArray):
            coords.update({c: var.variable for c, var in value.coords.items() if c not in parameters})
    for name, value in parameters.items():
        coords[name] = value.variable if isinstance(value, xr.DataArray) else ((), float(value))
    return coords


def _declared(name, table=None):
    try:
        schema.attributes(name, table)
    except KeyError:
        return False
    return True


def finish(ds, table=None):
    """:func:`screening.solvers.schema.apply_schema` on ``ds``, leaving alone the coordinates the schema does not
    declare (labels the caller brought along on its own DataArrays: they keep their own attributes).

    Every producer of a dataset ends with it, so every variable of every result has its CF ``units``
    and ``long_name`` from one table.  An undeclared data variable still raises ``KeyError``.

    Parameters
    ----------
    ds : xarray.Dataset
        The dataset, its variables named as in :mod:`screening.solvers.schema`.
    table : dict, optional
        The producer's own schema table (e.g. :data:`MONTE_CARLO`), tried before the shared ones;
        default none (the shared declarations only).

    Returns
    -------
    xarray.Dataset
        A new dataset with the schema's attributes on its declared variables and the global attributes
        (``Conventions``, ``references``, ...).

    Raises
    ------
    KeyError
        For a data variable the schema does not declare.

    """
    foreign = [name for name in ds.coords if not _declared(name, table)]
    return schema.apply_schema(ds.drop_vars(foreign), table=table).assign_coords({c: ds[c].variable for c in foreign})


def linearization_dataset(result, times, dims, parameters, derived, attrs):
    """The dataset of :func:`screening.linearize`: the solver's plain arrays labelled again.

    Histories go on ``dims + ("t",)``, per-point summaries on ``dims``, parameters become coordinates,
    derived quantities data variables; :func:`finish` adds units and long names.

    Parameters
    ----------
    result : dict of numpy.ndarray
        From :func:`screening.solvers.moments.solve_moments`: the histories
        (:data:`screening.solvers.outputs.HISTORY_VARIABLES`) on ``dims + ("t",)`` and the summaries
        (:func:`screening.solvers.outputs.linearize_variables`) on ``dims``.
    times : array_like of float
        Output times [s].
    dims : tuple of str
        Names of the grid dimensions (``()`` for one point).
    parameters : dict
        Parameter name -> value (float or DataArray on some of ``dims``, SI), stored as coordinates.
    derived : dict
        Name -> value (float or DataArray on some of ``dims``), stored as data variables
        (``theta_ul`` [rad], ``slenderness`` [rad], ...).
    attrs : dict
        Global attributes (string choices, method, tolerances).

    Returns
    -------
    xarray.Dataset
        The labelled result, with CF units (:func:`finish`).

    """
    dims = tuple(dims)
    data = {name: (dims + ("t",), result[name]) for name in HISTORY_VARIABLES}
    data.update({name: (dims, result[name]) for name in linearize_variables()})
    data.update(derived)
    return finish(xr.Dataset(data, coords=_coordinates(times, parameters), attrs=attrs))


def _status_text(n_samples, n_overturned, n_diverged):
    n_used = n_samples - n_overturned - n_diverged
    if n_used >= 2:
        return "ok"
    if n_overturned == n_samples:
        return "all samples overturned"
    if n_diverged == n_samples:
        return "all samples diverged"
    if n_used == 0:
        return f"all samples excluded ({n_overturned} overturned, {n_diverged} diverged)"
    return f"fewer than 2 usable samples ({n_overturned} overturned, {n_diverged} diverged)"


def monte_carlo_dataset(times, stats, peak, overturned, diverged, n_acc, n_rej, reason, n_over, n_div,
                        block, foundation, excitation, model, n_samples, seed, t_end, dt, opts, plan, h_min, wall,
                        condensation=DEFAULT_CONDENSATION, mc_model=None):
    """The dataset of :func:`screening.solvers.montecarlo.monte_carlo`: a run's plain arrays labelled.

    Parameters
    ----------
    times : numpy.ndarray
        Output times ``t`` [s], shape ``(n_t,)``.
    stats : dict of numpy.ndarray
        The ensemble statistics on ``t`` (:func:`~screening.solvers.montecarlo.ensemble_statistics`), one
        array per name of :data:`MONTE_CARLO_STATISTICS` ([rad2], [rad2 s-2], [rad2 s-1], [1]).
    peak : numpy.ndarray
        Peak of ``|theta|`` per sample [rad], shape ``(n_samples,)``.
    overturned, diverged : numpy.ndarray of bool
        Per sample: it overturned; its integration failed.
    n_acc, n_rej : numpy.ndarray of int
        Accepted and rejected integration steps per sample.
    reason : numpy.ndarray of int
        :class:`~screening.core.status.DivergenceReason` code per sample (read where ``diverged``).
    n_over, n_div : int
        Counts of overturned and diverged samples.
    block : Block
        The block.
    foundation : Foundation
        The bed.
    excitation : Excitation
        The ground motion.
    model : str
        The registered Monte Carlo model's name (``"coupled"``, ``"condensed"``, ...).
    n_samples : int
        Samples of the run.
    seed : int
        The seed of the input samples.
    t_end : float
        End of the record [s].
    dt : float
        Output step [s].
    opts : dict
        The numerics: ``rtol`` [1], ``h_max`` [s], ``max_flight_time`` [s] and optionally ``integrator``
        (a key of :data:`INTEGRATOR_TEXT`, default ``"dopri"``).
    plan : SpectralPlan
        The spectral plan of the input (:func:`~screening.solvers.synthesis.spectral_plan`).
    h_min : numpy.ndarray
        Smallest accepted step per sample after the start-up ramp [s].
    wall : float
        The integration's wall time [s].
    condensation : str, optional
        The condensation of the bed (default: the package's).
    mc_model : MonteCarloModel, optional
        The :class:`~screening.solvers.mc_registry.MonteCarloModel` (default: the registered ``model``),
        which gives ``theta_ul`` and its own attributes.

    Returns
    -------
    xarray.Dataset
        The statistics on ``t``, ``peak_abs_theta``, ``overturned``, ``diverged`` and ``n_steps`` on
        ``sample``, the counts ``n_overturned``, ``n_diverged``, ``n_used``, the uplift threshold
        ``theta_ul`` [rad] and ``slenderness`` [rad]; the model's parameters as coordinates; the run's
        numerics, synthesis and status as attributes; units from the schema (CF-1.8).

    Notes
    -----
    The statistics are over the used samples, ``n_used = n_samples - n_over - n_div``; the ``status``
    attribute is ``"ok"`` when ``n_used >= 2``.  The mean integration step is
    ``dt_integration_mean = t_end / mean(n_acc)`` over the used samples.

    """
    mc = mc_registry.get(model if mc_model is None else mc_model)

    n_used = n_samples - n_over - n_div
    data = {name: ("t", stats[name]) for name in MONTE_CARLO_STATISTICS}
    data.update(peak_abs_theta=("sample", peak), overturned=("sample", overturned), diverged=("sample", diverged),
                n_steps=("sample", n_acc + n_rej), n_overturned=((), n_over), n_diverged=((), n_div),
                n_used=((), n_used))
    theta_ul, theta_ul_attrs = mc.uplift_threshold(block, foundation, condensation)
    data.update(theta_ul=((), theta_ul), slenderness=((), float(block.slenderness)))
    coords = _coordinates(times, model_fields(block, foundation, excitation))
    coords["sample"] = ("sample", np.arange(n_samples))
    reasons = sorted({DIVERGENCE_TEXT[DivergenceReason(int(r))] for r in reason[diverged]})
    accepted = n_acc[~overturned & ~diverged]
    attrs = {
        "title": f"Monte Carlo rocking response ({model} model)",
        "status": _status_text(n_samples, n_over, n_div),
        "model": model,
        "n_samples": n_samples,
        "seed": seed,
        "t_end": t_end,
        "dt_output": dt,
        **model_labels(foundation, excitation),
        "statistics": "moments about the sample mean (ddof=1) over samples that neither overturned nor diverged",
        "integrator": INTEGRATOR_TEXT[opts.get("integrator", "dopri")],
        "rtol": opts["rtol"],
        "h_max": opts["h_max"],
        "dt_integration_mean": float(t_end * accepted.size / max(accepted.sum(), 1)) if accepted.size else float("nan"),
        "dt_integration_min": float(np.min(h_min)) if np.isfinite(np.min(h_min)) else float("nan"),
        "dt_integration_note": "dt_integration_mean = t_end / mean accepted steps of the used samples; "
                               "dt_integration_min = smallest accepted step after the start-up ramp",
        "synthesis": "spectral representation (Shinozuka-Deodatis), random phases, FFT; cubic Hermite between grid points",
        "cutoff_rad_s": float(plan.cutoff),
        "d_omega_rad_s": float(plan.d_omega),
        "n_frequencies": plan.n_frequencies,
        "dt_synthesis": float(plan.dt),
        "input_stationary_variance": plan.stationary_variance,
        "max_flight_time": opts["max_flight_time"],
        "diverged_reasons": ", ".join(reasons) if reasons else "none",
        "wall_time_s": float(wall),
        **theta_ul_attrs,
    }
    attrs.update(mc.dataset_attributes(block, foundation, condensation))
    return finish(xr.Dataset(data, coords=coords, attrs=attrs), table=MONTE_CARLO)


def with_probabilities(ds, thresholds=None):
    """A :func:`screening.monte_carlo` dataset with the probabilities of its samples: ``p_overturn`` and
    ``p_overturn_se`` [1], and with ``thresholds`` (rotations [rad]) ``p_exceed`` and ``p_exceed_se`` [1] on the
    coordinate ``threshold`` [rad].

    The estimates are :func:`screening.solvers.estimates.sample_probabilities` over the samples that
    did not diverge; overturned samples exceed every threshold.

    Parameters
    ----------
    ds : xarray.Dataset
        A Monte Carlo result, with ``peak_abs_theta`` [rad], ``overturned`` and ``diverged`` on ``sample``.
    thresholds : array_like of float, optional
        Rotation thresholds [rad]; None (default) adds ``p_overturn`` only.

    Returns
    -------
    xarray.Dataset
        ``ds`` with ``p_overturn``, ``p_overturn_se`` [1] and, with thresholds, ``p_exceed``,
        ``p_exceed_se`` [1] on ``threshold`` [rad].

    Notes
    -----
    ``p_overturn = #overturned / N`` and ``p_exceed(a) = #(max_t |theta| > a or overturned) / N`` over
    the ``N`` samples that did not diverge, with Agresti-Coull standard errors
    (:func:`screening.solvers.estimates.binomial_estimate`).

    References
    ----------
    .. [1] [agresti1998] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/outputs_probabilities.md``.
    """
    levels = np.asarray(() if thresholds is None else thresholds, dtype=float)
    prob = sample_probabilities(ds["peak_abs_theta"].values, ds["overturned"].values, ~ds["diverged"].values, levels)
    data = {"p_overturn": ((), prob["p_overturn"]), "p_overturn_se": ((), prob["p_overturn_se"])}
    coords = {}
    if thresholds is not None:
        data.update(p_exceed=("threshold", prob["p_exceed"]), p_exceed_se=("threshold", prob["p_exceed_se"]))
        coords["threshold"] = ("threshold", levels)
    added = finish(xr.Dataset(data, coords=coords), table=MONTE_CARLO)
    return ds.assign_coords({name: added[name] for name in coords}).assign({name: added[name] for name in data})
