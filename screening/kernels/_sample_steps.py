"""What the compiled sample integrators share (package-internal; those of the Monte Carlo models in
:mod:`screening.kernels.mcs_kernels` and the stiff-bed model's in :mod:`screening.kernels.stiff_bed_kernels`).

The ground input of a sample between the grid points of its synthesis: the cubic Hermite interpolant
of the grid values and exact rates of each channel (horizontal ``x_g''``, vertical ``a_v``), and its
rate (for the linearly implicit integrator); one term of the error norm of an adaptive step; the
store of a sample's outcome into its row of the chunk's outputs.  No model knowledge: the models'
equations stay with their integrators.
"""

from __future__ import annotations

import numba
import numpy as np

from screening.core.interpolation import hermite, hermite_rate

#: "No vertical channel": the vertical ground acceleration and rate of a run without one (read as 0).
NO_VERTICAL = np.zeros((1, 0))


@numba.njit(cache=True, inline="always")
def _grid_interval(n, dt, t):
    """``(j, s)``: the interval ``[j dt, (j + 1) dt]`` of a grid of ``n`` points holding ``t`` (the end
    intervals beyond the grid) and the fraction ``s = t / dt - j``."""
    x = t / dt
    j = int(x)
    if j > n - 2:
        j = n - 2
    if j < 0:
        j = 0
    return j, x - j


@numba.njit(cache=True)
def _channel(row, acc, acc_dot, dt, t):
    """One channel of the ground acceleration at ``t`` from grid values and rates of row ``row`` (cubic
    Hermite)."""
    j, s = _grid_interval(acc.shape[1], dt, t)
    return hermite(acc[row, j], acc[row, j + 1], acc_dot[row, j], acc_dot[row, j + 1], s, dt)


@numba.njit(cache=True, inline="always")
def vertical_row(row, vertical):
    """Row of the vertical channel read by sample ``row`` (-1: none, read as 0; a single row: every sample's)."""
    if vertical.shape[1] == 0:
        return np.int64(-1)
    return np.int64(row) if vertical.shape[0] > 1 else np.int64(0)     # prange rows may be unsigned


@numba.njit(cache=True, inline="always")
def ground_input(row, acc, acc_dot, dt, t):
    """Ground input ``(x_g'', a_v)`` [m/s^2] at ``t``: ``acc = (horizontal, vertical)`` grid values and
    ``acc_dot`` their rates (:func:`_channel` each; a vertical channel of no columns reads 0)."""
    horizontal = _channel(row, acc[0], acc_dot[0], dt, t)
    vrow = vertical_row(row, acc[1])
    if vrow < 0:
        return horizontal, 0.0
    return horizontal, _channel(vrow, acc[1], acc_dot[1], dt, t)


@numba.njit(cache=True)
def _channel_rate(row, acc, acc_dot, dt, t):
    """Rate of one channel at ``t`` [m/s^3]: derivative of :func:`_channel`."""
    j, s = _grid_interval(acc.shape[1], dt, t)
    return hermite_rate(acc[row, j], acc[row, j + 1], acc_dot[row, j], acc_dot[row, j + 1], s, dt)


@numba.njit(cache=True, inline="always")
def ground_input_rate(row, acc, acc_dot, dt, t):
    """Rates of the ground input ``(x_g'', a_v)`` at ``t`` [m/s^3]: derivative of :func:`ground_input`."""
    vrow = vertical_row(row, acc[1])
    vertical = _channel_rate(vrow, acc[1], acc_dot[1], dt, t) if vrow >= 0 else 0.0
    return _channel_rate(row, acc[0], acc_dot[0], dt, t), vertical


@numba.njit(cache=True)
def err_term(e, y, ynew, scale, rtol):
    """One component's term ``(e / (scale + rtol max(|y|, |ynew|)))^2`` of an adaptive step's error norm."""
    sc = scale + rtol * max(abs(y), abs(ynew))
    r = e / sc
    return r * r


@numba.njit(cache=True)
def store_outcome(row, outcome, status, reason, peak, n_accepted, n_rejected, h_min):
    """Row ``row`` of a chunk's per-sample outputs from a sample integrator's ``outcome``, the tuple
    ``(status, reason, peak, n_accepted, n_rejected, h_min)``."""
    status[row] = outcome[0]
    reason[row] = outcome[1]
    peak[row] = outcome[2]
    n_accepted[row] = outcome[3]
    n_rejected[row] = outcome[4]
    h_min[row] = outcome[5]
