"""Study files: a parameter study described in TOML, validated before any work is done.

A study file holds one block, one foundation and one excitation; any of the parameters
``eps``, ``S0`` (or ``pga``), ``k``, ``lam``, ``c``, ``omega_g`` and ``zeta_g`` may be *swept*: given as a
list of values or as a range ``{start, stop, num, log}`` (endpoints included, ``log = true``
for geometric spacing).  Every swept parameter becomes a dimension of the result and the
grid is the outer product of the swept values, in the order the keys appear in the file
(``[block]``, then ``[foundation]``, then ``[excitation]``).

Example (SI units throughout)::

    title = "Hardening vs softening bed under white noise"

    [block]
    m = 8.67          # kg
    b = 0.035         # m, half-width
    h = 0.21          # m, height of the centre of mass
    # I_cm = ...      # kg m2, default m (b^2 + h^2) / 3;  g = 9.81 m s-2

    [foundation]
    contact = "hunt_crossley"   # or "winkler" (then give c instead of lam)
    condensation = "virtual_work"   # the default; "paper" (the paper's), "cubic" (see below)
    k = 2.89e7                  # N m-2
    lam = 8.95e8                # N s m-3
    eps = [-6e5, 0.0, 6e7]      # m-2: a list -> dimension "eps"

    [excitation]
    kind = "white"              # or "kanai_tajimi" (then omega_g [rad/s], zeta_g [1])
    S0 = {start = 1e-5, stop = 1e-3, num = 20, log = true}   # m2 s-3 -> dimension "S0"
    # pga = [0.5, 1.0, 2.0]     # m s-2, instead of S0: target median PGA -> dimension "pga"
    envelope = "exponential"    # q(t) = 4 (exp(-t/T1) - exp(-t/T2)); or "constant"
    T1 = 4.0                    # s
    T2 = 2.0                    # s

    [time]
    t_end = 20.0                # s, record length (default 20)
    dt = 0.05                   # s, output step (default 0.05)

    [solver]
    rtol = 1e-8                 # optional; max_steps optional

    [output]                    # optional: what the result stores besides the per-point summaries
    histories = "all"           # or "none": summaries only (peaks and their times, p_uplift, k_eq, status);
                                # or "spots": histories only at the Monte Carlo spot points
    variables = ["var_theta", "p_uplift"]   # with "all": the histories to store (default: all six)

    [fragility]                 # optional: exceedance probabilities computed on the workers
    thresholds = [0.5, 1.0]     # rotations [rad], or fractions with relative_to
    relative_to = "theta_ul"    # or "slenderness"; absent: absolute angles [rad]
    method = "vanmarcke"        # or "poisson" (screening.analysis.fragility)

    [accuracy]                  # optional: escalate to Monte Carlo where the trust rule cannot promise
    target = 0.15               # relative error of peak var_theta (0 < target <= 1; absent: no escalation)
    budget_s = 600              # wall seconds of Monte Carlo at most (default 600)
    seed = 0
    multifidelity = false       # true: pair coupled runs with the condensed model where it pays (docs/multifidelity.md)

    [mcs]                       # optional Monte Carlo spot checks
    points = "auto"             # or [{eps = 6e7, S0 = 1e-3}, {index = {eps = 0, S0 = 19}}]
    count = 3                   # with "auto": how many points
    samples = 200
    model = "coupled"           # or "condensed", "stiff_bed" (docs/stiff_bed.md)
    seed = 0

Named cases
-----------
Studies that are not an outer product (such as the paper's eight configurations) list
``[[case]]`` tables.  Each case has a ``name`` and overrides *scalar* keys of
``[block]``, ``[foundation]`` and ``[excitation]`` (dotted keys are handy:
``foundation.eps = 6e7``).  Base keys that do not apply to a case (``lam`` for a case
that switches to ``contact = "winkler"``) are ignored for that case, but each must apply
to at least one case.  The cases become the leading dimension ``case`` of the result
(an integer coordinate, with the names in the ``case_name`` coordinate), combined as an
outer product with whatever the base tables sweep.  A case cannot override a swept key;
every case is validated on its own (errors are prefixed with ``case 'name':``).

Condensation
------------
``foundation.condensation`` selects the quasi-static condensation behind the linearization
and the condensed Monte Carlo model: ``"virtual_work"`` (the default,
:data:`screening.core.condensation.DEFAULT_CONDENSATION`: the cubic static balance with the damping
of virtual work, closest to the coupled model up to heavy uplift; docs/error_atlas.md),
``"paper"`` (eqs. 17–25: pin it to reproduce the paper) or ``"cubic"`` (the static vertical
balance keeps the ``eps`` term, :mod:`screening.core.condensation.cubic`).  Cases may override it,
so one study can compare them.  ``"cubic"`` and ``"virtual_work"`` need a bed that can carry
the block through uplift onset, ``|eps| (m g / (2 b k))^2 < 2/27``; every grid point is
checked before any work (a refused bed is pointed to ``"paper"``, which has no such limit).
Coupled Monte Carlo spot checks do not depend on it.

Spot points
-----------
``mcs.points = "auto"`` picks, after the sweep, the ``count`` status-ok points with the
highest peak uplift probability ``peak_p_uplift`` (eq. 58): the Gaussian closure of the
linearization is least trustworthy where the response spends most time beyond the uplift
threshold.  Explicit points give each grid dimension either by coordinate value
(``{eps = 6e7, S0 = 1e-3}``; for the case dimension, the case name) or by index
(``{index = {eps = 0, S0 = 19}}``).

Every problem (TOML syntax, unknown key, wrong type, empty list, ``num = 0``, value out of
range, ``T2 >= T1``, ...) raises :class:`StudyError` with a one-line message naming the key.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType, SimpleNamespace

import numpy as np

from screening._version import __version__
from screening.core import limits
from screening.solvers import mc_registry, model_choice
from screening.solvers.moments import DEFAULT_MAX_STEPS, DEFAULT_RTOL, HISTORY_VARIABLES
from screening.solvers.timegrid import output_times
from screening.sweep.config import (band_limit_value, build_models, Case, case_block_and_foundation,
                                    ClusterSpec, cluster_table,
                                    check_choice, check_grid_size, check_keys, check_list, check_value, choice,
                                    integer, model_tables, name_string, number_list, NUMERIC, numeric_table,
                                    parse_toml, read_study_text, required, resolve_case, short_repr, StudyError, table,
                                    TABLE_KEYS, time_table, title_and_description, type_name)
from screening.sweep.inventory import with_collection

__all__ = ["Accuracy", "Case", "SpotChecks", "Study", "StudyError", "build_models", "load_study", "parse_study",
           "study_from_tables", "EXAMPLE_STUDY"]

#: The smallest useful study, for examples: the paper's block (m = 8.67 kg, b = 0.035 m, h = 0.21 m) on a
#: Hunt-Crossley bed (k = 2.89e7 N m-2, lam = 8.95e8 N s m-3) with eps swept over 0 and 6e7 m-2 (two
#: points), under modulated white noise of S0 = 1e-4 m2 s-3 (default envelope, 20 s at 0.05 s).  The
#: examples of the workflow's docstrings start from it (:func:`parse_study`).
EXAMPLE_STUDY = """\
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = [0.0, 6e7]
[excitation]
kind = "white"
S0 = 1e-4
"""

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


# ----------------------------------------------------------------------------- data
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
    ``variables``."""

    histories: str = "all"
    variables: tuple = HISTORY_VARIABLES

    @property
    def stored(self):
        """The history variables the result holds (none with ``histories = "none"``)."""
        return self.variables if self.histories == "all" else ()

    @property
    def at_spots(self):
        """The history variables stored at the spot points only (``histories = "spots"``)."""
        return self.variables if self.histories == "spots" else ()


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


