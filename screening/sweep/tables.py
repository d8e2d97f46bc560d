"""The sweep study's own tables (``[mcs]``, ``[output]``, ``[fragility]``, ``[accuracy]``, ``[run]``, ...),
validated in one pass (:func:`study_fields`) into the fields of :class:`screening.sweep.study.Study`.

The tables every study file shares, and the helpers that check them, are :mod:`screening.sweep.config`'s.
"""

from __future__ import annotations

import hashlib
import math
import re
import warnings
from dataclasses import dataclass, field
from types import MappingProxyType, SimpleNamespace

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10: the same parser as the backport
    import tomli as tomllib

import numpy as np

from screening._version import __version__
from screening.core import limits
from screening.solvers import mc_registry, model_choice
from screening.solvers.moments import DEFAULT_MAX_STEPS, DEFAULT_RTOL, HISTORY_VARIABLES
from screening.sweep.config import (NUMERIC, TABLE_KEYS, StudyError, band_limit_value, case_block_and_foundation,
                                    check_choice, check_grid_size, check_keys, check_list, check_value, choice,
                                    cluster_table, integer, model_tables, name_string, number_list,
                                    numeric_table, required, resolve_case, short_repr, table, time_table,
                                    title_and_description, type_name)

__all__ = []

_TOP_KEYS = ("title", "description", "block", "foundation", "excitation", "time", "solver", "mcs",
             "case", "collection", "output", "fragility", "run", "accuracy", "cluster")
#: ``[output] histories``: every chosen history at every point, only at the spot points, or none.
HISTORY_CHOICES = ("all", "spots", "none")
FRAGILITY_RELATIVE_TO = ("slenderness", "theta_ul")
FRAGILITY_METHODS = ("vanmarcke", "poisson")

#: ``[accuracy] budget_s``: default and ceiling [s] of wall time (a week).
DEFAULT_BUDGET_S = 600.0
MAX_BUDGET_S = 7 * 86400.0

#: Version of the result layout: part of the study key, so old partial results are not mixed in.
LAYOUT_VERSION = 3


@dataclass(frozen=True)
class SpotChecks:
    """The ``[mcs]`` table: ``points`` is ``"auto"`` or a tuple of grid index tuples."""

    points: object
    count: int
    samples: int
    model: str
    seed: int
    strict_validity: bool = False


@dataclass(frozen=True)
class Output:
    """The ``[output]`` table: ``histories`` (``"all"``, ``"spots"`` or ``"none"``) and the history
    ``variables``; ``stored``: the history variables the result holds (none unless ``histories = "all"``),
    ``at_spots``: those stored at the spot points only (``histories = "spots"``)."""

    histories: str = "all"
    variables: tuple = HISTORY_VARIABLES
    stored: tuple = field(init=False, compare=False)
    at_spots: tuple = field(init=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "stored", self.variables if self.histories == "all" else ())
        object.__setattr__(self, "at_spots", self.variables if self.histories == "spots" else ())


@dataclass(frozen=True)
class Fragility:
    """The ``[fragility]`` table: ``thresholds`` (tuple; [rad], or fractions of ``relative_to``),
    ``relative_to`` (``None``, ``"slenderness"`` or ``"theta_ul"``) and the up-crossing ``method``."""

    thresholds: tuple
    relative_to: str | None = None
    method: str = "vanmarcke"


@dataclass(frozen=True)
class Accuracy:
    """The ``[accuracy]`` table: ``target`` (relative error of peak var_theta [1]), ``budget_s`` (wall
    seconds of the Monte Carlo on the workers the run has [s]), the Monte Carlo ``seed``, ``model``: ``"auto"`` (the stiff-bed model
    where its measured validity holds, elsewhere condensed where the calibration shows it within the
    target, else coupled) or a registered model run at every escalated point, and ``multifidelity`` (pair
    the coupled runs with a cheap model where the pilot says it pays: :mod:`screening.analysis.multifidelity`)."""

    target: float
    budget_s: float = DEFAULT_BUDGET_S
    seed: int = 0
    model: str = "auto"
    multifidelity: bool = False


