"""Monte Carlo reference: ensemble statistics of the rocking response under synthesized input.

:func:`monte_carlo` integrates a registered Monte Carlo model (:mod:`screening.solvers.mc_registry`,
resolved once at set-up): the full coupled model (paper eqs. 7–8 with the exact contact
resultants of :mod:`screening.core.physics.contact`), the condensed SDOF (eq. 22 with eqs. 24–25, or
with ``condensation="cubic"`` the ``C``, ``K`` of :mod:`screening.core.condensation.cubic`) or the
stiff-bed model (:mod:`screening.solvers.stiff_bed`, which reads the samples low-passed at its own
band) for ``n_samples`` ground-acceleration samples
synthesized by the spectral representation method (:mod:`screening.solvers.synthesis`), and
returns the time histories of the ensemble moments of ``theta`` and ``theta'`` on the
shared output grid (:func:`screening.solvers.timegrid.output_times`).

Numerics (all overridable through ``**numerics``; recorded in the dataset attributes):

* each sample is integrated by an adaptive Dormand–Prince 5(4) pair (compiled, one
  sample per loop iteration, ``prange`` over samples) with relative tolerance ``rtol``
  (default ``"auto"``, :func:`auto_rtol`: the loosest tolerance whose bias stays below a tenth of the
  run's sampling error, 1e-6 for the coupled model up to 4000 samples, tighter beyond; ``None``: the
  fixed :data:`DEFAULT_RTOL`, 1e-7 coupled, 1e-6 condensed) and absolute scales
  ``rtol x (theta_ul, theta_ul w_r, z_st, z_st w_v)``; steps land exactly on the output
  instants and never exceed ``h_max``.  On a bed whose vertical mode is heavily overdamped
  the coupled model takes the linearly implicit RODAS 4(3) pair instead, with the same
  tolerances (``integrator``: ``"auto"``, the default, see :func:`choose_integrator`;
  ``"dopri"`` or ``"rodas"`` to force one; ``docs/montecarlo_numerics.md``); under a band-limited input on a
  bed whose vertical mode is fast against the input grid (:data:`EXACT_CONTACT_MIN`) it adds exact steps
  through quiet full contact (``"exact"``);
* the input is synthesized up to :func:`screening.solvers.synthesis.synthesis_cutoff`: the top of the
  excitation's band (its PSD carries the band's low-pass), or, for an idealized spectrum
  (``band_limit_hz=None``), ``cutoff`` (default :func:`screening.solvers.synthesis.default_cutoff`,
  3 x the larger of the rocking and vertical frequencies); it is read between its grid
  points by cubic Hermite interpolation;
* the coupled model starts from static equilibrium (``theta = 0``, ``z_cb`` = exact static
  indentation including the cubic term, all rates zero), the condensed one from rest.

A sample is *overturned* when ``|theta|`` exceeds the slenderness angle ``atan(b/h)`` and
*diverged* when its state stops being finite or physical, when it stays in flight longer
than ``max_flight_time``, or when the step size underflows / the step budget runs out.
Such samples are excluded from every ensemble statistic (the statistics are conditional
on survival of the whole record) and reported in ``overturned``, ``diverged`` and the
counts; they never stop the run.

Method and how it is checked: ``docs/method.md#monte-carlo``.
"""

from __future__ import annotations

import math
import numbers
import sys
import time
from dataclasses import dataclass

import numpy as np

from screening.core import limits
from screening.core.condensation import DEFAULT_CONDENSATION, get as get_condensation
from screening.core.excitations import Excitation, names as excitation_names
from screening.core.physics.contact import vertical_damping_ratio
from screening.core.progress import Progress
from screening.core.validation import check_integer, check_size
from screening.kernels import mcs_kernels as kern
from screening.solvers import mc_registry, schema
from screening.solvers.datasets import MONTE_CARLO, monte_carlo_dataset, with_probabilities
from screening.solvers.model_choice import resolve as resolve_model
from screening.solvers.synthesis import (check_band, CUTOFF_FACTOR, envelope_rate, low_passed, OVERSAMPLING,
                                         spectral_plan, stationary_samples, synthesis_cutoff, validate_seed,
                                         vertical_frequency)
from screening.solvers.timegrid import output_times

