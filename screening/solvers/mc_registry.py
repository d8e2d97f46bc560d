"""The interface every Monte Carlo model implements, and the registry that resolves a model name.

A Monte Carlo model is a set of equations for one block on its bed that the engine
(:func:`screening.solvers.montecarlo.monte_carlo`, :func:`screening.solvers.simulate.simulate`)
integrates one sample at a time.  Like the condensations (:mod:`screening.core.condensation.registry`),
a model name is turned into a :class:`MonteCarloModel` once, at set-up; the run path then calls
the :class:`ChunkIntegrator` it returns and never looks at the name again.

A model registers itself by subclassing :class:`MonteCarloModel` with its own ``name`` and ``flag_code``
(as hazardlib's GSIMs do): the built-in ``coupled``, ``condensed`` (:mod:`screening.solvers.mc_models`),
``stiff_bed`` and ``stiff_bed_fast``.  Everything that lists the models reads the registry when used.

Every model reports the same per-sample results: the state on the output grid as
``(theta, theta', z_cb, z_cb')`` (models without a vertical state fill ``z_cb`` columns with
zeros), an uplift flag, the peak ``|theta|``, the status (ok / overturned / diverged with a
reason, :class:`screening.core.status.SampleStatus`) and its step counts.
"""

from __future__ import annotations

import abc
import enum
import warnings

from screening.core import condensation as condensations
from screening.core.registry import NamedModel
from screening.core.status import BestMethod, EscalationModel

__all__ = []

#: The condensation a model that is not condensed builds its kernel record with (none of its
#: functions is used there): the paper's.  Such a model accepts it as well as the default
#: (:func:`check_not_condensed`).
KERNEL_CONDENSATION = "paper"


def check_not_condensed(model, condensation):
    """Refuse a condensation chosen for a model that is not condensed (it would have no effect).

    Parameters
    ----------
    model : str
        The model's name (for the message).
    condensation : str or screening.core.condensation.Condensation
        What the caller passed.

    Returns
    -------
    None
        Returns for :data:`screening.core.condensation.DEFAULT_CONDENSATION` and :data:`KERNEL_CONDENSATION`
        (the paper's, what callers pass for "none").

    Raises
    ------
    ValueError
        Naming the parameter ``condensation`` for any other.

    """
    cond = condensations.get(condensation)
    if cond not in (condensations.get(condensations.DEFAULT_CONDENSATION), condensations.get(KERNEL_CONDENSATION)):
        raise ValueError(f"parameter 'condensation' applies to model='condensed' only "
                         f"(got condensation={cond.name!r} with model={model!r})")


class ChunkIntegrator(abc.ABC):
    """A model set up for one block and bed: integrates a chunk of samples (one row each).

    Call signature (every array C-contiguous; outputs are filled row by row)::

        integrator(acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps,
                   out_theta, out_theta_dot, out_z, out_z_dot, out_uplift,
                   peak, status, reason, n_accepted, n_rejected, h_min, vertical=None)

    ``acc``, ``acc_dot``: ``(n_rows, n_grid)`` inertial ground acceleration ``x_g''`` [m/s2] and its
    rate [m/s3] on the grid ``j dt_grid`` [s]; ``t_out`` [s] the output instants; ``y_init`` the
    initial ``(theta, theta', z_cb, z_cb')``; ``scale`` the absolute tolerances of the 4 states;
    ``rtol`` [1]; ``h_max`` [s]; ``max_steps`` the step budget per sample.  ``vertical``: None (no
    vertical ground motion) or the pair ``(a_v, a_v')`` of the vertical ground acceleration [m/s2]
    (positive up) and its rate [m/s3] on the same grid, ``(n_rows, n_grid)`` or ``(1, n_grid)`` (one
    for every row), passed only when a record has a vertical component (a model without it then
    fails with ``TypeError``); a model that cannot leave the ground stops a sample where
    ``g + a_v < 0`` (diverged, reason ``lift_off``).
    """

    @abc.abstractmethod
    def __call__(self, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                 out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min,
                 vertical=None):
        """Integrate every row of ``acc``; fill the outputs (class docstring)."""


