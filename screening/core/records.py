"""Ground-motion records: readers for PEER NGA ``.AT2`` files [ancheta2014] and text/CSV records.

A :class:`Record` is a uniformly sampled horizontal ground acceleration [m/s2] (positive along the
instrument's +x axis), optionally a vertical one (positive upwards), its time step ``dt`` [s], a name
and its source.  Every value must be a plain decimal number; errors name the file and the line, never
its content.  Units (``"g"``, ``"m/s2"``, ``"cm/s2"``) are never guessed: the file states them (an AT2
third line, a text header ``units: g`` or column titles ``acc [g]``) or the caller gives them, and the
two must agree.  The layouts, the strictness and the units: ``docs/records.md``.
"""

from __future__ import annotations

import glob as _glob
import math
import numbers
import os
import re
from dataclasses import dataclass, field, replace

import numpy as np

from screening.core.atomicfile import atomic_open
from screening.core.validation import input_path, read_input_text
from screening.core import limits

__all__ = ["STANDARD_GRAVITY", "UNITS", "Record", "check_time_step", "check_scale",
           "unit_factor", "read_at2", "read_text_record", "read_two_column", "read_single_column", "read_record",
           "expand_records", "write_at2"]

#: Standard gravity [m/s2] used to convert records given in g.
STANDARD_GRAVITY = 9.80665

#: Accepted acceleration units and their factor to m/s2.
UNITS = {"g": STANDARD_GRAVITY, "m/s2": 1.0, "m/s^2": 1.0, "m s-2": 1.0, "cm/s2": 0.01, "cm/s^2": 0.01,
         "gal": 0.01}

#: A plain decimal number (optional sign, digits with an optional point, optional exponent; Fortran's
#: ``D`` exponent too).  No ``nan``, ``inf``, hexadecimal or ``1_0``: Python's ``float`` accepts those.
_PLAIN = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?"
_NUMBER = re.compile(_PLAIN)
_SEPARATORS = re.compile(r"[,;\s]+")
#: A data line of a text record: plain numbers separated by blanks, tabs, commas or semicolons.
_DATA_LINE = re.compile(rf"{_PLAIN}(?:[,;\s]+{_PLAIN})*[,;]?")
#: A data line of an AT2 file: Fortran fixed-width fields may touch when a value is negative.
_AT2_LINE = re.compile(rf"\s*{_PLAIN}(?:(?:[\s,]+|(?=[-+])){_PLAIN})*\s*")
#: Units stated in a header or comment line: ``units: g``, ``units = m/s2``.
_UNITS_STATEMENT = re.compile(r"\bunits?\s*[:=]\s*([^\s,;]+)", re.I)
#: Units of a column title: ``acc [g]``, ``a (cm/s2)``.
_BRACKETED = re.compile(r"[\[(]\s*([^\]()\[]{1,12}?)\s*[\])]")
_TIME_UNITS = ("s", "sec", "second", "seconds")