__all__ = ["MODELS", "DEFAULT_RTOL", "AUTO_RTOL", "AUTO_RTOL_SAMPLES", "auto_rtol", "DEFAULT_NUMERICS",
           "RODAS_DAMPING_RATIO", "EXACT_CONTACT_MIN", "check_scalar_models",
           "vertical_damping_ratio", "choose_integrator", "initial_state", "ensemble_statistics", "SampleSetup",
           "sample_setup", "monte_carlo"]


def __getattr__(name):
    """``MODELS``: the registered Monte Carlo models; ``DEFAULT_RTOL``: each one's ``default_rtol`` (what
    ``rtol="auto"`` gives a model without a measured rule); both read from the registry when asked."""
    if name == "MODELS":
        return mc_registry.names()
    if name == "DEFAULT_RTOL":
        return {model: mc_registry.get(model).default_rtol for model in mc_registry.names()}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: ``rtol="auto"`` (the default): per model, the loosest relative tolerance whose bias of every ensemble statistic
#: against a ``rtol = 1e-10`` run on the same samples was measured below a tenth of the plain Monte Carlo standard
#: error at :data:`AUTO_RTOL_SAMPLES` samples (``benchmarks/bench_mc_tolerance.py``; ``docs/montecarlo_numerics.md``,
#: "Tolerance from the sample count").  Models not listed keep :data:`DEFAULT_RTOL`.
AUTO_RTOL = {"coupled": 1e-6}
#: The sample count the :data:`AUTO_RTOL` tolerances were chosen for: the escalation's most samples per point.
AUTO_RTOL_SAMPLES = 4000

#: Default numerical settings (see the module docstring).
DEFAULT_NUMERICS = {
    "rtol": "auto",             # relative tolerance of the adaptive pair [1]; "auto" -> auto_rtol(model, n_samples),
                                # None -> DEFAULT_RTOL[model]
    "cutoff": None,             # band limit of the input [rad/s]; None -> cutoff_factor x max frequency
    "cutoff_factor": CUTOFF_FACTOR,
    "band": None,               # band [rad/s] the model reads: the samples low-passed there (same seed and
                                # components below it); None -> the model's own (MonteCarloModel.input_band)
    "oversampling": OVERSAMPLING,
    "h_max": None,              # largest integration step [s]; None -> the model's default_h_max (5 ms but
                                # for the stiff-bed model, 10 ms)
    "max_steps": 5_000_000,     # step budget per sample (accepted + rejected)
    "max_flight_time": 0.5,     # longest admissible continuous flight [s]
    "chunk_size": 64,           # samples synthesized and integrated per batch
    "integrator": "auto",       # "dopri" (explicit 5(4) pair), "rodas" (linearly implicit 4(3) pair), "exact"
                                # (explicit pair, exact steps in quiet full contact) or "auto" (per point: see
                                # choose_integrator and EXACT_CONTACT_MIN)
}

#: ``integrator="auto"`` takes RODAS for the coupled model where the bed's vertical mode has at least
#: this damping ratio (:func:`screening.core.physics.contact.vertical_damping_ratio`), the explicit pair elsewhere.
#: ``docs/montecarlo_numerics.md`` gives the measurements behind it.
RODAS_DAMPING_RATIO = 20.0

#: ``integrator="auto"`` takes the exact full-contact steps (``"exact"``) for the coupled model under a
#: band-limited input where the bed's vertical frequency times the input grid's step is at least this: the
#: explicit pair's stability-held steps (``h w_v`` about 2) would take two or more per grid interval
#: (``benchmarks/bench_coupled_band.py``; ``docs/montecarlo_numerics.md``).  The idealized input keeps the pair.
EXACT_CONTACT_MIN = 4.0

