"""What every study file shares: validation helpers, the model tables and the model builder.

Sweep studies (:mod:`screening.sweep.study`) and the speed-accuracy trade study
(:mod:`screening.applications.tradeoff_study`) read ``[block]``, ``[foundation]``, ``[excitation]``
and ``[time]`` with the code below, and report every problem as :class:`StudyError`: one line,
``"<source>: <key>: <message>"``, naming the key as it is spelled in the file (``block.m``,
``family[0].eps``, ``convergence.points[1].index``).

Conventions of the helpers: ``where`` is the prefix of the keys of a table, with its trailing dot
(``"block."``, ``""`` at the top level); ``key`` is a full key.
"""

from __future__ import annotations

import hashlib
import math
import numbers
import os
import re
import warnings

__all__ = []
try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10: the same parser as the backport
    import tomli as tomllib
from dataclasses import dataclass, field
from types import MappingProxyType, SimpleNamespace

import numpy as np

from screening._version import __version__
from screening.core import condensation as condensations, excitations, laws
from screening.core.condensation import names as condensation_names
from screening.core.model import Block, Foundation
from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, band_top, ground_cutoff
from screening.core.model.block import LENGTH_RANGE
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.registry import Live, LiveTuple
from screening.solvers import mc_registry, model_choice
from screening.solvers.moments import DEFAULT_MAX_STEPS, DEFAULT_RTOL, HISTORY_VARIABLES
from screening.solvers.timegrid import output_times
from screening.core.validation import InputFileError, read_input_text
from screening.core import limits

#: Numeric parameters of the registered excitations besides S0 (``omega_g``, ``zeta_g``, ...); this and the
#: tables below read the registries when used, so an excitation registered later is a study key too.
EXCITATION_PARAMETERS = Live(excitations.parameters)
#: Parameters that may be swept (given as a list or a range).
SWEEPABLE = LiveTuple(lambda: ("eps", "S0", "pga", "k", "lam", "c", *excitations.parameters()))

EXCITATIONS = LiveTuple(excitations.names)
ENVELOPES = ("exponential", "constant")


def _numeric():
    """:data:`NUMERIC`, read now."""
    return {
        "m": ("block", 0.0, False, None), "b": ("block", LENGTH_RANGE[0], True, LENGTH_RANGE[1]),
        "h": ("block", LENGTH_RANGE[0], True, LENGTH_RANGE[1]),
        "I_cm": ("block", 0.0, False, None), "g": ("block", 0.0, False, None),
        "k": ("foundation", 0.0, False, None), "lam": ("foundation", 0.0, True, None),
        "c": ("foundation", 0.0, True, None), "eps": ("foundation", None, False, None),
        "S0": ("excitation", 0.0, False, None), "pga": ("excitation", 0.0, False, None),
        **{name: ("excitation", p.lower, p.lower_inclusive, p.upper) for name, p in excitations.parameters().items()},
        "T1": ("excitation", 0.0, False, None), "T2": ("excitation", 0.0, False, None),
        "band_limit_hz": ("excitation", 0.0, False, 1e5),
    }


#: Numeric model parameters: (table, lower bound, lower bound inclusive, upper bound or None).
NUMERIC = Live(_numeric)
#: Keys of the model tables of a sweep study (other study kinds allow a subset).
TABLE_KEYS = Live(lambda: {
    "block": ("m", "b", "h", "I_cm", "g"),
    "foundation": ("contact", "condensation", "k", "lam", "c", "eps"),
    "excitation": ("kind", "S0", "pga", *excitations.parameters(), "envelope", "T1", "T2", "band_limit_hz"),
})
MODEL_TABLES = ("block", "foundation", "excitation")
DEFAULTS = {"contact": "hunt_crossley", "condensation": condensations.DEFAULT_CONDENSATION, "envelope": "exponential", "eps": 0.0, "g": 9.81,
            "T1": 4.0, "T2": 2.0, "band_limit_hz": GROUND_BAND_LIMIT_HZ}
_RANGE_KEYS = ("start", "stop", "num", "log")
#: The condensation a refused bed is pointed to: the paper's accepts every bed (no bearing check).
_CONDENSES_EVERY_BED = "paper"


class StudyError(ValueError):
    """A study file problem; the message is one line and names the offending key."""


# ----------------------------------------------------------------------------- reading
def read_study_text(path):
    """The text of the study file ``path`` (UTF-8, a byte-order mark dropped); :class:`StudyError` if
    it is not a regular file of at most :data:`~screening.core.limits.MAX_STUDY_BYTES` or cannot
    be read (checked before reading: a FIFO or a device never blocks or fills the memory).

    Parameters
    ----------
    path : str or os.PathLike
        The study file.

    Returns
    -------
    str
        Its text.

    Raises
    ------
    StudyError
        A missing, unreadable, special or too large file (one line naming it).
    """
    try:
        return read_input_text(path, "the study file", limits.MAX_STUDY_BYTES)
    except InputFileError as exc:
        raise StudyError(f"{exc.path}: cannot read the study file ({exc.problem})") from None
    except ValueError as exc:
        raise StudyError(f"cannot read the study file ({one_line(exc)})") from None
    except OSError as exc:
        raise StudyError(f"{os.fsdecode(path)}: cannot read the study file ({exc.__class__.__name__}: "
                         f"{exc.strerror or exc})") from None


