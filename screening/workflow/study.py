"""Study files: a parameter study described in TOML, validated before any work is done.

A study file holds one block, one foundation and one excitation; any of the parameters
``eps``, ``S0``, ``k``, ``lam``, ``c``, ``omega_g`` and ``zeta_g`` may be *swept*: given as a
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
    condensation = "paper"      # or "cubic" (static balance with the eps term; see below)
    k = 2.89e7                  # N m-2
    lam = 8.95e8                # N s m-4
    eps = [-6e5, 0.0, 6e7]      # m-2: a list -> dimension "eps"

    [excitation]
    kind = "white"              # or "kanai_tajimi" (then omega_g [rad/s], zeta_g [1])
    S0 = {start = 1e-5, stop = 1e-3, num = 20, log = true}   # m2 s-3 -> dimension "S0"
    envelope = "exponential"    # q(t) = 4 (exp(-t/T1) - exp(-t/T2)); or "constant"
    T1 = 4.0                    # s
    T2 = 2.0                    # s

    [time]
    t_end = 20.0                # s, record length (default 20)
    dt = 0.05                   # s, output step (default 0.05)

    [solver]
    rtol = 1e-7                 # optional; max_steps optional

    [mcs]                       # optional Monte Carlo spot checks
    points = "auto"             # or [{eps = 6e7, S0 = 1e-3}, {index = {eps = 0, S0 = 19}}]
    count = 3                   # with "auto": how many points
    samples = 200
    model = "coupled"           # or "condensed"
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
and the condensed Monte Carlo model: ``"paper"`` (default, eqs. 17–25) or ``"cubic"`` (the
static vertical balance keeps the ``eps`` term, :mod:`screening.condensation.cubic`; closer
to the coupled model on hardening beds, slower to linearize).  Cases may override it, so one
study can compare both.  ``"cubic"`` needs a bed that can carry the block through uplift
onset, ``|eps| (m g / (2 b k))^2 < 2/27``; every grid point is checked before any work.
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
import numbers
try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10: the same parser as the backport
    import tomli as tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np

from screening import __version__
from screening import condensation as condensations
from screening.condensation.paper import CONDENSATIONS
from screening.model.excitation import ConstantEnvelope, Envelope, KanaiTajimi, WhiteNoise
from screening.solvers.moments import DEFAULT_MAX_STEPS, DEFAULT_RTOL
from screening.model import Block, Foundation, WinklerFoundation
from screening.solvers.timegrid import output_times

#: Parameters that may be swept (given as a list or a range).
SWEEPABLE = ("eps", "S0", "k", "lam", "c", "omega_g", "zeta_g")

CONTACTS = ("hunt_crossley", "winkler")
EXCITATIONS = ("white", "kanai_tajimi")
ENVELOPES = ("exponential", "constant")
MCS_MODELS = ("coupled", "condensed")

#: Numeric model parameters: (table, lower bound, lower bound inclusive).
_NUMERIC = {
    "m": ("block", 0.0, False), "b": ("block", 0.0, False), "h": ("block", 0.0, False),
    "I_cm": ("block", 0.0, False), "g": ("block", 0.0, False),
    "k": ("foundation", 0.0, False), "lam": ("foundation", 0.0, True),
    "c": ("foundation", 0.0, True), "eps": ("foundation", None, False),
    "S0": ("excitation", 0.0, False), "omega_g": ("excitation", 0.0, False),
    "zeta_g": ("excitation", 0.0, False), "T1": ("excitation", 0.0, False),
    "T2": ("excitation", 0.0, False),
}
_TABLE_KEYS = {
    "block": ("m", "b", "h", "I_cm", "g"),
    "foundation": ("contact", "condensation", "k", "lam", "c", "eps"),
    "excitation": ("kind", "S0", "omega_g", "zeta_g", "envelope", "T1", "T2"),
}
_TOP_KEYS = ("title", "description", "block", "foundation", "excitation", "time", "solver", "mcs",
             "case")
_RANGE_KEYS = ("start", "stop", "num", "log")
_DEFAULTS = {"contact": "hunt_crossley", "condensation": "paper", "envelope": "exponential", "eps": 0.0, "g": 9.81,
             "T1": 4.0, "T2": 2.0}

#: Version of the result layout: part of the study key, so old partial results are not mixed in.
LAYOUT_VERSION = 3


class StudyError(ValueError):
    """A study file problem; the message is one line and names the offending key."""


# ----------------------------------------------------------------------------- data
@dataclass(frozen=True)
class Case:
    """One named configuration: structure (contact law, excitation, envelope) and scalars.

    ``params`` maps parameter names to floats [SI] for every non-swept numeric parameter
    that applies to this case (``I_cm`` only when given).  ``condensation`` is the registered
    name; ``condensation_model`` the :class:`screening.condensation.Condensation` it names,
    looked up once when the case is made (what the solvers are given).
    """

    name: str
    contact: str
    excitation: str
    envelope: str
    params: MappingProxyType
    condensation: str = "paper"
    condensation_model: condensations.Condensation = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        if self.condensation_model is None:
            object.__setattr__(self, "condensation_model", condensations.get(self.condensation))

    def applies(self, name):
        """Whether parameter ``name`` is meaningful for this case."""
        return name in _applicable(self.contact, self.excitation, self.envelope)


@dataclass(frozen=True)
class SpotChecks:
    """The ``[mcs]`` table: ``points`` is ``"auto"`` or a tuple of grid index tuples."""

    points: object
    count: int
    samples: int
    model: str
    seed: int


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
def load_study(path):
    """Read and validate a study file; raises :class:`StudyError` (also for unreadable files)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"{path}: cannot read the study file ({exc.__class__.__name__}: "
                         f"{getattr(exc, 'strerror', None) or exc})") from None
    return parse_study(text, name=path.stem, source=str(path))