# ----------------------------------------------------------------------------- validation
def check_scalar_models(block, foundation, excitation=None, purpose="monte_carlo"):
    """Refuse model objects that are not one point, before any work.

    Parameters
    ----------
    block, foundation : screening.core.model.Block, screening.core.model.Foundation
        The model at one point: the block (``m`` [kg], ``b``, ``h`` [m], ``g`` [m s-2]) and its bed (``k`` [N m-2],
        ``eps`` [m-2], its damping), every field a scalar.
    excitation : screening.core.excitations.Excitation, optional
        The input (``S0`` [m2 s-3] and its parameters), if the caller has one.
    purpose : str, optional
        The caller's name in the message (default ``"monte_carlo"``).

    Returns
    -------
    None
        Returns only when every numeric field is a scalar and the excitation is a registered one.

    Raises
    ------
    ValueError
        One line naming the array-valued parameter (or the unknown excitation).

    Notes
    -----
    A Monte Carlo run integrates the equations of motion of one block on one bed (eqs. (7)-(8) or (22)
    in [1]); grids of points are the linearization's (:func:`screening.linearize`).

    """
    fields = {"block." + n: getattr(block, n) for n in ("m", "b", "h", "I_cm", "g")}
    fields.update({"foundation." + n: getattr(foundation, n) for n in ("k", "eps")})
    fields["foundation.damping"] = foundation.damping
    if excitation is not None:
        fields["excitation.S0"] = excitation.S0
    for name, value in fields.items():
        if np.ndim(value) != 0:
            raise ValueError(f"parameter '{name}' must be a scalar for {purpose} (got an array of shape "
                             f"{np.shape(value)}); loop over parameter points instead")
    if excitation is not None and not isinstance(excitation, Excitation):
        raise ValueError(f"parameter 'excitation' must be an excitation of screening.core.excitations "
                         f"(one of {excitation_names()}; got {type(excitation).__name__})")
    for name in (excitation.parameters if excitation is not None else ()):
        if np.ndim(getattr(excitation, name)) != 0:
            raise ValueError(f"parameter 'excitation.{name}' must be a scalar for monte_carlo (got an array of "
                             f"shape {np.shape(getattr(excitation, name))}); loop over parameter points instead")


def _check_numerics(numerics):
    unknown = sorted(set(numerics) - set(DEFAULT_NUMERICS))
    if unknown:
        raise ValueError(f"unknown numerics option(s) {unknown}; allowed: {sorted(DEFAULT_NUMERICS)}")
    opts = dict(DEFAULT_NUMERICS, **numerics)

    def positive(name, upper=math.inf):
        v = opts[name]
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not (0.0 < v <= upper) or not math.isfinite(v):
            raise ValueError(f"parameter '{name}' must be a finite number in (0, {upper:g}] (got {v!r})")
        return float(v)

    if isinstance(opts["rtol"], str) and opts["rtol"] != "auto":
        raise ValueError(f"parameter 'rtol' must be \"auto\" or a finite number in (0, {limits.MAX_RTOL:g}] "
                         f"(got {opts['rtol']!r})")
    if opts["rtol"] is not None and not isinstance(opts["rtol"], str):        # None: the model's; "auto"
        opts["rtol"] = positive("rtol", limits.MAX_RTOL)
    if opts["cutoff"] is not None:
        opts["cutoff"] = positive("cutoff")
    if opts["band"] is not None:
        opts["band"] = positive("band")
    opts["cutoff_factor"] = positive("cutoff_factor")
    if opts["h_max"] is not None:
        opts["h_max"] = positive("h_max")
    opts["max_flight_time"] = positive("max_flight_time")
    opts["oversampling"] = check_integer("oversampling", opts["oversampling"], 2)
    opts["max_steps"] = check_integer("max_steps", opts["max_steps"], 1)
    opts["chunk_size"] = check_integer("chunk_size", opts["chunk_size"], 1)
    if opts["integrator"] not in (*kern.INTEGRATORS, "auto"):
        raise ValueError(f"parameter 'integrator' must be one of {sorted((*kern.INTEGRATORS, 'auto'))} "
                         f"(got {opts['integrator']!r})")
    return opts