def parse_toml(text, source, build):
    """``build(raw)`` on the parsed TOML ``text``; every :class:`StudyError` is prefixed with ``source``.

    Parameters
    ----------
    text : str
        The study, in TOML.
    source : str
        Where it came from (the prefix of every message).
    build : callable
        ``build(raw)`` makes the study of the parsed tables ``raw`` (a dict).

    Returns
    -------
    object
        What ``build`` returned.

    Raises
    ------
    StudyError
        Text too long or nested too deep, invalid TOML, or a :class:`StudyError` of ``build``; prefixed with ``source``.

    References
    ----------
    .. [1] screening documentation, "The study file", ``docs/study.md``.
    .. [2] TOML v1.0.0 specification, https://toml.io/en/v1.0.0
    """
    if len(text) > limits.MAX_STUDY_CHARS:
        raise StudyError(f"{source}: the study file has {len(text)} characters; at most "
                         f"{limits.MAX_STUDY_CHARS} are read")
    depth = limits.nesting_depth(text)
    if depth > limits.MAX_NESTING:
        raise StudyError(f"{source}: invalid TOML: arrays/tables nested {depth} deep (parts of dotted keys "
                         f"count as levels); at most "
                         f"{limits.MAX_NESTING} levels are read")
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source}: invalid TOML: {one_line(exc)}") from None
    except RecursionError:
        raise StudyError(f"{source}: invalid TOML: nested too deep") from None
    try:
        return build(raw)
    except StudyError as exc:
        raise StudyError(f"{source}: {exc}") from None


# ----------------------------------------------------------------------------- helpers
def one_line(exc):
    """The message of ``exc`` on one line."""
    return " ".join(str(exc).split())


def type_name(value):
    """How a wrong value is named in a message (``got ...``)."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def table(raw, key, where=""):
    """Sub-table ``key`` of ``raw`` (empty if absent).

    Raises :class:`StudyError`: ``key`` is not a table.
    """
    value = raw.get(key, {})
    if not isinstance(value, dict):
        raise StudyError(f"{where}{key}: must be a table (got {type_name(value)})")
    return value


def check_keys(tbl, allowed, where):
    """Refuse a key of ``tbl`` not in ``allowed`` (a typo is never ignored).

    Raises :class:`StudyError`: an unknown key (the allowed ones listed).
    """
    for key in tbl:
        if key not in allowed:
            raise StudyError(f"{where}{key}: unknown key (allowed: {', '.join(allowed)})")


def required(tbl, key, where, why=""):
    """``tbl[key]``, or :class:`StudyError` naming the missing key.

    Raises :class:`StudyError`: ``key`` is missing.
    """
    if key not in tbl:
        raise StudyError(f"{where}{key}: required{why}")
    return tbl[key]


def is_number(value):
    """Whether ``value`` is a real number (a TOML boolean is not)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_value(key, value, lower=None, inclusive=False, upper=None):
    """``value`` as a float: a finite number above ``lower`` and at most ``upper`` (each optional).

    Raises :class:`StudyError`: not a number, not finite, or out of range (the range stated).
    """
    if not is_number(value):
        raise StudyError(f"{key}: must be a number (got {type_name(value)})")
    try:
        value = float(value)
    except OverflowError:                           # an integer with hundreds of digits
        value = math.inf if value > 0 else -math.inf
    ok = math.isfinite(value)
    if ok and lower is not None:
        ok = value >= lower if inclusive else value > lower
    if ok and upper is not None:
        ok = value <= upper
    if not ok:
        rng = "a finite number"
        if lower is not None:
            rng += f" {'>=' if inclusive else '>'} {lower:g}"
        if upper is not None:
            rng += f"{' and' if lower is not None else ''} <= {upper:g}"
        raise StudyError(f"{key}: must be {rng} (got {value!r})")
    return value


def check_integer(key, value, lower, upper=None):
    """``value``: an integer (no float, no boolean) ``>= lower`` (and ``<= upper`` if given).

    Raises :class:`StudyError`: not an integer (a float or a boolean is not), or out of range.
    """
    if (isinstance(value, bool) or not isinstance(value, int) or value < lower
            or (upper is not None and value > upper)):
        rng = f">= {lower}" if upper is None else f"in {lower}..{upper}"
        raise StudyError(f"{key}: must be an integer {rng} (got {short_repr(value)})")
    return value


