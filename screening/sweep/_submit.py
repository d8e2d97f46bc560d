"""The client side of the sweep's tasks (package-internal; used by :mod:`screening.sweep.run` and
:mod:`screening.sweep.accuracy`): submitting a batch, a spot check or an escalated point to dask, the task of
a zarr batch that writes its own region, the stand-ins for a refused batch or a failed spot check, and the checks
and warm-up run on the workers.  The task functions themselves are :mod:`screening.sweep.execution`'s.
"""

from __future__ import annotations

import os
import time
import warnings

import numpy as np

from screening.analysis.trust import trust_models
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation
from screening.core.status import SampleState
from screening.io.layout import hyperslabs
from screening.io.zarrfile import ZarrFormat
from screening.solvers.outputs import client_variables, GRID_OUTPUTS, HISTORY_VARIABLES
from screening.sweep.config import build_models
from screening.sweep.execution import (escalation_task, solve_batch, SPOT_HISTORIES, SPOT_LINEAR, spot_task,
                                       TASK_RETRIES)
from screening.sweep.grid import batch_point_models, point_values


# ============================================================================ stand-ins
def refused_batch(message):
    """The task of a batch whose models could not be built on the client: fails with ``message``, so
    that its points get status ``task_failed`` like any failed batch."""
    raise ValueError(message)


def spot_linear_names(study):
    """The linearization histories a spot task must return: those the comparison needs but the grid
    does not store, and those stored at the spots only (``[output] histories = "spots"``)."""
    stored = set(study.output.stored)
    wanted = set(study.output.at_spots) | set(SPOT_LINEAR) - stored
    return tuple(name for name in HISTORY_VARIABLES if name in wanted)


def failed_spot(nt, samples, linear_names=SPOT_LINEAR):
    """Spot-check result of a task that failed: NaN histories, every sample ``diverged_or_failed``."""
    out = {name: np.full(nt, np.nan) for name in SPOT_HISTORIES}
    out.update({f"sl_{name}": np.full(nt, np.nan) for name in linear_names})
    out.update(n_overturned=np.int32(0), n_diverged=np.int32(0), n_used=np.int32(0),
               peak_abs_theta=np.full(samples, np.nan),
               sample_state=np.full(samples, SampleState.diverged_or_failed, dtype=np.int8))
    return out


# ============================================================================ submission
def submit_batch(client, study, batch, key, target=None):
    """Submit :func:`~screening.sweep.execution.solve_batch` for ``batch`` (retried :data:`~screening.sweep.execution.TASK_RETRIES` times); with a
    :class:`~screening.io.store.RegionTarget` ``target``, :func:`solve_and_store_batch`."""
    case = study.cases[batch.case]
    block, foundation, excitation, underivable = batch_point_models(study, batch)
    args = (block, foundation, excitation, case.condensation_model, study.times, study.rtol, study.max_steps,
            study.output.stored, study.fragility, trust_models(case.condensation_model.name), study.derived_inputs,
            underivable if np.any(underivable) else None, case.cutoff, study.probabilities)
    if target is not None:
        return client.submit(solve_and_store_batch, target, batch, *args, retries=TASK_RETRIES, pure=False, key=key)
    return client.submit(solve_batch, *args, retries=TASK_RETRIES, pure=False, key=key)


def submit_spot(client, study, index, key, progress=None):
    """Submit :func:`~screening.sweep.execution.spot_task` at grid index tuple ``index`` (retried :data:`~screening.sweep.execution.TASK_RETRIES` times);
    ``progress = (topic, spot)``: its samples are reported as worker events on ``topic``."""
    case, values = point_values(study, index)
    spec = study.mcs
    names = spot_linear_names(study)
    linear = (study.times, study.rtol, study.max_steps, names) if names else None
    return client.submit(spot_task, *build_models(study.cases[case], values, study.t_end), study.cases[case].condensation_model,
                         spec.samples, spec.model, study.t_end, study.dt, spec.seed, linear, progress,
                         retries=TASK_RETRIES, pure=False, key=key)