class MonteCarloModel(NamedModel, abc.ABC):
    """A model the Monte Carlo engine can integrate.  Subclasses set :attr:`name`."""

    axis = "Monte Carlo model"
    #: registry name (the value of ``model`` in function arguments and studies)
    name: str = ""
    #: one line for attributes and reports
    description: str = ""
    #: default relative tolerance of the adaptive integrator [1]
    default_rtol: float = 1e-6
    #: default largest step of the adaptive integrator [s] (``monte_carlo``'s ``h_max`` when not given)
    default_h_max: float = 0.005
    #: whether the model reads the condensation argument (``condensation=``)
    uses_condensation: bool = False
    #: whether ``z_cb``, ``z_cb'`` are states of the model (else reported as 0)
    vertical_state: bool = False
    #: its code in files (``mcs_model``; ``p_source`` ``monte_carlo_<name>`` is 10 + it): declared, never reused
    flag_code: int | None = None
    #: its :class:`~screening.core.status.EscalationModel` code under ``[accuracy]`` (None: not escalated)
    escalation_code: int | None = None
    #: CPU seconds per integration step of one sample, the escalation's cost model (``analysis.escalation``)
    step_cost_s: float = 0.4e-6
    #: the integration it always runs, a key of :data:`screening.solvers.datasets.INTEGRATOR_TEXT` (None: the
    #: run's ``integrator`` numerics choose)
    run_integrator: str | None = None
    #: the :class:`~screening.core.status.BestMethod` of a best estimate it gives under ``[accuracy]``
    best_method: int = BestMethod.coupled_monte_carlo

    def __init_subclass__(cls, **kwargs):
        """A subclass declaring its own ``name`` and ``flag_code`` registers itself (made when first asked for)."""
        super().__init_subclass__(**kwargs)
        if cls.name and "name" in vars(cls) and "flag_code" in vars(cls):
            _add(cls.name, cls)

    def check(self, block, foundation, condensation):
        """Raise ``ValueError`` naming the parameter for a combination the model cannot run: the one place
        that refuses it (:func:`screening.monte_carlo` and :func:`screening.simulate` call it alike).  Default: a
        model that does not read the condensation (:attr:`uses_condensation` False) refuses any but the
        default and :data:`KERNEL_CONDENSATION` (:func:`check_not_condensed`); an override calls this one."""
        if not self.uses_condensation:
            check_not_condensed(self.name, condensation)

    @abc.abstractmethod
    def initial_state(self, block, foundation, theta0=0.0, theta_dot0=0.0):
        """Initial ``(theta, theta', z_cb, z_cb')`` [rad, rad/s, m, m/s] at rest (or from the given rotation)."""

    @abc.abstractmethod
    def state_scales(self, block, foundation):
        """Absolute error scales of ``(theta, theta', z_cb, z_cb')`` (multiplied by ``rtol`` by the engine)."""

    @abc.abstractmethod
    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        """The :class:`ChunkIntegrator` of this model for scalar ``block`` and ``foundation`` (SI);
        ``sample_integrator``: a key of :data:`screening.kernels.mcs_kernels.INTEGRATORS` for the models
        integrated by that kernel (others ignore it)."""

    @abc.abstractmethod
    def uplift_threshold(self, block, foundation, condensation):
        """``(theta_ul [rad], attrs)``: the uplift angle the model's uplift flag refers to, and attributes
        saying where it comes from."""

    def validity_problem(self, block, foundation, excitation=None):
        """``None`` where the model may run at the point, else one line naming the validity rule it is outside
        (:func:`screening.monte_carlo` warns with it, or refuses with ``strict_validity=True``); default None."""
        return None

    def input_band(self, block, foundation):
        """Band [rad/s] of the synthesized ground motion the model reads, or None (default) for all of it.

        With a band, :func:`screening.solvers.montecarlo.monte_carlo` hands the model the same samples
        (same seed, same synthesis) low-passed at the band on a coarser grid
        (:func:`screening.solvers.synthesis.low_passed`).
        """
        return None

    def dataset_attributes(self, block, foundation, condensation):
        """Extra attributes of a Monte Carlo dataset of this model (default: none)."""
        return {}



def check_validity(model, block, foundation, excitation=None, strict=False):
    """Warn (``UserWarning``) with the model's :meth:`MonteCarloModel.validity_problem` at the point, or with
    ``strict`` raise ``ValueError`` with it; nothing where the model is within its validity.

    A model may carry a measured validity (the stiff-bed model does, docs/stiff_bed_validity.md);
    the engines call this once per run, before any sample is integrated, so a point outside it is
    said (or refused) up front.

    Parameters
    ----------
    model : MonteCarloModel
        The model (e.g. ``get("stiff_bed")``).
    block : screening.Block
        The block (SI: ``m`` [kg], ``b``, ``h`` [m]).
    foundation : screening.Foundation
        The bed (``k`` [N/m^2], ``lam`` [N s/m^3]).
    excitation : Excitation, optional
        The point's excitation (its kind may be part of the rule), or None for a record.
    strict : bool, optional
        Raise instead of warning.

    Returns
    -------
    None
        Nothing; the model's one-line problem is a ``UserWarning``, or with ``strict`` a ``ValueError``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/stiff_bed_validity.md`` (the measured validity of a model).
    """
    problem = model.validity_problem(block, foundation, excitation)
    if problem is None:
        return
    if strict:
        raise ValueError(problem)
    warnings.warn(problem, stacklevel=4)


