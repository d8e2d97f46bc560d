"""The output time coordinate shared by the linearization, Monte Carlo and sweeps."""

from __future__ import annotations

import numpy as np

from screening.core.validation import checked
from screening.core import limits

__all__ = []


def output_times(t_end=20.0, dt=0.05):
    """Output instants ``0, dt, 2 dt, ..., t_end`` [s]: the time coordinate every method reports on.

    The linearization, the Monte Carlo judge and the sweeps all write their histories on this one
    grid, so their results line up instant by instant.  ``t_end`` must be a whole number of steps
    (to 1e-9 relative) and the grid at most ``MAX_TIMES`` instants (:mod:`screening.core.limits`); bad
    input is a one-line ``ValueError`` naming the parameter before any array is built.

    Parameters
    ----------
    t_end : float
        Duration of the record [s], ``> 0``.
    dt : float
        Output step [s], in ``(0, t_end]``; ``t_end / dt`` a whole number, at most ``MAX_TIMES - 1``.

    Returns
    -------
    numpy.ndarray
        The ``round(t_end / dt) + 1`` instants ``k dt`` [s], float64, from 0 to ``t_end``.

    Notes
    -----
    ``t_k = k dt`` for ``k = 0, ..., n`` with ``n = t_end / dt``; the records of the paper are 20 s
    long, read every 0.05 s (the defaults).

    """
    t_end = checked("t_end", t_end, lower=0.0)
    dt = checked("dt", dt, lower=0.0, upper=t_end, upper_inclusive=True)
    steps = limits.output_steps(t_end, dt)
    if not steps < limits.MAX_TIMES:
        raise ValueError(f"parameter 'dt': t_end / dt = {steps:.3g} output steps; at most {limits.MAX_TIMES - 1} "
                         f"(got t_end={t_end}, dt={dt})")
    n = int(round(t_end / dt))
    if abs(n * dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"parameter 'dt' must divide 't_end' into whole steps (got t_end={t_end}, dt={dt})")
    return dt * np.arange(n + 1)