def submit_escalation(client, study, flat_index, samples, model, key, cheap=None, progress=None):
    """Submit :func:`~screening.sweep.execution.escalation_task` at flat grid index ``flat_index`` with ``samples`` samples of ``model``
    (a registered Monte Carlo model's name; ``cheap``: the paired model of :func:`~screening.sweep.execution.escalation_task`; retried
    :data:`~screening.sweep.execution.TASK_RETRIES` times); ``progress = (topic, run)``: the samples done are sent as worker events
    (:func:`~screening.sweep.execution.spot_task`)."""
    index = tuple(int(i) for i in np.unravel_index(flat_index, study.shape))
    case, values = point_values(study, index)
    return client.submit(escalation_task, *build_models(study.cases[case], values, study.t_end),
                         study.cases[case].condensation_model, int(samples), model, study.t_end, study.dt,
                         study.accuracy.seed, cheap, progress, retries=TASK_RETRIES, pure=False, key=key)


def solve_and_store_batch(target, batch, *solve_args):
    """The dask task of a zarr result: :func:`~screening.sweep.execution.solve_batch`, then its arrays written into the region of
    ``batch`` in the store and the batch marked done with its chunk files (:class:`~screening.io.store.RegionTarget`
    ``target``); returns what the client keeps of the batch
    (:func:`screening.solvers.outputs.client_variables`)."""
    out = solve_batch(*solve_args)
    fmt = ZarrFormat(target.store, "r+")
    write_region(fmt, target.shape, target.histories, batch, out)
    slabs = [slab for slab, _, _ in hyperslabs(batch.lo, batch.hi, target.shape)]
    target.mark_done(batch, fmt.chunk_files(target.variables, slabs))
    return {name: out[name] for name in client_variables()}


def write_region(fmt, shape, histories, batch, result):
    """Write the arrays of ``batch`` (:func:`~screening.sweep.execution.solve_batch`'s, flat over its points
    ``lo <= i < hi``) into their hyperslabs of the result format ``fmt`` on the grid ``shape``: the stored
    ``histories`` and every other declared variable (:mod:`screening.solvers.outputs`) a result always holds, or
    that ``result`` has."""
    names = set(histories)
    outputs = [o for o in GRID_OUTPUTS if o.name in names or o.shape != "history" and
               (o.when == "always" or o.name in result)]
    for slab, a, b in hyperslabs(batch.lo, batch.hi, shape):
        rows = slice(a - batch.lo, b - batch.lo)
        region = tuple(s.stop - s.start for s in slab)
        for o in outputs:                   # a history or per-threshold variable: its trailing axis whole
            values = result[o.name]
            key = (slab if slab else Ellipsis) if o.shape == "point" else slab + (slice(None),)
            fmt.write(o.name, key, values[rows].reshape(region + values.shape[1:]))


# ============================================================================ on the workers
def sees_folder(path):
    """Whether the folder ``path`` exists for this worker (the workers write a zarr result in place)."""
    return os.path.isdir(path)


def warm_up_monte_carlo(models=("coupled", "condensed")):
    """Compile the kernels of the Monte Carlo ``models`` (names) on a worker (two short samples each); returns the
    time [s]."""
    from screening.solvers.montecarlo import monte_carlo

    start = time.perf_counter()
    with warnings.catch_warnings():       # the paper's bed may lie outside a model's measured validity: compiling only
        warnings.simplefilter("ignore")
        for model in models:
            monte_carlo(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8), WhiteNoise(1e-5), n_samples=2,
                        model=model, t_end=0.2, dt=0.1, progress=False)
            if model == "coupled":       # and the exact full-contact steps it takes on stiff beds at the band
                monte_carlo(Block(8.67, 0.035, 0.21), Foundation(2.89e7, 8.95e8), WhiteNoise(1e-5), n_samples=2,
                            model=model, t_end=0.2, dt=0.1, progress=False, integrator="exact")
    return time.perf_counter() - start