@dataclass(frozen=True)
class Record:
    """A uniformly sampled ground acceleration: horizontal, and optionally vertical.

    Attributes
    ----------
    acceleration : horizontal ground acceleration [m/s2], usual sign convention (positive along +x).
    dt : time step [s], in ``[MIN_RECORD_DT, MAX_RECORD_DT]`` of :mod:`screening.core.limits`.
    name : a short name (the file stem by default).
    source : the file read, or ``""``.
    units_in : the units of the file (``"g"``, ``"m/s2"``, ...).
    metadata : header information (AT2 title and station).
    vertical : vertical ground acceleration [m/s2] (positive upwards) on the same samples, or
        ``None``.  Read from the third column of a text record; :func:`screening.simulate` drives
        the block with it as a change of gravity ``g -> g + a_v(t)`` unless ``vertical=False``.
    """

    acceleration: np.ndarray
    dt: float
    name: str = "record"
    source: str = ""
    units_in: str = "m/s2"
    metadata: dict = field(default_factory=dict)
    vertical: np.ndarray | None = None

    def __post_init__(self):
        acc = _samples(self.name, "acceleration", self.acceleration)
        object.__setattr__(self, "acceleration", acc)
        object.__setattr__(self, "dt", check_time_step(self.dt, f"record {self.name!r}: time step 'dt'"))
        if self.vertical is not None:
            vert = _samples(self.name, "vertical", self.vertical)
            if vert.size != acc.size:
                raise ValueError(f"record {self.name!r}: 'vertical' has {vert.size} samples, 'acceleration' "
                                 f"{acc.size}")
            object.__setattr__(self, "vertical", vert)

    @property
    def times(self):
        """Sample times ``j dt`` [s]."""
        return self.dt * np.arange(self.acceleration.size)

    @property
    def duration(self):
        """``(n - 1) dt`` [s]."""
        return self.dt * (self.acceleration.size - 1)

    @property
    def pga(self):
        """Peak ground acceleration ``max |a|`` [m/s2] (horizontal)."""
        return float(np.max(np.abs(self.acceleration)))

    def scaled(self, factor):
        """The record with both components multiplied by ``factor`` (checked by :func:`check_scale`)."""
        factor = check_scale(factor)
        vertical = None if self.vertical is None else self.vertical * factor
        return replace(self, acceleration=self.acceleration * factor, vertical=vertical)

    def to_dataarray(self):
        """The record as an ``xarray.DataArray`` on ``t`` [s] (CF attributes)."""
        import xarray as xr
        return xr.DataArray(self.acceleration, dims="t", coords={"t": ("t", self.times, {"units": "s"})},
                            name="ground_acceleration",
                            attrs={"units": "m s-2", "long_name": "horizontal ground acceleration (+x)",
                                   "record": self.name, "source": self.source})


def _samples(name, what, values):
    arr = np.asarray(values)
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"record {name!r}: '{what}' must be numbers (got dtype {arr.dtype})")
    if arr.size > limits.MAX_RECORD_SAMPLES:
        raise ValueError(f"record {name!r} has {arr.size} samples; at most {limits.MAX_RECORD_SAMPLES}")
    arr = np.ascontiguousarray(arr, dtype=float).ravel()
    if arr.size < 2:
        raise ValueError(f"record {name!r} has {arr.size} sample(s); need at least 2")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"record {name!r} has non-finite accelerations ('{what}')")
    return arr


def check_time_step(dt, what="parameter 'dt'"):
    """``dt`` [s] as a float in ``[MIN_RECORD_DT, MAX_RECORD_DT]`` (:mod:`screening.core.limits`).

    Parameters
    ----------
    dt : float
        A record's time step [s]; a boolean is refused.
    what : str, default "parameter 'dt'"
        How ``dt`` is named in the message.

    Returns
    -------
    float
        ``dt`` [s]; ``ValueError`` ``"<what> must be a number of seconds in [1e-06, 1] (got ...)"`` otherwise.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    >>> check_time_step(0.005)
    0.005
    >>> check_time_step(2)
    Traceback (most recent call last):
    ...
    ValueError: parameter 'dt' must be a number of seconds in [1e-06, 1] (got 2)
    """
    lo, hi = limits.MIN_RECORD_DT, limits.MAX_RECORD_DT
    ok = isinstance(dt, numbers.Real) and not isinstance(dt, (bool, np.bool_)) and lo <= float(dt) <= hi
    if not ok:
        raise ValueError(f"{what} must be a number of seconds in [{lo:g}, {hi:g}] (got {dt!r})")
    return float(dt)


