"""Automatic choice of the Monte Carlo model per point (``model = "auto"``).

``"auto"`` is resolved once per point, at set-up, to a registered :class:`~screening.solvers.mc_registry.MonteCarloModel`
(:func:`resolve`): the first model of the rule whose *measured* validity holds at the point, else the
rule's fallback (the coupled model).  The run path receives the resolved model and never sees the
string ``"auto"``.

The rule is data, ``screening/data/model_choice.toml``: per model, closed intervals of dimensionless
indicators the point already has (:func:`indicators`) and the excitation kinds it was measured under,
each taken from the benchmark named in the file (``benchmarks/stiff_bed_validity.py``: the model against
coupled Monte Carlo on the same ground motions, exceedance and overturning probabilities within
``max(0.03, 2.5 SE)``, peak ``var_theta`` within ``max(15 %, 2.5 SE)``), whose table ships beside it
(:data:`VALIDITY_TABLE`; the tests hold the rule inside it).  A model is never chosen outside those intervals; a
model without a measured rule (the condensed model today) is never chosen.  Method: ``docs/model_choice.md``, the
measurements: ``docs/stiff_bed_validity.md``.
"""

from __future__ import annotations

import functools
import math
import tomllib
from dataclasses import dataclass
from importlib import resources

from screening.core.condensation import cubic
from screening.core.physics import contact
from screening.solvers import mc_registry
from screening.solvers.synthesis import rocking_frequency, vertical_frequency

__all__ = []

#: The value of ``model`` that asks for the automatic choice.
AUTO = "auto"
#: The shipped rule (package data).
RULE_FILE = "model_choice.toml"
#: The measurements the rule is taken from (package data): one line per case and cheap model against coupled
#: Monte Carlo, written by ``benchmarks/stiff_bed_validity.py --report --csv`` (``docs/stiff_bed_validity.md``).
VALIDITY_TABLE = "stiff_bed_validity.csv"
#: The dimensionless indicators a rule may bound, with what they are.
INDICATORS = {
    "theta_ul_over_slenderness": "uplift angle of the bed's quasi-static contact (cubic condensation) / atan(b/h) [1]",
    "slenderness": "atan(b/h) [rad]",
    "vertical_over_rocking": "vertical frequency sqrt(2 b k / m) / full-contact rocking frequency [1]",
    "vertical_damping_ratio": "damping ratio of the block bouncing on the bed about its static indentation [1]",
}


@dataclass(frozen=True)
class Rule:
    """Where one model is vouched for: ``bounds`` ``((indicator, (low, high)), ...)`` (closed), the excitation
    kinds measured, the benchmark that measured them, ``by_excitation`` ``((kind, bounds), ...)``:
    narrower intervals for one excitation kind (each inside the common one), and ``sampler``: the registered
    model that runs ``model`` under ``"auto"`` (the same equations integrated otherwise; ``""``: ``model``)."""

    model: str
    bounds: tuple
    excitations: tuple
    benchmark: str = ""
    note: str = ""
    by_excitation: tuple = ()
    sampler: str = ""

    def bound(self, name):
        """``(low, high)`` of indicator ``name``, common to every excitation kind (``KeyError`` if the rule does
        not bound it)."""
        return dict(self.bounds)[name]

    def bounds_for(self, kind):
        """The intervals that hold for excitation ``kind``: the common ones, narrowed by that kind's."""
        out = dict(self.bounds)
        out.update(dict(self.by_excitation).get(kind, ()))
        return tuple(out.items())