#: name -> the model (a class until first asked for, then its instance), in registration order
_REGISTRY = {}
#: name -> flag code of ``mcs_model`` in files
_CODES = {}


def _add(name, model):
    """Register ``model`` (a class or an instance) under ``name``: a declared flag code must be free, an inherited
    (or no) code that is taken becomes the next free one."""
    cls = model if isinstance(model, type) else type(model)
    taken = {c: n for n, c in _CODES.items() if n != name}
    code = cls.flag_code
    if code is not None and "flag_code" in vars(cls) and code in taken:
        raise ValueError(f"flag_code {code} of Monte Carlo model {name!r} is {taken[code]!r}'s")
    if code is None or code in taken:           # inherited by a model registered by hand: the next free code
        code = _CODES.get(name, max([*taken, -1]) + 1)
    _REGISTRY[name], _CODES[name] = model, int(code)
    return model


def _class(name):
    """The class of registered model ``name``."""
    model = _REGISTRY[name]
    return model if isinstance(model, type) else type(model)


def register(model):
    """Add a :class:`MonteCarloModel` instance under its ``name`` (replacing one of the same name); returns it.

    A subclass that declares its own ``name`` and ``flag_code`` registers itself when defined; ``register``
    is for instances made with arguments and for models without a code of their own (tests), which take the
    next free code.  ``TypeError`` for anything else.
    """
    if not isinstance(model, MonteCarloModel):
        raise TypeError(f"register() takes a MonteCarloModel instance (got {type(model).__name__})")
    return _add(model.name, model)


def unregister(name):
    """Remove a registered model (tests that register their own); an unknown name is ignored."""
    _REGISTRY.pop(name, None)
    _CODES.pop(name, None)


def names():
    """Registered names, in registration order (the built-in ``coupled``, ``condensed``, ``stiff_bed`` first)."""
    return tuple(_REGISTRY)


def code(name):
    """The flag code of a registered model (name or instance) in ``mcs_model`` (its declared ``flag_code``)."""
    return _CODES[get(name).name]


def codes():
    """``{name: flag code}`` of the registered models, in registration order."""
    return dict(_CODES)


def name_of(flag):
    """The name of the registered model with flag code ``flag``."""
    return {c: n for n, c in _CODES.items()}[int(flag)]


def escalation_models():
    """The :class:`~screening.core.status.EscalationModel` codes of the registered models, read now: an
    ``IntEnum`` with one member per model that declares an ``escalation_code`` (a model sharing another's
    code, e.g. a sampler, is its alias), each with its ``meaning``."""
    pairs = [(name, _class(name).escalation_code) for name in names()]
    pairs = [(name, int(c)) for name, c in pairs if c is not None]
    codes_ = enum.IntEnum("EscalationModel", pairs, module=__name__)
    builtin = {int(m): m.meaning for m in EscalationModel}
    for member in codes_:
        member.meaning = builtin.get(int(member), _class(member.name).description)
    return codes_


def escalation_model(code_):
    """The registered :class:`MonteCarloModel` that an :class:`EscalationModel` code names."""
    return get(escalation_models()(int(code_)).name)


def get(model):
    """The :class:`MonteCarloModel` for a registered name (an instance is returned as it is).

    The one place a model name becomes a model: every run resolves it here, once, at set-up.

    Parameters
    ----------
    model : str or MonteCarloModel
        A registered name (:func:`names`) or a model instance.

    Returns
    -------
    MonteCarloModel
        The registered model (or ``model`` itself for an instance).

    Raises
    ------
    ValueError
        Naming the parameter and the registered names, for anything else.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/models.md`` (the Monte Carlo models).
    """
    if isinstance(model, MonteCarloModel):
        return model
    if isinstance(model, str) and model in _REGISTRY:
        if isinstance(_REGISTRY[model], type):      # declared by subclassing: made when first asked for
            _REGISTRY[model] = _REGISTRY[model]()
        return _REGISTRY[model]
    raise ValueError(f"parameter 'model' must be one of {names()} (got {model!r})")