def check_scale(scale, what="parameter 'scale'", signed=False):
    """A factor [-] on a record: finite, ``0 < scale <= MAX_RECORD_SCALE`` (``signed``: ``0 < |scale|``, a mirrored record).

    Parameters
    ----------
    scale : float
        The factor on the accelerations [-].
    what : str, default "parameter 'scale'"
        How ``scale`` is named in the message.
    signed : bool, default False
        Allow a negative factor.

    Returns
    -------
    float
        ``scale``; ``ValueError`` where it is not a finite number in the range.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    >>> check_scale(2), check_scale(-1.0, signed=True)
    (2.0, -1.0)
    >>> check_scale(-1.0)
    Traceback (most recent call last):
    ...
    ValueError: parameter 'scale' must be a finite number with 0 < scale <= 1000 (got -1.0)
    """
    top = limits.MAX_RECORD_SCALE
    ok = isinstance(scale, numbers.Real) and not isinstance(scale, (bool, np.bool_)) and math.isfinite(scale)
    ok = ok and (0.0 < abs(scale) <= top if signed else 0.0 < scale <= top)
    if not ok:
        rng = f"0 < |scale| <= {top:g}" if signed else f"0 < scale <= {top:g}"
        raise ValueError(f"{what} must be a finite number with {rng} (got {scale!r})")
    return float(scale)


def unit_factor(units):
    """Factor [m s-2 per unit] turning ``units`` into m/s2: 9.80665 (:data:`STANDARD_GRAVITY`) for ``"g"``, 1 for ``"m/s2"``, 0.01 for ``"cm/s2"``/``"gal"``.

    Parameters
    ----------
    units : str
        The units of a record's accelerations; case and blanks ignored, and the spellings ``m/s^2``,
        ``m s-2``, ``m/s**2``, ``m/sec2``, ``m/s/s`` (and their ``cm`` forms) accepted.

    Returns
    -------
    float
        The factor; ``ValueError`` for other units.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    >>> unit_factor("g"), unit_factor("CM/S2"), unit_factor("gal"), unit_factor("m s-2")
    (9.80665, 0.01, 0.01, 1.0)
    >>> unit_factor("ft/s2")
    Traceback (most recent call last):
    ...
    ValueError: parameter 'units' must be one of ('g', 'm/s2', 'cm/s2') (got 'ft/s2')
    """
    key = _unit_key(units)
    if key is None:
        raise ValueError(f"parameter 'units' must be one of ('g', 'm/s2', 'cm/s2') (got {units!r})")
    return UNITS[key]


def _unit_key(units):
    key = str(units).strip().lower().replace(" ", "")
    key = {"m/s**2": "m/s2", "ms-2": "m s-2", "cm/s**2": "cm/s2", "m/sec2": "m/s2", "cm/sec2": "cm/s2",
           "m/s/s": "m/s2", "cm/s/s": "cm/s2"}.get(key, key)
    return key if key in UNITS else None


def _name(path):
    return os.path.splitext(os.path.basename(str(path)))[0]


def _read_text(path):
    return read_input_text(path, "record file", limits.MAX_RECORD_BYTES)


def _stated_units(path, stated, given, option, hint="a header line such as 'units: g'"):
    """The units of a record: ``given`` (the caller's option) and ``stated`` (``{line: units}`` read
    from the file) must agree; neither: ``ValueError`` naming ``option`` and the header ``hint``."""
    found = set(stated.values())
    if len(found) > 1:
        lines = ", ".join(str(n) for n in sorted(stated))
        raise ValueError(f"{path}: lines {lines} state different acceleration units")
    if given is not None:
        unit_factor(given)
        if found and _unit_key(given) != _unit_key(next(iter(found))):
            line = min(stated)
            raise ValueError(f"{path}: line {line} states the units {next(iter(found))!r} but {option} "
                             f"{given!r} was given")
        return given
    if not found:
        raise ValueError(f"{path}: the acceleration units are not stated; give {option} (g, m/s2 or cm/s2) "
                         f"or {hint}")
    return next(iter(found))


def _header_units(line):
    """Units stated on a header or comment line (``units: g`` or column titles ``acc [g]``), or ``None``.
    Time units (``[s]``) are skipped; brackets holding anything else than a known unit are ignored."""
    match = _UNITS_STATEMENT.search(line)
    words = [match.group(1)] if match else _BRACKETED.findall(line)
    found = {_unit_key(w) for w in words if w.strip().lower() not in _TIME_UNITS} - {None}
    if match and not found:
        raise ValueError("states acceleration units other than g, m/s2 or cm/s2")
    if len(found) > 1:
        raise ValueError("states two different acceleration units")
    return next(iter(found)) if found else None


