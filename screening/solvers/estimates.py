"""Fractions of Monte Carlo samples and their standard errors: the probabilities a run estimates.

* :func:`binomial_estimate` -- a fraction of samples and its standard error (Agresti-Coull);
* :func:`sample_probabilities` -- ``p_overturn`` and ``p_exceed`` per threshold from the per-sample
  peaks ``max_t |theta|`` of a Monte Carlo run (overturned samples count as exceeding every
  threshold; diverged samples are left out).

They sit with the solvers (:func:`screening.solvers.datasets.with_probabilities` adds them to a
:func:`screening.monte_carlo` result); :mod:`screening.analysis.probabilities` uses them for sweeps.
"""

from __future__ import annotations

import numpy as np

__all__ = []

#: ``z`` of the Agresti-Coull interval (about 95 %, ``p_tilde +- Z se``).
Z = 2.0


def binomial_estimate(hits, n):
    """Fraction ``p = hits / n`` [1] of Bernoulli trials and its standard error [1].

    The fraction of Monte Carlo samples that overturned (or exceeded a rotation) and how far it
    may be from the true probability: an Agresti-Coull error, which stays positive when no sample
    (or every sample) hit.

    Parameters
    ----------
    hits : array_like of int
        Number of successes [-], ``>= 0``.
    n : array_like of int
        Number of trials [-], broadcast with ``hits``; NaN results where ``n = 0``.

    Returns
    -------
    p : numpy.ndarray or float
        The fraction ``hits / n`` [1] (a scalar for scalar input).
    se : numpy.ndarray or float
        Its Agresti-Coull standard error [1].

    Notes
    -----
    The estimate is the unbiased ``p = k / n``.  Its standard error is the Agresti-Coull one [1]_,

    .. math:: se = \\sqrt{\\tilde p (1 - \\tilde p) / (n + z^2)}, \\qquad
              \\tilde p = (k + z^2 / 2) / (n + z^2), \\quad z = 2

    (:data:`Z`): ``p~ +- 2 se`` is the Agresti-Coull 95 % interval.  Unlike the Wald error
    ``sqrt(p (1 - p) / n)`` it does not vanish when no sample (or every sample) overturned: at
    ``k = 0`` it is about ``1.4 / n``, so ``p + 2 se`` bounds ``p`` by about ``3 / n`` as the rule of
    three does.

    """
    k = np.asarray(hits, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.where(n > 0, k / n, np.nan)
        tilde = (k + Z * Z / 2.0) / (n + Z * Z)
        se = np.where(n > 0, np.sqrt(tilde * (1.0 - tilde) / (n + Z * Z)), np.nan)
    return p[()], se[()]


def sample_probabilities(peak_abs_theta, overturned, valid, levels=()):
    """``p_overturn`` and ``p_exceed`` of a Monte Carlo run from its per-sample peaks.

    Counts the valid samples that overturned and, per threshold, those whose peak rotation passed
    it, and turns the counts into fractions with :func:`binomial_estimate`.  An overturned sample
    counts as exceeding every threshold; samples not valid (diverged, task failed) are left out.

    Parameters
    ----------
    peak_abs_theta : array_like of float
        Peak ``max_t |theta|`` [rad] of each sample over the record, samples on the LAST axis.
    overturned : array_like of bool
        True for the samples that overturned (same shape).
    valid : array_like of bool
        True for the samples in the estimate (not diverged, task not failed; same shape).
    levels : array_like of float, optional
        Rotation thresholds [rad], shape ``(L,)`` or the leading shape of the peaks plus ``(L,)``.

    Returns
    -------
    dict of numpy.ndarray
        ``p_overturn``, ``p_overturn_se`` (leading shape) and ``p_exceed``, ``p_exceed_se``
        (leading shape + ``(L,)``), all [1], from :func:`binomial_estimate` over the valid samples;
        NaN where no sample is valid.

    Notes
    -----
    With ``N`` the number of valid samples, ``p_overturn = #(overturned & valid) / N`` and
    ``p_exceed(a) = #((max_t |theta| > a or overturned) & valid) / N``: an overturned sample has
    passed every rotation on its way down.  These are the Monte Carlo estimates the judge holds the
    linearization's probabilities against (section 3 of [1]_ compares the two methods).
    """
    peaks = np.asarray(peak_abs_theta, dtype=float)
    over = np.asarray(overturned, dtype=bool) & np.asarray(valid, dtype=bool)
    valid = np.broadcast_to(np.asarray(valid, dtype=bool), peaks.shape)
    n = valid.sum(axis=-1)
    p_over, se_over = binomial_estimate(over.sum(axis=-1), n)
    levels = np.asarray(levels, dtype=float)
    if levels.ndim <= 1:
        levels = np.broadcast_to(levels, peaks.shape[:-1] + levels.shape[-1:])
    with np.errstate(invalid="ignore"):
        beyond = (peaks[..., None, :] > levels[..., :, None]) | over[..., None, :]
    hits = (beyond & valid[..., None, :]).sum(axis=-1)
    p_exc, se_exc = binomial_estimate(hits, n[..., None])
    return {"p_overturn": p_over, "p_overturn_se": se_over, "p_exceed": p_exc, "p_exceed_se": se_exc}
