"""Ground-acceleration samples by the spectral representation method (Shinozuka–Deodatis).

A zero-mean stationary process with two-sided PSD ``S(omega)`` [m^2/s^3] (the convention of
:mod:`screening.model.excitation`: ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)`` for white noise, i.e.
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

from screening.physics.contact import linear_rocking_stiffness

__all__ = ["CUTOFF_FACTOR", "OVERSAMPLING", "rocking_frequency", "vertical_frequency", "default_cutoff",
           "default_cutoffs", "envelope_rate", "band_limited_variance", "SpectralPlan", "next_regular_length",
           "grid_points", "spectral_plan", "low_passed", "validate_seed", "sample_phases", "stationary_samples",
           "ground_acceleration_samples", "ground_acceleration"]


#: Default cutoff = CUTOFF_FACTOR x the larger of the rocking and vertical frequencies.
CUTOFF_FACTOR = 3.0
#: Default grid oversampling relative to the Nyquist step pi / omega_c.
OVERSAMPLING = 4


def rocking_frequency(block, foundation):
    """Small-amplitude rocking frequency ``sqrt(((2/3) b^3 k - m g h) / m_sdof)`` [rad/s] (eqs. 22, 25).

    ``eps`` is ignored (it adds ``eps m^2 g^2 b / (2 k)`` to the stiffness).  Zero if the
    linear rocking stiffness is not positive.
    """
    stiffness = linear_rocking_stiffness(block, foundation)
    return math.sqrt(max(float(stiffness), 0.0) / float(block.m_sdof))


def vertical_frequency(block, foundation):
    """Vertical (bouncing) frequency of the block on the bed, ``sqrt(2 b k / m)`` [rad/s] (eq. 13)."""
    return math.sqrt(2.0 * float(block.b) * float(foundation.k) / float(block.m))


def default_cutoff(block, foundation, factor=CUTOFF_FACTOR):
    """Band limit ``omega_c`` [rad/s] of the synthesized input: ``factor`` x the larger of
    :func:`rocking_frequency` and :func:`vertical_frequency`."""
    return float(factor) * max(rocking_frequency(block, foundation), vertical_frequency(block, foundation))


def default_cutoffs(block, foundation, factor=CUTOFF_FACTOR):
    """:func:`default_cutoff` [rad/s] of every point of a block and bed with array fields (NaN where the
    point's scales are beyond float64)."""
    from screening.model import Block, Foundation

    def one(m, b, h, I_cm, g, k):
        try:
            return default_cutoff(Block(m, b, h, I_cm, g), Foundation(k=k, lam=0.0), factor)
        except (ArithmeticError, ValueError):
            return np.nan

    return np.vectorize(one, otypes=[float])(block.m, block.b, block.h, block.I_cm, block.g, foundation.k)


def envelope_rate(envelope, t):
    """Time derivative ``q'(t)`` [1/s] of the modulating function at ``t`` [s] (eq. 57)."""
    t = np.asarray(t, dtype=float)
    if envelope.kind == "constant":
        return np.zeros_like(t)
    T1, T2 = envelope.T1, envelope.T2
    return 4.0 * (-np.exp(-t / T1) / T1 + np.exp(-t / T2) / T2)


def band_limited_variance(excitation, cutoff):
    """``int_{-omega_c}^{omega_c} S(omega) d omega`` [m^2/s^4]: stationary variance of the
    unmodulated input band-limited to ``cutoff`` [rad/s] (``2 S0 omega_c`` for white noise)."""
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
    """Smallest ``2^a 3^b 5^c >= n``: FFT lengths with only small prime factors are fastest."""
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
    ``dt = pi / (oversampling cutoff)`` (``t_end`` [s], ``cutoff`` [rad/s])."""
    return int(math.ceil(t_end / (math.pi / (oversampling * cutoff)))) + 2


def spectral_plan(excitation, t_end, cutoff, oversampling=OVERSAMPLING):
    """Build the :class:`SpectralPlan` for ``excitation`` over ``[0, t_end]``.

    ``t_end`` [s] > 0, ``cutoff`` [rad/s] > 0, ``oversampling`` >= 2 (grid step
    ``pi / (oversampling cutoff)``).  The FFT length is the next fast length covering the
    record, so the sample period ``2 pi / d_omega`` is at least ``t_end``; ``N`` is the
    nearest integer to ``cutoff / d_omega``.
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
    """Return ``seed`` as a Python int after checking it is an integer >= 0 (else ``ValueError``)."""
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"parameter 'seed' must be an integer >= 0 (got {seed!r})")
    return int(seed)


def sample_phases(seed, index, n_frequencies):
    """Random phases ``phi_k`` [rad], ``k = 0..N-1``, of sample ``index`` (``default_rng([seed, index])``)."""
    rng = np.random.default_rng([int(seed), int(index)])
    return rng.uniform(0.0, 2.0 * np.pi, n_frequencies)


def stationary_samples(plan, seed, sample_indices):
    """Unmodulated samples ``f`` [m/s^2] and their rates ``f'`` [m/s^3] on ``plan.times``.

    Returns two arrays of shape ``(len(sample_indices), plan.n_times)``; row ``r`` is
    sample ``sample_indices[r]`` of the run ``seed``.

    With ``c_k = sqrt(2) A_k exp(i phi_k)`` and ``w_k = (k + 1/2) d_omega``, one complex
    FFT gives both: ``f + i f' = sum_k [c_k (1 - w_k) e^{+i w_k t} + conj(c_k) (1 + w_k) e^{-i w_k t}] / 2``,
    and after the factor ``e^{i d_omega t / 2}`` the two exponentials sit on FFT bins ``k``
    and ``-(k + 1)``.
    """
    indices = np.atleast_1d(np.asarray(sample_indices, dtype=np.int64))
    n, M = plan.n_frequencies, plan.n_fft
    omega = plan.omega
    coef = np.zeros((indices.size, M), dtype=complex)
    for row, index in enumerate(indices):
        c = (M * math.sqrt(2.0) / 2.0) * plan.amplitudes * np.exp(1j * sample_phases(seed, index, n))
        coef[row, :n] = c * (1.0 - omega)
        coef[row, M - 1:M - 1 - n:-1] = np.conj(c) * (1.0 + omega)
    z = sfft.ifft(coef, axis=1, overwrite_x=True)[:, :plan.n_times]
    z *= np.exp(0.5j * plan.d_omega * plan.times)
    return np.ascontiguousarray(z.real), np.ascontiguousarray(z.imag)


def ground_acceleration_samples(excitation, plan, seed, sample_indices):
    """Modulated ground acceleration ``q(t) f(t)`` [m/s^2] and its rate [m/s^3] on ``plan.times``.

    Shape ``(len(sample_indices), plan.n_times)`` each; see :func:`stationary_samples`.
    """
    values, rates = stationary_samples(plan, seed, sample_indices)
    t = plan.times
    q = excitation.envelope(t)
    q_dot = envelope_rate(excitation.envelope, t)
    return q * values, q_dot * values + q * rates


def ground_acceleration(excitation, t_end, cutoff, n_samples, seed=0, oversampling=OVERSAMPLING):
    """Convenience wrapper: ``(times [s], acceleration [m/s^2] of shape (n_samples, n_times), plan)``."""
    seed = validate_seed(seed)
    plan = spectral_plan(excitation, t_end, cutoff, oversampling)
    acc, _ = ground_acceleration_samples(excitation, plan, seed, np.arange(n_samples))
    return plan.times, acc, plan
