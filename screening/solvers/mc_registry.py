"""The interface every Monte Carlo model implements, and the registry that resolves a model name.

A Monte Carlo model is a set of equations for one block on its bed that the engine
(:func:`screening.solvers.montecarlo.monte_carlo`, :func:`screening.solvers.simulate.simulate`)
integrates one sample at a time.  Like the condensations (:mod:`screening.condensation.registry`),
a model name is turned into a :class:`MonteCarloModel` once, at set-up; the run path then calls
the :class:`ChunkIntegrator` it returns and never looks at the name again.

The built-in models are registered by :mod:`screening.solvers.mc_models` (``"coupled"``,
``"condensed"``) and :mod:`screening.solvers.stiff_bed` (``"stiff_bed"``); a new model is one
module with a :class:`MonteCarloModel` subclass and a call to :func:`register`.

Every model reports the same per-sample results: the state on the output grid as
``(theta, theta', z_cb, z_cb')`` (models without a vertical state fill ``z_cb`` columns with
zeros), an uplift flag, the peak ``|theta|``, the status (ok / overturned / diverged with a
reason, :class:`screening.status.SampleStatus`) and its step counts.
"""

from __future__ import annotations

import abc

__all__ = ["ChunkIntegrator", "MonteCarloModel", "check_validity", "code", "get", "names", "register", "unregister"]


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


class MonteCarloModel(abc.ABC):
    """A model the Monte Carlo engine can integrate.  Subclasses set :attr:`name`."""

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

    def check(self, block, foundation, condensation):
        """Raise ``ValueError`` naming the parameter for a combination the model cannot run (default: accept)."""

    @abc.abstractmethod
    def initial_state(self, block, foundation, theta0=0.0, theta_dot0=0.0):
        """Initial ``(theta, theta', z_cb, z_cb')`` [rad, rad/s, m, m/s] at rest (or from the given rotation)."""

    @abc.abstractmethod
    def state_scales(self, block, foundation):
        """Absolute error scales of ``(theta, theta', z_cb, z_cb')`` (multiplied by ``rtol`` by the engine)."""

    @abc.abstractmethod
    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        """The :class:`ChunkIntegrator` of this model for scalar ``block`` and ``foundation`` (SI);
        ``sample_integrator``: a key of :data:`screening.solvers.mcs_kernels.INTEGRATORS` for the models
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

    def __eq__(self, other):
        return type(other) is type(self) and other.__dict__ == self.__dict__

    def __hash__(self):
        return hash((type(self), self.name))

    def __repr__(self):
        return f"<Monte Carlo model {self.name!r}>"


def check_validity(model, block, foundation, excitation=None, strict=False):
    """Warn (``UserWarning``) with the model's :meth:`MonteCarloModel.validity_problem` at the point, or with
    ``strict`` raise ``ValueError`` with it; nothing where the model is within its validity."""
    problem = model.validity_problem(block, foundation, excitation)
    if problem is None:
        return
    if strict:
        raise ValueError(problem)
    import warnings

    warnings.warn(problem, stacklevel=4)


_REGISTRY: dict[str, MonteCarloModel] = {}


def register(model):
    """Add a :class:`MonteCarloModel` instance under its ``name`` (a later one with the same name replaces it)."""
    if not isinstance(model, MonteCarloModel):
        raise TypeError(f"register() takes a MonteCarloModel instance (got {type(model).__name__})")
    _REGISTRY[model.name] = model
    return model


def unregister(name):
    """Remove a registered model (tests that register their own)."""
    _REGISTRY.pop(name, None)


def names():
    """Registered names, in registration order."""
    return tuple(_REGISTRY)


def code(name):
    """The code of a registered model in per-point records (``mcs_model``): its position in :func:`names`."""
    return names().index(get(name).name)


def get(model):
    """The :class:`MonteCarloModel` for a registered name (an instance is returned as it is).

    Raises ``ValueError`` naming the parameter and the registered names otherwise.
    """
    if isinstance(model, MonteCarloModel):
        return model
    if isinstance(model, str) and model in _REGISTRY:
        return _REGISTRY[model]
    raise ValueError(f"parameter 'model' must be one of {names()} (got {model!r})")


from screening.solvers import mc_models as _builtin  # noqa: E402,F401,I001  (registers the built-in models)