def parse_study(text, name="study", source="<string>"):
    """Validate study ``text`` (TOML) and return a :class:`Study`."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source}: invalid TOML: {_one_line(exc)}") from None
    try:
        return _build(raw, text, name, source)
    except StudyError as exc:
        raise StudyError(f"{source}: {exc}") from None


def build_models(case, values):
    """Model objects for ``case`` with ``values`` (swept parameters, scalars or arrays) merged in.

    Returns ``(block, foundation, excitation)``; array fields broadcast as in
    :func:`screening.solvers.moments.solve_moments`.
    """
    p = dict(case.params)
    p.update(values)
    block = Block(m=p["m"], b=p["b"], h=p["h"], I_cm=p.get("I_cm"), g=p["g"])
    if case.contact == "hunt_crossley":
        foundation = Foundation(k=p["k"], lam=p["lam"], eps=p["eps"])
    else:
        foundation = WinklerFoundation(k=p["k"], c=p["c"], eps=p["eps"])
    envelope = Envelope(p["T1"], p["T2"]) if case.envelope == "exponential" else ConstantEnvelope()
    if case.excitation == "white":
        excitation = WhiteNoise(S0=p["S0"], envelope=envelope)
    else:
        excitation = KanaiTajimi(S0=p["S0"], omega_g=p["omega_g"], zeta_g=p["zeta_g"], envelope=envelope)
    return block, foundation, excitation


# ----------------------------------------------------------------------------- building
def _one_line(exc):
    return " ".join(str(exc).split())


def _applicable(contact, excitation, envelope):
    names = {"m", "b", "h", "I_cm", "g", "k", "eps", "S0"}
    names.add("lam" if contact == "hunt_crossley" else "c")
    if excitation == "kanai_tajimi":
        names |= {"omega_g", "zeta_g"}
    if envelope == "exponential":
        names |= {"T1", "T2"}
    return names


def _table(raw, key, where):
    value = raw.get(key, {})
    if not isinstance(value, dict):
        raise StudyError(f"{where}{key}: must be a table (got {_type_name(value)})")
    return value


def _type_name(value):
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def _check_keys(table, allowed, where):
    for key in table:
        if key not in allowed:
            raise StudyError(f"{where}{key}: unknown key (allowed: {', '.join(allowed)})")


def _is_number(value):
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _check_value(key, value, lower, inclusive):
    if not _is_number(value):
        raise StudyError(f"{key}: must be a number (got {_type_name(value)})")
    value = float(value)
    ok = math.isfinite(value)
    if ok and lower is not None:
        ok = value >= lower if inclusive else value > lower
    if not ok:
        rng = "a finite number"
        if lower is not None:
            rng += f" {'>=' if inclusive else '>'} {lower:g}"
        raise StudyError(f"{key}: must be {rng} (got {value!r})")
    return value


def _choice(table, key, choices, where, default=None):
    value = table.get(key, default)
    if value is None:
        raise StudyError(f"{where}{key}: required (one of {', '.join(map(repr, choices))})")
    if value not in choices:
        raise StudyError(f"{where}{key}: must be one of {', '.join(map(repr, choices))} "
                         f"(got {_type_name(value) if not isinstance(value, str) else repr(value)})")
    return value


def _sweep_values(key, spec, lower, inclusive):
    """Values of a swept parameter from a list or a range table (validated)."""
    if isinstance(spec, list):
        if not spec:
            raise StudyError(f"{key}: empty list (give at least one value)")
        values = [_check_value(f"{key}[{i}]", v, lower, inclusive) for i, v in enumerate(spec)]
    else:
        _check_keys(spec, _RANGE_KEYS, f"{key}.")
        for part in ("start", "stop", "num"):
            if part not in spec:
                raise StudyError(f"{key}.{part}: required in a range (keys: start, stop, num, log)")
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise StudyError(f"{key}.num: must be an integer >= 1 (got {num!r})")
        log = spec.get("log", False)
        if not isinstance(log, bool):
            raise StudyError(f"{key}.log: must be true or false (got {_type_name(log)})")
        start = _check_value(f"{key}.start", spec["start"], lower, inclusive)
        stop = _check_value(f"{key}.stop", spec["stop"], lower, inclusive)
        if log:
            if start <= 0.0 or stop <= 0.0:
                raise StudyError(f"{key}: log = true needs start > 0 and stop > 0 (got {start!r}, {stop!r})")
            values = np.geomspace(start, stop, num)
            values[0] = start
            if num > 1:
                values[-1] = stop
        else:
            values = np.linspace(start, stop, num)
    values = np.asarray(values, dtype=float)
    if values.size > 1:
        step = np.diff(values)
        if not (np.all(step > 0) or np.all(step < 0)):
            raise StudyError(f"{key}: values must be strictly increasing or strictly decreasing "
                             "(a coordinate cannot repeat values)")
    return values


def _numeric_table(table, tname, sweeps, where):
    """Scalars of one model table; swept entries go to ``sweeps`` (only when allowed)."""
    scalars = {}
    for key, value in table.items():
        if key not in _NUMERIC:
            continue
        _, lower, inclusive = _NUMERIC[key]
        full = f"{where}{tname}.{key}"
        if isinstance(value, (list, dict)):
            if key not in SWEEPABLE:
                raise StudyError(f"{full}: must be a number (got {_type_name(value)}; only "
                                 f"{', '.join(SWEEPABLE)} may be swept)")
            if sweeps is None:
                raise StudyError(f"{full}: a case sets scalars only (sweep in the base tables)")
            sweeps[key] = _sweep_values(full, value, lower, inclusive)
        else:
            scalars[key] = _check_value(full, value, lower, inclusive)
    return scalars


def _resolve_case(name, tables, sweeps, where, inherited=frozenset()):
    """Check one configuration (base tables merged with a case) and return a :class:`Case`.

    Parameters named in ``inherited`` (set by the base tables, not by the case) are dropped
    when they do not apply to the case's contact law / excitation / envelope.
    """
    block, foundation, excitation = tables["block"], tables["foundation"], tables["excitation"]
    contact = _choice(foundation, "contact", CONTACTS, f"{where}foundation.", _DEFAULTS["contact"])
    kind = _choice(excitation, "kind", EXCITATIONS, f"{where}excitation.")
    envelope = _choice(excitation, "envelope", ENVELOPES, f"{where}excitation.", _DEFAULTS["envelope"])
    condensation = _choice(foundation, "condensation", CONDENSATIONS, f"{where}foundation.",
                           _DEFAULTS["condensation"])
    applicable = _applicable(contact, kind, envelope)
    params = {}
    for tname, table in (("block", block), ("foundation", foundation), ("excitation", excitation)):
        table = {k: v for k, v in table.items() if k in applicable or k not in inherited}
        params.update(_numeric_table(table, tname, None, where))
    structure = {"contact": f"contact = {contact!r}", "kind": f"kind = {kind!r}",
                 "envelope": f"envelope = {envelope!r}"}
    reason = {"lam": structure["contact"], "c": structure["contact"], "omega_g": structure["kind"],
              "zeta_g": structure["kind"], "T1": structure["envelope"], "T2": structure["envelope"]}
    for key in list(params) + list(sweeps):
        if key not in applicable:
            raise StudyError(f"{where}{_NUMERIC[key][0]}.{key}: does not apply to {reason[key]}")
    for key in sorted(applicable - set(params) - set(sweeps), key=list(_NUMERIC).index):
        if key in _DEFAULTS:
            params[key] = _DEFAULTS[key]
        elif key != "I_cm":
            why = f" for {reason[key]}" if key in reason else ""
            raise StudyError(f"{where}{_NUMERIC[key][0]}.{key}: required{why}")
    if envelope == "exponential" and params["T2"] >= params["T1"]:
        raise StudyError(f"{where}excitation.T2: must be smaller than excitation.T1 "
                         f"(got T1={params['T1']!r}, T2={params['T2']!r})")
    case = Case(name=name, contact=contact, excitation=kind, envelope=envelope,
                params=MappingProxyType(params), condensation=condensation)
    _check_condensation(case, sweeps, where)
    return case


def _check_condensation(case, sweeps, where):
    """Every grid point of ``case`` must be a bed its condensation can condense
    (:meth:`screening.condensation.Condensation.check` on the arrays of grid values)."""
    cond = case.condensation_model
    names = list(sweeps)
    grids = np.meshgrid(*sweeps.values(), indexing="ij", sparse=True) if names else []
    try:
        cond.check(*build_models(case, dict(zip(names, grids)))[:2])
    except ValueError as exc:
        at = _failing_point(case, sweeps)
        default = _DEFAULTS["condensation"]
        raise StudyError(f"{where}foundation.condensation: {cond.name!r} needs a bed it can condense and "
                         + (f"the one at {at}" if at else "this one") + f" is not ({_one_line(exc)})"
                         + (f"; use condensation = {default!r}" if cond.name != default else "")) from None


def _failing_point(case, sweeps):
    """``"name = value, ..."`` of the swept block/foundation parameters at the first grid point
    (C order) that the case's condensation refuses; ``""`` if none is swept or none is found."""
    names = [n for n in sweeps if _NUMERIC[n][0] != "excitation"]
    others = {n: v[0] for n, v in sweeps.items() if n not in names}   # do not enter the check
    for j in np.ndindex(*(len(sweeps[n]) for n in names)) if names else ():
        values = {n: sweeps[n][i] for n, i in zip(names, j)}
        try:
            case.condensation_model.check(*build_models(case, {**values, **others})[:2])
        except ValueError:
            return ", ".join(f"{n} = {float(v)!r}" for n, v in values.items())
    return ""