def study_fields(raw, text, name, source, inventory=None, collect=None):
    """Every field of a sweep study (:class:`screening.sweep.study.Study`) from its parsed tables ``raw``, validated
    in one pass: ``collect(raw, source, inventory)`` turns a ``[collection]`` (or the ``inventory`` CSV) into cases
    and returns ``(raw, collection text)`` (:func:`screening.sweep.inventory.with_collection`); the ``key`` hashes
    ``text`` (without ``[cluster]``), the package version, the result layout and the collection.  Raises
    :class:`StudyError` (one line naming the key)."""
    check_keys(raw, _TOP_KEYS, "")
    raw, collection = collect(raw, source, inventory)       # its text is part of the study's hash
    title, description = title_and_description(raw, f"Stochastic-linearization screening: {name}")
    max_points = _run(raw)
    base = model_tables(raw)
    sweeps = {}
    for tname, tbl in base.items():             # validates values and collects sweeps (grid size bounded)
        numeric_table(tbl, tname, sweeps, "", max_points=max_points)

    cases = _cases(raw, base, sweeps)
    if "case" in raw:
        check_grid_size(sweeps, max_points, "case", n_cases=len(cases))
    t_end, dt = time_table(raw)
    for case in cases:                          # a band the synthesis of a t_end record cannot carry
        band_limit_value(f"case {case.name!r}: excitation.band_limit_hz" if case.name else "excitation.band_limit_hz",
                         case.params.get("band_limit_hz", math.inf), t_end)
    rtol, max_steps = _solver(raw)
    shape = ((len(cases),) if "case" in raw else ()) + tuple(len(v) for v in sweeps.values())
    mcs = _mcs(raw, sweeps, cases, "case" in raw, shape, round(t_end / dt) + 1)
    digest = hashlib.sha256(f"{_without_cluster(text, raw)}\n--\nscreening {__version__}\nlayout {LAYOUT_VERSION}".encode()
                            + (f"\n--collection--\n{collection}".encode() if collection else b""))
    fields = dict(name=name, title=title, text=text, source=source,
                  sweeps=MappingProxyType(sweeps), cases=tuple(cases), has_case_dim="case" in raw,
                  t_end=t_end, dt=dt, rtol=rtol, max_steps=max_steps, mcs=mcs,
                  description=description, key=digest.hexdigest(), output=_output(raw),
                  fragility=_fragility(raw), accuracy=_accuracy(raw, cases, sweeps),
                  cluster=cluster_table(raw))
    if fields["output"].histories == "spots" and mcs is None:
        raise StudyError("output.histories: 'spots' stores the histories at the [mcs] spot points; "
                         "give an [mcs] table (or histories = 'none')")
    return fields


def _without_cluster(text, raw):
    """``text`` without its ``[cluster]`` table, for the study's key: where a study runs does not change its
    result, so a run resumed with other jobs or lifetimes, or moved to a cluster, keeps its finished batches.
    The table is cut from its header to the next header, with the blank lines before it; when what is left does not parse to the other tables (a dotted
    ``cluster.kind`` key, a header inside a string), the whole text is kept."""
    if "cluster" not in raw:
        return text
    lines, kept, inside = text.splitlines(keepends=True), [], False
    for line in lines:
        head = line.strip()
        if head.startswith("["):
            inside = re.fullmatch(r"\[\s*cluster\s*\](\s*#.*)?", head) is not None
            while inside and kept and not kept[-1].strip():        # the blank lines before it go too
                kept.pop()
        if not inside:
            kept.append(line)
    cut = "".join(kept)
    try:
        same = tomllib.loads(cut) == {k: v for k, v in raw.items() if k != "cluster"}
    except tomllib.TOMLDecodeError:
        same = False
    return cut if same else text