def parse_rules(raw):
    """``(rules, fallback)`` from the parsed TOML of a rule file; ``ValueError`` naming the entry for a bad one.

    Checks every entry before any point is run: a registered model name, at least one indicator of
    :data:`INDICATORS` with finite ``[low, high]``, the excitation kinds measured, and per-kind
    intervals (``by_excitation``) inside the common ones.

    Parameters
    ----------
    raw : dict
        The parsed TOML (``fallback``: a registered model, default ``"coupled"``; ``model``: a list of
        tables with ``name``, ``excitations``, indicator intervals and optionally ``benchmark``,
        ``measured``, ``note``, ``by_excitation``).

    Returns
    -------
    rules : tuple of Rule
        One :class:`Rule` per ``[[model]]`` table, in file order.
    fallback : str
        The model chosen where no rule holds.

    Raises
    ------
    ValueError
        One line naming the bad entry and what it must be.

    References
    ----------
    .. [1] The package's documentation, ``docs/model_choice.md`` ("The rule is data").
    """
    fallback = raw.get("fallback", "coupled")
    if fallback not in mc_registry.names():
        raise ValueError(f"model choice: 'fallback' must be a registered model {mc_registry.names()} (got {fallback!r})")
    out = []
    for i, entry in enumerate(raw.get("model", [])):
        name = entry.get("name")
        if name not in mc_registry.names():
            raise ValueError(f"model choice: model[{i}].name must be a registered model {mc_registry.names()} "
                             f"(got {name!r})")
        bounds = _intervals(entry, f"model[{i}]", skip=("name", "benchmark", "measured", "note", "excitations",
                                                           "by_excitation", "sampler", "sampler_note"))
        sampler = entry.get("sampler", "")
        if sampler and sampler not in mc_registry.names():
            raise ValueError(f"model choice: model[{i}].sampler must be a registered model {mc_registry.names()} "
                             f"(got {sampler!r})")
        if not bounds:
            raise ValueError(f"model choice: model[{i}] ({name}) bounds no indicator: it would vouch everywhere")
        kinds = entry.get("excitations")
        if not (isinstance(kinds, list) and kinds and all(isinstance(k, str) for k in kinds)):
            raise ValueError(f"model choice: model[{i}].excitations must list the excitation kinds measured "
                             f"(got {kinds!r})")
        by_excitation = []
        for kind, table in entry.get("by_excitation", {}).items():
            where = f"model[{i}].by_excitation.{kind}"
            if kind not in kinds or not isinstance(table, dict):
                raise ValueError(f"model choice: {where} must be a table of one of the excitations {kinds}")
            narrower = _intervals(table, where)
            common = dict(bounds)
            for key, (low, high) in narrower:
                if key not in common or not common[key][0] <= low <= high <= common[key][1]:
                    raise ValueError(f"model choice: {where}.{key} must lie inside the common interval of {key} "
                                     f"(got [{low:g}, {high:g}])")
            by_excitation.append((kind, narrower))
        out.append(Rule(name, bounds, tuple(kinds), str(entry.get("benchmark", "")), str(entry.get("note", "")),
                        tuple(by_excitation), sampler))
    return tuple(out), fallback


def _intervals(table, where, skip=()):
    """``((indicator, (low, high)), ...)`` of the indicator keys of a rule table; ``ValueError`` naming a bad one."""
    bounds = []
    for key, value in table.items():
        if key in skip:
            continue
        if key not in INDICATORS:
            raise ValueError(f"model choice: {where}.{key} is not an indicator (one of {sorted(INDICATORS)})")
        ok = (isinstance(value, list) and len(value) == 2
              and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
              and value[0] <= value[1])
        if not ok:
            raise ValueError(f"model choice: {where}.{key} must be [low, high] with finite low <= high "
                             f"(got {value!r})")
        bounds.append((key, (float(value[0]), float(value[1]))))
    return tuple(bounds)


@functools.lru_cache(maxsize=1)
def rules():
    """The shipped rule: ``(rules, fallback)`` (:func:`parse_rules` of :data:`RULE_FILE`)."""
    text = resources.files("screening.data").joinpath(RULE_FILE).read_text("utf-8")
    return parse_rules(tomllib.loads(text))