# ----------------------------------------------------------------------------- set-up
def auto_rtol(model, n_samples):
    """Relative tolerance of the sample integrator that keeps its bias below a tenth of the sampling error.

    Parameters
    ----------
    model : str or screening.solvers.mc_registry.MonteCarloModel
        A registered Monte Carlo model or its name.
    n_samples : int
        Samples of the run [1], >= 1.

    Returns
    -------
    float
        ``rtol`` [1]: :data:`AUTO_RTOL` of the model up to :data:`AUTO_RTOL_SAMPLES` samples, tightened as
        ``sqrt(AUTO_RTOL_SAMPLES / n_samples)`` beyond; :data:`DEFAULT_RTOL` for a model without a measured rule.

    Notes
    -----
    The integration error of a sample scales as the tolerance (an error-per-step controlled pair is
    tolerance-proportional), so the bias ``B`` it leaves in an ensemble statistic is ``B = beta rtol``,
    while the standard error of that statistic is ``SE(n) = sigma / sqrt(n)``.  Keeping ``B <= SE(n) / 10``
    therefore asks for ``rtol <= SE(n) / (10 beta)``, proportional to ``1 / sqrt(n)``:

    .. math:: rtol(n) = rtol_0 \\min(1, \\sqrt{n_0 / n})

    with ``rtol_0`` the loosest of the measured tolerances (1e-4 ... 1e-7) that showed no bias: the bias of
    peak ``var_theta``, ``E[peak |theta|]``, exceedance and overturning probabilities of the coupled model
    (eqs. (7)-(8) of [1]) against a ``rtol = 1e-10`` run on the same samples, on the paper block at light to
    heavy uplift and on a statue block on stiff beds [2].  1e-5 met the criterion in light and moderate
    uplift but moved samples between overturned and survived near overturning; 1e-6 did not in the
    filtered heavy case.  Below ``n_0`` the tolerance stays at ``rtol_0``, so that the runs of one
    escalation (pilot and main run) take the same steps per sample.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] ``docs/montecarlo_numerics.md``, "Tolerance from the sample count" (this package's documentation).
    """
    name = model if isinstance(model, str) else model.name
    base = AUTO_RTOL.get(name)
    if base is None:
        return float(mc_registry.get(name).default_rtol)
    return float(base * min(1.0, math.sqrt(AUTO_RTOL_SAMPLES / n_samples)))


def choose_integrator(block, foundation, model, integrator="auto"):
    """The sample integrator (a key of :data:`~screening.kernels.mcs_kernels.INTEGRATORS`) of a run.

    Parameters
    ----------
    block, foundation
        As in :func:`check_scalar_models`.
    model : str
        The resolved Monte Carlo model's name.
    integrator : str, optional
        ``"auto"`` (default), ``"dopri"`` or ``"rodas"``.

    Returns
    -------
    str
        ``"auto"``: ``"rodas"`` for the coupled model on a bed whose vertical mode is overdamped beyond
        :data:`RODAS_DAMPING_RATIO` (there the explicit pair's step is held by stability, not accuracy),
        ``"dopri"`` otherwise; any other value as given.

    Notes
    -----
    The stiffness comes from the bed's vertical dashpot in eqs. (7)-(8) of [1] (:func:`screening.core.physics.contact.vertical_damping_ratio`).

    """
    if integrator != "auto":
        return integrator
    if model == "coupled" and vertical_damping_ratio(block, foundation) >= RODAS_DAMPING_RATIO:
        return "rodas"
    return "dopri"


def initial_state(block, foundation, model):
    """Initial state ``(theta, theta', z_cb, z_cb')`` of a registered Monte Carlo model at rest.

    Parameters
    ----------
    block, foundation
        As in :func:`check_scalar_models`.
    model : str or screening.solvers.mc_registry.MonteCarloModel
        A registered model or its name.

    Returns
    -------
    numpy.ndarray
        [rad], [rad s-1], [m], [m s-1]: static equilibrium for the coupled model (``z_cb`` the rest
        indentation of eq. (13) in [1]), rest for the others.

    Notes
    -----
    Every sample starts from this state; the input starts at ``t = 0`` with the envelope (eq. (57) in [1]).

    """
    return mc_registry.get(model).initial_state(block, foundation)


