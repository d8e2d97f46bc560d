"""The output time coordinate shared by the linearization, Monte Carlo and sweeps."""

from __future__ import annotations

import numpy as np

from screening.validation import checked


def output_times(t_end=20.0, dt=0.05):
    """Output instants ``0, dt, 2 dt, ..., t_end`` [s].

    ``t_end`` [s] > 0 and ``dt`` [s] in ``(0, t_end]``; ``t_end`` must be a whole number of
    steps (to 1e-9 relative) so that every method reports on the same grid.
    """
    t_end = checked("t_end", t_end, lower=0.0)
    dt = checked("dt", dt, lower=0.0, upper=t_end, upper_inclusive=True)
    n = int(round(t_end / dt))
    if abs(n * dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"parameter 'dt' must divide 't_end' into whole steps (got t_end={t_end}, dt={dt})")
    return dt * np.arange(n + 1)