def _cases(raw, base, sweeps):
    if "case" not in raw:
        tables = {k: {kk: vv for kk, vv in v.items() if kk not in sweeps} for k, v in base.items()}
        return [resolve_case("", tables, sweeps, "")]
    entries = raw["case"]
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise StudyError("case: must be an array of tables ([[case]] entries)")
    if len(entries) > limits.MAX_CASES:
        raise StudyError(f"case: {len(entries)} [[case]] tables; at most {limits.MAX_CASES} (sweep a parameter "
                         f"instead)")
    if not entries:
        raise StudyError("case: empty list (give at least one [[case]])")
    cases, seen, inherited, used = [], set(), set(), set()
    for i, entry in enumerate(entries):
        cname = name_string(f"case[{i}].name", entry.get("name"))
        if cname in seen:
            raise StudyError(f"case[{i}].name: duplicate case name {cname!r}")
        seen.add(cname)
        where = f"case {cname!r}: "
        check_keys(entry, ("name", "block", "foundation", "excitation"), where)
        tables = {}
        for tname in ("block", "foundation", "excitation"):
            override = table(entry, tname, where)
            check_keys(override, TABLE_KEYS[tname], f"{where}{tname}.")
            for key in override:
                if key in sweeps:
                    raise StudyError(f"{where}{tname}.{key}: is swept in the base study; a case "
                                     "cannot override it")
            merged = {k: v for k, v in base[tname].items() if k not in sweeps}
            merged.update(override)
            tables[tname] = merged
            inherited.update(k for k in base[tname] if k not in override and k in NUMERIC)
        case = resolve_case(cname, tables, sweeps, where, frozenset(inherited))
        cases.append(case)
        inherited.clear()
        used.update(case.params)
    for tname in ("block", "foundation", "excitation"):
        for key in base[tname]:
            if key in NUMERIC and key not in sweeps and key not in used:
                raise StudyError(f"{tname}.{key}: does not apply to any case")
    return cases


def _run(raw):
    """``[run] max_points``: the largest grid the study may have (:mod:`screening.core.limits`)."""
    tbl = table(raw, "run")
    check_keys(tbl, ("max_points",), "run.")
    return integer(tbl, "max_points", limits.DEFAULT_MAX_POINTS, 1, "run.", limits.MAX_POINTS_CEILING)


def _solver(raw):
    tbl = table(raw, "solver")
    check_keys(tbl, ("rtol", "max_steps"), "solver.")
    rtol = check_value("solver.rtol", tbl.get("rtol", DEFAULT_RTOL), 0.0, False)
    if rtol >= 1.0:
        raise StudyError(f"solver.rtol: must be a finite number > 0 and < 1 (got {rtol!r})")
    max_steps = tbl.get("max_steps", DEFAULT_MAX_STEPS)
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or not 1 <= max_steps < 2**31:
        raise StudyError(f"solver.max_steps: must be an integer in 1..{2**31 - 1} (got {max_steps!r})")
    return rtol, max_steps


def _output(raw):
    tbl = table(raw, "output")
    check_keys(tbl, ("histories", "variables"), "output.")
    histories = choice(tbl, "histories", HISTORY_CHOICES, "output.", "all")
    if "variables" not in tbl:
        return Output(histories)
    if histories == "none":
        raise StudyError("output.variables: only with histories = 'all' or 'spots'")
    names = check_list("output.variables", tbl["variables"])
    for i, name in enumerate(names):
        check_choice(f"output.variables[{i}]", name, HISTORY_VARIABLES)
    if len(set(names)) != len(names):
        raise StudyError("output.variables: a variable is listed twice")
    return Output(histories, tuple(n for n in HISTORY_VARIABLES if n in names))


