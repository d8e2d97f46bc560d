"""Automatic choice of the Monte Carlo model per point (``model = "auto"``).

``"auto"`` is resolved once per point, at set-up, to a registered :class:`~screening.solvers.mc_registry.MonteCarloModel`
(:func:`resolve`): the first model of the rule whose *measured* validity holds at the point, else the
rule's fallback (the coupled model).  The run path receives the resolved model and never sees the
string ``"auto"``.

The rule is data, ``screening/data/model_choice.toml``: per model, closed intervals of dimensionless
indicators the point already has (:func:`indicators`) and the excitation kinds it was measured under,
each taken from the benchmark named in the file (``benchmarks/stiff_bed_validity.py``: the model against
coupled Monte Carlo on the same ground motions, exceedance and overturning probabilities within
``max(0.03, 2.5 SE)``).  A model is never chosen outside those intervals; a model without a measured
rule (the condensed model today) is never chosen.  Method: ``docs/model_choice.md``.
"""

from __future__ import annotations

import functools
import math
import tomllib
from dataclasses import dataclass
from importlib import resources

from screening.condensation import cubic
from screening.solvers import mc_registry
from screening.solvers.synthesis import rocking_frequency, vertical_frequency

__all__ = ["AUTO", "INDICATORS", "Rule", "RULE_FILE", "choices", "choose", "indicators", "parse_rules", "resolve",
           "rule_of", "rules", "vouches"]

#: The value of ``model`` that asks for the automatic choice.
AUTO = "auto"
#: The shipped rule (package data).
RULE_FILE = "model_choice.toml"
#: The dimensionless indicators a rule may bound, with what they are.
INDICATORS = {
    "theta_ul_over_slenderness": "uplift angle of the bed's quasi-static contact (cubic condensation) / atan(b/h) [1]",
    "slenderness": "atan(b/h) [rad]",
    "vertical_over_rocking": "vertical frequency sqrt(2 b k / m) / full-contact rocking frequency [1]",
}


@dataclass(frozen=True)
class Rule:
    """Where one model is vouched for: ``bounds`` ``{indicator: (low, high)}`` (closed), the excitation
    kinds measured, and the benchmark that measured them."""

    model: str
    bounds: tuple
    excitations: tuple
    benchmark: str = ""
    note: str = ""

    def bound(self, name):
        """``(low, high)`` of indicator ``name`` (``KeyError`` if the rule does not bound it)."""
        return dict(self.bounds)[name]


def parse_rules(raw):
    """``(rules, fallback)`` from the parsed TOML of a rule file; ``ValueError`` naming the entry for a bad one."""
    fallback = raw.get("fallback", "coupled")
    if fallback not in mc_registry.names():
        raise ValueError(f"model choice: 'fallback' must be a registered model {mc_registry.names()} (got {fallback!r})")
    out = []
    for i, entry in enumerate(raw.get("model", [])):
        name = entry.get("name")
        if name not in mc_registry.names():
            raise ValueError(f"model choice: model[{i}].name must be a registered model {mc_registry.names()} "
                             f"(got {name!r})")
        bounds = []
        for key, value in entry.items():
            if key in ("name", "benchmark", "measured", "note", "excitations"):
                continue
            if key not in INDICATORS:
                raise ValueError(f"model choice: model[{i}].{key} is not an indicator (one of {sorted(INDICATORS)})")
            ok = (isinstance(value, list) and len(value) == 2
                  and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
                  and value[0] <= value[1])
            if not ok:
                raise ValueError(f"model choice: model[{i}].{key} must be [low, high] with finite low <= high "
                                 f"(got {value!r})")
            bounds.append((key, (float(value[0]), float(value[1]))))
        if not bounds:
            raise ValueError(f"model choice: model[{i}] ({name}) bounds no indicator: it would vouch everywhere")
        kinds = entry.get("excitations")
        if not (isinstance(kinds, list) and kinds and all(isinstance(k, str) for k in kinds)):
            raise ValueError(f"model choice: model[{i}].excitations must list the excitation kinds measured "
                             f"(got {kinds!r})")
        out.append(Rule(name, tuple(bounds), tuple(kinds), str(entry.get("benchmark", "")), str(entry.get("note", ""))))
    return tuple(out), fallback


