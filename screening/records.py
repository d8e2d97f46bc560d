"""Ground-motion records: readers for PEER NGA ``.AT2`` files, two-column and one-column text.

One record is a :class:`Record`: a uniformly sampled horizontal ground acceleration [m/s2]
in the usual sign convention (positive along the +x axis of the recording instrument; see
:func:`screening.solvers.simulate.simulate` for how it drives the block), its time step
``dt`` [s], a name and where it came from.

Formats
-------
* **PEER NGA** ``.AT2`` (:func:`read_at2`): four header lines — title, event/station/component,
  ``ACCELERATION TIME SERIES IN UNITS OF G``, then either ``NPTS=  5590, DT=   .0050 SEC``
  (NGA-West2) or ``5590    .0050    NPTS, DT`` (the older NGA-West1 layout) — followed by the
  accelerations, any number per line, in ``g``.
* **Two columns** (:func:`read_two_column`): time [s] and acceleration, separated by blanks,
  tabs, commas or semicolons (``.csv`` or text); non-numeric leading lines (a header) and
  ``#`` comments are skipped.  The time step must be uniform (relative spread < 1e-6 of
  ``dt``, after rounding in the file's printed digits up to 1e-3 of ``dt``).
* **One column** (:func:`read_single_column`): the accelerations only, one per line (or any
  number per line), with the time step given.

Units of the acceleration: ``"g"`` (multiplied by :data:`STANDARD_GRAVITY`), ``"m/s2"`` or
``"cm/s2"`` (``"gal"``).  :func:`read_record` picks the reader from the suffix (``.at2``) or
from the number of columns, and takes the units from the AT2 header, else from ``units``.
"""

from __future__ import annotations

import glob as _glob
import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

#: Standard gravity [m/s2] used to convert records given in g.
STANDARD_GRAVITY = 9.80665

#: Accepted acceleration units and their factor to m/s2.
UNITS = {"g": STANDARD_GRAVITY, "m/s2": 1.0, "m/s^2": 1.0, "m s-2": 1.0, "cm/s2": 0.01, "cm/s^2": 0.01,
         "gal": 0.01}

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?")
_SEPARATORS = re.compile(r"[,;\s]+")


@dataclass(frozen=True)
class Record:
    """A uniformly sampled horizontal ground acceleration.

    Attributes
    ----------
    acceleration : ground acceleration [m/s2], usual sign convention (positive along +x).
    dt : time step [s], > 0.
    name : a short name (the file stem by default).
    source : the file read, or ``""``.
    units_in : the units of the file (``"g"``, ``"m/s2"``, ...).
    """

    acceleration: np.ndarray
    dt: float
    name: str = "record"
    source: str = ""
    units_in: str = "m/s2"
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        acc = np.ascontiguousarray(np.asarray(self.acceleration, dtype=float).ravel())
        if acc.size < 2:
            raise ValueError(f"record {self.name!r} has {acc.size} sample(s); need at least 2")
        if not np.all(np.isfinite(acc)):
            raise ValueError(f"record {self.name!r} has non-finite accelerations")
        dt = float(self.dt)
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"record {self.name!r}: time step 'dt' must be a finite number > 0 (got {self.dt!r})")
        object.__setattr__(self, "acceleration", acc)
        object.__setattr__(self, "dt", dt)

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
        """Peak ground acceleration ``max |a|`` [m/s2]."""
        return float(np.max(np.abs(self.acceleration)))

    def to_dataarray(self):
        """The record as an ``xarray.DataArray`` on ``t`` [s] (CF attributes)."""
        import xarray as xr
        return xr.DataArray(self.acceleration, dims="t", coords={"t": ("t", self.times, {"units": "s"})},
                            name="ground_acceleration",
                            attrs={"units": "m s-2", "long_name": "horizontal ground acceleration (+x)",
                                   "record": self.name, "source": self.source})


def unit_factor(units):
    """Factor turning ``units`` into m/s2 (``"g"``, ``"m/s2"``, ``"cm/s2"``/``"gal"``)."""
    key = str(units).strip().lower().replace(" ", "")
    key = {"m/s**2": "m/s2", "ms-2": "m s-2", "cm/s**2": "cm/s2"}.get(key, key)
    if key not in UNITS:
        raise ValueError(f"parameter 'units' must be one of ('g', 'm/s2', 'cm/s2') (got {units!r})")
    return UNITS[key]


def _numbers(text):
    return [float(x.replace("D", "E").replace("d", "e")) for x in _NUMBER.findall(text)]


def _name(path):
    return os.path.splitext(os.path.basename(str(path)))[0]