def _fragility(raw):
    if "fragility" not in raw:
        return None
    tbl = table(raw, "fragility")
    check_keys(tbl, ("thresholds", "relative_to", "method"), "fragility.")
    given = required(tbl, "thresholds", "fragility.")
    if isinstance(given, list) and len(given) > limits.MAX_THRESHOLDS:
        raise StudyError(f"fragility.thresholds: {len(given)} thresholds; at most {limits.MAX_THRESHOLDS}")
    thresholds = number_list("fragility.thresholds", given, lower=0.0)
    if len(set(thresholds)) != len(thresholds):
        raise StudyError("fragility.thresholds: a threshold is listed twice")
    relative_to = tbl.get("relative_to")
    if relative_to is not None:
        check_choice("fragility.relative_to", relative_to, FRAGILITY_RELATIVE_TO)
    method = choice(tbl, "method", FRAGILITY_METHODS, "fragility.", "vanmarcke")
    return Fragility(thresholds, relative_to, method)


def _accuracy(raw, cases=(), sweeps=None):
    """``[accuracy]``: absent (or without ``target``) keeps today's behaviour (no escalation)."""
    tbl = table(raw, "accuracy")
    check_keys(tbl, ("target", "budget_s", "seed", "model", "multifidelity"), "accuracy.")
    budget = check_value("accuracy.budget_s", tbl.get("budget_s", DEFAULT_BUDGET_S), 0.0, False, MAX_BUDGET_S)
    seed = integer(tbl, "seed", 0, 0, "accuracy.", limits.MAX_SEED)
    model = choice(tbl, "model", (*mc_registry.escalation_models().__members__, model_choice.AUTO), "accuracy.",
                   model_choice.AUTO)
    if "target" not in tbl:
        return None
    target = check_value("accuracy.target", tbl["target"], 0.0, False, 1.0)
    check_model_validity(model, cases, sweeps or {}, False, "accuracy.")
    paired = tbl.get("multifidelity", False)
    if not isinstance(paired, bool):
        raise StudyError(f"accuracy.multifidelity: must be true or false (got {type_name(paired)})")
    return Accuracy(target, budget, seed, model, paired)


