"""A collection of objects as a CSV table, turned into the named ``[[case]]`` tables of a study.

``[collection] file = "objects.csv"`` in a study (relative to the study's folder), or ``screening run
STUDY --inventory objects.csv``: one row per object.  Columns (SI units; the header names them, in any
order, ``#`` starts a comment line):

* ``name`` (unique), ``m`` [kg], ``b`` [m] (half-width), ``h`` [m] (height of the centre of mass),
  ``depth`` [m] (out-of-plane depth of the base): required;
* the bed, each optional (an empty cell or a missing column keeps the study's ``[foundation]``):
  ``k`` [N m-2], ``lam`` [N s m-3], ``c`` [N s m-2], ``eps`` [m-2], or ``material`` (a key of
  :data:`screening.analysis.beds.TYPICAL`, e.g. ``lime mortar``) with ``thickness`` [m] of the layer, from which
  ``k = E_c depth / thickness`` (:func:`screening.analysis.beds.layer_stiffness`, the middle of the material's
  ranges: geometric mean of ``E``, mean of ``nu`` and of the damping ratio) and the damping
  (:func:`screening.analysis.beds.lam_from_vertical_damping` or :func:`~screening.analysis.beds.c_from_vertical_damping`).

Every row becomes a case named by ``name`` that sets ``block.m``, ``block.b``, ``block.h`` and the bed
keys it gives; the study validates each case as a ``[[case]]`` table.  Bad rows stop the study
before any work with one line naming the file, the line and the field.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from screening.analysis import beds
from screening.sweep.config import StudyError

__all__ = []

#: Columns every row must give, with their units.
REQUIRED_COLUMNS = {"name": "", "m": "kg", "b": "m", "h": "m", "depth": "m"}
#: Optional bed columns (numbers), with their units.
BED_COLUMNS = {"k": "N m-2", "lam": "N s m-3", "c": "N s m-2", "eps": "m-2", "thickness": "m"}
#: Optional text columns.
TEXT_COLUMNS = ("material", "contact")


def _fail(path, line, field, problem):
    raise StudyError(f"{path}:{line}: {field}: {problem}")


def _material_bed(path, line, material, row, contact):
    if material not in beds.TYPICAL:
        _fail(path, line, "material", f"unknown material {material!r} (one of: {', '.join(beds.TYPICAL)})")
    if "thickness" not in row:
        _fail(path, line, "thickness", f"material {material!r} needs the layer's thickness [m]")
    spec = beds.TYPICAL[material]
    E = math.sqrt(spec["E"][0] * spec["E"][1])
    nu = 0.5 * (spec["nu"][0] + spec["nu"][1])
    zeta = 0.5 * (spec["zeta_v"][0] + spec["zeta_v"][1])
    if material.startswith("elastomeric"):      # a bonded pad: its shape factor from the base and the thickness
        loaded = 2 * row["b"] * row["depth"]
        bulging = 2 * (2 * row["b"] + row["depth"]) * row["thickness"]
        modulus = float(beds.pad_compression_modulus(E, loaded / bulging))
    else:
        modulus = float(beds.oedometric_modulus(E, nu))
    k = float(beds.layer_stiffness(modulus, row["thickness"], row["depth"]))
    if contact == "winkler":
        return {"k": k, "c": float(beds.c_from_vertical_damping(k, row["m"], row["b"], zeta))}
    return {"k": k, "lam": float(beds.lam_from_vertical_damping(k, row["m"], row["b"], zeta))}


def read_inventory(path):
    """The ``[[case]]`` tables of a collection CSV, and the file's text.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    cases : list of dict
        ``{"name": ..., "block": {"m", "b", "h"}, "foundation": {...}}`` per row.
    text : str
        The file's text (it goes into the study's hash: a changed collection is a changed study).

    Raises
    ------
    StudyError
        One line ``FILE:LINE: FIELD: problem``: a missing column, an empty required cell, a value that is
        not a number or not > 0 (``eps`` may have either sign), a duplicate name, an unknown material.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"{path}: cannot read the collection ({exc})") from None
    numbered = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        _fail(path, 1, "header", "empty file (expected a header: " + ",".join(REQUIRED_COLUMNS) + ", ...)")
    n0 = numbered[0][0]
    rows = list(csv.reader(io.StringIO("\n".join(line for _, line in numbered))))
    header = [h.strip() for h in rows[0]]
    known = (*REQUIRED_COLUMNS, *BED_COLUMNS, *TEXT_COLUMNS)
    for h in header:
        if h not in known:
            _fail(path, n0, h or "header", f"unknown column (allowed: {', '.join(known)})")
    for col in REQUIRED_COLUMNS:
        if col not in header:
            _fail(path, n0, col, f"missing column ({col} [{REQUIRED_COLUMNS[col]}])" if REQUIRED_COLUMNS[col]
                  else f"missing column ({col})")
    if len(rows) < 2:
        _fail(path, n0, "rows", "no object below the header")
    cases, seen = [], {}
    for (n, _), cells in zip(numbered[1:], rows[1:]):
        if len(cells) != len(header):
            _fail(path, n, "row", f"{len(cells)} cells for {len(header)} columns")
        raw = {h: c.strip() for h, c in zip(header, cells)}
        name = raw["name"]
        if not name:
            _fail(path, n, "name", "empty")
        if name in seen:
            _fail(path, n, "name", f"duplicate name {name!r} (also on line {seen[name]})")
        seen[name] = n
        row = {}
        for col in (*REQUIRED_COLUMNS, *BED_COLUMNS):
            if col == "name" or col not in raw or (raw[col] == "" and col in BED_COLUMNS):
                continue
            if raw[col] == "":
                _fail(path, n, col, "empty (a number is required)")
            try:
                value = float(raw[col])
            except ValueError:
                _fail(path, n, col, f"not a number ({raw[col]!r})")
            if not np.isfinite(value):
                _fail(path, n, col, f"not finite ({raw[col]!r})")
            if col != "eps" and not value > 0:
                _fail(path, n, col, f"{value:g} must be > 0")
            row[col] = value
        bed = {k: row[k] for k in ("k", "lam", "c", "eps") if k in row}
        contact = raw.get("contact", "")
        if contact:
            if contact not in ("hunt_crossley", "winkler"):
                _fail(path, n, "contact", f"{contact!r} is not hunt_crossley or winkler")
            bed["contact"] = contact
        material = raw.get("material", "")
        if material:
            if "k" in bed:
                _fail(path, n, "material", "give the bed either as a material or as k, not both")
            bed = {**_material_bed(path, n, material, row, contact), **bed}
        cases.append({"name": name, "block": {"m": row["m"], "b": row["b"], "h": row["h"]}, "foundation": bed})
    return cases, text