def read_at2(path):
    """Read a PEER NGA ``.AT2`` file (both header layouts); accelerations converted from g to m/s2.

    Raises ``ValueError`` for a header without NPTS/DT or a sample count other than NPTS.
    """
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = fh.read().splitlines()
    if len(lines) < 4:
        raise ValueError(f"{path}: not a PEER .AT2 file (fewer than 4 header lines)")
    units_line = lines[2].upper()
    units = "g"
    if "UNITS OF" in units_line:
        rest = units_line.split("UNITS OF", 1)[1].split()
        word = rest[0] if rest else "G"
        units = {"G": "g", "CM/S2": "cm/s2", "CM/SEC2": "cm/s2", "CM/S/S": "cm/s2", "M/S2": "m/s2"}.get(word, None)
        if units is None:
            raise ValueError(f"{path}: unknown units {word!r} in the AT2 header")
    header = lines[3]
    m_npts = re.search(r"NPTS\s*=\s*(\d+)", header, re.I)
    m_dt = re.search(r"DT\s*=\s*(" + _NUMBER.pattern + ")", header, re.I)
    if m_npts and m_dt:
        npts, dt = int(m_npts.group(1)), float(m_dt.group(1))
    else:
        values = _numbers(header)
        if len(values) < 2 or "NPTS" not in header.upper():
            raise ValueError(f"{path}: AT2 header line 4 has no NPTS and DT ({header.strip()!r})")
        npts, dt = int(values[0]), float(values[1])
    data = np.array(_numbers(" ".join(lines[4:])), dtype=float)
    if data.size != npts:
        raise ValueError(f"{path}: the AT2 header says NPTS={npts} but the file has {data.size} values")
    return Record(data * unit_factor(units), dt, name=_name(path), source=str(path), units_in=units,
                  metadata={"title": lines[0].strip(), "station": lines[1].strip()})


def _numeric_rows(path):
    rows = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            parts = [p for p in _SEPARATORS.split(text) if p]
            try:
                rows.append([float(p.replace("D", "E").replace("d", "e")) for p in parts])
            except ValueError:
                if rows:
                    raise ValueError(f"{path}: non-numeric line after the data started: {line.strip()!r}")
                continue                                        # header line
    if not rows:
        raise ValueError(f"{path}: no numeric data")
    return rows


def read_two_column(path, units="m/s2"):
    """Read time [s] and acceleration columns (blank, tab, comma or semicolon separated).

    The time step must be uniform; the record starts at the first time given (shifted to 0).
    """
    rows = _numeric_rows(path)
    if any(len(r) != 2 for r in rows):
        raise ValueError(f"{path}: expected two columns (time, acceleration) on every data line")
    data = np.array(rows)
    t, a = data[:, 0], data[:, 1]
    steps = np.diff(t)
    if steps.size == 0 or np.any(steps <= 0.0):
        raise ValueError(f"{path}: the time column must increase strictly")
    dt = (t[-1] - t[0]) / (t.size - 1)
    if np.max(np.abs(steps - dt)) > 1e-3 * dt:
        raise ValueError(f"{path}: the time step is not uniform (from {steps.min():g} to {steps.max():g} s); "
                         f"resample the record first")
    return Record(a * unit_factor(units), dt, name=_name(path), source=str(path), units_in=str(units))


def read_single_column(path, dt, units="m/s2"):
    """Read accelerations only (one or more per line) with the time step ``dt`` [s] given."""
    if dt is None:
        raise ValueError(f"{path}: a one-column record needs its time step 'dt' [s]")
    rows = _numeric_rows(path)
    values = np.array([v for r in rows for v in r], dtype=float)
    return Record(values * unit_factor(units), float(dt), name=_name(path), source=str(path), units_in=str(units))


def read_record(path, dt=None, units=None):
    """Read a record in any supported format (see the module docstring).

    ``.at2`` files are PEER NGA (units from the header); otherwise two columns are time and
    acceleration, one column needs ``dt`` [s].  ``units`` (``"g"``, ``"m/s2"``, ``"cm/s2"``)
    defaults to ``"m/s2"`` for text files.
    """
    path = str(path)
    if not os.path.isfile(path):
        raise ValueError(f"record file {path!r} does not exist")
    if path.lower().endswith(".at2"):
        return read_at2(path)
    units = "m/s2" if units is None else units
    rows = _numeric_rows(path)
    width = {len(r) for r in rows}
    if width == {2} and dt is None:
        return read_two_column(path, units)
    if dt is None:
        raise ValueError(f"{path}: not two columns (time, acceleration); give the time step 'dt' for a "
                         f"one-column record")
    return read_single_column(path, dt, units)


def expand_records(spec, root="."):
    """Files of a record list: a folder (every ``.at2``/``.csv``/``.txt``/``.dat`` in it), a glob or
    a list of these, relative to ``root``; sorted, duplicates dropped."""
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
    """Write ``record`` as a PEER NGA-West2 style ``.AT2`` file in g (5 values per line)."""
    acc_g = record.acceleration / STANDARD_GRAVITY
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("PEER NGA STRONG MOTION DATABASE RECORD\n")
        fh.write(f"{title}, {station}\n")
        fh.write("ACCELERATION TIME SERIES IN UNITS OF G\n")
        fh.write(f"NPTS= {acc_g.size:7d}, DT= {record.dt:.6f} SEC\n")
        for i in range(0, acc_g.size, 5):
            fh.write("".join(f"{v:15.7E}" for v in acc_g[i:i + 5]) + "\n")
