"""The grid of a study cut into batches: pure functions of a :class:`~screening.sweep.study.Study`.

The grid (``case`` x swept parameters) is flattened in C order and cut into batches of contiguous
points (never across a case; by default about :data:`DEFAULT_BATCH` points, a whole number of rows
of the last dimension).  Nothing here touches dask or the disk.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np

from screening.core.limits import batch_budget
from screening.core.status import PointStatus
from screening.solvers.moments import HISTORY_VARIABLES
from screening.sweep.config import build_models, build_point_models, NUMERIC, point_excitation

__all__ = []

#: Points per task when the histories are held in memory (stored, or needed for fragility).
DEFAULT_BATCH = 500
#: Most points per task when no histories are held: such a task holds only per-point summaries, so
#: its size is set by the pace of the run (a task of a few seconds keeps progress and Ctrl-C prompt).
HISTORY_FREE_BATCH = 10_000
#: Tasks per worker a history-free grid is cut into (load balance at the end of the run).
BATCHES_PER_WORKER = 8


@dataclass(frozen=True)
class Batch:
    """Points ``lo <= i < hi`` (flat C-order indices of the grid), all in case ``case``."""

    index: int
    case: int
    lo: int
    hi: int
    #: ``hi - lo``
    size: int = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "size", self.hi - self.lo)


def holds_histories(study):
    """Whether a task of ``study`` holds time histories in memory: stored, or needed for ``[fragility]``."""
    return bool(study.output.stored) or study.fragility is not None


def default_batch_size(study, n_workers, target=None):
    """Points per batch.

    With histories in memory (:func:`holds_histories`): about ``target`` (default
    :data:`DEFAULT_BATCH`), at least 2 batches per worker, whole rows of the last dimension if
    possible.  Without: about :data:`BATCHES_PER_WORKER` batches per worker, from
    :data:`DEFAULT_BATCH` to ``target`` (default :data:`HISTORY_FREE_BATCH`) points: the client's and
    the scheduler's work per batch is fixed, so few large batches leave the cores to the workers;
    whole rows if possible, the number of rows (within 25 %) that ends the run most evenly.
    Never across a case, never more than the arrays over the output times of one task fit in
    :data:`~screening.core.limits.TASK_BYTES` (6 histories per point, or one envelope).

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    n_workers : int
        Worker processes (or threads) of the cluster.
    target : int, optional
        The batch size aimed at (see above for the defaults).

    Returns
    -------
    int
        Points per batch, at least 1.
    """
    per_case = study.points_per_case
    workers = max(int(n_workers), 1)
    n_times = round(study.t_end / study.dt) + 1
    spread = math.ceil(study.n_points / (2 * workers))
    if holds_histories(study):
        cap = min(DEFAULT_BATCH if target is None else target, spread)
        size = cap
        budget = batch_budget(n_times, len(HISTORY_VARIABLES))
    else:
        cap = min(HISTORY_FREE_BATCH if target is None else target, spread)
        size = min(max(DEFAULT_BATCH, math.ceil(study.n_points / (BATCHES_PER_WORKER * workers))), cap)
        budget = batch_budget(n_times, 1)
    cap = max(1, min(cap, per_case, budget))
    size = max(1, min(size, cap))
    n_last = study.swept_shape[-1] if study.swept_shape else 1
    if n_last <= size:
        rows = size // n_last
        if holds_histories(study):
            size = rows * n_last
        else:                           # within 25 % of the size: the row count that ends most evenly
            low, high = max(1, (3 * rows) // 4), min(cap // n_last, (5 * rows) // 4 + 1)
            candidates = range(low, max(high, low) + 1, max(1, (high - low) // 16))
            size = n_last * min(candidates, key=lambda r: (_makespan(study, r * n_last, workers), -r))
    return size


def _makespan(study, size, workers):
    """Points the busiest of ``workers`` solves when the grid of ``study`` is cut into batches of
    ``size`` (:func:`plan_batches`) handed out in order to whichever worker is free first (all
    points taken to cost the same)."""
    loads = [0] * workers
    full, rest = divmod(study.points_per_case, size)
    for _ in range(len(study.cases)):
        for points in [size] * full + ([rest] if rest else []):
            heapq.heapreplace(loads, loads[0] + points)
    return max(loads)


def plan_batches(study, batch_size):
    """Cut the grid into :class:`Batch` es of at most ``batch_size`` points, case by case.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    batch_size : int
        Most points per batch, at least 1.

    Returns
    -------
    list of Batch
        The batches in order; each holds the flat C-order indices ``lo <= i < hi`` of one case.

    Raises
    ------
    ValueError
        ``batch_size`` below 1.
    """
    if batch_size < 1:
        raise ValueError(f"parameter 'batch_size' must be an integer >= 1 (got {batch_size!r})")
    per_case = study.points_per_case
    batches = []
    for case in range(len(study.cases)):
        for lo in range(0, per_case, batch_size):
            hi = min(lo + batch_size, per_case)
            batches.append(Batch(len(batches), case, case * per_case + lo, case * per_case + hi))
    return batches


def batch_values(study, batch):
    """Swept parameter values of the points of ``batch`` (dict of 1-d arrays).

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    batch : Batch
        A batch of :func:`plan_batches`.

    Returns
    -------
    dict
        ``{swept parameter: values}``, one value per point of the batch, in the parameter's SI unit.
    """
    per_case = study.points_per_case
    flat = np.arange(batch.lo - batch.case * per_case, batch.hi - batch.case * per_case)
    if not study.swept_dims:
        return {}
    idx = np.unravel_index(flat, study.swept_shape)
    return {name: study.sweeps[name][i] for name, i in zip(study.swept_dims, idx)}


def swept_columns(study):
    """``(columns, case)``: the swept parameter values (``{name: values}`` in the parameter's SI unit, by
    :func:`batch_values` of each case's points) and the case index (0 without cases) of every point of
    ``study`` (flat, C order)."""
    n, per_case = study.n_points, study.points_per_case
    columns = {name: np.empty(n) for name in study.swept_dims}
    for c in range(len(study.cases)):
        whole = Batch(0, c, c * per_case, (c + 1) * per_case)
        for name, values in batch_values(study, whole).items():
            columns[name][whole.lo:whole.hi] = values
    return columns, np.repeat(np.arange(len(study.cases)), per_case)


def point_values(study, index):
    """``(case, values)`` at grid index tuple ``index`` (swept values as floats).

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    index : tuple of int
        The grid index (leading the case index when the study has cases).

    Returns
    -------
    case : int
        The case index (0 without cases).
    values : dict
        ``{swept parameter: value}`` in the parameter's SI unit.
    """
    case = index[0] if study.has_case_dim else 0
    swept = index[1:] if study.has_case_dim else index
    return case, {name: float(study.sweeps[name][i]) for name, i in zip(study.swept_dims, swept)}


def warm_up_excitations(study, s0=1e-5):
    """The cases' excitations (each at its first point, PSD level ``s0`` [m2 s-3]), one per number of filter states
    in increasing order: what the workers' warm-up solves under, so that it loads the moment solver's loops a run
    of ``study`` needs (one per state size, :func:`screening.solvers.moments.batch_solver`) and no other."""
    first = (0,) * len(study.swept_dims)
    by_states = {}
    for c, case in enumerate(study.cases):
        excitation = point_excitation(case, point_values(study, ((c,) if study.has_case_dim else ()) + first)[1], s0)
        by_states.setdefault(int(np.shape(excitation.filter().A)[-1]), excitation)
    return [by_states[n] for n in sorted(by_states)]


def batch_models(study, batch):
    """``(block, foundation, excitation)`` with array fields for the points of ``batch``.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    batch : Batch
        A batch of :func:`plan_batches`.

    Returns
    -------
    block : screening.core.model.Block
        The rigid block (SI fields, arrays over the batch where swept).
    foundation : Foundation
        The bed.
    excitation : Excitation
        The ground motion model.
    """
    return build_models(study.cases[batch.case], batch_values(study, batch), study.t_end)


def batch_point_models(study, batch):
    """:func:`batch_models` and the points whose ``S0`` cannot follow from a target PGA
    (:func:`~screening.sweep.config.build_point_models`): ``(block, foundation, excitation, underivable)``.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study.
    batch : Batch
        A batch of :func:`plan_batches`.

    Returns
    -------
    tuple
        ``(block, foundation, excitation, underivable)``; ``underivable`` flags the points whose target
        PGA [m s-2] gives no ``S0`` (False when the study gives ``S0`` itself).
    """
    return build_point_models(study.cases[batch.case], batch_values(study, batch), study.t_end)


def select_spots(study, status, peak_p_uplift):
    """Grid index tuples of the Monte Carlo spot points.

    Explicit points are returned as given.  ``"auto"`` takes ``count`` points with ``status == ok``:
    the first at the highest ``peak_p_uplift`` (ties: lowest flat index first), the others where the
    linearization's errors are largest, at intermediate intensity: one nearest each of the uplift levels
    ``top x (count - k) / count`` (``k = 1 .. count - 1``; ``top`` the highest uplift), each preferring,
    among the points within 0.05 of its level, a block/bed not yet visited (so that softening and
    hardening beds both get a check).  ``status`` and ``peak_p_uplift`` are flat arrays over the grid.

    Parameters
    ----------
    study : screening.sweep.study.Study
        The study (its ``[mcs]`` table).
    status : numpy.ndarray
        :class:`~screening.core.status.PointStatus` per point, flat over the grid.
    peak_p_uplift : numpy.ndarray
        Peak probability of uplift [1] per point, flat over the grid.

    Returns
    -------
    list of tuple
        The grid index of each spot point (empty without ``[mcs]``).
    """
    spec = study.mcs
    if spec is None:
        return []
    if spec.points != "auto":
        return list(spec.points)
    ok = np.flatnonzero((status == PointStatus.ok) & np.isfinite(peak_p_uplift))
    if not ok.size or not spec.count:
        return []
    order = ok[np.argsort(-peak_p_uplift[ok], kind="stable")]
    chosen = [int(order[0])]
    top = float(peak_p_uplift[order[0]])
    beds = _bed_keys(study)
    free = np.ones(ok.size, dtype=bool)
    free[np.searchsorted(ok, chosen[0])] = False
    for k in range(1, min(spec.count, ok.size)):
        level = top * (spec.count - k) / spec.count
        distance = np.where(free, np.abs(peak_p_uplift[ok] - level), np.inf)
        near = free & (distance <= distance.min() + 0.05)
        fresh = near & ~np.isin(beds[ok], beds[chosen])
        pool = fresh if fresh.any() else near
        pick = int(np.argmin(np.where(pool, distance, np.inf)))
        free[pick] = False
        chosen.append(int(ok[pick]))
    return [tuple(int(i) for i in np.unravel_index(j, study.shape)) for j in chosen]


def _bed_keys(study):
    """For each flat grid index, a number naming its case and swept block/bed parameters (the excitation
    dimensions left out): points with equal numbers stand on the same block and bed."""
    shape = study.shape
    keep = [i for i, d in enumerate(study.dims) if d == "case" or NUMERIC.get(d, ("",))[0] != "excitation"]
    if not keep:
        return np.zeros(int(np.prod(shape, dtype=np.int64)), dtype=np.int64)
    index = np.unravel_index(np.arange(int(np.prod(shape, dtype=np.int64))), shape)
    return np.ravel_multi_index([index[i] for i in keep], [shape[i] for i in keep])