@dataclass(frozen=True)
class Study:
    """A validated study.

    ``sweeps`` maps each swept parameter to its values (1-d float arrays, in grid order);
    ``cases`` lists the configurations (one unnamed case when the file has no ``[[case]]``;
    then ``has_case_dim`` is false).  ``t_end`` and ``dt`` [s] set the output grid.
    """

    name: str
    title: str
    text: str
    source: str
    sweeps: MappingProxyType
    cases: tuple
    has_case_dim: bool
    t_end: float
    dt: float
    rtol: float
    max_steps: int
    mcs: SpotChecks | None = None
    description: str = ""
    _hash: str = field(default="", repr=False)
    output: Output = Output()
    fragility: Fragility | None = None
    accuracy: Accuracy | None = None
    #: ``[cluster]``: where the run goes when no workers or scheduler are given (not part of the ``key``)
    cluster: ClusterSpec | None = None

    @property
    def derived_inputs(self):
        """Model inputs that vary per point without being grid coordinates: ``("S0",)`` when the
        intensity is given as a target PGA (``S0`` then follows per point), else ``()``."""
        return ("S0",) if "pga" in self.sweeps or any("pga" in c.params for c in self.cases) else ()

    @property
    def swept_dims(self):
        """Names of the swept parameters, in grid order."""
        return tuple(self.sweeps)

    @property
    def dims(self):
        """Grid dimensions: ``case`` (if the study has cases) then the swept parameters."""
        return (("case",) if self.has_case_dim else ()) + self.swept_dims

    @property
    def swept_shape(self):
        return tuple(len(v) for v in self.sweeps.values())

    @property
    def shape(self):
        """Grid shape (without time)."""
        return ((len(self.cases),) if self.has_case_dim else ()) + self.swept_shape

    @property
    def n_points(self):
        return int(np.prod(self.shape, dtype=np.int64))

    @property
    def points_per_case(self):
        return int(np.prod(self.swept_shape, dtype=np.int64))

    @property
    def times(self):
        """Output times [s]."""
        return output_times(self.t_end, self.dt)

    @property
    def key(self):
        """Hash of the study text, the package version and the result layout (for reuse)."""
        return self._hash

    def coordinate(self, dim):
        """Values of grid dimension ``dim`` (case index for ``case``)."""
        if dim == "case":
            return np.arange(len(self.cases))
        return self.sweeps[dim]