def short_repr(value):
    """``repr(value)``, shortened for integers of hundreds of digits."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        return f"an integer of {len(str(abs(value)))} digits"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def integer(tbl, key, default, lower, where, upper=None):
    """``tbl[key]`` (or ``default``) checked by :func:`check_integer`.

    Raises :class:`StudyError`: not an integer, or out of range.
    """
    return check_integer(f"{where}{key}", tbl.get(key, default), lower, upper)


def check_list(key, value):
    """``value``: a non-empty list.

    Raises :class:`StudyError`: not a list, or an empty one.
    """
    if not isinstance(value, list):
        raise StudyError(f"{key}: must be a list (got {type_name(value)})")
    if not value:
        raise StudyError(f"{key}: empty list (give at least one value)")
    return value


def number_list(key, value, **bounds):
    """A non-empty list of numbers, each checked by :func:`check_value` (``bounds``); a tuple of floats.

    Raises :class:`StudyError`: not a non-empty list, or an entry out of range (named by its index).
    """
    return tuple(check_value(f"{key}[{i}]", v, **bounds) for i, v in enumerate(check_list(key, value)))


def integer_list(key, value, lower):
    """A non-empty list of integers ``>= lower``; a tuple.

    Raises :class:`StudyError`: not a non-empty list, or an entry that is not an integer ``>= lower``.
    """
    return tuple(check_integer(f"{key}[{i}]", v, lower) for i, v in enumerate(check_list(key, value)))


def check_choice(key, value, choices):
    """``value`` if it is one of ``choices``, else :class:`StudyError` listing them.

    Raises :class:`StudyError`: a value not among ``choices`` (listed).
    """
    if value not in choices:
        raise StudyError(f"{key}: must be one of {', '.join(map(repr, choices))} "
                         f"(got {type_name(value) if not isinstance(value, str) else repr(value)})")
    return value


def choice(tbl, key, choices, where, default=None):
    """``tbl[key]`` (or ``default``) checked by :func:`check_choice`.

    Raises :class:`StudyError`: missing without a default, or not among ``choices``.
    """
    value = tbl.get(key, default)
    if value is None:
        raise StudyError(f"{where}{key}: required (one of {', '.join(map(repr, choices))})")
    return check_choice(f"{where}{key}", value, choices)


def name_string(key, value):
    """A name: a non-empty string.

    Raises :class:`StudyError`: not a string, or only white space.
    """
    if not isinstance(value, str) or not value.strip():
        raise StudyError(f"{key}: required, a non-empty string (got {type_name(value)})")
    return value


def title_and_description(raw, default_title):
    """The study's ``title`` and ``description`` (both optional strings).

    Raises :class:`StudyError`: a title or description that is not a string.
    """
    title = raw.get("title", default_title)
    description = raw.get("description", "")
    for key, value in (("title", title), ("description", description)):
        if not isinstance(value, str):
            raise StudyError(f"{key}: must be a string (got {type_name(value)})")
    return title, description


def time_table(raw):
    """``[time]``: ``(t_end, dt)`` [s] (defaults 20 and 0.05); ``dt`` must divide ``t_end``.

    Parameters
    ----------
    raw : dict
        The parsed tables.

    Returns
    -------
    tuple of float
        ``(t_end, dt)`` [s].

    Raises
    ------
    StudyError
        Unknown keys, values that are not positive, ``dt`` not dividing ``t_end``, or too many output steps.
    """
    tbl = table(raw, "time")
    check_keys(tbl, ("t_end", "dt"), "time.")
    t_end = check_value("time.t_end", tbl.get("t_end", 20.0), 0.0, False)
    dt = check_value("time.dt", tbl.get("dt", 0.05), 0.0, False)
    steps = limits.output_steps(t_end, dt)
    if not steps < limits.MAX_TIMES:           # checked before output_times builds the array
        key = "time.t_end" if "dt" not in tbl else "time.dt" if "t_end" not in tbl else "time.t_end / time.dt"
        raise StudyError(f"{key}: t_end / dt = {steps:.3g} output steps; at most {limits.MAX_TIMES - 1} "
                         f"are allowed (got t_end={t_end!r}, dt={dt!r})")
    try:
        output_times(t_end, dt)
    except ValueError as exc:
        raise StudyError(f"time.dt: {one_line(exc)}") from None
    return t_end, dt


# ----------------------------------------------------------------------------- model tables
@dataclass(frozen=True)
class Case:
    """One named configuration: structure (contact law, excitation, envelope) and scalars.

    ``params`` maps parameter names to floats [SI] for every non-swept numeric parameter
    that applies to this case (``I_cm`` only when given).  ``condensation`` is the registered
    name; ``condensation_model`` the :class:`screening.core.condensation.Condensation` it names,
    looked up once when the case is made (what the solvers are given).
    """

    name: str
    contact: str
    excitation: str
    envelope: str
    params: MappingProxyType
    condensation: str = condensations.DEFAULT_CONDENSATION
    condensation_model: condensations.Condensation = field(default=None, compare=False, repr=False)
    #: The band [rad/s] of its intensity measures and target PGA (:func:`case_cutoff`), set when the case is made.
    cutoff: float = field(init=False, compare=False, repr=False)

    def __post_init__(self):
        if self.condensation_model is None:
            object.__setattr__(self, "condensation_model", condensations.get(self.condensation))
        object.__setattr__(self, "cutoff", case_cutoff(self))

    def applies(self, name):
        """Whether parameter ``name`` is meaningful for this case."""
        return name in applicable(self.contact, self.excitation, self.envelope)


def applicable(contact, excitation, envelope):
    """The numeric parameters that mean something for this contact law, excitation and envelope.

    Parameters
    ----------
    contact : str
        The registered contact law.
    excitation : str
        The registered excitation.
    envelope : str
        ``"exponential"`` or ``"constant"``.

    Returns
    -------
    set of str
        The parameter names: the block's, ``k``, ``eps``, the law's damping parameter, the intensity,
        the excitation's and the envelope's.
    """
    names = {"m", "b", "h", "I_cm", "g", "k", "eps", "S0", "pga", "band_limit_hz"}
    names.add(laws.get(contact).parameter)
    names |= set(excitations.get(excitation).parameters)
    if envelope == "exponential":
        names |= {"T1", "T2"}
    return names


def model_tables(raw, allowed=TABLE_KEYS):
    """The model tables ``[block]``, ``[foundation]``, ``[excitation]`` of ``raw``, their keys checked
    against ``allowed`` (table name -> keys).

    Parameters
    ----------
    raw : dict
        The parsed tables.
    allowed : dict, optional
        Table name -> allowed keys (default :data:`TABLE_KEYS`).

    Returns
    -------
    dict
        ``{"block": ..., "foundation": ..., "excitation": ...}`` (empty tables when absent).

    Raises
    ------
    StudyError
        A table that is not one, or an unknown key.
    """
    tables = {}
    for tname in MODEL_TABLES:
        tbl = table(raw, tname)
        check_keys(tbl, allowed[tname], f"{tname}.")
        tables[tname] = tbl
    return tables


def sweep_values(key, spec, lower, inclusive, max_num=limits.DEFAULT_MAX_POINTS, upper=None):
    """Values of a swept parameter from a list or a range table (validated; a range has at most
    ``max_num`` values, checked before the values are built).

    Parameters
    ----------
    key : str
        The full key.
    spec : list or dict
        A list of values, or a range ``{start, stop, num, log}``.
    lower : float or None
        Lower bound of every value.
    inclusive : bool
        Whether ``lower`` itself is allowed.
    max_num : int, optional
        Most values of a range.
    upper : float, optional
        Upper bound.

    Returns
    -------
    numpy.ndarray
        The values, strictly monotonic, in the parameter's SI unit.

    Raises
    ------
    StudyError
        A bad list or range, values out of range, too many, or repeated.

    Notes
    -----
    A range holds ``num`` values from ``start`` to ``stop``, both included: evenly spaced, or with
    ``log = true`` geometrically (:math:`x_i = x_0 (x_{n-1}/x_0)^{i/(n-1)}`).
    """
    if isinstance(spec, list):
        values = number_list(key, spec, lower=lower, inclusive=inclusive, upper=upper)
    else:
        check_keys(spec, _RANGE_KEYS, f"{key}.")
        for part in ("start", "stop", "num"):
            if part not in spec:
                raise StudyError(f"{key}.{part}: required in a range (keys: start, stop, num, log)")
        num = spec["num"]
        if isinstance(num, int) and not isinstance(num, bool) and num > max_num:
            raise StudyError(f"{key}.num: must be an integer in 1..{max_num} (the grid limit run.max_points; "
                             f"got {short_repr(num)})")
        num = check_integer(f"{key}.num", num, 1)
        log = spec.get("log", False)
        if not isinstance(log, bool):
            raise StudyError(f"{key}.log: must be true or false (got {type_name(log)})")
        start = check_value(f"{key}.start", spec["start"], lower, inclusive, upper)
        stop = check_value(f"{key}.stop", spec["stop"], lower, inclusive, upper)
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


def numeric_table(tbl, tname, sweeps, where, sweepable=SWEEPABLE, max_points=limits.DEFAULT_MAX_POINTS):
    """Scalars of one model table; swept entries go to ``sweeps`` (only when allowed: ``sweeps`` not
    None and the key in ``sweepable``).  The grid of ``sweeps`` may have at most ``max_points``
    points (checked as each swept parameter is added, before anything is built on the grid).

    Parameters
    ----------
    tbl : dict
        One model table.
    tname : str
        Its name (``"block"``, ...).
    sweeps : dict or None
        Receives the swept parameters' values (None: a case, scalars only).
    where : str
        The prefix of the table's keys.
    sweepable : sequence of str, optional
        The parameters that may be swept.
    max_points : int, optional
        Most grid points.

    Returns
    -------
    dict
        ``{parameter: value}`` of the scalars (SI); the swept ones are added to ``sweeps``.

    Raises
    ------
    StudyError
        A value out of its range, a sweep where none is allowed, or a grid too large.
    """
    scalars = {}
    for key, value in tbl.items():
        if key not in NUMERIC:
            continue
        _, lower, inclusive, upper = NUMERIC[key]
        full = f"{where}{tname}.{key}"
        if isinstance(value, (list, dict)):
            if key not in sweepable:
                only = f"; only {', '.join(sweepable)} may be swept" if sweepable else ""
                raise StudyError(f"{full}: must be a number (got {type_name(value)}{only})")
            if sweeps is None:
                raise StudyError(f"{full}: a case sets scalars only (sweep in the base tables)")
            sweeps[key] = sweep_values(full, value, lower, inclusive, max_points, upper)
            check_grid_size(sweeps, max_points, full)
        elif key == "band_limit_hz":
            scalars[key] = band_limit_value(full, value)
        else:
            scalars[key] = check_value(full, value, lower, inclusive, upper)
    return scalars


def band_limit_value(key, value, t_end=None):
    """``excitation.band_limit_hz`` [Hz] as a float: a number in ``(0, most]`` Hz, or ``inf`` for ``"none"`` (the
    idealized spectrum).  ``most`` is what the Monte Carlo synthesis of a ``t_end`` record can carry
    (:func:`~screening.solvers.synthesis.max_band_limit_hz`; without ``t_end``, the key's bound in :data:`NUMERIC`).

    Parameters
    ----------
    key : str
        The full key, named in the message.
    value : object
        The value in the study.
    t_end : float, optional
        Record length [s].

    Returns
    -------
    float
        The corner [Hz], ``inf`` for ``"none"``.

    Raises
    ------
    StudyError
        One line naming the key and its range.
    """
    if value == "none" or (value == math.inf and t_end is not None):
        return math.inf
    from screening.solvers.synthesis import max_band_limit_hz

    most = NUMERIC["band_limit_hz"][3] if t_end is None else max_band_limit_hz(t_end)
    ok = is_number(value) and math.isfinite(float(value)) and 0.0 < float(value) <= most
    if not ok:
        why = "" if t_end is None else f" (what the synthesis of a {t_end:g} s record can carry)"
        raise StudyError(f'{key}: must be a number in (0, {most:.4g}] Hz{why} or "none" (got {short_repr(value)})')
    return float(value)


def check_grid_size(sweeps, max_points, key, n_cases=1):
    """:class:`StudyError` naming ``key`` if ``n_cases`` x the swept values exceed ``max_points``.

    Parameters
    ----------
    sweeps : dict
        Swept parameter -> values (None: not known yet, left out).
    max_points : int
        Most grid points.
    key : str
        The key named in the message.
    n_cases : int, optional
        Cases of the study.

    Returns
    -------
    int
        The grid's points.

    Raises
    ------
    StudyError
        More than ``max_points``.
    """
    sizes = [n_cases] if n_cases > 1 else []
    sizes += [len(v) for v in sweeps.values() if v is not None]
    n = math.prod(sizes)
    if n > max_points:
        names = (["case"] if n_cases > 1 else []) + [k for k, v in sweeps.items() if v is not None]
        shape = " x ".join(f"{d} {s}" for d, s in zip(names, sizes))
        raise StudyError(f"{key}: the grid has {n} points ({shape}); at most run.max_points = {max_points} "
                         "are allowed (sweep fewer values, or raise [run] max_points)")
    return n


def resolve_case(name, tables, sweeps, where, inherited=frozenset()):
    """Check one configuration (model tables, e.g. base tables merged with a case) and return a :class:`Case`.

    ``sweeps`` maps the parameters given per grid point to their values (the values of excitation
    parameters are not read: None is fine).  Parameters named in ``inherited`` (set by the base
    tables, not by the case) are dropped when they do not apply to the case's contact law /
    excitation / envelope.

    Parameters
    ----------
    name : str
        The case's name (``""`` without cases).
    tables : dict
        The model tables of the configuration.
    sweeps : dict
        Parameters given per grid point -> values.
    where : str
        The prefix of the keys (``"case[0]."``).
    inherited : frozenset of str, optional
        Parameters set by the base tables.

    Returns
    -------
    Case
        The configuration, with defaults filled in (``eps`` 0, ``g`` 9.81 m s-2, ``T1`` 4 s, ``T2`` 2 s, ...).

    Raises
    ------
    StudyError
        A parameter that does not apply, one missing, S0 and pga both given, or a bed the condensation cannot carry.
    """
    block, foundation, excitation = tables["block"], tables["foundation"], tables["excitation"]
    contact = choice(foundation, "contact", laws.names(), f"{where}foundation.", DEFAULTS["contact"])
    kind = choice(excitation, "kind", EXCITATIONS, f"{where}excitation.")
    envelope = choice(excitation, "envelope", ENVELOPES, f"{where}excitation.", DEFAULTS["envelope"])
    condensation = choice(foundation, "condensation", condensation_names(), f"{where}foundation.",
                          DEFAULTS["condensation"])
    names = applicable(contact, kind, envelope)
    params = {}
    for tname, tbl in (("block", block), ("foundation", foundation), ("excitation", excitation)):
        tbl = {k: v for k, v in tbl.items() if k in names or k not in inherited}
        params.update(numeric_table(tbl, tname, None, where))
    structure = {"contact": f"contact = {contact!r}", "kind": f"kind = {kind!r}",
                 "envelope": f"envelope = {envelope!r}"}
    reason = {**dict.fromkeys(laws.DAMPING_FIELDS, structure["contact"]),
              **dict.fromkeys(EXCITATION_PARAMETERS, structure["kind"]),
              "T1": structure["envelope"], "T2": structure["envelope"]}
    for key in list(params) + list(sweeps):
        if key not in names:
            raise StudyError(f"{where}{NUMERIC[key][0]}.{key}: does not apply to {reason[key]}")
    given = set(params) | set(sweeps)
    if {"S0", "pga"} <= given:
        raise StudyError(f"{where}excitation.pga: give the intensity as S0 or as pga, not both")
    if not {"S0", "pga"} & given:
        raise StudyError(f"{where}excitation.S0: required (or give a target median PGA as excitation.pga [m s-2])")
    for key in sorted(names - given - {"S0", "pga"}, key=list(NUMERIC).index):
        if key in DEFAULTS:
            params[key] = DEFAULTS[key]
        elif key != "I_cm":
            why = f" for {reason[key]}" if key in reason else ""
            raise StudyError(f"{where}{NUMERIC[key][0]}.{key}: required{why}")
    if envelope == "exponential" and params["T2"] >= params["T1"]:
        raise StudyError(f"{where}excitation.T2: must be smaller than excitation.T1 "
                         f"(got T1={params['T1']!r}, T2={params['T2']!r})")
    case = Case(name=name, contact=contact, excitation=kind, envelope=envelope,
                params=MappingProxyType(params), condensation=condensation)
    _check_condensation(case, sweeps, where)
    _check_target_pga(case, sweeps, where)
    return case


#: Target median PGA [m s-2] a study may give (``excitation.pga``): about 1e-7 g to 100 g.
PGA_RANGE = (1e-6, 1e3)


def _check_target_pga(case, sweeps, where):
    """A target PGA must lie in :data:`PGA_RANGE` (its ``S0`` follows with the excitation's own band limit
    ``band_limit_hz``, whatever the bed)."""
    if "pga" not in case.params and "pga" not in sweeps:
        return
    values = sweeps["pga"] if "pga" in sweeps else [case.params["pga"]]
    for v in values if values is not None else ():
        if not PGA_RANGE[0] <= v <= PGA_RANGE[1]:
            raise StudyError(f"{where}excitation.pga: must be a number in {PGA_RANGE[0]:g}..{PGA_RANGE[1]:g} m s-2 "
                             f"(got {float(v)!r})")


def _check_condensation(case, sweeps, where):
    """Every grid point of ``case`` must be a bed its condensation can condense
    (:meth:`screening.core.condensation.Condensation.check` on the arrays of grid values)."""
    cond = case.condensation_model
    sweeps = {n: v for n, v in sweeps.items() if NUMERIC[n][0] != "excitation"}   # trailing dims: no effect
    if any(v is None for v in sweeps.values()):
        return                      # values given later (trade-study families): checked there
    names = list(sweeps)
    grids = np.meshgrid(*sweeps.values(), indexing="ij", sparse=True) if names else []
    p = {**case.params, **dict(zip(names, grids))}
    try:
        cond.check(_block(p), _foundation(case, p))
    except ValueError as exc:
        at = _failing_point(case, sweeps)
        raise StudyError(f"{where}foundation.condensation: {cond.name!r} needs a bed it can condense and "
                         + (f"the one at {at}" if at else "this one") + f" is not ({one_line(exc)})"
                         + f"; use condensation = {_CONDENSES_EVERY_BED!r}") from None


def _failing_point(case, sweeps):
    """``"name = value, ..."`` of the swept block/foundation parameters at the first grid point
    (C order) that the case's condensation refuses; ``""`` if none is swept or none is found."""
    names = list(sweeps)
    for j in np.ndindex(*(len(sweeps[n]) for n in names)) if names else ():
        values = {n: sweeps[n][i] for n, i in zip(names, j)}
        p = {**case.params, **values}
        try:
            case.condensation_model.check(_block(p), _foundation(case, p))
        except ValueError:
            return ", ".join(f"{n} = {float(v)!r}" for n, v in values.items())
    return ""


# ----------------------------------------------------------------------------- models
def _block(p):
    return Block(m=p["m"], b=p["b"], h=p["h"], I_cm=p.get("I_cm"), g=p["g"])


def _foundation(case, p):
    damping = laws.get(case.contact).parameter
    return Foundation(k=p["k"], eps=p["eps"], law=case.contact, **{damping: p[damping]})


def case_block_and_foundation(case, values):
    """The block and the bed of ``case`` with ``values`` merged in (no excitation: nothing to derive).

    Parameters
    ----------
    case : Case
        A resolved case (:func:`resolve_case`).
    values : dict
        Swept parameters by name (SI: ``m`` [kg], ``b``, ``h`` [m], ``k`` [N m-2], ...), scalars or arrays.

    Returns
    -------
    block : screening.core.model.Block
    foundation : screening.core.model.Foundation
        With the case's contact law and its damping parameter.
    """
    p = {**case.params, **values}
    return _block(p), _foundation(case, p)


def build_models(case, values, t_end=None):
    """Model objects for ``case`` with ``values`` (swept parameters, scalars or arrays) merged in.

    Returns ``(block, foundation, excitation)``; array fields broadcast as in
    :func:`screening.solvers.moments.solve_moments`.  An intensity given as a target median PGA
    (``pga`` [m s-2]) becomes the ``S0`` whose record of ``t_end`` [s] has that median PGA
    (:func:`screening.analysis.intensity.s0_for_pga`, with the excitation's ground-motion band limit);
    ``ValueError`` where a point's ``S0`` cannot be derived (:func:`build_point_models` flags them instead).

    Parameters
    ----------
    case : Case
        The configuration.
    values : dict
        Values of the swept parameters (scalars or arrays, SI).
    t_end : float, optional
        Record length [s]; needed with a target PGA.

    Returns
    -------
    tuple
        ``(block, foundation, excitation)``.

    References
    ----------
    .. [1] screening documentation, "The study file", ``docs/study.md``.
    .. [2] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> import numpy as np
    >>> tables = {"block": {"m": 8.67, "b": 0.035, "h": 0.21}, "foundation": {"k": 2.89e7, "lam": 8.95e8},
    ...           "excitation": {"kind": "white", "S0": 1e-4}}
    >>> case = resolve_case("", tables, {"eps": np.array([0.0, 6e7])}, "")
    >>> block, foundation, excitation = build_models(case, {"eps": np.array([0.0, 6e7])})
    >>> block.m, foundation.eps, excitation.S0
    (8.67, array([       0., 60000000.]), 0.0001)
    """
    block, foundation, excitation, underivable = build_point_models(case, values, t_end)
    if np.any(underivable):
        raise ValueError("excitation.pga: S0 cannot be derived from the target PGA at "
                         f"{int(np.sum(underivable))} point(s) (the median PGA per unit S0 is zero, infinite or "
                         "cannot be computed for their filter and envelope)")
    return block, foundation, excitation


def case_cutoff(case):
    """The band [rad/s] a case's intensity measures and target PGA integrate the input's spectrum over,
    whatever stands on the ground: the top of its band's low-pass
    (:func:`~screening.core.excitations.base.band_top` of ``excitation.band_limit_hz``, default 25 Hz), or, for
    ``band_limit_hz = "none"``, a sharp cut at :data:`~screening.core.excitations.base.GROUND_BAND_LIMIT_HZ`.

    Parameters
    ----------
    case : Case
        The configuration.

    Returns
    -------
    float
        [rad s-1]: 5.62 x :math:`2\\pi f` with ``band_limit_hz`` :math:`f`; :math:`2\\pi` 25 Hz without a band.
    """
    band = case.params.get("band_limit_hz", GROUND_BAND_LIMIT_HZ)
    return ground_cutoff() if math.isinf(band) else band_top(band)


def build_point_models(case, values, t_end=None):
    """:func:`build_models` that flags instead of refusing: ``(block, foundation, excitation, underivable)``,
    ``underivable`` a boolean array (broadcast with the fields; ``False`` without a target PGA) of the
    points whose ``S0`` cannot follow from the target PGA; their excitation carries ``S0 = 1`` as a
    placeholder (the caller flags them and discards what is computed there).

    Parameters
    ----------
    case : Case
        The configuration.
    values : dict
        Values of the swept parameters (SI).
    t_end : float, optional
        Record length [s]; needed with a target PGA.

    Returns
    -------
    tuple
        ``(block, foundation, excitation, underivable)``.
    """
    p = dict(case.params)
    p.update(values)
    block, foundation = _block(p), _foundation(case, p)
    excitation = _excitation_builder(case, p)

    if "pga" in p:
        from screening.analysis.intensity import s0_for_pga

        if t_end is None:
            raise ValueError("t_end is needed to turn a target PGA into S0")
        s0 = np.asarray(s0_for_pga(excitation(1.0), p["pga"], t_end, case.cutoff))
        with np.errstate(invalid="ignore"):
            underivable = ~(np.isfinite(s0) & (s0 > 0))
        s0 = np.where(underivable, 1.0, s0)
        return block, foundation, excitation(float(s0) if s0.ndim == 0 else s0), underivable
    return block, foundation, excitation(p["S0"]), np.zeros((), dtype=bool)


def _excitation_builder(case, p):
    """``excitation(S0)``: the case's excitation with parameters ``p`` (its own and the point's, SI)."""
    envelope = Envelope(p["T1"], p["T2"]) if case.envelope == "exponential" else ConstantEnvelope()
    band = p.get("band_limit_hz", GROUND_BAND_LIMIT_HZ)
    return lambda s0: excitations.build(case.excitation, s0, p, envelope, None if math.isinf(band) else band)


def point_excitation(case, values, s0):
    """The case's excitation at a point (``values``: the swept parameters, SI) at the PSD level ``s0`` [m2 s-3]."""
    return _excitation_builder(case, {**case.params, **values})(s0)


# ----------------------------------------------------------------------------- [cluster]
#: ``[cluster] kind``: the batch queue dask-jobqueue submits the worker jobs to; ``"local"``: the jobs are
#: processes of this machine (dask-jobqueue's own ``LocalCluster``, to try a recipe before the queue).
CLUSTER_KINDS = ("slurm", "pbs", "local")
#: The keys of ``[cluster]`` (``docs/distributed.md``).
CLUSTER_KEYS = ("kind", "cores", "memory", "walltime", "jobs", "lifetime", "lifetime_stagger", "batch_size", "queue",
                "account", "interface", "local_directory", "job_extra_directives", "job_script_prologue",
                "numba_cache_dir")
#: Most jobs ``[cluster] jobs`` may keep running, and most worker processes per job (``cores``).
MAX_JOBS = 10_000
MAX_CORES = 1024
#: Where a job's workers keep numba's compiled code unless ``numba_cache_dir`` says otherwise: a folder of the
#: node (``$TMPDIR`` of the job, else ``/tmp``), per user; expanded by the job script's shell.
NUMBA_CACHE_DEFAULT = "${TMPDIR:-/tmp}/screening-numba-$(id -u)"
_DURATION_UNITS = {"s": 1.0, "m": 60.0, "min": 60.0, "h": 3600.0}


@dataclass(frozen=True)
class ClusterSpec:
    """The ``[cluster]`` table: a dask-jobqueue cluster of ``jobs`` batch jobs of ``kind``, each with ``cores``
    single-threaded worker processes, ``memory`` (dask's spelling, ``"4GB"``) and ``walltime`` (``HH:MM:SS``,
    ``walltime_s`` [s]); its workers retire after ``lifetime_s`` +- ``lifetime_stagger_s`` [s] and new jobs take
    their place; ``batch_size`` (points per task, None: the sweep's default) bounds how long a task runs.
    The other fields go to the job script as given."""

    kind: str
    memory: str
    walltime: str
    walltime_s: float
    lifetime_s: float
    lifetime_stagger_s: float
    cores: int = 1
    jobs: int = 1
    batch_size: int | None = None
    queue: str | None = None
    account: str | None = None
    interface: str | None = None
    local_directory: str | None = None
    job_extra_directives: tuple = ()
    job_script_prologue: tuple = ()
    numba_cache_dir: str = NUMBA_CACHE_DEFAULT


def duration(key, value):
    """Seconds of a duration given as a number [s] or a string ``"<number><unit>"`` (unit ``s``, ``m``,
    ``min`` or ``h``); :class:`StudyError` naming ``key`` unless it is positive and finite.

    Parameters
    ----------
    key : str
        The full key (for the message).
    value : object
        The value from the file.

    Returns
    -------
    float
        The duration [s].

    Raises
    ------
    StudyError
        Anything but a positive finite duration.
    """
    seconds = None
    if is_number(value):
        seconds = float(value)
    elif isinstance(value, str):
        text = value.strip()
        unit = next((u for u in sorted(_DURATION_UNITS, key=len, reverse=True) if text.endswith(u)), None)
        if unit is not None:
            try:
                seconds = float(text[:-len(unit)]) * _DURATION_UNITS[unit]
            except ValueError:
                seconds = None
    if seconds is None or not (math.isfinite(seconds) and seconds > 0):
        raise StudyError(f"{key}: must be a positive duration, seconds or a string like \"30s\", \"55m\", \"2h\" "
                         f"(got {short_repr(value)})")
    return seconds


def _line_string(key, value):
    """A non-empty string of one line (it goes into a job script)."""
    if not isinstance(value, str) or not value.strip() or "\n" in value or "\r" in value:
        raise StudyError(f"{key}: must be a non-empty string of one line (got {short_repr(value)})")
    return value


def cluster_table(raw):
    """The ``[cluster]`` table of a study: a :class:`ClusterSpec`, or None without one.

    ``kind`` (:data:`CLUSTER_KINDS`) and ``memory`` are required; ``cores`` (worker processes per job, default
    1), ``jobs`` (jobs kept running, default 1), ``walltime`` (``HH:MM:SS``, default ``"01:00:00"``),
    ``lifetime`` and ``lifetime_stagger`` (durations; by default a margin ``min(5 min, walltime / 20)`` is the
    stagger and the lifetime is the walltime less two margins, so a worker leaves before the queue kills its
    job); ``batch_size`` (points per task, so that a task ends well within a lifetime; default the sweep's,
    ``--batch-size`` wins); ``queue``, ``account``, ``interface``, ``local_directory``, ``job_extra_directives``,
    ``job_script_prologue`` (lists of lines) and ``numba_cache_dir`` (default :data:`NUMBA_CACHE_DEFAULT`) go to
    the job script.  An unknown key or a bad value is one line naming it.

    Parameters
    ----------
    raw : dict
        The study file's tables.

    Returns
    -------
    ClusterSpec or None
        The cluster, or None when the study has no ``[cluster]``.

    Raises
    ------
    StudyError
        An unknown key, a missing required key or a value out of its range (one line naming it).

    References
    ----------
    .. [1] dask-jobqueue documentation, "How to handle job queueing system walltime killing workers",
       https://jobqueue.dask.org/en/latest/clusters-advanced-tips-and-tricks.html
    .. [2] screening documentation, "Distributed runs", ``docs/distributed.md``.
    """
    if "cluster" not in raw:
        return None
    tbl = table(raw, "cluster")
    check_keys(tbl, CLUSTER_KEYS, "cluster.")
    kind = required(tbl, "kind", "cluster.", f" ({', '.join(CLUSTER_KINDS)})")
    check_choice("cluster.kind", kind, CLUSTER_KINDS)
    memory = _line_string("cluster.memory", required(tbl, "memory", "cluster.", " (the memory of one job, e.g. \"8GB\")"))
    if not re.fullmatch(r"\s*\d+(\.\d+)?\s*([kKMGTP]i?)?B\s*", memory):
        raise StudyError(f"cluster.memory: must be an amount of memory like \"8GB\" or \"16GiB\" (got {memory!r})")
    cores = integer(tbl, "cores", 1, 1, "cluster.", MAX_CORES)
    jobs = integer(tbl, "jobs", 1, 1, "cluster.", MAX_JOBS)
    batch_size = integer(tbl, "batch_size", 1, 1, "cluster.", 2**31 - 1) if "batch_size" in tbl else None
    walltime = _line_string("cluster.walltime", tbl.get("walltime", "01:00:00"))
    hms = re.fullmatch(r"(\d{1,4}):([0-5]\d):([0-5]\d)", walltime)
    walltime_s = float(int(hms[1]) * 3600 + int(hms[2]) * 60 + int(hms[3])) if hms else 0.0
    if walltime_s <= 0:
        raise StudyError(f"cluster.walltime: must be HH:MM:SS, more than zero (got {short_repr(walltime)})")
    margin = min(300.0, walltime_s / 20)
    stagger = duration("cluster.lifetime_stagger", tbl["lifetime_stagger"]) if "lifetime_stagger" in tbl else margin
    lifetime = duration("cluster.lifetime", tbl["lifetime"]) if "lifetime" in tbl else walltime_s - 2 * margin
    if lifetime + stagger >= walltime_s and kind != "local":
        raise StudyError(f"cluster.lifetime: {lifetime:g} s + lifetime_stagger {stagger:g} s must end before the "
                         f"walltime ({walltime} = {walltime_s:g} s), so that a worker leaves before its job is killed")
    if stagger >= lifetime:
        raise StudyError(f"cluster.lifetime_stagger: must be shorter than the lifetime ({lifetime:g} s; "
                         f"got {stagger:g} s)")
    lines = {}
    for key in ("job_extra_directives", "job_script_prologue"):
        value = tbl.get(key, [])
        if not isinstance(value, list):
            raise StudyError(f"cluster.{key}: must be a list of strings (got {type_name(value)})")
        lines[key] = tuple(_line_string(f"cluster.{key}[{i}]", v) for i, v in enumerate(value))
    if kind == "local" and lines["job_script_prologue"]:
        raise StudyError("cluster.job_script_prologue: not used by kind = 'local' (its jobs are processes of this "
                         "machine, with this process's environment)")
    text = {key: _line_string(f"cluster.{key}", tbl[key]) if key in tbl else None
            for key in ("queue", "account", "interface", "local_directory")}
    cache = _line_string("cluster.numba_cache_dir", tbl.get("numba_cache_dir", NUMBA_CACHE_DEFAULT))
    return ClusterSpec(kind=kind, memory=memory, walltime=walltime, walltime_s=walltime_s, lifetime_s=lifetime,
                       lifetime_stagger_s=stagger, cores=cores, jobs=jobs, batch_size=batch_size, **text, **lines, numba_cache_dir=cache)


# ----------------------------------------------------------------------------- the sweep study's tables
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