def _mcs(raw, sweeps, cases, has_case_dim, shape, n_times):
    if "mcs" not in raw:
        return None
    tbl = table(raw, "mcs")
    check_keys(tbl, ("enabled", "points", "count", "samples", "model", "seed", "strict_validity"), "mcs.")
    enabled = tbl.get("enabled", True)
    if not isinstance(enabled, bool):
        raise StudyError(f"mcs.enabled: must be true or false (got {type_name(enabled)})")
    most = min(limits.MAX_SAMPLES, limits.MAX_SAMPLE_VALUES // n_times)
    samples = tbl.get("samples", 200)
    if isinstance(samples, int) and not isinstance(samples, bool) and samples > most:
        raise StudyError(f"mcs.samples: must be an integer in 2..{most} (at most {limits.MAX_SAMPLE_VALUES} "
                         f"samples x {n_times} output instants in one spot check; got {short_repr(samples)})"
                         if most < limits.MAX_SAMPLES else
                         f"mcs.samples: must be an integer in 2..{most} (got {short_repr(samples)})")
    samples = integer(tbl, "samples", 200, 2, "mcs.")
    seed = integer(tbl, "seed", 0, 0, "mcs.", limits.MAX_SEED)
    model = choice(tbl, "model", model_choice.choices(), "mcs.", model_choice.AUTO)
    strict = tbl.get("strict_validity", False)
    if not isinstance(strict, bool):
        raise StudyError(f"mcs.strict_validity: must be true or false (got {type_name(strict)})")
    if enabled:
        check_model_validity(model, cases, sweeps, strict, "mcs.")
    points = tbl.get("points", "auto")
    dims = (("case",) if has_case_dim else ()) + tuple(sweeps)
    if points == "auto":
        count = integer(tbl, "count", 3, 1, "mcs.")
    elif isinstance(points, list):
        if "count" in tbl:
            raise StudyError("mcs.count: only used with points = 'auto'")
        if not points:
            raise StudyError("mcs.points: empty list (give spot points, or points = 'auto')")
        points = tuple(_spot_index(i, entry, dims, sweeps, cases, shape) for i, entry in enumerate(points))
        if len(set(points)) != len(points):
            raise StudyError("mcs.points: the same grid point is listed twice")
        count = len(points)
    else:
        raise StudyError(f"mcs.points: must be 'auto' or a list of tables (got {type_name(points)})")
    if not enabled:
        return None
    return SpotChecks(points=points, count=count, samples=samples, model=model, seed=seed, strict_validity=strict)


def check_model_validity(model, cases, sweeps, strict, where):
    """A Monte Carlo ``model`` named explicitly must be within its measured validity
    (:meth:`~screening.solvers.mc_registry.MonteCarloModel.validity_problem`) at every grid point's block and bed:
    with ``strict`` a :class:`StudyError` naming the rule and the first point outside it, else a ``UserWarning``
    saying so (the run goes on).  ``"auto"`` is never outside (it picks per point)."""
    if model == model_choice.AUTO:
        return
    mc = mc_registry.get(model)
    sweeps = {n: v for n, v in sweeps.items() if NUMERIC[n][0] != "excitation" and v is not None}
    names = list(sweeps)
    for case in cases:
        kind = SimpleNamespace(kind=case.excitation)        # validity rules read the excitation's kind only
        seen = 0
        for j in np.ndindex(*(len(sweeps[n]) for n in names)) if names else [()]:
            values = {n: float(sweeps[n][i]) for n, i in zip(names, j)}
            problem = mc.validity_problem(*case_block_and_foundation(case, values), kind)
            if problem is None:
                continue
            at = ", ".join(f"{n} = {v!r}" for n, v in values.items()) or "every point"
            if strict:
                raise StudyError(f"{where}model: {problem}; at {at} (strict_validity = true)")
            seen += 1
            if seen == 1:
                warnings.warn(f"{where}model: {problem}; at {at}", UserWarning, stacklevel=2)




def _spot_index(i, entry, dims, sweeps, cases, shape):
    """Grid index tuple of one explicit spot point."""
    where = f"mcs.points[{i}]"
    if not isinstance(entry, dict):
        raise StudyError(f"{where}: must be a table such as {{eps = 6e7}} or {{index = {{eps = 0}}}} "
                         f"(got {type_name(entry)})")
    by_index = "index" in entry
    if by_index:
        check_keys(entry, ("index",), f"{where}.")
        entry = entry["index"]
        if not isinstance(entry, dict):
            raise StudyError(f"{where}.index: must be a table of integer indices")
        where += ".index"
    for key in entry:
        if key not in dims:
            raise StudyError(f"{where}.{key}: not a grid dimension (dimensions: "
                             f"{', '.join(dims) if dims else 'none'})")
    index = []
    for axis, dim in enumerate(dims):
        if dim not in entry:
            raise StudyError(f"{where}: missing {dim!r} (a spot point gives every grid dimension: "
                             f"{', '.join(dims)})")
        value = entry[dim]
        if by_index:
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < shape[axis]:
                raise StudyError(f"{where}.{dim}: must be an integer index in 0..{shape[axis] - 1} "
                                 f"(got {value!r})")
            index.append(value)
        elif dim == "case":
            names = [c.name for c in cases]
            if value not in names:
                raise StudyError(f"{where}.case: unknown case {value!r} (cases: {', '.join(names)})")
            index.append(names.index(value))
        else:
            v = check_value(f"{where}.{dim}", value, None, False)
            grid = sweeps[dim]
            hit = np.flatnonzero(np.isclose(grid, v, rtol=1e-9, atol=0.0))
            if hit.size == 0:
                nearest = grid[np.argmin(np.abs(grid - v))]
                raise StudyError(f"{where}.{dim}: {v!r} is not a grid value (nearest {nearest!r}; "
                                 "or give an index: {index = {...}})")
            index.append(int(hit[0]))
    return tuple(index)