def _layout(path, text, data_line, first=0):
    """``(data, header)`` of a record's ``text``: the data block (:class:`_Data`) and the header and
    comment lines before it (``(line number, text)``).

    The data runs from the first to the last line of numbers; lines before it that are not numbers
    are a header, lines after it a footer.  A line inside the data that is not numbers is refused
    (by :func:`_values`).  Lines from ``first`` (0-based) on are read."""
    lines = text.splitlines()

    def numbers(line):
        return bool(data_line.fullmatch(line.partition("#")[0].strip()))

    header, i = [], first
    while i < len(lines) and not numbers(lines[i]):
        line, _, comment = lines[i].partition("#")
        header.extend((i + 1, part) for part in (comment, line.strip()) if part)
        i += 1
    if i == len(lines):
        raise ValueError(f"{path}: no data (no line of plain decimal numbers)")
    j = len(lines) - 1
    while not numbers(lines[j]):
        j -= 1
    if j - i + 1 > limits.MAX_RECORD_SAMPLES:
        raise ValueError(f"{path}: more than {limits.MAX_RECORD_SAMPLES} data lines")
    return _Data(path, i + 1, lines[i:j + 1], data_line), header


#: Characters of a data block once comments are gone: digits, signs, points, exponents, separators.
_DATA_CHARS = frozenset("0123456789+-.eEdD,; \t\n")
#: Separators to blanks and Fortran's ``D`` exponent to ``E``.
_NORMAL = str.maketrans({",": " ", ";": " ", "\t": " ", "D": "E", "d": "e"})
#: A sign that follows a digit or a point: two Fortran fields that touch (AT2 files).
_TOUCHING = re.compile(r"(?<=[0-9.])(?=[-+])")


@dataclass
class _Data:
    """The data lines of a record: ``lines`` from line number ``start`` (1-based) on."""

    path: str
    start: int
    lines: list
    data_line: re.Pattern

    def values(self, touching=False):
        """``(values, widths)``: every number in the data (float64, row by row) and the count of
        numbers on each line (0 on empty lines).  ``touching``: split Fortran fields that touch.

        The fast path checks the characters of the whole block and lets numpy convert the
        tokens (with only digits, signs, points and exponents, a token numpy takes is a plain
        decimal number); any failure re-checks line by line to name the first bad line."""
        text = "\n".join(self.lines)
        if "#" in text:
            text = re.sub(r"#[^\n]*", "", text)
        if touching:
            text = _TOUCHING.sub(" ", text)
        if set(text) <= _DATA_CHARS:
            text = text.translate(_NORMAL)
            try:
                values = np.array(text.split(), dtype=float)
            except ValueError:
                values = None
            if values is not None:
                if not np.all(np.isfinite(values)):
                    raise ValueError(f"{self.path}: a value overflows a float (larger than 1.8e308)")
                return values, np.array([len(line.split()) for line in text.split("\n")])
        rows = []
        for k, line in enumerate(self.lines):
            line = line.partition("#")[0].strip()
            if line and not self.data_line.fullmatch(line):
                raise ValueError(f"{self.path}, line {self.start + k}: not a row of plain decimal numbers, inside "
                                 f"the data (lines {self.start} to {self.start + len(self.lines) - 1})")
            rows.append(_NUMBER.findall(line))
        # every line is numbers, separated by characters the fast path does not know (a non-breaking space)
        values = np.array([t.translate(_NORMAL) for row in rows for t in row], dtype=float)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{self.path}: a value overflows a float (larger than 1.8e308)")
        return values, np.array([len(row) for row in rows])


