"""Ground-acceleration samples by the spectral representation method (Shinozuka–Deodatis).

A zero-mean stationary process with two-sided PSD ``S(omega)`` [m^2/s^3] (the convention of
:mod:`screening.core.model.excitation`: ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)`` for white noise, i.e.
``S = S0`` on ``-inf < omega < inf``) is simulated, band-limited to ``|omega| <= omega_c``, by

    f(t) = sqrt(2) sum_{k=0}^{N-1} A_k cos(omega_k t + phi_k),   A_k = sqrt(2 S(omega_k) d_omega),

with midpoint frequencies ``omega_k = (k + 1/2) d_omega``, ``N d_omega = omega_c``, and
independent phases ``phi_k ~ U[0, 2 pi)`` (Shinozuka & Deodatis 1991).  Its ensemble variance
is exactly ``sum A_k^2``, the midpoint rule for ``int_{-omega_c}^{omega_c} S d_omega``
(``2 S0 omega_c`` exactly for white noise; no bin is lost at ``omega = 0``, where the
Kanai–Tajimi and white spectra are not zero).  The sum and its exact time derivative are
evaluated together on a grid of step ``dt = pi / (oversampling omega_c)`` by one complex
FFT per sample (``f + i f'``, the half-bin shift applied as ``exp(i d_omega t / 2)``), so
integrators can read the band-limited process between grid points by cubic Hermite
interpolation (relative error ``(omega dt)^4 / 384``: ~1e-3 at the cutoff, ~1e-9 at the
rocking frequency).  A sample is anti-periodic with period ``2 pi / d_omega`` >= the
record length, so nothing repeats within the record.

The ground acceleration is ``q(t) f(t)`` (eqs. 39 and 47): white noise (``S = S0``) or the
Kanai–Tajimi filter output (``S`` = eq. 50 as coded in :meth:`KanaiTajimi.psd`).  Note the
Kanai–Tajimi samples are the *stationary* filtered process, modulated; a filter started
from rest (as in a Lyapunov integration from zero covariance) differs during its first
``~1/(zeta_g omega_g)`` seconds, where ``q(t)`` is still small.

Sample ``i`` of a run with seed ``seed`` draws its phases from
``numpy.random.default_rng([seed, i])``: a run is reproducible and a sample does not depend
on how the samples are split into chunks or workers.

Method and how it is checked: ``docs/method.md#ground-motion-synthesis``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from screening.core import limits
from screening.core.excitations.base import band_top
from screening.core.model import Block, Foundation
from screening.core.physics.contact import linear_rocking_stiffness

__all__ = []


#: Default cutoff = CUTOFF_FACTOR x the larger of the rocking and vertical frequencies.
CUTOFF_FACTOR = 3.0
#: Default grid oversampling relative to the Nyquist step pi / omega_c.
OVERSAMPLING = 4


def rocking_frequency(block, foundation):
    """Small-amplitude rocking frequency ``sqrt(((2/3) b^3 k - m g h) / m_sdof)`` [rad/s] (eqs. 22, 25).

    The natural frequency of the condensed rocking equation in full contact at rest: one of the two
    scales that set the band of the synthesized ground motion (:func:`default_cutoff`).

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields: ``m`` [kg], ``b``, ``h`` [m], ``g`` [m/s^2], ``m_sdof`` [kg m^2]).
    foundation : screening.Foundation
        The bed (scalar fields: ``k`` [N/m^2]).

    Returns
    -------
    float
        ``omega_r`` [rad/s]; zero if the linear rocking stiffness is not positive.

    Notes
    -----
    ``omega_r = sqrt(K_0 / m_sdof)`` with ``K_0 = (2/3) b^3 k - m g h``, the stiffness of eq. (25) in
    [1]_ at ``theta = 0`` without the cubic term (``eps`` is ignored: it adds ``eps m^2 g^2 b / (2 k)``),
    and ``m_sdof = I_cm + m h^2`` of eq. (22).

    """
    stiffness = linear_rocking_stiffness(block, foundation)
    return math.sqrt(max(float(stiffness), 0.0) / float(block.m_sdof))


def vertical_frequency(block, foundation):
    """Vertical (bouncing) frequency of the block on the bed, ``sqrt(2 b k / m)`` [rad/s] (eq. 13).

    Parameters
    ----------
    block : screening.Block
        The block (scalar fields: ``m`` [kg], ``b`` [m]).
    foundation : screening.Foundation
        The bed (scalar fields: ``k`` [N/m^2]).

    Returns
    -------
    float
        ``omega_v`` [rad/s].

    Notes
    -----
    The linear part of the vertical equation (eq. (13) in [1]_) in full contact: the base ``2 b``
    on a bed of stiffness ``k`` per unit length is a spring ``2 b k`` [N/m] under the mass ``m``,
    ``omega_v = sqrt(2 b k / m)``.

    """
    return math.sqrt(2.0 * float(block.b) * float(foundation.k) / float(block.m))


def default_cutoff(block, foundation, factor=CUTOFF_FACTOR):
    """Band limit ``omega_c`` [rad/s] of the synthesized input: ``factor`` x the larger of
    :func:`rocking_frequency` and :func:`vertical_frequency`.

    Parameters
    ----------
    block, foundation : screening.Block, screening.Foundation
        The block and its bed (scalar fields, SI).
    factor : float, optional
        Multiple of the larger natural frequency [1] (default :data:`CUTOFF_FACTOR`, 3).

    Returns
    -------
    float
        ``omega_c = factor max(omega_r, omega_v)`` [rad/s].

    References
    ----------
    .. [1] [shinozuka1991] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/method.md`` ("Ground motion synthesis").
    """
    return float(factor) * max(rocking_frequency(block, foundation), vertical_frequency(block, foundation))


def default_cutoffs(block, foundation, factor=CUTOFF_FACTOR):
    """:func:`default_cutoff` [rad/s] of every point of a block and bed with array fields (NaN where the
    point's scales are beyond float64).

    Parameters
    ----------
    block : screening.Block
        The block, fields scalars or arrays that broadcast together (SI).
    foundation : screening.Foundation
        The bed, ``k`` [N/m^2] a scalar or an array broadcast with the block's fields.
    factor : float, optional
        Multiple of the larger natural frequency [1] (default :data:`CUTOFF_FACTOR`).

    Returns
    -------
    numpy.ndarray
        ``omega_c`` [rad/s] per point, the broadcast shape of the fields.

    """
    def one(m, b, h, I_cm, g, k):
        try:
            return default_cutoff(Block(m, b, h, I_cm, g), Foundation(k=k, lam=0.0), factor)
        except (ArithmeticError, ValueError):
            return np.nan

    return np.vectorize(one, otypes=[float])(block.m, block.b, block.h, block.I_cm, block.g, foundation.k)


def max_band_limit_hz(t_end, oversampling=OVERSAMPLING):
    """The largest ``band_limit_hz`` [Hz] the synthesis can carry over a record of ``t_end`` [s].

    Parameters
    ----------
    t_end : float
        Record length [s], > 0.
    oversampling : int, optional
        Grid points per Nyquist step [1] (default :data:`OVERSAMPLING`).

    Returns
    -------
    float
        The corner [Hz] whose :func:`~screening.core.excitations.base.band_top` puts the synthesis grid (step
        ``pi / (oversampling omega_top)``) at :data:`~screening.core.limits.MAX_SYNTHESIS_POINTS` points per sample.

    Notes
    -----
    The synthesis reaches the band's top ``omega_top`` (5.6 x its corner): its time step is
    ``pi / (oversampling omega_top)``, whose Nyquist frequency carries the band; a finer step than
    ``t_end / MAX_SYNTHESIS_POINTS`` is refused (a sample would no longer fit in memory).

    """
    top = (limits.MAX_SYNTHESIS_POINTS - 2) * math.pi / (oversampling * float(t_end))
    return top / band_top(1.0)


def check_band(excitation, t_end, cutoff=None, oversampling=OVERSAMPLING):
    """Refuse a band the synthesis cannot carry: ``ValueError`` naming ``band_limit_hz`` and its range.

    Parameters
    ----------
    excitation : Excitation
        The input (``band_limit_hz`` [Hz] or None: nothing to check).
    t_end : float
        Record length [s].
    cutoff : float, optional
        A cut-off [rad/s] the synthesis is held to (Monte Carlo ``numerics``); the band's corner must lie
        below it.
    oversampling : int, optional
        Grid points per Nyquist step [1].

    Returns
    -------
    None

    Raises
    ------
    ValueError
        One line naming the parameter and its range.

    """
    band = getattr(excitation, "band_limit_hz", None)
    if band is None:
        return
    most = max_band_limit_hz(t_end, oversampling)
    reason = f"for a {float(t_end):g} s record"
    if cutoff is not None and cutoff / (2.0 * math.pi) < most:
        most, reason = cutoff / (2.0 * math.pi), f"for the synthesis' cutoff {float(cutoff):g} rad/s"
    if not np.all(np.asarray(band) <= most):
        raise ValueError(f"parameter 'band_limit_hz' must be in (0, {most:.4g}] Hz {reason}, or None "
                         f"(got {band!r})")


def synthesis_cutoff(excitation, block, foundation, cutoff=None, factor=CUTOFF_FACTOR):
    """The band [rad/s] a Monte Carlo run synthesizes its input to.

    Parameters
    ----------
    excitation : Excitation
        The input; its ``band_limit_hz`` [Hz] or None.
    block : screening.Block
        The block (scalar fields, SI).
    foundation : screening.Foundation
        The bed (scalar fields, SI).
    cutoff : float, optional
        A cut-off [rad/s] asked for (``numerics["cutoff"]``).
    factor : float, optional
        :func:`default_cutoff`'s multiple [1].

    Returns
    -------
    float
        With a band: its :meth:`~screening.core.excitations.Excitation.reference_cutoff` (where ``|H|^2`` has
        fallen to :data:`~screening.core.excitations.base.BAND_TAIL`), or ``cutoff`` if lower; without one
        (the idealized spectrum): ``cutoff``, else :func:`default_cutoff`.

    """
    if getattr(excitation, "band_limit_hz", None) is None:
        return float(cutoff) if cutoff is not None else default_cutoff(block, foundation, factor)
    top = float(excitation.reference_cutoff())
    return top if cutoff is None else min(float(cutoff), top)


def envelope_rate(envelope, t):
    """Time derivative ``q'(t)`` [1/s] of the modulating function at ``t`` [s] (eq. 57).

    The synthesis needs the exact rate of the modulated input ``d(q f)/dt = q' f + q f'`` for the
    cubic Hermite interpolation between grid points.

    Parameters
    ----------
    envelope : Envelope
        The modulating function (``kind`` ``"exponential"`` with ``T1``, ``T2`` [s], or ``"constant"``).
    t : array_like of float
        Times [s].

    Returns
    -------
    numpy.ndarray
        ``q'(t)`` [1/s], the shape of ``t`` (zeros for a constant envelope).

    Notes
    -----
    From ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` (eq. (57) in [1]_):
    ``q'(t) = 4 (-exp(-t/T1) / T1 + exp(-t/T2) / T2)``.

    """
    t = np.asarray(t, dtype=float)
    if envelope.kind == "constant":
        return np.zeros_like(t)
    T1, T2 = envelope.T1, envelope.T2
    return 4.0 * (-np.exp(-t / T1) / T1 + np.exp(-t / T2) / T2)


def band_limited_variance(excitation, cutoff):
    """``int_{-omega_c}^{omega_c} S(omega) d omega`` [m^2/s^4]: stationary variance of the
    unmodulated input band-limited to ``cutoff`` [rad/s] (``2 S0 omega_c`` for white noise).

    Parameters
    ----------
    excitation : Excitation
        The input (two-sided PSD ``S(omega)`` [m^2/s^3], :meth:`psd`).
    cutoff : float
        Band limit ``omega_c`` [rad/s].

    Returns
    -------
    float
        The variance [m^2/s^4] (adaptive quadrature, relative tolerance 1e-12).

    Notes
    -----
    With ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)`` (eq. (39) in [1]_) the spectrum is two-sided,
    ``S = S0`` for white noise and eq. (50) for Kanai-Tajimi; the variance of the band ``|omega| <= omega_c``
    is ``int S d omega``, which :attr:`SpectralPlan.stationary_variance` approximates by the midpoint rule.
    """
    return excitation.spectral_moment(0, cutoff, epsrel=1e-12)


@dataclass(frozen=True)
class SpectralPlan:
    """Frequency and time grids of a spectral-representation synthesis.

    Attributes
    ----------
    cutoff : band limit ``omega_c = N d_omega`` [rad/s] (the requested one, rounded to whole bins).
    d_omega : frequency step [rad/s]; period of every sample ``2 pi / d_omega`` [s].
    n_fft : FFT length ``M`` (grid points per period).
    dt : grid step [s], ``2 pi / (M d_omega)``.
    n_times : grid points returned per sample (cover ``[0, t_end]`` plus one).
    amplitudes : ``A_k = sqrt(2 S(omega_k) d_omega)`` [m/s^2] for ``k = 0..N-1``.
    """

    cutoff: float
    d_omega: float
    n_fft: int
    dt: float
    n_times: int
    amplitudes: np.ndarray

    @property
    def n_frequencies(self):
        """Number ``N`` of frequencies ``omega_k = (k + 1/2) d_omega``, ``k = 0..N-1``."""
        return int(self.amplitudes.size)

    @property
    def omega(self):
        """The frequencies ``omega_k`` [rad/s]."""
        return self.d_omega * (np.arange(self.n_frequencies) + 0.5)

    @property
    def times(self):
        """Grid times ``j dt`` [s] of the returned samples."""
        return self.dt * np.arange(self.n_times)

    @property
    def stationary_variance(self):
        """Exact ensemble variance of the unmodulated synthesized process, ``sum A_k^2`` [m^2/s^4]."""
        return float(np.sum(self.amplitudes**2))


def next_regular_length(n):
    """Smallest ``2^a 3^b 5^c >= n``: FFT lengths with only small prime factors are fastest.

    Parameters
    ----------
    n : int
        The least length wanted, ``>= 1``.

    Returns
    -------
    int
        The smallest 5-smooth integer ``>= n``.

    """
    best = 1 << max(int(n - 1).bit_length(), 0)
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


def grid_points(t_end, cutoff, oversampling=OVERSAMPLING):
    """Points of the synthesis grid of one sample: ``ceil(t_end / dt) + 2`` with the grid step
    ``dt = pi / (oversampling cutoff)``.

    Parameters
    ----------
    t_end : float
        Record length [s].
    cutoff : float
        Band limit ``omega_c`` [rad/s].
    oversampling : int, optional
        Grid points per Nyquist step ``pi / omega_c`` [1] (default :data:`OVERSAMPLING`, 4).

    Returns
    -------
    int
        Number of grid points [-], covering ``[0, t_end]`` plus one.

    """
    return int(math.ceil(t_end / (math.pi / (oversampling * cutoff)))) + 2


def spectral_plan(excitation, t_end, cutoff, oversampling=OVERSAMPLING):
    """Build the :class:`SpectralPlan` for ``excitation`` over ``[0, t_end]``.

    The FFT length is the next fast length covering the record, so the sample period
    ``2 pi / d_omega`` is at least ``t_end``; ``N`` is the nearest integer to ``cutoff / d_omega``.

    Parameters
    ----------
    excitation : Excitation
        The input (its two-sided PSD ``S(omega)`` [m^2/s^3]).
    t_end : float
        Record length [s], ``> 0``.
    cutoff : float
        Requested band limit [rad/s], ``> 0`` (rounded to whole bins).
    oversampling : int, optional
        ``>= 2``: grid step ``pi / (oversampling cutoff)`` [s] (default :data:`OVERSAMPLING`).

    Returns
    -------
    SpectralPlan
        The frequency and time grids and the amplitudes ``A_k`` [m/s^2].

    Raises
    ------
    ValueError
        One line naming the parameter, for a bad ``cutoff``, ``t_end`` or ``oversampling``.

    Notes
    -----
    ``f(t) = sqrt(2) sum_k A_k cos(omega_k t + phi_k)`` with ``A_k = sqrt(2 S(omega_k) d_omega)`` and
    midpoint frequencies ``omega_k = (k + 1/2) d_omega`` [1]_; its ensemble variance ``sum A_k^2`` is
    the midpoint rule for :func:`band_limited_variance` (exact for white noise).

    References
    ----------
    .. [1] [shinozuka1991] in the bibliography, ``docs/bibliography.md``.
    """
    if not (np.isfinite(cutoff) and cutoff > 0.0):
        raise ValueError(f"parameter 'cutoff' must be a finite number > 0 rad/s (got {cutoff!r})")
    if not (np.isfinite(t_end) and t_end > 0.0):
        raise ValueError(f"parameter 't_end' must be a finite number > 0 s (got {t_end!r})")
    if not oversampling >= 2:
        raise ValueError(f"parameter 'oversampling' must be >= 2 (got {oversampling!r})")
    dt = math.pi / (oversampling * cutoff)
    n_times = grid_points(t_end, cutoff, oversampling)
    n_fft = next_regular_length(n_times)
    d_omega = 2.0 * math.pi / (n_fft * dt)
    n_freq = max(int(round(cutoff / d_omega)), 1)
    omega = d_omega * (np.arange(n_freq) + 0.5)
    psd = np.asarray(excitation.psd(omega), dtype=float)
    amplitudes = np.sqrt(2.0 * psd * d_omega)
    return SpectralPlan(cutoff=float(n_freq * d_omega), d_omega=d_omega, n_fft=int(n_fft), dt=dt,
                        n_times=n_times, amplitudes=amplitudes)


def low_passed(plan, band):
    """The same samples low-passed at ``band`` [rad/s], on a coarser grid: ``(plan_low, stride)``.

    ``plan_low`` keeps the frequencies ``omega_k < band`` of ``plan`` (same ``d_omega``, so with the
    same seed every kept component has the same amplitude and phase: the phases of a sample are the
    first draws of its generator) on the grid ``j stride dt`` of ``plan`` (``plan_low.dt = stride
    plan.dt``), with its own FFT of length ``plan.n_fft / stride``: ``stride`` divides the FFT length,
    keeps at least the plan's oversampling of the kept band, and the coarse grid still covers the
    record, so synthesizing the low-passed samples costs in proportion to their own grid, not to
    ``plan``'s.  ``stride = 1`` and ``plan`` itself when ``band`` is not below half the plan's cutoff.

    Parameters
    ----------
    plan : SpectralPlan
        The full-band plan (:func:`spectral_plan`).
    band : float
        Band limit of the model that reads the samples [rad/s].

    Returns
    -------
    plan_low : SpectralPlan
        The low-passed plan (``plan`` itself where no coarser grid pays).
    stride : int
        Grid points of ``plan`` per point of ``plan_low`` [-].

    References
    ----------
    .. [1] [shinozuka1991] in the bibliography, ``docs/bibliography.md``.
    .. [2] The package's documentation, ``docs/model_choice.md`` ("Same ground motions, and the band each
       model reads").
    """
    n_keep = max(int(round(band / plan.d_omega)), 1)
    if not n_keep * plan.d_omega < 0.5 * plan.cutoff:
        return plan, 1
    t_end = (plan.n_times - 2) * plan.dt
    largest = max(int(plan.cutoff / (n_keep * plan.d_omega)), 1)
    stride = 1
    for s in range(largest, 1, -1):
        n_times = int(math.ceil(t_end / (s * plan.dt))) + 2
        if plan.n_fft % s == 0 and n_times <= plan.n_fft // s and 2 * n_keep < plan.n_fft // s:
            stride = s
            break
    if stride == 1:
        return plan, 1
    low = SpectralPlan(cutoff=float(n_keep * plan.d_omega), d_omega=plan.d_omega, n_fft=plan.n_fft // stride,
                       dt=stride * plan.dt, n_times=int(math.ceil(t_end / (stride * plan.dt))) + 2,
                       amplitudes=plan.amplitudes[:n_keep].copy())
    return low, stride


def validate_seed(seed):
    """Return ``seed`` as a Python int after checking it is an integer >= 0 (else ``ValueError``).

    Parameters
    ----------
    seed : int
        The run's seed (any integral type; not a bool), ``>= 0``.

    Returns
    -------
    int
        ``seed`` as a Python int.

    Raises
    ------
    ValueError
        One line naming the parameter.

    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"parameter 'seed' must be an integer >= 0 (got {seed!r})")
    return int(seed)


def sample_phases(seed, index, n_frequencies):
    """Random phases ``phi_k`` [rad], ``k = 0..N-1``, of sample ``index`` (``default_rng([seed, index])``).

    A sample's phases depend on the run's seed and its own index only, so a sample is the same
    however the samples are split into chunks or workers.

    Parameters
    ----------
    seed : int
        The run's seed, ``>= 0``.
    index : int
        The sample's index in the run, ``>= 0``.
    n_frequencies : int
        Number ``N`` of phases.

    Returns
    -------
    numpy.ndarray
        ``N`` phases [rad], independent and uniform on ``[0, 2 pi)``.

    References
    ----------
    .. [1] [shinozuka1991] in the bibliography, ``docs/bibliography.md``.
    .. [2] NumPy documentation, "Random Generator", https://numpy.org/doc/stable/reference/random/generator.html
    """
    rng = np.random.default_rng([int(seed), int(index)])
    return rng.uniform(0.0, 2.0 * np.pi, n_frequencies)


def stationary_samples(plan, seed, sample_indices):
    """Unmodulated samples ``f`` [m/s^2] and their rates ``f'`` [m/s^3] on ``plan.times``.

    Row ``r`` is sample ``sample_indices[r]`` of the run ``seed``; both come from one complex FFT.

    Parameters
    ----------
    plan : SpectralPlan
        The frequency and time grids (:func:`spectral_plan`).
    seed : int
        The run's seed, ``>= 0``.
    sample_indices : array_like of int
        Indices of the samples in the run.

    Returns
    -------
    values : numpy.ndarray
        ``f`` [m/s^2], shape ``(len(sample_indices), plan.n_times)``.
    rates : numpy.ndarray
        ``f'`` [m/s^3], same shape.

    Notes
    -----
    ``f(t) = sqrt(2) sum_k A_k cos(omega_k t + phi_k)`` [1]_.  With ``c_k = sqrt(2) A_k exp(i phi_k)``
    and ``w_k = (k + 1/2) d_omega``, one complex FFT gives both:
    ``f + i f' = sum_k [c_k (1 - w_k) e^{+i w_k t} + conj(c_k) (1 + w_k) e^{-i w_k t}] / 2``,
    and after the factor ``e^{i d_omega t / 2}`` the two exponentials sit on FFT bins ``k``
    and ``-(k + 1)``.

    References
    ----------
    .. [1] [shinozuka1991] in the bibliography, ``docs/bibliography.md``.
    """
    indices = np.atleast_1d(np.asarray(sample_indices, dtype=np.int64))
    phases = np.empty((indices.size, plan.n_frequencies))
    for row, index in enumerate(indices):
        phases[row] = sample_phases(seed, index, plan.n_frequencies)
    return samples_from_phases(plan, phases)


def samples_from_phases(plan, phases):
    """Unmodulated samples ``f`` [m/s^2] and rates ``f'`` [m/s^3] on ``plan.times`` from given phases.

    What :func:`stationary_samples` computes once it has drawn the phases of its samples; samplers that
    move the phases themselves (:mod:`screening.solvers.tail`) call it directly.

    Parameters
    ----------
    plan : SpectralPlan
        The frequency and time grids (:func:`spectral_plan`).
    phases : array_like
        Phases ``phi_k`` [rad], shape ``(n_rows, plan.n_frequencies)``.

    Returns
    -------
    values, rates : numpy.ndarray
        ``f`` [m/s^2] and ``f'`` [m/s^3], shape ``(n_rows, plan.n_times)``.

    Notes
    -----
    The equation is :func:`stationary_samples`'s.

    """
    phases = np.atleast_2d(np.asarray(phases, dtype=float))
    n, M = plan.n_frequencies, plan.n_fft
    if phases.shape[1] != n:
        raise ValueError(f"parameter 'phases' must have {n} columns, one per frequency (got shape {phases.shape})")
    omega = plan.omega
    coef = np.zeros((phases.shape[0], M), dtype=complex)
    c = (M * math.sqrt(2.0) / 2.0) * plan.amplitudes * np.exp(1j * phases)
    coef[:, :n] = c * (1.0 - omega)
    coef[:, M - 1:M - 1 - n:-1] = np.conj(c) * (1.0 + omega)
    z = sfft.ifft(coef, axis=1, overwrite_x=True)[:, :plan.n_times]
    z *= np.exp(0.5j * plan.d_omega * plan.times)
    return np.ascontiguousarray(z.real), np.ascontiguousarray(z.imag)


def ground_acceleration_samples(excitation, plan, seed, sample_indices):
    """Modulated ground acceleration ``q(t) f(t)`` [m/s^2] and its rate [m/s^3] on ``plan.times``.

    Parameters
    ----------
    excitation : Excitation
        The input (its envelope ``q(t)``).
    plan : SpectralPlan
        The grids of the stationary process (:func:`spectral_plan` of ``excitation``).
    seed, sample_indices
        As in :func:`stationary_samples`.

    Returns
    -------
    acceleration : numpy.ndarray
        ``x_g'' = q f`` [m/s^2], shape ``(len(sample_indices), plan.n_times)``.
    rate : numpy.ndarray
        ``q' f + q f'`` [m/s^3], same shape.

    Notes
    -----
    ``x_g''(t) = q(t) f(t)``: eq. (39) in [1]_ (white noise) or eq. (47) (a filtered input), with the
    envelope of eq. (57); ``f`` from :func:`stationary_samples`.
    """
    values, rates = stationary_samples(plan, seed, sample_indices)
    t = plan.times
    q = excitation.envelope(t)
    q_dot = envelope_rate(excitation.envelope, t)
    return q * values, q_dot * values + q * rates


def ground_acceleration(excitation, t_end, cutoff, n_samples, seed=0, oversampling=OVERSAMPLING):
    """Convenience wrapper: the times, ``n_samples`` modulated ground accelerations and their plan.

    Parameters
    ----------
    excitation : Excitation
        The input (two-sided PSD [m^2/s^3] and envelope).
    t_end : float
        Record length [s], ``> 0``.
    cutoff : float
        Band limit [rad/s], ``> 0``.
    n_samples : int
        Number of samples (indices ``0 .. n_samples - 1``).
    seed : int, optional
        The run's seed, ``>= 0``.
    oversampling : int, optional
        Grid points per Nyquist step [1] (default :data:`OVERSAMPLING`).

    Returns
    -------
    times : numpy.ndarray
        Grid times [s], ``plan.times``.
    acceleration : numpy.ndarray
        ``x_g''`` [m/s^2], shape ``(n_samples, plan.n_times)``.
    plan : SpectralPlan
        The grids used.
    """
    seed = validate_seed(seed)
    plan = spectral_plan(excitation, t_end, cutoff, oversampling)
    acc, _ = ground_acceleration_samples(excitation, plan, seed, np.arange(n_samples))
    return plan.times, acc, plan