# ----------------------------------------------------------------------------- entry points
def load_study(path, inventory=None):
    """Read and validate a study file; raises :class:`StudyError` (also for unreadable files).

    Every table and key is checked before any work (docs/study.md lists them): a bad value is one line
    naming the key and its allowed range.  The study's name is the file name without its suffix.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML study file.
    inventory : str or os.PathLike, optional
        A collection CSV (``run --inventory``) instead of the study's ``[collection]``.

    Returns
    -------
    Study
        The validated study: its swept parameters, cases, output times [s] and optional stages.

    Raises
    ------
    StudyError
        An unreadable file, invalid TOML or an invalid key or value (one line).

    References
    ----------
    .. [1] screening documentation, "The study file", ``docs/study.md``.
    .. [2] TOML v1.0.0 specification, https://toml.io/en/v1.0.0

    Examples
    --------
    >>> import os, tempfile
    >>> from screening.sweep.study import EXAMPLE_STUDY as text
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "bed.toml")
    ...     with open(path, "w") as fh:
    ...         _ = fh.write(text)
    ...     study = load_study(path)
    >>> study.name, study.dims, study.shape, study.t_end
    ('bed', ('eps',), (2,), 20.0)
    """
    text = read_study_text(path)
    path = os.fsdecode(path)
    return parse_study(text, name=Path(path).stem, source=str(path), inventory=inventory)