# ----------------------------------------------------------------------------- statistics
def ensemble_statistics(theta, theta_dot, uplift, used):
    """Ensemble moments over the used samples of ``(n_samples, n_times)`` arrays.

    Parameters
    ----------
    theta : numpy.ndarray
        Rotations [rad], one row per sample.
    theta_dot : numpy.ndarray
        Rotation rates [rad s-1], same shape.
    uplift : numpy.ndarray
        Whether each sample is in uplift at each time (bool), same shape.
    used : numpy.ndarray
        Boolean per sample: the rows that enter the statistics.

    Returns
    -------
    dict
        ``var_theta`` [rad2], ``var_theta_dot`` [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1], their standard
        errors ``var_theta_se``, ``var_theta_dot_se`` and ``p_uplift`` [1], one value per time; NaN with
        fewer than two rows.

    Notes
    -----
    Variances and the covariance are about the sample mean with ``ddof = 1``.  The standard error of a
    sample variance ``s^2`` is ``sqrt((m4 - (n-3)/(n-1) s^4) / n)`` with ``m4`` the fourth central sample
    moment (no Gaussian assumption) [2].  These are the Monte Carlo counterparts of the moments of eq. (44)
    in [1].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] A. Stuart and J. K. Ord, Kendall's Advanced Theory of Statistics, vol. 1, 6th ed., Arnold (1994).
    """
    n = int(np.count_nonzero(used))
    n_t = theta.shape[1]
    if n < 2:
        nan = np.full(n_t, np.nan)
        return {"var_theta": nan, "var_theta_dot": nan.copy(), "cov_theta_theta_dot": nan.copy(),
                "var_theta_se": nan.copy(), "var_theta_dot_se": nan.copy(), "p_uplift": nan.copy()}
    x = theta[used]
    v = theta_dot[used]
    dx = x - x.mean(axis=0)
    dv = v - v.mean(axis=0)
    var_x = np.sum(dx * dx, axis=0) / (n - 1)
    var_v = np.sum(dv * dv, axis=0) / (n - 1)
    cov = np.sum(dx * dv, axis=0) / (n - 1)

    def se(d, s2):
        m4 = np.mean(d**4, axis=0)
        return np.sqrt(np.maximum(m4 - (n - 3.0) / (n - 1.0) * s2 * s2, 0.0) / n)

    return {"var_theta": var_x, "var_theta_dot": var_v, "cov_theta_theta_dot": cov,
            "var_theta_se": se(dx, var_x), "var_theta_dot_se": se(dv, var_v),
            "p_uplift": np.mean(uplift[used], axis=0)}


def _show_progress(progress, n_samples, chunk_size):
    if progress is None:
        return n_samples > chunk_size and hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
    if callable(progress):
        return False                    # the caller shows it
    if not isinstance(progress, bool):
        raise ValueError(f"parameter 'progress' must be None, True, False or a function (got {progress!r})")
    return progress


# ----------------------------------------------------------------------------- entry point
def _check_thresholds(thresholds):
    """``thresholds`` as a tuple of rotations [rad] (None stays None)."""
    if thresholds is None:
        return None
    values = np.atleast_1d(np.asarray(thresholds, dtype=object))
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not (0.0 < v < math.inf):
            raise ValueError(f"parameter 'thresholds' must be rotations [rad] in (0, inf) (got {thresholds!r})")
        out.append(float(v))
    if not out or len(set(out)) != len(out):
        raise ValueError(f"parameter 'thresholds' must list distinct rotations [rad] in (0, inf) (got {thresholds!r})")
    return tuple(out)


@dataclass(frozen=True)
class SampleSetup:
    """A Monte Carlo model set up for one point (:func:`sample_setup`): what integrating a sample needs.

    ``model`` and ``condensation`` resolved; ``times`` [s] the output instants; ``opts`` the numerics
    (:data:`DEFAULT_NUMERICS`, resolved); ``plan`` the synthesis and ``read_plan`` the (low-passed) samples the
    model reads; ``q``, ``q_dot`` the envelope [1] and its rate [1/s] on ``read_plan.times``; ``integrate`` the
    model's :class:`~screening.solvers.mc_registry.ChunkIntegrator`; ``scales`` its absolute tolerances;
    ``y0`` the initial state.
    """

    model: object
    condensation: object
    times: np.ndarray
    opts: dict
    plan: object
    read_plan: object
    q: np.ndarray
    q_dot: np.ndarray
    integrate: object
    scales: np.ndarray
    y0: np.ndarray


