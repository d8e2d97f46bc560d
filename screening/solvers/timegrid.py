"""The output time coordinate shared by the linearization, Monte Carlo and sweeps."""

from __future__ import annotations

import numpy as np

from screening.validation import checked
from screening import limits

__all__ = ["output_times"]


def output_times(t_end=20.0, dt=0.05):
    """Output instants ``0, dt, 2 dt, ..., t_end`` [s].

    ``t_end`` [s] > 0 and ``dt`` [s] in ``(0, t_end]``, at most ``MAX_TIMES - 1`` steps
    (:mod:`screening.limits`); ``t_end`` must be a whole number of
    steps (to 1e-9 relative) so that every method reports on the same grid.
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