def _build(raw, text, name, source):
    _check_keys(raw, _TOP_KEYS, "")
    title = raw.get("title", f"Stochastic-linearization screening: {name}")
    description = raw.get("description", "")
    for key, value in (("title", title), ("description", description)):
        if not isinstance(value, str):
            raise StudyError(f"{key}: must be a string (got {_type_name(value)})")

    base = {}
    sweeps = {}
    for tname in ("block", "foundation", "excitation"):
        table = _table(raw, tname, "")
        _check_keys(table, _TABLE_KEYS[tname], f"{tname}.")
        base[tname] = table
        _numeric_table(table, tname, sweeps, "")   # validates values and collects sweeps

    cases = _cases(raw, base, sweeps)
    t_end, dt = _time(raw)
    rtol, max_steps = _solver(raw)
    shape = ((len(cases),) if "case" in raw else ()) + tuple(len(v) for v in sweeps.values())
    mcs = _mcs(raw, sweeps, cases, "case" in raw, shape)
    digest = hashlib.sha256(f"{text}\n--\nscreening {__version__}\nlayout {LAYOUT_VERSION}".encode())
    return Study(name=name, title=title, text=text, source=source,
                 sweeps=MappingProxyType(sweeps), cases=tuple(cases), has_case_dim="case" in raw,
                 t_end=t_end, dt=dt, rtol=rtol, max_steps=max_steps, mcs=mcs,
                 description=description, _hash=digest.hexdigest())