def read_at2(path, units=None, option="units", dt=None):
    r"""Read a PEER NGA ``.AT2`` file (NGA-West2 ``NPTS=  5590, DT=   .0050 SEC`` or NGA-West1 ``5590 .0050 NPTS, DT`` header) in m/s2.

    Parameters
    ----------
    path : str or path-like
        The ``.AT2`` file.
    units : {"g", "m/s2", "cm/s2"}, optional
        The file's units where its third line (``... IN UNITS OF G``) does not state them; both must agree.
    option : str, default "units"
        How ``units`` is spelled in messages (``"--units"``, ``"records.units"``).
    dt : float, optional
        The time step [s] the caller expects; must agree with the header's DT (relative 1e-6).

    Returns
    -------
    Record
        ``dt`` [s] from the header, ``name`` the file stem, ``units_in`` the file's units, ``metadata`` the
        title and station lines.  ``ValueError`` (file and line number) for a header without NPTS and DT,
        another sample count, a token that is not a plain decimal number, numbers after a footer line.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files"); [ancheta2014]

    Examples
    --------
    A four-sample NGA-West2 file in g:

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "RSN1_TEST.AT2"
    ...     _ = path.write_text("PEER NGA STRONG MOTION DATABASE RECORD\n"
    ...                         "Test event, station, 090\n"
    ...                         "ACCELERATION TIME SERIES IN UNITS OF G\n"
    ...                         "NPTS=      4, DT=   .0100 SEC\n"
    ...                         "  0.1000E+00 -0.2000E+00  0.0000E+00  0.4000E+00\n")
    ...     record = read_at2(path)
    >>> record.name, record.dt, record.units_in, record.acceleration.round(6).tolist()   # g -> m/s2
    ('RSN1_TEST', 0.01, 'g', [0.980665, -1.96133, 0.0, 3.92266])
    """
    lines = _read_text(path).splitlines()
    if len(lines) < 5:
        raise ValueError(f"{path}: not a PEER .AT2 file (fewer than 4 header lines and data)")
    upper = lines[2].upper()
    stated = {}
    if "UNITS OF" in upper:
        rest = upper.split("UNITS OF", 1)[1].split()
        word = rest[0].strip(".,") if rest else ""
        key = {"G": "g"}.get(word) or _unit_key(word.lower())
        if key is None:
            raise ValueError(f"{path}, line 3: units other than G, CM/S2 or M/S2")
        stated[3] = key
    units = _stated_units(path, stated, units, option, "a third line '... IN UNITS OF G'")
    npts, step = _at2_npts_dt(path, lines[3])
    if dt is not None and abs(check_time_step(dt) - step) > 1e-6 * step:
        raise ValueError(f"{path}: the AT2 header gives DT = {step:g} s but dt = {dt!r} was given")
    data, _ = _layout(path, "\n".join(lines), _AT2_LINE, first=4)
    values, _ = data.values(touching=True)
    if values.size != npts:
        raise ValueError(f"{path}: the AT2 header says NPTS={npts} but the file has {values.size} values")
    return Record(values * unit_factor(units), step, name=_name(path), source=str(path), units_in=units,
                  metadata={"title": lines[0].strip(), "station": lines[1].strip()})


def _at2_npts_dt(path, header):
    """``(NPTS, DT)`` of AT2 header line 4: ``NPTS= 5590, DT= .0050 SEC`` or ``5590 .0050 NPTS, DT``
    (the numbers in the order of the labels)."""
    where = f"{path}, line 4"
    m_npts = re.search(r"NPTS\s*=\s*([^\s,]+)", header, re.I)
    m_dt = re.search(r"DT\s*=\s*([^\s,]+?)(?:SEC)?(?=[\s,]|$)", header, re.I)
    if m_npts and m_dt:
        npts_text, dt_text = m_npts.group(1), m_dt.group(1)
    else:
        labels = re.findall(r"\b(NPTS|DT)\b", header, re.I)
        head = header[:re.search(r"\b(NPTS|DT)\b", header, re.I).start()] if labels else ""
        values = [v for v in _SEPARATORS.split(head) if v]
        if sorted(x.upper() for x in labels) != ["DT", "NPTS"] or len(values) != 2:
            raise ValueError(f"{where}: expected 'NPTS= n, DT= dt SEC' or 'n dt NPTS, DT'")
        given = dict(zip((x.upper() for x in labels), values))
        npts_text, dt_text = given["NPTS"], given["DT"]
    if not re.fullmatch(r"\d+", npts_text) or not 2 <= int(npts_text) <= limits.MAX_RECORD_SAMPLES:
        raise ValueError(f"{where}: NPTS must be an integer in 2..{limits.MAX_RECORD_SAMPLES}")
    if not _NUMBER.fullmatch(dt_text):
        raise ValueError(f"{where}: DT is not a plain decimal number")
    dt = float(dt_text.replace("D", "E").replace("d", "e"))
    return int(npts_text), check_time_step(dt, f"{where}: DT")