def indicators(block, foundation):
    """The dimensionless indicators of :data:`INDICATORS` at one point (scalar model objects, SI).

    What a rule bounds: numbers the point already has, cheap to compute, with no Monte Carlo run.

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields: ``m`` [kg], ``b``, ``h`` [m]).
    foundation : screening.Foundation
        The bed (scalar fields: ``k`` [N/m^2], ``eps`` [1/m^2], its damping).

    Returns
    -------
    dict of float
        ``theta_ul_over_slenderness`` [1], ``slenderness`` [rad], ``vertical_over_rocking`` [1] and
        ``vertical_damping_ratio`` [1].

    Notes
    -----
    ``theta_ul`` is the uplift angle of the cubic condensation's quasi-static contact
    (:func:`screening.core.condensation.cubic.uplift_threshold`, ``m g / (2 b^2 k)`` for ``eps = 0``, eq. (19)
    in [1]_); the slenderness is ``atan(b / h)``; the frequencies are
    :func:`~screening.solvers.synthesis.vertical_frequency` (``sqrt(2 b k / m)``) and
    :func:`~screening.solvers.synthesis.rocking_frequency` (``inf`` where the block cannot stand); the damping
    ratio is :func:`vertical_damping_ratio`.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/model_choice.md``.
    """
    alpha = float(block.slenderness)
    w_r = rocking_frequency(block, foundation)
    return {"theta_ul_over_slenderness": float(cubic.uplift_threshold(block, foundation)) / alpha,
            "slenderness": alpha,
            "vertical_over_rocking": vertical_frequency(block, foundation) / w_r if w_r > 0 else math.inf,
            "vertical_damping_ratio": vertical_damping_ratio(block, foundation)}


def vertical_damping_ratio(block, foundation):
    """Damping ratio [1] of the block bouncing vertically on the bed, about the linear bed's static indentation.

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields; ``m`` [kg], ``b`` [m], ``g`` [m s-2]).
    foundation : screening.Foundation
        The bed (scalar fields; ``k`` [N m-2] and the damping of its contact law).

    Returns
    -------
    float
        ``zeta_v`` [1]; above 1 the vertical mode is overdamped.

    Notes
    -----
    :func:`screening.core.physics.contact.vertical_damping_ratio` with the dashpot taken at the static
    indentation of the linear bed ``z_st = m g / (2 b k)`` (eq. (17) in [1]_), as the rule's intervals were
    measured (``eps = 0``: the same; with a cubic term the physics layer takes the rest indentation):

        zeta_v = b (w_rate + w_indentation z_st) / sqrt(2 b k m)

    the inverse of :func:`screening.analysis.beds.c_from_vertical_damping` (Winkler ``c``) and
    :func:`screening.analysis.beds.lam_from_vertical_damping` (Hunt-Crossley ``lam``).

    """
    return float(contact.vertical_damping_ratio(block, foundation, contact.linear_indentation(block, foundation)))


def rule_of(model):
    """The shipped :class:`Rule` of ``model`` (a registered name); ``KeyError`` for a model without one.

    Parameters
    ----------
    model : str
        A registered Monte Carlo model name.

    Returns
    -------
    Rule
        Its measured validity, from :data:`RULE_FILE`.

    Raises
    ------
    KeyError
        For a model without a measured rule (the coupled and condensed models).

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed_validity.md`` (the measurements behind the rule).
    """
    for rule in rules()[0]:
        if rule.model == model:
            return rule
    raise KeyError(f"no measured rule for Monte Carlo model {model!r} in {RULE_FILE}")


def sampler_of(model, rule_set=None):
    """The registered model that runs ``model`` when ``"auto"`` picks it: its rule's ``sampler``, else ``model``.

    Parameters
    ----------
    model : str
        A model name :func:`choose` returns.
    rule_set : tuple, optional
        ``(rules, fallback)`` as :func:`parse_rules` returns; default the shipped :func:`rules`.

    Returns
    -------
    str
        A registered Monte Carlo model name.

    References
    ----------
    .. [1] The package's documentation, ``docs/stiff_bed.md`` ("Exact-contact sampler").
    """
    for rule in (rules() if rule_set is None else rule_set)[0]:
        if rule.model == model and rule.sampler:
            return rule.sampler
    return model


