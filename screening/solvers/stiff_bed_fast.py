"""The stiff-bed model's exact-contact sampler (``model="stiff_bed_fast"``): the same model as
``model="stiff_bed"`` (:mod:`screening.solvers.stiff_bed`, the reference), integrated with closed-form
full contact, located phase changes and dense output (:mod:`screening.kernels.stiff_bed_fast`), and its
ground motions synthesized in batches up to the excitation's band (:func:`band_samples`).

A record with a vertical component is integrated by the reference kernel (the closed form assumes the
weight ``m g``).  Method and measurements: ``docs/stiff_bed.md`` ("Exact-contact sampler").
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft

from screening.kernels import stiff_bed_fast as fast
from screening.kernels import mcs_kernels as kern
from screening.solvers.mc_registry import register
from screening.solvers.stiff_bed import StiffBedModel, StiffIntegrator, check_standing
from screening.kernels.stiff_bed_kernels import COUNT_ROWS
from screening.solvers.synthesis import (check_band, envelope_rate, OVERSAMPLING, sample_phases,
                                         spectral_plan, synthesis_cutoff, validate_seed)
from screening.solvers.timegrid import output_times

__all__ = []


# ----------------------------------------------------------------------------- synthesis
def band_plan(excitation, t_end, cutoff_hz, oversampling=OVERSAMPLING):
    """The spectral plan of ground motions synthesized up to ``cutoff_hz``.

    Parameters
    ----------
    excitation : screening.core.excitations.Excitation
        The input: its two-sided PSD (:meth:`psd`, [m2 s-3]) and envelope.
    t_end : float
        Record length [s], > 0.
    cutoff_hz : float
        Cut-off frequency [Hz], > 0.
    oversampling : int, optional
        Grid points per Nyquist step [1] (default 4).

    Returns
    -------
    screening.solvers.synthesis.SpectralPlan
        The plan of :func:`screening.solvers.synthesis.spectral_plan` at ``2 pi cutoff_hz``.

    Raises
    ------
    ValueError
        One line naming ``cutoff_hz`` when it is not a finite number > 0.
    """
    if isinstance(cutoff_hz, bool) or not isinstance(cutoff_hz, (int, float, np.floating, np.integer)) \
            or not (math.isfinite(cutoff_hz) and cutoff_hz > 0.0):
        raise ValueError(f"parameter 'cutoff_hz' must be a finite number > 0 Hz (got {cutoff_hz!r})")
    return spectral_plan(excitation, t_end, 2.0 * math.pi * float(cutoff_hz), oversampling)


def band_samples(excitation, plan, seed, sample_indices):
    """Modulated ground accelerations [m s-2] and their rates [m s-3] of a batch of samples on ``plan.times``.

    The samples of :func:`screening.solvers.synthesis.ground_acceleration_samples` (same seed, same phases,
    same values), synthesized for the whole batch at once: one batched FFT gives the values and their exact
    rates.

    Parameters
    ----------
    excitation : screening.core.excitations.Excitation
        The input (its envelope ``q(t)``).
    plan : screening.solvers.synthesis.SpectralPlan
        The plan (:func:`band_plan`).
    seed : int
        The run's seed, >= 0.
    sample_indices : array_like of int
        The samples' indices in the run.

    Returns
    -------
    acc : numpy.ndarray
        ``q f`` [m s-2], ``(len(sample_indices), plan.n_times)``.
    acc_dot : numpy.ndarray
        ``q' f + q f'`` [m s-3], same shape.

    Notes
    -----
    ``f + i f' = sum_k [c_k (1 - w_k) e^{i w_k t} + conj(c_k) (1 + w_k) e^{-i w_k t}] / 2``,
    ``c_k = sqrt(2) A_k e^{i phi_k}``, ``w_k = (k + 1/2) d_omega``: one complex FFT of length ``M`` per
    sample (as long as one real FFT of length ``2 M`` of the values alone) after the half-bin shift
    ``e^{i d_omega t / 2}`` (Shinozuka and Deodatis 1991; ``docs/method.md``).
    """
    seed = validate_seed(seed)
    indices = np.atleast_1d(np.asarray(sample_indices, dtype=np.int64))
    n, M = plan.n_frequencies, plan.n_fft
    omega = plan.omega
    phases = np.empty((indices.size, n))
    for row, index in enumerate(indices):
        phases[row] = sample_phases(seed, index, n)
    c = (M * math.sqrt(2.0) / 2.0) * plan.amplitudes * np.exp(1j * phases)
    coef = np.zeros((indices.size, M), dtype=complex)
    coef[:, :n] = c * (1.0 - omega)
    coef[:, M - 1:M - 1 - n:-1] = np.conj(c) * (1.0 + omega)
    z = sfft.ifft(coef, axis=1, overwrite_x=True, workers=1)
    t = plan.times
    acc = np.empty((indices.size, plan.n_times))
    rate = np.empty_like(acc)
    fast.modulate(z, np.cos(0.5 * plan.d_omega * t), np.sin(0.5 * plan.d_omega * t), excitation.envelope(t),
                  envelope_rate(excitation.envelope, t), acc, rate)
    return acc, rate


# ----------------------------------------------------------------------------- the integrator
class _FastIntegrator(StiffIntegrator):
    """The exact-contact kernel; a record with a vertical channel goes to the reference kernel."""

    def __init__(self, block, foundation, log_amp, log_eta, by_rate=False):
        super().__init__(block, foundation, log_amp, log_eta, locate=True, by_rate=by_rate)
        omega2 = self.k0 / self.m0
        self.osc = np.array([omega2, self.c0 / self.m0, self.mh / self.m0, math.sqrt(omega2)])
        self._maps = {}

    def maps(self, dt):
        """``([Phi | Gamma], pieces)`` of the grid step ``dt`` [s] (:func:`screening.kernels.stiff_bed_fast.grid_pieces`)."""
        if dt not in self._maps:
            omega2, c, g, _ = self.osc
            self._maps[dt] = (np.ascontiguousarray(fast.grid_propagator(omega2, c, g, dt)),
                              np.ascontiguousarray(fast.grid_pieces(omega2, c, g, dt)))
        return self._maps[dt]

    def __call__(self, acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                 out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted, n_rejected, h_min,
                 vertical=None):
        if vertical is not None:
            return super().__call__(acc, acc_dot, dt_grid, t_out, y_init, scale, rtol, h_max, max_steps, out_theta,
                                    out_theta_dot, out_z, out_z_dot, out_uplift, peak, status, reason, n_accepted,
                                    n_rejected, h_min, vertical)
        prop, pieces = self.maps(float(dt_grid))
        counts = np.zeros((0 if self.step_counts is None else acc.shape[0], len(fast.COUNTS)), dtype=np.int64)
        fast.integrate_chunk(self.sp, self.cp, self.osc, prop, pieces, self.log_amp, self.log_eta, acc, acc_dot,
                             float(dt_grid), t_out, np.ascontiguousarray(y_init[:2], dtype=float),
                             np.ascontiguousarray(scale[:2], dtype=float), float(rtol), float(h_max),
                             int(max_steps), out_theta, out_theta_dot, out_uplift, peak, status, reason, n_accepted,
                             n_rejected, h_min, counts)
        if self.step_counts is not None:
            self.step_counts += counts.sum(axis=0)
        out_z[...] = 0.0
        out_z_dot[...] = 0.0


class FastStiffBedModel(StiffBedModel):
    """The stiff-bed model (:class:`screening.solvers.stiff_bed.StiffBedModel`, its equations, transfer law,
    band and validity) integrated by the exact-contact kernel (module docstring).  ``transfer`` and ``band``
    as the reference's; the transfer is always located (at the zero crossing, in closed form)."""

    flag_code = 3
    name = "stiff_bed_fast"
    run_integrator = "exact_contact"
    description = ("the stiff-bed model with closed-form full contact, located phase changes and dense output "
                   "(docs/stiff_bed.md, 'Exact-contact sampler')")

    def __init__(self, transfer="impact", band="rocking"):
        super().__init__(transfer=transfer, band=band, locate=True)

    def integrator(self, block, foundation, condensation, max_flight_time, sample_integrator="dopri"):
        return _FastIntegrator(block, foundation, *self.table(block, foundation), by_rate=self.transfer == "impact")