def _columns(data):
    """The numbers of ``data`` (:class:`_Data`) as a 2-d array of columns (1, 2 or 3 numbers per line,
    the same on every line), or a 1-d stream when lines hold 4 or more numbers (the last line may
    hold fewer); empty lines are skipped."""
    values, widths = data.values()
    used = np.flatnonzero(widths)
    width = int(widths[used[0]])
    check = used if width <= 3 else used[:-1]
    bad = check[widths[check] != width]
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"{data.path}, line {data.start + k}: {int(widths[k])} numbers, but the data starts with "
                         f"{width} per line (line {data.start + int(used[0])})")
    return values.reshape(-1, width) if width <= 3 else values


def _time_step(path, t, dt):
    """The time step of a uniform time column ``t`` [s]; ``dt`` (if given) must agree with it."""
    steps = np.diff(t)
    if steps.size == 0 or np.any(steps <= 0.0):
        raise ValueError(f"{path}: the time column must increase strictly")
    step = (t[-1] - t[0]) / (t.size - 1)
    if np.max(np.abs(steps - step)) > 1e-3 * step:
        raise ValueError(f"{path}: the time step is not uniform (from {steps.min():g} to {steps.max():g} s); "
                         f"resample the record first")
    if dt is not None and abs(check_time_step(dt) - step) > 1e-3 * step:
        raise ValueError(f"{path}: the time column gives a step of {step:g} s but dt = {dt!r} was given "
                         f"(a record with a time column needs no dt)")
    return step


def read_text_record(path, dt=None, units=None, option="units"):
    r"""Read a text or CSV record: time and horizontal (and vertical) acceleration columns, or accelerations only.

    Parameters
    ----------
    path : str or bytes or path-like
        The file: two columns time [s] and acceleration, three with the vertical one (uniform time step
        within 1e-3), or one column (or four and more numbers a line, read row by row) of accelerations.
    dt : float, optional
        The time step [s]: required without a time column, checked against it otherwise.
    units : {"g", "m/s2", "cm/s2"}, optional
        Required unless a header line or the column titles state them (module docstring).
    option : str, default "units"
        How the caller's ``units`` is spelled in messages.

    Returns
    -------
    Record
        In m/s2 (``vertical`` from a third column, else None), ``dt`` [s], ``name`` the file stem,
        ``units_in``; ``ValueError`` (file and line) for units stated nowhere or disagreeing, a time step
        missing or not uniform, a row that is not plain decimal numbers.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    A CSV file whose column titles state the units:

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "station.csv"
    ...     _ = path.write_text("time [s], acc [cm/s2]\n0.00, 10\n0.02, -20\n0.04, 5\n")
    ...     record = read_text_record(path)                      # units from the column titles
    >>> record.dt, record.units_in, record.acceleration.tolist()
    (0.02, 'cm/s2', [0.1, -0.2, 0.05])
    """
    return _text_record(path, dt, units, option)[0]