def vouches(rule, block, foundation, excitation_kind, check_excitation=True):
    """``(True, "")`` where ``rule`` holds at the point, else ``(False, why)``: the first indicator out of its
    measured interval, or an excitation kind not measured.

    Parameters
    ----------
    rule : Rule
        The measured validity of one model.
    block : screening.Block
        The block (scalar fields, SI).
    foundation : screening.Foundation
        The bed (scalar fields, SI).
    excitation_kind : str or None
        The excitation's ``kind`` (``"white"``, ``"kanai_tajimi"``, ...), ``None`` for ground-motion records.
    check_excitation : bool, optional
        Check the kind; with False the point needs the intervals of one of the measured kinds.

    Returns
    -------
    ok : bool
        Whether the rule holds at the point.
    why : str
        ``""``, or one line naming the indicator (its value and interval) or the kind outside the rule.

    Notes
    -----
    A rule holds where every indicator ``x_i`` of :func:`indicators` lies in its closed interval,
    ``low_i <= x_i <= high_i`` (the common interval narrowed by the excitation kind's, where given).

    References
    ----------
    .. [1] The package's documentation, ``docs/model_choice.md`` ("The rule is data").
    """
    if check_excitation and excitation_kind not in rule.excitations:
        return False, (f"excitation {excitation_kind or 'record'!r} not among those measured for {rule.model} "
                       f"{list(rule.excitations)}")
    values = indicators(block, foundation)
    why = ""
    for kind in ([excitation_kind] if check_excitation else rule.excitations):
        outside = [f"{name} = {values[name]:.3g} outside the measured [{low:g}, {high:g}] of {rule.model}"
                   + (f" under {kind}" if rule.by_excitation else "")
                   for name, (low, high) in rule.bounds_for(kind) if not low <= values[name] <= high]
        if not outside:
            return True, ""
        why = why or outside[0]
    return False, why


def choose(block, foundation, excitation_kind, rule_set=None):
    """``(model name, reason)``: the first model of the rule vouched for at the point, else the fallback.

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields, SI).
    foundation : screening.Foundation
        The bed (scalar fields, SI).
    excitation_kind : str or None
        The excitation's ``kind`` (``None`` for records).
    rule_set : tuple, optional
        ``(rules, fallback)`` as :func:`parse_rules` returns; default the shipped :func:`rules`.

    Returns
    -------
    name : str
        The registered model chosen.
    reason : str
        One line saying why (the benchmark that vouches, or why each rule failed).

    References
    ----------
    .. [1] The package's documentation, ``docs/model_choice.md``.
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
    :func:`choose`, any other name or instance by :func:`screening.solvers.mc_registry.get`.

    Parameters
    ----------
    model : str or MonteCarloModel
        ``"auto"`` (:data:`AUTO`), a registered name or a model instance.
    block : screening.Block
        The block (scalar fields, SI).
    foundation : screening.Foundation
        The bed (scalar fields, SI).
    excitation : Excitation, optional
        The point's excitation (its ``kind`` is read), ``None`` for records.

    Returns
    -------
    MonteCarloModel
        The model the point runs with (``"auto"``: the chosen model's :func:`sampler_of`).

    References
    ----------
    .. [1] The package's documentation, ``docs/model_choice.md``.
    """
    if isinstance(model, str) and model == AUTO:
        kind = getattr(excitation, "kind", None) if excitation is not None else None
        return mc_registry.get(sampler_of(choose(block, foundation, kind)[0]))
    return mc_registry.get(model)


def choices():
    """The values ``model`` accepts: the registered models and :data:`AUTO`.

    Returns
    -------
    tuple of str
        :func:`screening.solvers.mc_registry.names`, then ``"auto"``.

    References
    ----------
    .. [1] The package's documentation, ``docs/model_choice.md``.
    """
    return (*mc_registry.names(), AUTO)
