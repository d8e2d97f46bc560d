"""Does the linearized system make a useful control variate for coupled Monte Carlo? (issue #14, point 5)

Run::

    nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/control_variate.py [--samples 200]

For each point, every input sample ``a_i(t) = q(t) f_i(t)`` (the same synthesis as
:func:`screening.monte_carlo`: :func:`screening.solvers.synthesis.stationary_samples`, seed 0) drives

* the coupled model (:func:`screening.simulate`): ``X_i = theta_i(t*)^2``;
* the linearized system ``theta'' + c_eq(t)/M theta' + k_eq(t)/M theta = (m h / M) a_i(t)`` with the
  coefficients of the stochastic linearization at the point (classical RK4 on the input grid):
  ``Y_i = theta_lin,i(t*)^2``, whose mean is known: SL's ``var_theta(t*)``;

at ``t*`` the time of SL's peak variance.  The control-variate estimate of ``var_theta(t*)`` is
``mean(X) - beta (mean(Y) - var_SL(t*))``, ``beta = cov(X, Y) / var(Y)``; its variance is the plain one
times ``1 - rho^2`` (``rho = corr(X, Y)``), so the samples needed for a given standard error fall by
the factor ``1 / (1 - rho^2)``.  Printed per point: ``rho``, that factor, both estimates with their
standard errors, and the check ``mean(Y)`` against SL (the linear simulation is right if they agree
within its standard error).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi  # noqa: E402
from screening.core.excitations.white import WhiteNoise
from screening.analysis.linearization import linearize  # noqa: E402
from screening.solvers.simulate import simulate  # noqa: E402
from screening.solvers.synthesis import default_cutoff, spectral_plan, stationary_samples  # noqa: E402

PAPER = dict(m=8.67, b=0.035, h=0.21)
#: (name, block, bed, excitation): calibration points of the trust rule, low to high uplift.
POINTS = (
    ("paper_0_white_p0.1", PAPER, dict(k=2.89e7, lam=8.95e8, eps=0.0), WhiteNoise(4.45e-5)),
    ("paper_h_white_p0.15", PAPER, dict(k=2.89e7, lam=8.95e8, eps=6e7), WhiteNoise(8.01e-5)),
    ("paper_0_white_p0.5", PAPER, dict(k=2.89e7, lam=8.95e8, eps=0.0), WhiteNoise(1.83e-4)),
    ("paper_s_kt10_p0.3", PAPER, dict(k=2.89e7, lam=8.95e8, eps=-6e5), KanaiTajimi(1.1e-3, 10.0, 0.4)),
)
T_END, DT = 20.0, 0.05


def linear_response(times, acc, t_sl, c_eq, k_eq, m_sdof, gain, t_out):
    """theta of the linear time-varying oscillator for each row of ``acc`` (RK4 on ``times``), at ``t_out``."""
    dt = times[1] - times[0]
    c = np.interp(times, t_sl, c_eq) / m_sdof
    k = np.interp(times, t_sl, k_eq) / m_sdof
    c_half = np.interp(times + dt / 2, t_sl, c_eq) / m_sdof
    k_half = np.interp(times + dt / 2, t_sl, k_eq) / m_sdof
    f = gain * acc
    f_half = 0.5 * (f[:, :-1] + f[:, 1:])
    th = np.zeros(acc.shape[0])
    om = np.zeros(acc.shape[0])
    out = np.empty((acc.shape[0], times.size))
    out[:, 0] = 0.0
    for j in range(times.size - 1):
        def rhs(t_c, t_k, force, x, v):
            return v, force - t_c * v - t_k * x
        k1 = rhs(c[j], k[j], f[:, j], th, om)
        k2 = rhs(c_half[j], k_half[j], f_half[:, j], th + dt / 2 * k1[0], om + dt / 2 * k1[1])
        k3 = rhs(c_half[j], k_half[j], f_half[:, j], th + dt / 2 * k2[0], om + dt / 2 * k2[1])
        k4 = rhs(c[j + 1], k[j + 1], f[:, j + 1], th + dt * k3[0], om + dt * k3[1])
        th = th + dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        om = om + dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        out[:, j + 1] = th
    return np.array([np.interp(t_out, times, row) for row in out])


def one_point(name, block_kw, bed_kw, excitation, samples, seed=0):
    block, foundation = Block(**block_kw), Foundation(**bed_kw)
    sl = linearize(block, foundation, excitation, t_end=T_END, dt=DT)
    i_peak = int(np.nanargmax(sl["var_theta"].values))
    t_star = float(sl["t"].values[i_peak])
    var_sl = float(sl["var_theta"].values[i_peak])
    plan = spectral_plan(excitation, T_END, default_cutoff(block, foundation))
    acc, _ = stationary_samples(plan, seed, np.arange(samples))
    acc *= np.asarray(excitation.envelope(plan.times), dtype=float)
    start = time.perf_counter()
    x = np.full(samples, np.nan)
    for i in range(samples):
        run = simulate(block, foundation, acc[i], dt=plan.dt, model="coupled", t_end=T_END, output_dt=DT)
        if not (bool(run["overturned"]) or bool(run["diverged"])):
            x[i] = float(run["theta"].values[i_peak]) ** 2
    t_coupled = time.perf_counter() - start
    start = time.perf_counter()
    y = linear_response(plan.times, acc, sl["t"].values, sl["c_eq"].values, sl["k_eq"].values, float(block.m_sdof),
                        float(block.m * block.h / block.m_sdof), np.array([t_star]))[:, 0] ** 2
    t_linear = time.perf_counter() - start
    ok = np.isfinite(x)
    x, y = x[ok], y[ok]
    n = x.size
    rho = float(np.corrcoef(x, y)[0, 1])
    beta = float(np.cov(x, y)[0, 1] / np.var(y, ddof=1))
    plain, plain_se = x.mean(), x.std(ddof=1) / np.sqrt(n)
    resid = x - beta * (y - var_sl)
    cv, cv_se = resid.mean(), resid.std(ddof=1) / np.sqrt(n)
    return dict(name=name, n=n, t_star=t_star, rho=rho, factor=1 / (1 - rho ** 2), plain=plain, plain_se=plain_se,
                cv=cv, cv_se=cv_se, y_mean=y.mean(), y_se=y.std(ddof=1) / np.sqrt(n), var_sl=var_sl,
                t_coupled=t_coupled, t_linear=t_linear)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=200)
    args = ap.parse_args(argv)
    print(f"{'point':22s} {'n':>4s} {'t*':>5s} {'rho':>6s} {'1/(1-rho2)':>10s} {'plain var':>10s} {'SE':>6s} "
          f"{'CV var':>10s} {'SE':>6s} {'lin mean/SL':>11s} {'coupled s':>9s} {'linear s':>8s}")
    for point in POINTS:
        r = one_point(*point, samples=args.samples)
        print(f"{r['name']:22s} {r['n']:4d} {r['t_star']:5.2f} {r['rho']:6.3f} {r['factor']:10.2f} "
              f"{r['plain']:10.3e} {r['plain_se'] / r['plain']:6.1%} {r['cv']:10.3e} {r['cv_se'] / r['cv']:6.1%} "
              f"{r['y_mean'] / r['var_sl']:6.3f}+-{r['y_se'] / r['var_sl']:.3f} {r['t_coupled']:9.1f} "
              f"{r['t_linear']:8.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