def _text_record(path, dt, units, option):
    """``(record, columns)``: :func:`read_text_record` and the number of columns (0: a stream of
    accelerations, several per line)."""
    data, header = _layout(path, _read_text(path), _DATA_LINE)
    stated = {}
    for number, line in header:
        try:
            found = _header_units(line)
        except ValueError as exc:
            raise ValueError(f"{path}, line {number}: {exc}") from None
        if found is not None:
            stated[number] = found
    units = _stated_units(path, stated, units, option)
    values = _columns(data)
    factor = unit_factor(units)
    vertical = None
    if values.ndim == 2 and values.shape[1] >= 2:
        dt = _time_step(path, values[:, 0], dt)
        acc = values[:, 1]
        if values.shape[1] == 3:
            vertical = values[:, 2] * factor
    else:
        if dt is None:
            raise ValueError(f"{path}: accelerations without a time column need the time step 'dt' [s]")
        acc = values.ravel()
    record = Record(acc * factor, dt, name=_name(path), source=str(path), units_in=str(units), vertical=vertical)
    return record, (values.shape[1] if values.ndim == 2 else 0)


def read_two_column(path, units=None):
    r"""Read time [s] and acceleration columns; the record starts at the first time (shifted to 0).

    Parameters
    ----------
    path : str or path-like
        Two numbers a data line, uniform time step.
    units : {"g", "m/s2", "cm/s2"}, optional
        Required unless the file states them.

    Returns
    -------
    Record
        In m/s2, ``dt`` [s] from the time column; ``ValueError`` for other columns, units stated nowhere or
        a non-uniform time step.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    Times from 1 s: the record is shifted to start at 0.

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "a.txt"
    ...     _ = path.write_text("1.00 0.1\n1.01 0.2\n1.02 -0.1\n")
    ...     record = read_two_column(path, units="g")
    >>> round(record.dt, 12), record.pga                           # PGA [m/s2] = 0.2 g
    (0.01, 1.96133)
    """
    record, columns = _text_record(path, None, units, "units")
    if columns != 2:
        raise ValueError(f"{path}: expected two columns (time, acceleration) on every data line")
    return record


def read_single_column(path, dt, units=None):
    r"""Read accelerations only (one or more a line, row by row) with the time step ``dt`` [s] given.

    Parameters
    ----------
    path : str or path-like
        The file.
    dt : float
        The time step [s] (:func:`check_time_step`).
    units : {"g", "m/s2", "cm/s2"}, optional
        Required unless a header line states them.

    Returns
    -------
    Record
        In m/s2; ``ValueError`` for ``dt`` missing, a time column found, units stated nowhere.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    Six samples on two lines, the units in a header line:

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "a.txt"
    ...     _ = path.write_text("# units = m/s2\n0.1 0.2 0.3 0.4\n0.5 0.6\n")
    ...     record = read_single_column(path, dt=0.005)
    >>> record.acceleration.size, record.duration                  # six samples: 5 x 0.005 s
    (6, 0.025)
    """
    if dt is None:
        raise ValueError(f"{path}: a one-column record needs its time step 'dt' [s]")
    record, columns = _text_record(path, dt, units, "units")
    if columns not in (0, 1):
        raise ValueError(f"{path}: {columns} columns: the first is time; read it with read_record")
    return record


def read_record(path, dt=None, units=None, option="units"):
    r"""Read a record in any supported format: ``.at2`` (any case) by :func:`read_at2`, else :func:`read_text_record`.

    Parameters
    ----------
    path : str or bytes or path-like
        The record file.
    dt : float, optional
        The time step [s]: required without a time column, checked against it or the AT2 header otherwise.
    units : {"g", "m/s2", "cm/s2"}, optional
        Needed where the file does not state them (module docstring).
    option : str, default "units"
        How ``units`` is spelled in messages (``"--units"``, ``"records.units"``).

    Returns
    -------
    Record
        The accelerations [m/s2] and the time step [s].

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files"); [ancheta2014]

    Examples
    --------
    A file that states no units is refused unless they are given:

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "a.dat"
    ...     _ = path.write_text("0.1\n-0.3\n0.2\n")
    ...     try:
    ...         read_record(path, dt=0.01, option="--units")       # units stated nowhere: refused
    ...     except ValueError as exc:
    ...         print(str(exc).split(": ", 1)[1])
    ...     read_record(path, dt=0.01, units="g").pga               # declared: 0.3 g [m/s2]
    the acceleration units are not stated; give --units (g, m/s2 or cm/s2) or a header line such as 'units: g'
    2.941995
    """
    path = input_path(path, "record file")
    if path.lower().endswith(".at2"):
        return read_at2(path, units, option, dt)
    return read_text_record(path, dt, units, option)


