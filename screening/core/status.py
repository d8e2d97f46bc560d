"""Every status code the package stores or returns: one enum per code space.

The code spaces are declared once, as data, in ``screening/data/status_codes.toml``: each member's
name, integer code and meaning.  This module turns each table into an :class:`enum.IntEnum` at
import (``PointStatus``, ``SampleStatus``, ``DivergenceReason``, ``SampleState``, ``SpotStatus``,
``Trust``, ``BestMethod``, ``EscalationModel``, ``EscalationEstimator``, ``TargetMet``, ``ContactRegime``, ``FitFlag``,
``ProbabilitySource``, ``AnswerQuantity``); every member
carries its ``meaning`` (plain language, for messages and documentation).  Compiled kernels read
the members as integer constants (numba supports ``IntEnum``); files store the integer with CF
``flag_values`` / ``flag_meanings`` made by :func:`flag_attributes`.  Nothing else in the package
spells a status number.

Method and how it is checked: ``docs/method.md#status-flags``.
"""

from __future__ import annotations

import enum
from importlib import resources

import numpy as np

__all__ = ["PointStatus", "SampleStatus", "DivergenceReason", "SampleState", "SpotStatus", "Trust", "BestMethod",
           "EscalationModel", "EscalationEstimator", "TargetMet", "ContactRegime", "FitFlag", "ProbabilitySource",
           "AnswerQuantity"]

try:
    import tomllib
except ModuleNotFoundError:                      # Python 3.10
    import tomli as tomllib

#: The code-space tables, as read.
CODE_SPACES = tomllib.loads(resources.files("screening.data").joinpath("status_codes.toml").read_text("utf-8"))


def code_space(name):
    """The :class:`enum.IntEnum` of table ``name`` of :data:`CODE_SPACES`, each member with its ``meaning``.

    The table's ``doc`` becomes the enum's docstring; every other entry is a member, its ``code``
    the integer value and its ``meaning`` (plain language) an attribute.

    Parameters
    ----------
    name : str
        A table of ``screening/data/status_codes.toml`` (``"PointStatus"``, ``"Trust"``, ...).

    Returns
    -------
    enum.IntEnum
        A new enum named ``name``.

    Raises
    ------
    KeyError
        No such table.

    """
    table = dict(CODE_SPACES[name])
    doc = table.pop("doc")
    codes = enum.IntEnum(name, [(member, spec["code"]) for member, spec in table.items()], module=__name__)
    codes.__doc__ = doc
    for member in codes:
        member.meaning = table[member.name]["meaning"]
    return codes


PointStatus = code_space("PointStatus")
SampleStatus = code_space("SampleStatus")
DivergenceReason = code_space("DivergenceReason")
SampleState = code_space("SampleState")
SpotStatus = code_space("SpotStatus")
Trust = code_space("Trust")
BestMethod = code_space("BestMethod")
EscalationModel = code_space("EscalationModel")
EscalationEstimator = code_space("EscalationEstimator")
TargetMet = code_space("TargetMet")
ContactRegime = code_space("ContactRegime")
FitFlag = code_space("FitFlag")
ProbabilitySource = code_space("ProbabilitySource")
AnswerQuantity = code_space("AnswerQuantity")

#: ``p_source`` code of Monte Carlo model ``flag_code`` 0 (the others: this plus their flag code).
MONTE_CARLO_SOURCE_BASE = 10

#: Plain-language text of the divergence reasons (messages to users).
DIVERGENCE_TEXT = {reason: reason.meaning for reason in DivergenceReason}


def probability_sources(models):
    """``{name: code}`` of every :data:`ProbabilitySource`, with ``monte_carlo_<model>`` at
    :data:`MONTE_CARLO_SOURCE_BASE` plus the model's flag code for each of ``models`` (``{name: flag code}``;
    a sequence of names takes their positions).

    Parameters
    ----------
    models : mapping of str to int, or sequence of str
        The Monte Carlo models and their flag codes.

    Returns
    -------
    dict
        ``{source name: integer code}``: the codes of ``probability_source`` in result files.

    """
    pairs = models.items() if hasattr(models, "items") else ((m, i) for i, m in enumerate(models))
    return {**{m.name: int(m) for m in ProbabilitySource},
            **{f"monte_carlo_{model}": MONTE_CARLO_SOURCE_BASE + int(c) for model, c in pairs}}


def flag_attributes(code_space, long_name, dtype=np.int8):
    """CF flag attributes ``{long_name, flag_values, flag_meanings}`` of an enum or a list of its members
    (sorted by value).

    Parameters
    ----------
    code_space : enum.IntEnum or iterable of its members
        The codes a variable may hold.
    long_name : str
        The variable's CF ``long_name`` [-].
    dtype : numpy dtype, default numpy.int8
        The type of ``flag_values`` (that of the stored variable).

    Returns
    -------
    dict
        ``long_name``; ``flag_values``, the codes as an array of ``dtype``; ``flag_meanings``, the
        member names separated by blanks, in the order of the values.

    """
    members = sorted(code_space, key=int)
    return {"long_name": long_name,
            "flag_values": np.array([int(m) for m in members], dtype=dtype),
            "flag_meanings": " ".join(m.name for m in members)}