def sample_setup(block, foundation, excitation, n_samples, model="coupled", t_end=20.0, dt=0.05,
                 condensation=DEFAULT_CONDENSATION, strict_validity=False, **numerics):
    """Check the inputs of a Monte Carlo run and set its model up, before any sample is integrated.

    Parameters
    ----------
    block, foundation, excitation, n_samples, model, t_end, dt, condensation, strict_validity, **numerics
        As :func:`monte_carlo` (``n_samples`` sets the ``"auto"`` tolerance and the size checks).

    Returns
    -------
    SampleSetup
        The resolved model, its integrator, tolerances and synthesis plans.

    Raises
    ------
    ValueError
        One line naming the parameter, for any bad input (the checks of :func:`monte_carlo`).

    References
    ----------
    .. [1] The package's documentation, ``docs/method.md#monte-carlo``.
    """
    if not isinstance(strict_validity, bool):
        raise ValueError(f"parameter 'strict_validity' must be True or False (got {strict_validity!r})")
    check_scalar_models(block, foundation, excitation)
    mc = resolve_model(model, block, foundation, excitation)
    model = mc.name
    cond = get_condensation(condensation)
    times = output_times(t_end, dt)
    t_end, dt = float(t_end), float(dt)
    opts = _check_numerics(numerics)
    if opts["rtol"] is None:
        opts["rtol"] = mc.default_rtol
    elif opts["rtol"] == "auto":
        opts["rtol"] = auto_rtol(mc, n_samples)
    if opts["h_max"] is None:
        opts["h_max"] = mc.default_h_max
    y0 = mc.initial_state(block, foundation)           # may raise for a bed that cannot carry the block
    mc.check(block, foundation, cond)                  # a condensed model checks its condensation's bed
    mc_registry.check_validity(mc, block, foundation, excitation, strict_validity)
    check_size("n_samples", n_samples, limits.MAX_SAMPLES, "samples")
    check_size("n_samples", n_samples * times.size, limits.MAX_SAMPLE_VALUES, "samples x output instants")
    opts["integrator"] = choose_integrator(block, foundation, model, opts["integrator"])

    check_band(excitation, t_end, opts["cutoff"], opts["oversampling"])
    cutoff = synthesis_cutoff(excitation, block, foundation, opts["cutoff"], opts["cutoff_factor"])
    plan = spectral_plan(excitation, t_end, cutoff, opts["oversampling"])
    band = opts["band"] if opts["band"] is not None else mc.input_band(block, foundation)
    read_plan = plan if band is None else low_passed(plan, band)[0]     # the model reads these samples
    if (numerics.get("integrator", "auto") == "auto" and opts["integrator"] == "dopri" and model == "coupled"
            and getattr(excitation, "band_limit_hz", None) is not None
            and vertical_frequency(block, foundation) * read_plan.dt >= EXACT_CONTACT_MIN):
        opts["integrator"] = "exact"
    opts["integrator"] = mc.run_integrator or opts["integrator"]
    grid = read_plan.times
    q = np.ascontiguousarray(excitation.envelope(grid), dtype=float)
    q_dot = np.ascontiguousarray(envelope_rate(excitation.envelope, grid), dtype=float)
    integrate_chunk = mc.integrator(block, foundation, cond, opts["max_flight_time"], opts["integrator"])
    scales = opts["rtol"] * mc.state_scales(block, foundation)

    return SampleSetup(mc, cond, times, opts, plan, read_plan, q, q_dot, integrate_chunk, scales, y0)


def _with_probabilities(run):
    """``run`` (the Monte Carlo engine) with its ``thresholds`` checked before any work and the probabilities of
    its samples added to its dataset (:func:`screening.solvers.datasets.with_probabilities`)."""
    import functools

    @functools.wraps(run)
    def monte_carlo(*args, thresholds=None, **kwargs):
        thresholds = _check_thresholds(thresholds)
        return with_probabilities(run(*args, **kwargs), thresholds)

    return monte_carlo