def expand_records(spec, root="."):
    """Files of a record list, sorted within each item, in item order, each once.

    Parameters
    ----------
    spec : str or path-like or list of them
        A folder (every ``.at2``/``.csv``/``.txt``/``.dat`` in it), a file, a glob (``"records/*.AT2"``) or a list.
    root : str or path-like, default "."
        The folder relative paths are taken from (the study file's).

    Returns
    -------
    list of str
        The files; ``ValueError`` for an item that matches no file.

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files")

    Examples
    --------
    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as root:
    ...     os.mkdir(os.path.join(root, "records"))
    ...     for name in ("b.at2", "a.AT2", "notes.md"):
    ...         open(os.path.join(root, "records", name), "w").close()
    ...     files = expand_records(["records", "records/a.AT2"], root=root)   # a folder, then a file again
    ...     [os.path.relpath(f, root) for f in files]
    ['records/a.AT2', 'records/b.at2']
    """
    items = [spec] if isinstance(spec, (str, os.PathLike)) else list(spec)
    found = []
    for item in items:
        p = os.path.join(root, os.fspath(item))
        if os.path.isdir(p):
            hits = [os.path.join(p, f) for f in os.listdir(p)
                    if f.lower().endswith((".at2", ".csv", ".txt", ".dat"))]
        else:
            hits = _glob.glob(p)
        if not hits:
            raise ValueError(f"records {item!r} match no file (under {os.path.abspath(root)})")
        found.extend(sorted(hits))
    seen, out = set(), []
    for f in found:
        key = os.path.abspath(f)
        if key not in seen:
            seen.add(key)
            out.append(f)
    return out


def write_at2(path, record, title="screening synthetic record", station="synthetic"):
    """Write ``record`` as a PEER NGA-West2 style ``.AT2`` file in g, 5 values a line (8 significant digits), atomically.

    Parameters
    ----------
    path : str or path-like
        The file to write; an existing one is replaced whole or not at all.
    record : Record
        Its accelerations [m/s2] are written in g (:data:`STANDARD_GRAVITY`).
    title, station : str
        Header line 2.

    Returns
    -------
    None

    References
    ----------
    ``docs/records.md`` (sections "Units" and "Files"); [ancheta2014]

    Examples
    --------
    A round trip:

    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "pulse.AT2"
    ...     write_at2(path, Record([0.0, 9.80665, -4.903325], 0.01))
    ...     lines = path.read_text().splitlines()
    ...     again = read_at2(path)
    >>> lines[2], lines[3]
    ('ACCELERATION TIME SERIES IN UNITS OF G', 'NPTS=       3, DT= 0.010000 SEC')
    >>> again.acceleration.tolist()                                 # back in m/s2
    [0.0, 9.80665, -4.903325]
    """
    acc_g = record.acceleration / STANDARD_GRAVITY
    with atomic_open(path, encoding="utf-8") as fh:         # a reader never sees half a record
        fh.write("PEER NGA STRONG MOTION DATABASE RECORD\n")
        fh.write(f"{title}, {station}\n")
        fh.write("ACCELERATION TIME SERIES IN UNITS OF G\n")
        fh.write(f"NPTS= {acc_g.size:7d}, DT= {record.dt:.6f} SEC\n")
        for i in range(0, acc_g.size, 5):
            fh.write("".join(f"{v:15.7E}" for v in acc_g[i:i + 5]) + "\n")