STIFF_BED_FAST = register(FastStiffBedModel())


# ----------------------------------------------------------------------------- the sampler
def sample(block, foundation, excitation, n_samples, cutoff_hz=None, t_end=20.0, dt=0.05, seed=0, chunk_size=64,
           model=STIFF_BED_FAST, rtol=None, h_max=None, first=0, count=False):
    """Per-sample results of the stiff-bed model under ground motions synthesized up to the excitation's band
    (as :func:`screening.monte_carlo` does) or ``cutoff_hz``.

    The sampler without the ensemble statistics of :func:`screening.monte_carlo`: batches of ``chunk_size``
    samples synthesized (:func:`band_samples`) and integrated.

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m]); scalar fields.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping); scalar fields.
    excitation : screening.core.excitations.Excitation
        The input (PSD [m2 s-3] and envelope).
    n_samples : int
        Samples [1], >= 1.
    cutoff_hz : float, optional
        Cut-off frequency of the synthesis [Hz] (default: :func:`screening.solvers.synthesis.synthesis_cutoff`,
        the top of the excitation's band; a band above ``cutoff_hz`` is refused).
    t_end, dt : float, optional
        Record length and output step [s].
    seed : int, optional
        The run's seed (sample ``i`` is ``default_rng([seed, i])``'s).
    chunk_size : int, optional
        Samples per batch.
    model : StiffBedModel, optional
        The model (default the exact-contact sampler; ``screening.solvers.stiff_bed.STIFF_BED`` the reference).
    rtol, h_max : float, optional
        Tolerance [1] and largest step [s] of the adaptive steps (default the model's).
    first : int, optional
        Index of the first sample.
    count : bool, optional
        Also return ``counts``, the work per sample (the exact-contact kernel's
        :data:`screening.kernels.stiff_bed_fast.COUNTS`, the reference's
        :data:`screening.kernels.stiff_bed_kernels.COUNT_ROWS`).

    Returns
    -------
    dict
        ``peak`` [rad], ``status`` (:mod:`screening.kernels.mcs_kernels` codes), ``overturned``, ``diverged``,
        ``theta`` (samples x output times) [rad], ``n_steps``, ``plan``.
    """
    check_standing(block, foundation)
    if cutoff_hz is None:
        check_band(excitation, t_end)
        plan = spectral_plan(excitation, t_end, synthesis_cutoff(excitation, block, foundation))
    else:
        plan = band_plan(excitation, t_end, cutoff_hz)
        check_band(excitation, t_end, 2.0 * math.pi * float(cutoff_hz))
    times = output_times(t_end, dt)
    integrate = model.integrator(block, foundation, "paper", 0.5)
    if count:
        shape = len(fast.COUNTS) if isinstance(integrate, _FastIntegrator) else (len(COUNT_ROWS), 2)
        integrate.step_counts = np.zeros(shape, dtype=np.int64)
    rtol = model.default_rtol if rtol is None else float(rtol)
    h_max = model.default_h_max if h_max is None else float(h_max)
    scale = rtol * model.state_scales(block, foundation)
    y0 = model.initial_state(block, foundation)
    n_t = times.size
    theta = np.empty((n_samples, n_t))
    theta_dot = np.empty_like(theta)
    uplift = np.zeros((n_samples, n_t), dtype=np.bool_)
    peak = np.zeros(n_samples)
    status = np.zeros(n_samples, dtype=np.int64)
    reason = np.zeros(n_samples, dtype=np.int64)
    n_acc = np.zeros(n_samples, dtype=np.int64)
    n_rej = np.zeros(n_samples, dtype=np.int64)
    h_min = np.zeros(n_samples)
    z = np.empty((min(chunk_size, n_samples), n_t))
    for lo in range(0, n_samples, chunk_size):
        hi = min(lo + chunk_size, n_samples)
        acc, acc_dot = band_samples(excitation, plan, seed, np.arange(first + lo, first + hi))
        sl = slice(lo, hi)
        integrate(acc, acc_dot, plan.dt, times, y0, scale, rtol, h_max, 5_000_000, theta[sl], theta_dot[sl],
                  z[:hi - lo], z[:hi - lo], uplift[sl], peak[sl], status[sl], reason[sl], n_acc[sl], n_rej[sl],
                  h_min[sl])
    out = {"counts": integrate.step_counts / n_samples} if count else {}
    return {**out, "peak": peak, "status": status, "overturned": status == kern.STATUS_OVERTURNED,
            "diverged": status == kern.STATUS_DIVERGED, "theta": theta, "n_steps": n_acc + n_rej, "plan": plan}