@_with_probabilities
def monte_carlo(block, foundation, excitation, n_samples=1000, model="coupled", t_end=20.0, dt=0.05,
                seed=0, progress=None, condensation=DEFAULT_CONDENSATION, thresholds=None, strict_validity=False,
                sample_histories=False, **numerics):
    """Monte Carlo ensemble statistics of the rocking response (the reference for the linearization).

    Parameters
    ----------
    block : :class:`~screening.core.model.Block` with scalar fields (SI).
    foundation : :class:`~screening.core.model.Foundation` (Hunt–Crossley) or
        Winkler law, scalar fields (SI).
    excitation : :class:`~screening.core.excitations.white.WhiteNoise` or :class:`~screening.core.excitations.kanai_tajimi.KanaiTajimi`
        (horizontal ground acceleration ``q(t) xi(t)`` or ``q(t) z(t)``; ``S0`` [m^2/s^3] is the
        two-sided PSD level, ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``).
    n_samples : number of samples, integer >= 2.
    model : a registered Monte Carlo model (:mod:`screening.solvers.mc_registry`) or its name:
        ``"coupled"`` (eqs. 7–8, exact contact resultants), ``"condensed"`` (eq. 22) or
        ``"stiff_bed"`` (rigid block on the quasi-static contact with the bed-derived transfer
        loss, :mod:`screening.solvers.stiff_bed`; a warning names its validity rule when the bed
        is outside it); or ``"auto"``: the cheapest model whose measured validity holds at the point
        (:mod:`screening.solvers.model_choice`, resolved once here; ``attrs["model"]`` names the one that ran).
    t_end : record length [s], > 0.
    dt : OUTPUT step [s]; output times are ``output_times(t_end, dt)``.  The integration
        step is adaptive and finer (see ``rtol``, ``h_max``).
    seed : integer >= 0; sample ``i`` uses ``numpy.random.default_rng([seed, i])``.
    progress : None (a bar on stderr for multi-chunk runs on a terminal), True or False; or a function
        called with the number of samples done after each chunk (a sweep's spot checks report so).
    condensation : a registered condensation, default :data:`screening.core.condensation.DEFAULT_CONDENSATION`
        (``"virtual_work"``; ``"paper"``: eqs. 24–25; ``"cubic"``: :mod:`screening.core.condensation.cubic`):
        the ``C(theta)``, ``K(theta)`` of ``model="condensed"``.  Another than the default with
        ``model="coupled"`` raises (the coupled model is not condensed).  With ``"cubic"`` on
        a softening bed, samples passing the capacity angle (no quasi-static equilibrium)
        are flagged diverged.
    thresholds : rotations [rad] > 0 (a number or a sequence of distinct ones): the result also has
        ``p_exceed`` and ``p_exceed_se`` on the coordinate ``threshold`` [rad], the fraction of the
        samples that did not diverge whose peak ``|theta|`` exceeds each (overturned samples count)
        and its binomial standard error (:func:`screening.analysis.probabilities.sample_probabilities`).
    strict_validity : with True, a model asked for outside its measured validity
        (:meth:`~screening.solvers.mc_registry.MonteCarloModel.validity_problem`) raises ``ValueError``
        naming the rule instead of warning.
    sample_histories : bool; True adds ``theta_sample`` (sample, t) [rad], every sample's rotation on the
        output times (for estimators on the samples, e.g. :mod:`screening.analysis.multifidelity`).
    **numerics : overrides of :data:`DEFAULT_NUMERICS` — ``rtol`` [1] (``"auto"``, the default:
        :func:`auto_rtol` of the model and ``n_samples``; ``None``: the fixed :data:`DEFAULT_RTOL`), ``cutoff`` [rad/s],
        ``cutoff_factor`` [1], ``band`` [rad/s] (the model reads the samples low-passed at this band,
        the same realizations as every other model of the same seed and cutoff below it; default the
        model's own, :meth:`~screening.solvers.mc_registry.MonteCarloModel.input_band`), ``oversampling`` [1], ``h_max`` [s] (None: the model's ``default_h_max``), ``max_steps``,
        ``max_flight_time`` [s], ``chunk_size``, ``integrator`` (``"auto"``, ``"dopri"``, ``"rodas"``, ``"exact"``).

    Returns
    -------
    xarray.Dataset on coordinate ``t`` [s] (and ``sample``) with ``var_theta`` [rad2],
    ``var_theta_dot`` [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1] — ensemble moments about
    the sample mean (``ddof = 1``) over the samples that neither overturned nor diverged —,
    their standard errors ``var_theta_se``, ``var_theta_dot_se``, the uplift occupancy
    ``p_uplift`` [1] (coupled: either base edge out of contact, ``z_cb < b |sin theta|``;
    condensed: ``|theta| > theta_ul``), per-sample ``peak_abs_theta`` [rad] (maximum of
    ``|theta|`` over the cubic Hermite interpolant of the accepted steps, up to overturning or
    divergence; :func:`~screening.kernels.mcs_kernels.step_peak`), ``overturned``,
    ``diverged``, ``n_steps`` and scalars ``n_overturned``, ``n_diverged``, ``n_used``, ``p_overturn``
    [1] (fraction of the samples that did not diverge that overturned) and its standard error
    ``p_overturn_se`` [1] (Agresti-Coull; docs/outputs_probabilities.md).
    ``attrs["status"]`` is ``"ok"`` or says plainly why the statistics are NaN;
    ``attrs["condensation"]`` names the condensation of a condensed run.

    Raises
    ------
    ValueError
        For a bad ``n_samples``, ``model``, ``condensation``, ``seed``, ``thresholds``, ``t_end``/``dt``, numerics
        option, or array-valued model parameters — before any work is done.

    Notes
    -----
    Each sample integrates the coupled equations of motion (eqs. (7)-(8) in [1] with the exact contact
    resultants of eqs. (5)-(6)) or the condensed eq. (22) under one realization of the input
    (spectral representation of its PSD, eqs. (39) or (47)-(50), modulated by eq. (57)); the moments are
    ensemble statistics of the samples, the reference of the linearization (section 3 of [1]).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> from screening import Block, Foundation, WhiteNoise, monte_carlo
    >>> ds = monte_carlo(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8), WhiteNoise(1e-4),
    ...                  n_samples=8, t_end=2.0, dt=0.5, model="condensed")
    >>> int(ds["n_used"]), ds["var_theta"].sizes["t"], ds.attrs["status"]
    (8, 5, 'ok')
    """
    n_samples = check_integer("n_samples", n_samples, 2)
    if not isinstance(sample_histories, (bool, np.bool_)):
        raise ValueError(f"parameter 'sample_histories' must be True or False (got {sample_histories!r})")
    seed = validate_seed(seed)
    _show_progress(progress, n_samples, 1)                       # refuses a bad progress before any work
    run = sample_setup(block, foundation, excitation, n_samples, model, t_end, dt, condensation, strict_validity,
                       **numerics)
    mc, cond, times, opts, plan, read_plan = run.model, run.condensation, run.times, run.opts, run.plan, run.read_plan
    model, t_end, dt = mc.name, float(t_end), float(dt)
    q, q_dot, integrate_chunk, scales, y0 = run.q, run.q_dot, run.integrate, run.scales, run.y0
    show = _show_progress(progress, n_samples, opts["chunk_size"])

    n_t = times.size
    theta = np.empty((n_samples, n_t))
    theta_dot = np.empty((n_samples, n_t))
    chunk = opts["chunk_size"]
    z_cb = np.empty((min(chunk, n_samples), n_t))            # scratch: z_cb is not reported
    z_cb_dot = np.empty_like(z_cb)
    uplift = np.zeros((n_samples, n_t), dtype=np.bool_)
    peak, h_min = np.zeros(n_samples), np.zeros(n_samples)
    status, reason, n_acc, n_rej = (np.zeros(n_samples, dtype=np.int64) for _ in range(4))

    start = time.perf_counter()
    with Progress(n_samples, label=f"monte_carlo[{model}]", enabled=show) as bar:
        for lo in range(0, n_samples, chunk):
            hi = min(lo + chunk, n_samples)
            acc, acc_dot = stationary_samples(read_plan, seed, np.arange(lo, hi))
            acc_dot *= q                                    # d(q f)/dt = q f' + q' f
            acc_dot += q_dot * acc
            acc *= q
            sl = slice(lo, hi)
            integrate_chunk(acc, acc_dot, read_plan.dt, times, y0, scales, opts["rtol"], opts["h_max"], opts["max_steps"],
                            theta[sl], theta_dot[sl], z_cb[:hi - lo], z_cb_dot[:hi - lo], uplift[sl], peak[sl],
                            status[sl], reason[sl], n_acc[sl], n_rej[sl], h_min[sl])
            bar.update(hi - lo)
            if callable(progress):
                progress(hi)
    wall = time.perf_counter() - start

    overturned = status == kern.STATUS_OVERTURNED
    diverged = status == kern.STATUS_DIVERGED
    used = ~(overturned | diverged)
    stats = ensemble_statistics(theta, theta_dot, uplift, used)
    n_over, n_div = int(overturned.sum()), int(diverged.sum())
    ds = monte_carlo_dataset(times, stats, peak, overturned, diverged, n_acc, n_rej, reason, n_over, n_div,
                             block, foundation, excitation, model, n_samples, seed, t_end, dt, opts, plan,
                             h_min, wall, cond.name, mc)
    ds.attrs.update(input_band_rad_s=float(read_plan.cutoff), input_grid_points=int(read_plan.n_times),
                    input_band_note="the model read the synthesized samples (cutoff_rad_s) low-passed at "
                                    "input_band_rad_s: same seed, same components below it" if read_plan is not plan
                                    else "the model read the synthesized samples up to cutoff_rad_s")
    if sample_histories:
        ds["theta_sample"] = (("sample", "t"), theta, schema.attributes("theta_sample", MONTE_CARLO))
    return ds