def _cases(raw, base, sweeps):
    if "case" not in raw:
        tables = {k: {kk: vv for kk, vv in v.items() if kk not in sweeps} for k, v in base.items()}
        return [_resolve_case("", tables, sweeps, "")]
    entries = raw["case"]
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise StudyError("case: must be an array of tables ([[case]] entries)")
    if not entries:
        raise StudyError("case: empty list (give at least one [[case]])")
    cases, seen, inherited, used = [], set(), set(), set()
    for i, entry in enumerate(entries):
        cname = entry.get("name")
        if not isinstance(cname, str) or not cname.strip():
            raise StudyError(f"case[{i}].name: required, a non-empty string (got {_type_name(cname)})")
        if cname in seen:
            raise StudyError(f"case[{i}].name: duplicate case name {cname!r}")
        seen.add(cname)
        where = f"case {cname!r}: "
        _check_keys(entry, ("name", "block", "foundation", "excitation"), where)
        tables = {}
        for tname in ("block", "foundation", "excitation"):
            override = _table(entry, tname, where)
            _check_keys(override, _TABLE_KEYS[tname], f"{where}{tname}.")
            for key in override:
                if key in sweeps:
                    raise StudyError(f"{where}{tname}.{key}: is swept in the base study; a case "
                                     "cannot override it")
            merged = {k: v for k, v in base[tname].items() if k not in sweeps}
            merged.update(override)
            tables[tname] = merged
            inherited.update(k for k in base[tname] if k not in override and k in _NUMERIC)
        case = _resolve_case(cname, tables, sweeps, where, frozenset(inherited))
        cases.append(case)
        inherited.clear()
        used.update(case.params)
    for tname in ("block", "foundation", "excitation"):
        for key in base[tname]:
            if key in _NUMERIC and key not in sweeps and key not in used:
                raise StudyError(f"{tname}.{key}: does not apply to any case")
    return cases


