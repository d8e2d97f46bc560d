"""The block and bed of a study for deterministic record analyses (``screening simulate``, cloud analysis).

A study file describes one block and bed (or several ``[[case]]`` tables, or swept bed
parameters); a record analysis needs one of them: :func:`block_and_foundation` picks the
case by name and the swept values by ``overrides`` (``{"eps": 6e7}``), with one-line
:class:`~screening.sweep.config.StudyError` messages.  The excitation tables are not used.
"""

from __future__ import annotations

import os
from pathlib import Path

from screening.sweep.config import build_models, NUMERIC, parse_toml, read_study_text, StudyError
from screening.sweep.study import study_from_tables

__all__ = ["load_record_study", "pick_case", "block_and_foundation"]


def load_record_study(path):
    """``(study, records)``: a study file read for a record analysis — its ``[records]`` table (``None``
    if absent) taken out, and the ``[excitation]`` table optional (the records are the input).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML study file.

    Returns
    -------
    study : Study
        The validated study (a white-noise excitation stands in when the file has none; record
        analyses do not use it).
    records : dict or None
        The raw ``[records]`` table, validated by the command that reads it.

    Raises
    ------
    StudyError
        An unreadable file, invalid TOML, a ``records`` key that is not a table, or an invalid study.

    References
    ----------
    [1] ``docs/records.md``.

    Examples
    --------
    >>> import os, tempfile
    >>> from screening.sweep.study import EXAMPLE_STUDY
    >>> text = EXAMPLE_STUDY + '[records]\\nfiles = ["el_centro.AT2"]\\n'
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "bed.toml")
    ...     with open(path, "w") as fh:
    ...         _ = fh.write(text)
    ...     study, records = load_record_study(path)
    >>> study.dims, records
    (('eps',), {'files': ['el_centro.AT2']})
    """
    text = read_study_text(path)
    path = os.fsdecode(path)

    def build(raw):
        records = raw.pop("records", None)
        if records is not None and not isinstance(records, dict):
            raise StudyError("records: must be a table")
        raw.setdefault("excitation", {"kind": "white", "S0": 1.0})     # unused by record analyses
        return study_from_tables(raw, text, Path(path).stem, str(path)), records

    return parse_toml(text, str(path), build)


def pick_case(study, case=None):
    """The :class:`~screening.sweep.config.Case` named ``case`` (the only one when ``None``).

    Parameters
    ----------
    study : Study
        A validated study.
    case : str, optional
        The case's name (a ``[[case]]`` table's ``name``); may be omitted when the study has one case.

    Returns
    -------
    Case
        The chosen configuration.

    Raises
    ------
    StudyError
        No such case, or several cases and none chosen (the message lists them).

    References
    ----------
    [1] ``docs/records.md``.

    Examples
    --------
    >>> from screening.sweep.study import EXAMPLE_STUDY, parse_study
    >>> pick_case(parse_study(EXAMPLE_STUDY)).contact
    'hunt_crossley'
    """
    if case is None:
        if len(study.cases) > 1:
            names = ", ".join(repr(c.name) for c in study.cases)
            raise StudyError(f"the study has {len(study.cases)} cases; choose one with --case ({names})")
        return study.cases[0]
    for c in study.cases:
        if c.name == case:
            return c
    raise StudyError(f"--case {case!r}: no such case (cases: {', '.join(repr(c.name) for c in study.cases)})")


def block_and_foundation(study, case=None, overrides=None):
    """``(block, foundation, case)`` of one configuration of ``study`` for a record analysis.

    Swept block/bed parameters must be fixed in ``overrides`` (name -> value); swept excitation
    parameters are ignored (the record is the excitation).

    Parameters
    ----------
    study : Study
        A validated study.
    case : str, optional
        The case's name (see :func:`pick_case`).
    overrides : dict, optional
        Values of block and bed parameters (SI units, as in the study file: ``{"eps": 6e7}`` [m-2]);
        every swept block or bed parameter must be given.

    Returns
    -------
    block : Block
        The rigid block.
    foundation : Foundation
        The bed (contact law and its parameters).
    case : Case
        The configuration chosen.

    Raises
    ------
    StudyError
        An unknown case, an override that is not a block or bed parameter, a swept parameter left
        open, or values the models reject.

    References
    ----------
    [1] ``docs/records.md``.

    Examples
    --------
    >>> from screening.sweep.study import EXAMPLE_STUDY as text, parse_study
    >>> block, foundation, _ = block_and_foundation(parse_study(text), overrides={"eps": 6e7})
    >>> block.b, foundation.k, foundation.eps
    (0.035, 28900000.0, 60000000.0)
    """
    chosen = pick_case(study, case)
    overrides = dict(overrides or {})
    for key in overrides:
        if key not in NUMERIC or NUMERIC[key][0] == "excitation":
            raise StudyError(f"--set {key}: only block and foundation parameters can be set "
                             f"({', '.join(k for k, v in NUMERIC.items() if v[0] != 'excitation')})")
    values = {}
    for key, swept in study.sweeps.items():
        if NUMERIC[key][0] == "excitation":
            values[key] = float(swept[0])               # not used: the record replaces the excitation
        elif key not in overrides:
            raise StudyError(f"{NUMERIC[key][0]}.{key} is swept in the study; fix it with --set {key}=VALUE "
                             f"(swept values: {', '.join(f'{v:g}' for v in swept)})")
    values.update(overrides)
    try:
        block, foundation, _ = build_models(chosen, values, study.t_end)
    except (TypeError, ValueError) as exc:
        raise StudyError(f"study {study.name}: {exc}") from None
    return block, foundation, chosen