def with_collection(raw, source, inventory=None):
    """The study tables ``raw`` with its collection (``[collection] file`` or ``inventory``) as ``[[case]]``s.

    Parameters
    ----------
    raw : dict
        The parsed study.
    source : str
        The study file (its folder resolves a relative ``[collection] file``).
    inventory : str or os.PathLike, optional
        A collection CSV given on the command line (``--inventory``): replaces ``[collection]``.

    Returns
    -------
    raw : dict
        Without ``collection``, with ``case`` (a ``[block]`` table added when the study has none).
    text : str
        The collection's text (``""`` without one).

    Raises
    ------
    StudyError
        A study with both ``[[case]]`` and a collection, a ``[collection]`` without ``file``, or a bad CSV.
    """
    if inventory is None and "collection" not in raw:
        return raw, ""
    if "case" in raw:
        raise StudyError("collection: give the objects either as [[case]] tables or as a collection file, not both")
    if inventory is None:
        table = raw["collection"]
        if not isinstance(table, dict) or set(table) != {"file"} or not isinstance(table["file"], str):
            raise StudyError("collection: expected one key, file = \"objects.csv\" (a CSV, relative to the study)")
        path = Path(table["file"])
        if not path.is_absolute() and source not in ("", "<string>"):
            path = Path(source).parent / path
    else:
        path = Path(inventory)
    cases, text = read_inventory(path)
    out = {k: v for k, v in raw.items() if k != "collection"}
    out["case"] = cases
    out.setdefault("block", {})
    return out, text
