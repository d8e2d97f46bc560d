"""The intensity at which the linearization reaches a target peak uplift probability.

A study that sets its points by how hard they rock, not by ``S0``, asks for the white-noise or
filtered intensity ``S0`` [m2 s-3] at which the stochastic linearization's peak uplift probability
``max_t P(|theta| > theta_ul)`` equals a target: :func:`calibrate_intensity`, a bisection on
``log10 S0``.  The speed-accuracy trade study (:mod:`screening.report.tradeoff`) and the error atlas
(``research/atlas_run.py``) set their points with it.
"""

from __future__ import annotations

import math

from screening.solvers.moments import solve_moments
from screening.core.status import PointStatus

__all__ = []


def round_significant(x, digits=3):
    """``x`` rounded to ``digits`` significant digits.

    Returns: the rounded value [unit of ``x``].
    """
    if x == 0 or not math.isfinite(x):
        return x
    return float(f"{x:.{digits - 1}e}")


def calibrate_intensity(block, foundation, make_exc, target, t_out, rtol=1e-7, log10_bounds=(-10.0, 1.0),
                        condensation="paper"):
    """``S0`` [m2 s-3] at which SL's peak uplift probability equals ``target`` [1].

    Bisection (Brent) on ``log10 S0`` of ``log(peak_p_uplift) - log(target)``; a point whose
    SL integration stops (status != ok) counts as ``peak_p_uplift = 1``.  The result is
    rounded to 3 significant digits and must give status ok and a peak uplift probability
    within 10 % of the target, else ValueError.  ``make_exc(S0)`` builds the excitation.

    Parameters
    ----------
    block : screening.core.model.Block
        The block (scalar fields).
    foundation : screening.core.model.Foundation
        Its bed.
    make_exc : callable
        ``make_exc(S0)`` -> the excitation at ``S0`` [m2 s-3].
    target : float
        Peak uplift probability aimed at [1], in (0, 1).
    t_out : numpy.ndarray
        Output times of the linearization [s].
    rtol : float, default 1e-7
        Relative tolerance of the moment equations.
    log10_bounds : tuple of float, default (-10.0, 1.0)
        Bracket of ``log10 S0`` [log10 of m2 s-3].
    condensation : str, default "paper"
        The condensation.

    Returns
    -------
    float
        ``S0`` [m2 s-3], 3 significant digits.

    Notes
    -----
    The peak uplift probability is that of the stochastic linearization's moment equations
    (eqs. (39)-(46) in [1]); the root is found by Brent's method [2].

    """
    from scipy.optimize import brentq

    def solve(log_s0):
        r = solve_moments(block, foundation, make_exc(10.0 ** log_s0), t_out, rtol=rtol, condensation=condensation)
        return int(r["status"]), float(r["peak_p_uplift"])

    def f(log_s0):
        status, p = solve(log_s0)
        p = 1.0 if status != PointStatus.ok else max(p, 1e-300)
        return math.log(p) - math.log(target)

    lo, hi = log10_bounds
    if f(lo) >= 0 or f(hi) <= 0:
        raise ValueError(f"target_peak_p_uplift {target:g} is not bracketed by S0 in "
                         f"[1e{lo:g}, 1e{hi:g}] m2 s-3")
    x = brentq(f, lo, hi, xtol=1e-6)
    S0 = round_significant(10.0 ** x)
    status, p = solve(math.log10(S0))
    if status != PointStatus.ok or abs(p / target - 1.0) > 0.1:
        raise ValueError(f"target_peak_p_uplift {target:g} is not reachable with SL status ok "
                         f"(at S0 = {S0:.3g}: status {_status_name(status)}, peak p_uplift {p:.3g})")
    return S0


def _status_name(status):
    return PointStatus(status).name if status in set(PointStatus) else status
