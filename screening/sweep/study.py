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

import functools
import os
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np

from screening.solvers.timegrid import output_times
from screening.sweep.config import (Accuracy, build_models, Case, ClusterSpec, DEFAULT_BUDGET_S,  # noqa: F401
                                    Fragility, Output,
                                    parse_toml, read_study_text, SpotChecks, study_fields, StudyError)
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



# ----------------------------------------------------------------------------- data
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
    #: Hash of the study text (without ``[cluster]``), the package version and the result layout (for reuse).
    key: str = field(default="", repr=False)
    output: Output = Output()
    fragility: Fragility | None = None
    accuracy: Accuracy | None = None
    #: ``[cluster]``: where the run goes when no workers or scheduler are given (not part of the ``key``)
    cluster: ClusterSpec | None = None
    #: Filled from the fields above when the study is made (a complete record: nothing is computed on reading).
    #: ``swept_dims``: the swept parameters, in grid order; ``dims``: ``case`` (with cases) then those;
    #: ``shape``: the grid's shape (without time), ``swept_shape`` without ``case``; ``times``: output times [s];
    #: ``derived_inputs``: model inputs that vary per point without being grid coordinates (``("S0",)`` when the
    #: intensity is a target PGA, else ``()``).  ``probabilities``: whether the points carry ``p_overturn`` (and, with
    #: ``[fragility]``, ``p_exceed``) with their standard errors and source: with ``[accuracy]`` or ``[fragility]``.
    swept_dims: tuple = field(init=False, repr=False, compare=False)
    dims: tuple = field(init=False, repr=False, compare=False)
    swept_shape: tuple = field(init=False, repr=False, compare=False)
    shape: tuple = field(init=False, repr=False, compare=False)
    n_points: int = field(init=False, repr=False, compare=False)
    points_per_case: int = field(init=False, repr=False, compare=False)
    times: np.ndarray = field(init=False, repr=False, compare=False)
    derived_inputs: tuple = field(init=False, repr=False, compare=False)
    probabilities: bool = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        swept_shape = tuple(len(v) for v in self.sweeps.values())
        shape = ((len(self.cases),) if self.has_case_dim else ()) + swept_shape
        derived = ("S0",) if "pga" in self.sweeps or any("pga" in c.params for c in self.cases) else ()
        for name, value in (("swept_dims", tuple(self.sweeps)),
                            ("dims", (("case",) if self.has_case_dim else ()) + tuple(self.sweeps)),
                            ("swept_shape", swept_shape), ("shape", shape),
                            ("n_points", int(np.prod(shape, dtype=np.int64))),
                            ("points_per_case", int(np.prod(swept_shape, dtype=np.int64))),
                            ("times", output_times(self.t_end, self.dt)), ("derived_inputs", derived),
                            ("probabilities", self.accuracy is not None or self.fragility is not None)):
            object.__setattr__(self, name, value)

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
    .. [1] As :func:`load_study`.

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
    return Study(**parse_toml(text, source, functools.partial(study_fields, text=text, name=name, source=source,
                                                              inventory=inventory, collect=with_collection)))


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
    return Study(**study_fields(raw, text, name, source, inventory, with_collection))