@functools.lru_cache(maxsize=1)
def rules():
    """The shipped rule: ``(rules, fallback)`` (:func:`parse_rules` of :data:`RULE_FILE`)."""
    text = resources.files("screening.data").joinpath(RULE_FILE).read_text("utf-8")
    return parse_rules(tomllib.loads(text))


def indicators(block, foundation):
    """The dimensionless indicators of :data:`INDICATORS` at one point (scalar model objects, SI).

    Notes
    -----
    ``theta_ul`` is the uplift angle of the cubic condensation's quasi-static contact
    (:func:`screening.condensation.cubic.uplift_threshold`, ``m g / (2 b^2 k)`` for ``eps = 0``);
    the frequencies are :func:`~screening.solvers.synthesis.vertical_frequency` and
    :func:`~screening.solvers.synthesis.rocking_frequency` (``inf`` where the block cannot stand).
    """
    alpha = float(block.slenderness)
    w_r = rocking_frequency(block, foundation)
    return {"theta_ul_over_slenderness": float(cubic.uplift_threshold(block, foundation)) / alpha,
            "slenderness": alpha,
            "vertical_over_rocking": vertical_frequency(block, foundation) / w_r if w_r > 0 else math.inf}


def rule_of(model):
    """The shipped :class:`Rule` of ``model`` (a registered name); ``KeyError`` for a model without one."""
    for rule in rules()[0]:
        if rule.model == model:
            return rule
    raise KeyError(f"no measured rule for Monte Carlo model {model!r} in {RULE_FILE}")


def vouches(rule, block, foundation, excitation_kind, check_excitation=True):
    """``(True, "")`` where ``rule`` holds at the point, else ``(False, why)``: the first indicator out of its
    measured interval, or an excitation kind not measured (``excitation_kind``: the excitation's
    ``kind``, ``None`` for ground-motion records; not checked with ``check_excitation=False``)."""
    if check_excitation and excitation_kind not in rule.excitations:
        return False, (f"excitation {excitation_kind or 'record'!r} not among those measured for {rule.model} "
                       f"{list(rule.excitations)}")
    values = indicators(block, foundation)
    for name, (low, high) in rule.bounds:
        v = values[name]
        if not low <= v <= high:
            return False, f"{name} = {v:.3g} outside the measured [{low:g}, {high:g}] of {rule.model}"
    return True, ""


def choose(block, foundation, excitation_kind, rule_set=None):
    """``(model name, reason)``: the first model of the rule vouched for at the point, else the fallback.

    ``rule_set``: ``(rules, fallback)`` (default the shipped :func:`rules`); ``excitation_kind``: the
    excitation's ``kind`` (``None`` for records).
    """
    chosen, fallback = rules() if rule_set is None else rule_set
    why = []
    for rule in chosen:
        ok, reason = vouches(rule, block, foundation, excitation_kind)
        if ok:
            return rule.model, f"{rule.model}: its measured validity holds ({rule.benchmark})"
        why.append(reason)
    return fallback, f"{fallback}: " + ("; ".join(why) if why else "no cheaper model has a measured rule")


def resolve(model, block, foundation, excitation=None):
    """The :class:`~screening.solvers.mc_registry.MonteCarloModel` of ``model`` at one point: ``"auto"`` by
    :func:`choose` (``excitation``: the point's excitation, ``None`` for records), any other name or
    instance by :func:`screening.solvers.mc_registry.get`."""
    if isinstance(model, str) and model == AUTO:
        kind = getattr(excitation, "kind", None) if excitation is not None else None
        return mc_registry.get(choose(block, foundation, kind)[0])
    return mc_registry.get(model)


def choices():
    """The values ``model`` accepts: the registered models and :data:`AUTO`."""
    return (*mc_registry.names(), AUTO)