def parse_study(text, name="study", source="<string>", inventory=None):
    """Validate study ``text`` (TOML) and return a :class:`Study`.

    The same checks as :func:`load_study`, on text in memory.

    Parameters
    ----------
    text : str
        The study, in TOML.
    name : str, optional
        The study's name (the result's default title and file stem).
    source : str, optional
        Where the text came from, named in error messages.
    inventory : str or os.PathLike, optional
        A collection CSV (``--inventory``) turned into the study's cases
        (:func:`screening.sweep.inventory.with_collection`).

    Returns
    -------
    Study
        The validated study.

    Raises
    ------
    StudyError
        Invalid TOML or an invalid key or value (one line naming it).

    References
    ----------
    .. [1] screening documentation, "The study file", ``docs/study.md``.
    .. [2] TOML v1.0.0 specification, https://toml.io/en/v1.0.0

    Examples
    --------
    >>> from screening.sweep.study import EXAMPLE_STUDY as text
    >>> study = parse_study(text, name="bed")
    >>> study.dims, study.coordinate("eps").tolist(), len(study.times)
    (('eps',), [0.0, 60000000.0], 401)
    >>> try:
    ...     parse_study(text.replace("b = 0.035", "b = -1"))
    ... except StudyError as exc:
    ...     print(exc)
    <string>: block.b: must be a finite number >= 1e-06 and <= 1000 (got -1.0)
    """
    return parse_toml(text, source, lambda raw: study_from_tables(raw, text, name, source, inventory))


# ----------------------------------------------------------------------------- building
def study_from_tables(raw, text, name, source, inventory=None):
    """The :class:`Study` of a parsed study file: its tables validated and built.

    The builder behind :func:`parse_study`, for a reader that parses the TOML itself (the record study
    reuses it for its shared tables).  Every table and key is checked before any work.

    Parameters
    ----------
    raw : dict
        The study file's TOML tables (``tomllib.loads(text)``).
    text : str
        The study's text, kept for the result's provenance and its hash.
    name : str
        The study's name (the result's default title and file stem).
    source : str
        Where the text came from, named in error messages.
    inventory : str or os.PathLike, optional
        A collection CSV instead of the study's ``[collection]``; its text joins the hash.

    Returns
    -------
    Study
        The study the tables describe, with the hash of ``text``, the package version and the result
        layout as its reuse ``key``.

    Raises
    ------
    StudyError
        An invalid key or value (one line naming the key and its allowed range).

    References
    ----------
    .. [1] screening documentation, "The study file", ``docs/study.md``.

    Examples
    --------
    >>> import tomllib
    >>> from screening.sweep.study import EXAMPLE_STUDY as text
    >>> study = study_from_tables(tomllib.loads(text), text, "bed", "<string>")
    >>> study.dims, study.shape, study.t_end, study.dt
    (('eps',), (2,), 20.0, 0.05)
    >>> study.key == parse_study(text, name="bed").key          # the same study as from the text
    True
    >>> try:
    ...     study_from_tables(dict(tomllib.loads(text), colour="red"), text, "bed", "<string>")
    ... except StudyError as exc:
    ...     print(str(exc)[:28])
    colour: unknown key (allowed
    """
    check_keys(raw, _TOP_KEYS, "")
    raw, collection = with_collection(raw, source, inventory)       # its text is part of the study's hash
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
    study = Study(name=name, title=title, text=text, source=source,
                 sweeps=MappingProxyType(sweeps), cases=tuple(cases), has_case_dim="case" in raw,
                 t_end=t_end, dt=dt, rtol=rtol, max_steps=max_steps, mcs=mcs,
                 description=description, _hash=digest.hexdigest(), output=_output(raw),
                 fragility=_fragility(raw), accuracy=_accuracy(raw, cases, sweeps),
                 cluster=cluster_table(raw))
    if study.output.histories == "spots" and study.mcs is None:
        raise StudyError("output.histories: 'spots' stores the histories at the [mcs] spot points; "
                         "give an [mcs] table (or histories = 'none')")
    return study


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
    import warnings

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