def _time(raw):
    table = _table(raw, "time", "")
    _check_keys(table, ("t_end", "dt"), "time.")
    t_end = _check_value("time.t_end", table.get("t_end", 20.0), 0.0, False)
    dt = _check_value("time.dt", table.get("dt", 0.05), 0.0, False)
    try:
        output_times(t_end, dt)
    except ValueError as exc:
        raise StudyError(f"time.dt: {_one_line(exc)}") from None
    return t_end, dt


def _solver(raw):
    table = _table(raw, "solver", "")
    _check_keys(table, ("rtol", "max_steps"), "solver.")
    rtol = _check_value("solver.rtol", table.get("rtol", DEFAULT_RTOL), 0.0, False)
    if rtol >= 1.0:
        raise StudyError(f"solver.rtol: must be a finite number > 0 and < 1 (got {rtol!r})")
    max_steps = table.get("max_steps", DEFAULT_MAX_STEPS)
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or not 1 <= max_steps < 2**31:
        raise StudyError(f"solver.max_steps: must be an integer in 1..{2**31 - 1} (got {max_steps!r})")
    return rtol, max_steps


def _int(table, key, default, lower, where):
    value = table.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < lower:
        raise StudyError(f"{where}{key}: must be an integer >= {lower} (got {value!r})")
    return value


def _mcs(raw, sweeps, cases, has_case_dim, shape):
    if "mcs" not in raw:
        return None
    table = _table(raw, "mcs", "")
    _check_keys(table, ("enabled", "points", "count", "samples", "model", "seed"), "mcs.")
    enabled = table.get("enabled", True)
    if not isinstance(enabled, bool):
        raise StudyError(f"mcs.enabled: must be true or false (got {_type_name(enabled)})")
    samples = _int(table, "samples", 200, 2, "mcs.")
    seed = _int(table, "seed", 0, 0, "mcs.")
    model = _choice(table, "model", MCS_MODELS, "mcs.", "coupled")
    points = table.get("points", "auto")
    dims = (("case",) if has_case_dim else ()) + tuple(sweeps)
    if points == "auto":
        count = _int(table, "count", 3, 1, "mcs.")
    elif isinstance(points, list):
        if "count" in table:
            raise StudyError("mcs.count: only used with points = 'auto'")
        if not points:
            raise StudyError("mcs.points: empty list (give spot points, or points = 'auto')")
        points = tuple(_spot_index(i, entry, dims, sweeps, cases, shape) for i, entry in enumerate(points))
        if len(set(points)) != len(points):
            raise StudyError("mcs.points: the same grid point is listed twice")
        count = len(points)
    else:
        raise StudyError(f"mcs.points: must be 'auto' or a list of tables (got {_type_name(points)})")
    if not enabled:
        return None
    return SpotChecks(points=points, count=count, samples=samples, model=model, seed=seed)


def _spot_index(i, entry, dims, sweeps, cases, shape):
    """Grid index tuple of one explicit spot point."""
    where = f"mcs.points[{i}]"
    if not isinstance(entry, dict):
        raise StudyError(f"{where}: must be a table such as {{eps = 6e7}} or {{index = {{eps = 0}}}} "
                         f"(got {_type_name(entry)})")
    by_index = "index" in entry
    if by_index:
        _check_keys(entry, ("index",), f"{where}.")
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
            v = _check_value(f"{where}.{dim}", value, None, False)
            grid = sweeps[dim]
            hit = np.flatnonzero(np.isclose(grid, v, rtol=1e-9, atol=0.0))
            if hit.size == 0:
                nearest = grid[np.argmin(np.abs(grid - v))]
                raise StudyError(f"{where}.{dim}: {v!r} is not a grid value (nearest {nearest!r}; "
                                 "or give an index: {index = {...}})")
            index.append(int(hit[0]))
    return tuple(index)
