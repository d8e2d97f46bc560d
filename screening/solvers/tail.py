"""Small probabilities of overturning and exceedance by subset simulation over the models' input phases.

:func:`subset_simulation` estimates ``P(Y > y)`` of any response ``Y = r(U)`` of a standard-normal vector
``U`` (Au & Beck 2001); :func:`tail_probability` applies it to a registered Monte Carlo model, whose input is
the spectral representation of :mod:`screening.solvers.synthesis` with phases ``phi_k = 2 pi Phi(U_k)``
(uniform on ``[0, 2 pi)``, as the phases crude Monte Carlo draws): the same model, sampled where it matters.
Method and validation: ``docs/tail.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.special import ndtr

from screening.core.condensation import DEFAULT_CONDENSATION
from screening.core.progress import Progress
from screening.core.validation import check_integer
from screening.kernels import mcs_kernels as kern
from screening.solvers import schema
from screening.solvers.montecarlo import sample_setup
from screening.solvers.synthesis import samples_from_phases, validate_seed

__all__ = ["tail_probability"]

#: Markov chain samplers of the levels: ``"acs"`` adaptive conditional sampling (Papaioannou et al. 2015),
#: ``"mma"`` the component-wise modified Metropolis of Au & Beck (2001).
SAMPLERS = ("acs", "mma")
#: Target acceptance rate of ``"acs"`` [1] and its initial scaling.
ACS_ACCEPTANCE, ACS_LAMBDA = 0.44, 0.6


@dataclass(frozen=True)
class SubsetEstimate:
    """What :func:`subset_simulation` returns.

    ``p`` [1] and ``cov`` [1] per threshold (NaN where no sample reached it), ``se = p cov``; ``n_calls`` the
    response evaluations; per level: ``level_threshold`` (the intermediate thresholds ``b_j``), ``level_p`` (the
    conditional probability ``p_j``) and ``level_gamma`` (the chain-correlation factor ``gamma_j``); ``n_missing``
    the evaluations without an answer (NaN response, counted as not exceeding).
    """

    thresholds: np.ndarray
    p: np.ndarray
    cov: np.ndarray
    n_calls: int
    level_threshold: np.ndarray
    level_p: np.ndarray
    level_gamma: np.ndarray
    n_missing: int

    @property
    def se(self):
        """Standard error ``p cov`` [1]."""
        return self.p * self.cov


def chain_correlation_factor(indicator):
    """Au & Beck's correlation factor ``gamma`` [1] of the hit indicator of a level's Markov chains.

    Parameters
    ----------
    indicator : array_like of bool
        Whether each sample exceeds the next threshold, shape ``(chain_length, n_chains)``.

    Returns
    -------
    float
        ``gamma`` [1]; 0 for independent samples (``chain_length = 1``) or a constant indicator.

    Notes
    -----
    With ``N_s`` the chain length, ``N_c`` the number of chains, ``N = N_s N_c`` and ``p`` the fraction of hits
    (eqs. (27)-(29) of Au & Beck [1]_):

    .. math:: R_k = \\frac{1}{N - k N_c} \\sum_{c} \\sum_{l=1}^{N_s - k} I_{l,c} I_{l+k,c} - p^2, \\qquad
              \\gamma = 2 \\sum_{k=1}^{N_s - 1} \\left(1 - \\frac{k}{N_s}\\right) \\frac{R_k}{R_0}

    and the coefficient of variation of the level's estimate is ``sqrt((1 - p) / (N p) (1 + gamma))``.

    References
    ----------
    .. [1] [au2001] in the bibliography, ``docs/bibliography.md``.
    """
    ind = np.asarray(indicator, dtype=float)
    n_s = ind.shape[0]
    p = ind.mean()
    r0 = p * (1.0 - p)
    if n_s < 2 or r0 <= 0.0:
        return 0.0
    gamma = 0.0
    for k in range(1, n_s):
        r_k = np.mean(ind[:-k] * ind[k:]) - p * p
        gamma += 2.0 * (1.0 - k / n_s) * r_k / r0
    return float(gamma)


def _advance(sampler, u, y, level, response, rng, state):
    """One step of every chain at ``level``: new ``(u, y)`` and the fraction accepted."""
    if sampler == "acs":
        sigma = np.minimum(state["lam"] * state["sigma"], 1.0)
        cand = np.sqrt(1.0 - sigma**2) * u + sigma * rng.standard_normal(u.shape)
        moved = np.ones(u.shape[0], dtype=bool)
    else:
        xi = u + rng.standard_normal(u.shape)
        keep = rng.random(u.shape) < np.exp(0.5 * (u**2 - xi**2))
        cand = np.where(keep, xi, u)
        moved = keep.any(axis=1)
    y_c = np.full(u.shape[0], -np.inf)
    if moved.any():
        y_c[moved] = response(cand[moved])
    accept = np.where(np.isnan(y_c), -np.inf, y_c) > level
    u, y = np.where(accept[:, None], cand, u), np.where(accept, y_c, y)
    rate = float(accept.mean())
    if sampler == "acs":
        state["step"] += 1
        state["lam"] *= math.exp((rate - ACS_ACCEPTANCE) / math.sqrt(state["step"]))
    return u, y, rate


def _level_threshold(y_sorted, n_seeds):
    hi, lo = y_sorted[n_seeds - 1], y_sorted[n_seeds]
    if not np.isfinite(lo):
        return hi
    return lo if not np.isfinite(hi) else 0.5 * (hi + lo)


def subset_simulation(response, dim, thresholds, n_per_level=1000, p0=0.1, seed=0, max_levels=12, sampler="acs",
                      progress=False):
    """``P(r(U) > y)`` [1] for ``U ~ N(0, I_dim)`` and each threshold ``y``, by subset simulation.

    Parameters
    ----------
    response : callable
        ``r``: maps an ``(n, dim)`` array of standard normals to ``n`` responses (NaN: no answer, counted as
        not exceeding; ``+inf`` allowed).
    dim : int
        Dimension of ``U`` [-], ``>= 1``.
    thresholds : array_like
        The thresholds ``y`` (units of the response).
    n_per_level : int, optional
        Samples per level ``N`` [-] (default 1000); ``p0 N`` must be an integer ``>= 1``.
    p0 : float, optional
        Conditional probability of the intermediate levels [1], in ``(0, 0.5]`` (default 0.1).
    seed : int, optional
        Seed of the sampler's generator, ``>= 0``.
    max_levels : int, optional
        Most levels [-] (default 12: thresholds down to ``p0^12``); beyond, a threshold not reached is NaN.
    sampler : str, optional
        One of :data:`SAMPLERS` (default ``"acs"``).
    progress : bool, optional
        A progress line per level on stderr.

    Returns
    -------
    SubsetEstimate
        ``p``, ``cov``, ``se`` per threshold and the levels.

    Notes
    -----
    Level 0 draws ``N`` independent samples; the intermediate threshold ``b_{j+1}`` is the ``(1 - p0)``
    quantile of level ``j``'s responses and its ``p0 N`` samples above it seed Markov chains of length
    ``1 / p0`` whose states stay above ``b_{j+1}`` (level ``j + 1``, distributed as ``U`` given
    ``r(U) > b_{j+1}``).  A threshold ``y`` reached by at least ``p0 N`` samples of level ``m`` (or by any at the
    last) gets ``P = p_0 p_1 ... p_{m-1} P_m(y)``, ``P_m(y)`` the fraction of level ``m`` above it; its
    coefficient of variation is ``delta^2 = sum_j (1 - p_j) / (N p_j) (1 + gamma_j)`` (Au & Beck [1]_, eq. (30):
    the levels taken as uncorrelated; :func:`chain_correlation_factor`).  The estimate is asymptotically
    unbiased, with a bias of order ``1 / N`` [1]_.

    References
    ----------
    .. [1] [au2001] in the bibliography, ``docs/bibliography.md``.
    .. [2] I. Papaioannou, W. Betz, K. Zwirglmaier and D. Straub, "MCMC algorithms for subset simulation",
       Probabilistic Engineering Mechanics 41 (2015) 89-103. https://doi.org/10.1016/j.probengmech.2015.06.006
    """
    dim = check_integer("dim", dim, 1)
    n = check_integer("n_per_level", n_per_level, 2)
    if not (isinstance(p0, float) and 0.0 < p0 <= 0.5) or abs(p0 * n - round(p0 * n)) > 1e-9 or round(p0 * n) < 1:
        raise ValueError(f"parameter 'p0' must be a float in (0, 0.5] with p0 * n_per_level a whole number >= 1 "
                         f"(got p0={p0!r}, n_per_level={n})")
    if sampler not in SAMPLERS:
        raise ValueError(f"parameter 'sampler' must be one of {SAMPLERS} (got {sampler!r})")
    max_levels = check_integer("max_levels", max_levels, 1)
    targets = np.atleast_1d(np.asarray(thresholds, dtype=float))
    if targets.ndim != 1 or targets.size == 0 or np.isnan(targets).any():
        raise ValueError(f"parameter 'thresholds' must be one or more numbers (got {thresholds!r})")
    rng = np.random.default_rng(validate_seed(seed))
    calls = {"n": 0, "missing": 0}

    def counted(u):
        out = np.asarray(response(u), dtype=float)
        calls["n"] += out.size
        calls["missing"] += int(np.isnan(out).sum())
        return out

    n_seeds = int(round(p0 * n))
    p, cov = np.full(targets.size, np.nan), np.full(targets.size, np.nan)
    open_ = np.ones(targets.size, dtype=bool)
    levels, level_p, level_gamma, delta2, prob = [], [], [], 0.0, 1.0
    state = {"lam": ACS_LAMBDA, "step": 0}
    with Progress(max_levels, label="subset simulation levels", enabled=progress) as bar:
        u = rng.standard_normal((n, dim))
        y = counted(u)
        ys = np.where(np.isnan(y), -np.inf, y)[None, :]       # (chain length, chains); NaN: never exceeds
        us = u[None]
        for level in range(max_levels + 1):
            flat = ys.reshape(-1)
            last = level == max_levels
            for i in np.flatnonzero(open_):
                hits = ys > targets[i]
                if hits.sum() >= n_seeds or last:
                    frac = hits.mean()
                    p[i] = prob * frac if hits.any() else np.nan
                    d2 = (1.0 - frac) / (flat.size * frac) * (1.0 + chain_correlation_factor(hits)) if frac else np.nan
                    cov[i] = math.sqrt(delta2 + d2) if hits.any() else np.nan
                    open_[i] = False
            bar.update(1)
            if not open_.any() or last:
                break
            order = np.argsort(flat)[::-1]
            b = _level_threshold(flat[order], n_seeds)
            if levels and not b > levels[-1]:
                break                                           # no progress: the rest stays NaN
            hits = ys > b
            frac = hits.mean()
            if frac == 0.0:
                break                                           # every sample without an answer
            levels.append(b)
            level_p.append(frac)
            level_gamma.append(chain_correlation_factor(hits))
            delta2 += (1.0 - frac) / (flat.size * frac) * (1.0 + level_gamma[-1])
            prob *= frac
            seeds = np.flatnonzero(hits.reshape(-1))
            u, y = us.reshape(-1, dim)[seeds], flat[seeds]
            if sampler == "acs":
                state["sigma"] = np.std(u, axis=0) if u.shape[0] > 1 else np.ones(dim)
            length = max(int(math.ceil(n / seeds.size)), 1)
            us, ys = np.empty((length, seeds.size, dim)), np.empty((length, seeds.size))
            us[0], ys[0] = u, y
            for step in range(1, length):
                u, y, _ = _advance(sampler, u, y, b, counted, rng, state)
                us[step], ys[step] = u, y
    return SubsetEstimate(targets, p, cov, calls["n"], np.array(levels), np.array(level_p), np.array(level_gamma),
                          calls["missing"])


def combine_runs(p, se):
    """One estimate [1] and its standard error [1] from independent subset-simulation runs.

    ``p`` and ``se``: ``(runs, thresholds)``, each run's estimate and Au & Beck's standard error.  The estimate
    is the runs' mean (each run is unbiased); its standard error the larger of the runs' spread over
    ``sqrt(runs)`` and Au & Beck's combined, ``sqrt(sum se_r^2) / runs`` (Au & Beck's alone from one run).
    Au & Beck's coefficient of variation neglects the correlation between levels and reads 1.3-3x below the
    spread of independent runs on the stiff-bed model (``docs/tail.md``): the spread is what vouches for it.
    A threshold that any run left unreached is NaN.
    """
    p, se = np.atleast_2d(p), np.atleast_2d(se)
    runs = p.shape[0]
    au_beck = np.sqrt((se ** 2).sum(axis=0)) / runs
    spread = p.std(axis=0, ddof=1) / math.sqrt(runs) if runs > 1 else np.zeros(p.shape[1])
    return p.mean(axis=0), np.maximum(au_beck, spread)


def _model_response(run):
    """``r(U)``: each row's peak ``|theta|`` [rad] under the phases ``2 pi Phi(U)`` (``+inf`` overturned, NaN
    diverged), integrated chunk by chunk as :func:`screening.solvers.montecarlo.monte_carlo` does."""
    plan, opts = run.read_plan, run.opts
    n_t, chunk = run.times.size, opts["chunk_size"]

    def response(u):
        out = np.empty(u.shape[0])
        for lo in range(0, u.shape[0], chunk):
            rows = u[lo:lo + chunk]
            acc, acc_dot = samples_from_phases(plan, 2.0 * np.pi * ndtr(rows))
            acc_dot *= run.q
            acc_dot += run.q_dot * acc
            acc *= run.q
            m = rows.shape[0]
            scratch = [np.empty((m, n_t)) for _ in range(4)]
            uplift = np.zeros((m, n_t), dtype=np.bool_)
            peak, h_min = np.zeros(m), np.zeros(m)
            status, reason, n_acc, n_rej = (np.zeros(m, dtype=np.int64) for _ in range(4))
            run.integrate(acc, acc_dot, plan.dt, run.times, run.y0, run.scales, opts["rtol"], opts["h_max"],
                          opts["max_steps"], *scratch, uplift, peak, status, reason, n_acc, n_rej, h_min)
            peak[status == kern.STATUS_OVERTURNED] = np.inf
            peak[status == kern.STATUS_DIVERGED] = np.nan
            out[lo:lo + m] = peak
        return out

    return response


def tail_probability(block, foundation, excitation, thresholds=(), model="stiff_bed", n_per_level=250, p0=0.1,
                     seed=0, runs=4, t_end=20.0, dt=0.05, sampler="acs", max_levels=12,
                     condensation=DEFAULT_CONDENSATION, strict_validity=False, progress=False, **numerics):
    """Small ``p_overturn`` and ``p_exceed`` [1] of a Monte Carlo model, with their standard errors, by subset
    simulation over the model's input phases.

    Parameters
    ----------
    block, foundation, excitation : the point (SI), as :func:`screening.monte_carlo`.
    thresholds : rotations [rad] > 0 of ``p_exceed`` (a number or a sequence; default none).
    model : a registered Monte Carlo model or its name (default ``"stiff_bed"``).
    n_per_level : samples per level of each run [-] (default 250).
    runs : independent runs [-] (default 4, ``>= 1``): their spread gives the standard error (:func:`combine_runs`).
    p0 : conditional probability of the levels [1] (default 0.1).
    seed : seed of the sampler [-], ``>= 0``.
    t_end, dt : record length and output step [s].
    sampler : ``"acs"`` (default) or ``"mma"`` (:data:`SAMPLERS`).
    max_levels : most levels [-]: probabilities below ``p0^max_levels`` are NaN.
    condensation, strict_validity, **numerics : as :func:`screening.monte_carlo`.
    progress : a line per level on stderr.

    Returns
    -------
    xarray.Dataset
        ``p_overturn``, ``p_overturn_se``, ``p_overturn_cov`` and ``p_exceed``, ``p_exceed_se``, ``p_exceed_cov`` on
        ``threshold`` [rad]; ``level_threshold`` [rad] and ``level_gamma`` on ``(run, level)`` (NaN past a run's
        last level); attributes ``n_model_runs`` (samples integrated), ``n_diverged``, ``model``, ``sampler``,
        ``n_per_level``, ``runs``, ``p0``, ``seed``.  A probability some run did not reach is NaN.

    Raises
    ------
    ValueError
        One line naming the parameter, before any sample is integrated.

    Notes
    -----
    The response is ``Y = max_t |theta(t)|`` (``+inf`` for an overturned sample: it exceeds every threshold, as in
    :func:`screening.solvers.estimates.sample_probabilities`); its input the samples of
    :func:`screening.solvers.synthesis.stationary_samples` with ``phi_k = 2 pi Phi(U_k)``, ``U ~ N(0, I)``, over
    the ``N`` frequencies the model reads: the phases are independent and uniform as in crude Monte Carlo, so
    ``P(Y > y)`` is the model's own.  :func:`subset_simulation` gives ``P`` and its coefficient of variation
    (Au & Beck's eq. (30)) per run; the runs are combined by :func:`combine_runs`.  A diverged sample counts as
    not exceeding (crude Monte Carlo leaves it out: ``n_diverged`` says how many).

    References
    ----------
    .. [1] [au2001] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> from screening import Block, Foundation, KanaiTajimi
    >>> ds = tail_probability(Block(m=1200.0, b=0.25, h=0.9), Foundation(k=1e10, lam=2.5e10),
    ...                       KanaiTajimi(S0=0.01, omega_g=15.6, zeta_g=0.6), thresholds=[0.02], n_per_level=20,
    ...                       t_end=2.0, dt=0.1, max_levels=1)
    >>> sorted(ds.data_vars)[:3], ds.attrs["model"]
    (['level_gamma', 'level_threshold', 'p_exceed'], 'stiff_bed')
    """
    rotations = np.atleast_1d(np.asarray(thresholds, dtype=float))
    if rotations.ndim != 1 or not np.all(np.isfinite(rotations) & (rotations > 0.0)):
        raise ValueError(f"parameter 'thresholds' must be rotations [rad] in (0, inf) (got {thresholds!r})")
    n = check_integer("n_per_level", n_per_level, 2)
    n_runs = check_integer("runs", runs, 1)
    run = sample_setup(block, foundation, excitation, n, model, t_end, dt, condensation, strict_validity, **numerics)
    response = _model_response(run)
    overturn = np.finfo(float).max                       # only +inf (overturned) exceeds it
    seeds = np.random.SeedSequence(validate_seed(seed)).generate_state(n_runs)
    ests = [subset_simulation(response, run.read_plan.n_frequencies, [overturn, *rotations], n, p0, int(s),
                              max_levels, sampler, progress) for s in seeds]
    p, se = combine_runs([e.p for e in ests], [e.se for e in ests])
    cov = se / p
    levels = max(len(e.level_threshold) for e in ests)
    per_level = {name: np.array([np.pad(getattr(e, name), (0, levels - len(getattr(e, name))), constant_values=np.nan)
                                 for e in ests]) for name in ("level_threshold", "level_gamma")}
    attrs = {name: schema.attributes(name, schema.TAIL) for name in schema.TAIL}
    ds = xr.Dataset(
        {"p_overturn": ((), p[0], attrs["p_overturn"]), "p_overturn_se": ((), se[0], attrs["p_overturn_se"]),
         "p_overturn_cov": ((), cov[0], attrs["p_overturn_cov"]),
         "p_exceed": (("threshold",), p[1:], attrs["p_exceed"]),
         "p_exceed_se": (("threshold",), se[1:], attrs["p_exceed_se"]),
         "p_exceed_cov": (("threshold",), cov[1:], attrs["p_exceed_cov"]),
         "level_threshold": (("run", "level"), per_level["level_threshold"], attrs["level_threshold"]),
         "level_gamma": (("run", "level"), per_level["level_gamma"], attrs["level_gamma"])},
        coords={"threshold": ("threshold", rotations, attrs["threshold"])})
    ds.attrs.update(method="subset simulation (Au & Beck 2001) over the input phases", model=run.model.name,
                    sampler=sampler, n_per_level=n, runs=n_runs, p0=float(p0), seed=int(seed),
                    n_model_runs=int(sum(e.n_calls for e in ests)), n_diverged=int(sum(e.n_missing for e in ests)),
                    t_end=float(t_end), dt=float(dt))
    return ds
