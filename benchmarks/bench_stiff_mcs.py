"""Monte Carlo cost against bed stiffness, the two sample integrators, and the cost model, in one run.

Run (one core, under the shared lock; about 10 minutes on the loaded development machine):

    flock /work/bench.lock nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD \\
        .venv/bin/python benchmarks/bench_stiff_mcs.py [--samples 24] [--repeat 3]

Prints five tables:

0. **What sets the step.**  The statue block on beds k = 1e8 … 1e11 (below) at the default input band
   (3 x the larger of the rocking and vertical frequencies) and at the ground's band (an explicit cutoff
   at ``GROUND_BAND_LIMIT_HZ``, 25 Hz), and at the default band on a synthesis grid of oversampling 2
   instead of the default 4 (half the grid points the synthesis computes): CPU per sample split into
   synthesis and integration, steps, rejected steps, the mean accepted step times the vertical
   frequency ``h w_v`` against the explicit pair's stability bound on that mode
   (:func:`screening.kernels.dopri.stability_bound` at the mode's damping ratio), and the peak
   ``var_theta`` (how much of the answer comes from the input above the ground's band).
1. **Stiff beds.**  The 600 kg statue block (m = 600 kg, b = 0.2 m, h = 0.8 m) on Hunt–Crossley beds
   k = 1e8 … 1e11 N/m2 (lam = 30 k, eps = 0) under the statue's Kanai–Tajimi motion (S0 = 3e-3 m2/s3,
   heavy uplift): CPU per sample and steps per sample of the explicit pair (``integrator="dopri"``,
   the default) and of the linearly implicit RODAS pair (``integrator="rodas"``), each at the default
   ``rtol``; and their accuracy against a tight-tolerance run (``dopri``, ``rtol = 1e-10``) on the same
   samples: peak ``var_theta`` change in units of its standard error, and per-sample peak ``|theta|``
   errors (median and largest, relative).
2. **Paper block**, first a per-part profile of one step (compiled loops of 2 M calls: the cubic
   Hermite reading of the input, the coupled right-hand side in full contact and in uplift, ``sin`` and
   ``cos``), then (m = 8.67 kg, b = 0.035 m, h = 0.21 m, k = 2.89e7, lam = 8.95e8, eps = 6e7; white noise
   S0 = 2.4e-4): CPU seconds per 1000 samples of the coupled and condensed models, split into input
   synthesis and integration.
3. **Cost model** (:func:`screening.analysis.escalation.estimated_cost`): predicted / measured CPU for
   each calibration bed (``benchmarks/trust_calibration.py``'s families) and each run above, with the
   synthesis-grid term and with its steps term alone.

With ``--stiff-bed``, instead: **the stiff-bed model's cost model**
(:func:`screening.analysis.escalation.estimated_cost` with the run's
:func:`~screening.analysis.escalation.full_contact_share`) on the statue (k = 1e8, 1e10, 1e11) and the
cabinet's pads (``benchmarks/bench_stiff_bed_cost.py``'s beds) at ``STIFF_SCALES`` times each bed's
intensity (from no uplift to near toppling): steps, grid intervals and full-contact share per sample,
measured and predicted CPU and their ratio per run, the single-cost model's ratio beside it, and the
relative least-squares fit of the two stiff-bed constants (the grid term fixed).

CPU time is ``time.process_time`` of this process with one numba thread (JIT warm-up excluded); each
timed run is repeated ``--repeat`` times (default 3) and the median taken, which keeps the timing noise
of this shared machine (about 20 % between identical single runs) out of the cost-model ratios.
"""

from __future__ import annotations

import argparse
import os
import time

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import math  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

from screening.analysis import escalation as esc  # noqa: E402
from screening.analysis.intensity import GROUND_BAND_LIMIT_HZ, ground_cutoff  # noqa: E402
from screening.kernels._sample_steps import ground_input  # noqa: E402
from screening.kernels.dopri import stability_bound  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.model.excitation import Envelope  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.condensation import get as get_condensation  # noqa: E402
from screening.kernels import mcs_kernels as kern  # noqa: E402
from screening.solvers.mc_models import quasi_static_indentation  # noqa: E402
from screening.solvers.montecarlo import auto_rtol, monte_carlo, vertical_damping_ratio  # noqa: E402
from screening.solvers.synthesis import (OVERSAMPLING, default_cutoff, grid_points,  # noqa: E402
                                         spectral_plan, stationary_samples, vertical_frequency)
from screening.core.status import EscalationModel  # noqa: E402

ENVELOPE = Envelope(4.0, 2.0)
STATUE = Block(m=600.0, b=0.2, h=0.8)
STATUE_MOTION = KanaiTajimi(S0=3e-3, omega_g=15.6, zeta_g=0.6, envelope=ENVELOPE)
PAPER = Block(m=8.67, b=0.035, h=0.21)
PAPER_BED = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
PAPER_MOTION = WhiteNoise(S0=2.4e-4, envelope=ENVELOPE)
#: The beds of the calibration (benchmarks/trust_calibration.py), with a motion that uplifts each.
CALIBRATION = {
    "paper bed": (PAPER, PAPER_BED, PAPER_MOTION),
    "paper block, k=1e9": (PAPER, Foundation(k=1e9, lam=1e10, eps=0.0), WhiteNoise(S0=3e-5, envelope=ENVELOPE)),
    "paper block, k=1e10": (PAPER, Foundation(k=1e10, lam=3e11, eps=0.0),
                            KanaiTajimi(S0=1e-4, omega_g=10.0, zeta_g=0.4, envelope=ENVELOPE)),
    "statue, k=1e10": (STATUE, Foundation(k=1e10, lam=3e11, eps=0.0), STATUE_MOTION),
    "heavy, k=1e9": (Block(m=300.0, b=0.3, h=0.9), Foundation(k=1e9, lam=1e10, eps=0.0),
                     WhiteNoise(S0=4e-4, envelope=ENVELOPE)),
}
T_END = 20.0


SEED = [0]
REPEAT = [3]


def timed(block, foundation, excitation, n, repeat=None, **kw):
    """``(dataset, CPU seconds)`` of a Monte Carlo run: the median CPU time of ``repeat`` (default
    ``REPEAT``) identical runs."""
    cpu = []
    for _ in range(repeat or REPEAT[0]):
        t0 = time.process_time()
        ds = monte_carlo(block, foundation, excitation, n_samples=n, t_end=T_END, progress=False, seed=SEED[0], **kw)
        cpu.append(time.process_time() - t0)
    return ds, float(np.median(cpu))


def synthesis_cpu(block, foundation, excitation, n, cutoff=None, oversampling=OVERSAMPLING):
    """CPU seconds per sample of the input synthesis alone (FFT, modulation, rate), median of ``REPEAT``."""
    plan = spectral_plan(excitation, T_END, cutoff or default_cutoff(block, foundation), oversampling)
    q = excitation.envelope(plan.times)
    cpu = []
    for _ in range(REPEAT[0]):
        t0 = time.process_time()
        for lo in range(0, n, 64):
            acc, acc_dot = stationary_samples(plan, 0, np.arange(lo, min(lo + 64, n)))
            acc_dot *= q
            acc *= q
        cpu.append((time.process_time() - t0) / n)
    return float(np.median(cpu))


def rodas_run(ds):
    return ds.attrs["integrator"].startswith("adaptive Ros")


def predicted(ds, model, n, block, foundation, with_grid=True, oversampling=OVERSAMPLING):
    steps = int(ds["n_steps"].sum())
    grid = n * grid_points(T_END, ds.attrs["cutoff_rad_s"], oversampling) if with_grid else 0
    return esc.estimated_cost(steps, int(EscalationModel[model]), grid, rodas_run(ds), n)


def record(ratios, name, ds, model, n, block, foundation, cpu, calibration=False, oversampling=OVERSAMPLING):
    """One row of the cost-model table: predicted with and without the grid term, and the counts."""
    ratios.append(dict(name=name, pred=predicted(ds, model, n, block, foundation, oversampling=oversampling),
                       cpu=cpu, old=predicted(ds, model, n, block, foundation, with_grid=False),
                       steps=float(ds["n_steps"].sum()),
                       grid=float(n * grid_points(T_END, ds.attrs["cutoff_rad_s"], oversampling)),
                       model=model, rodas=rodas_run(ds), calibration=calibration, samples=n))


def rejected_fraction(ds):
    """Rejected / all steps of the samples that neither overturned nor diverged."""
    used = ~(ds.overturned.values | ds.diverged.values)
    accepted = T_END / ds.attrs["dt_integration_mean"]
    return 1.0 - accepted / float(ds.n_steps.values[used].mean())


def step_table(n, ratios):
    """Table 0: steps, rejections and ``h w_v`` at the default band and at the ground's band."""
    band = ground_cutoff(GROUND_BAND_LIMIT_HZ)
    print(f"\n== 0. what sets the step: statue block, lam = 30 k; {n} samples x {T_END:g} s; default rtol; "
          f"default band (3 x max(w_r, w_v)) against the ground's band {GROUND_BAND_LIMIT_HZ:g} Hz "
          f"(cutoff {band:.0f} rad/s)")
    print("| k [N/m2] | w_v [rad/s] | band [rad/s] | oversampling | integrator | synthesis ms/sample "
          "| integration ms/sample | steps | rejected | h w_v | DOPRI bound on h w_v | peak var_theta |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k in (1e8, 1e9, 1e10, 1e11):
        bed = Foundation(k=k, lam=30.0 * k, eps=0.0)
        w_v = vertical_frequency(STATUE, bed)
        bound = stability_bound(vertical_damping_ratio(STATUE, bed))
        default = default_cutoff(STATUE, bed)
        for cutoff, oversampling, integrators in ((default, OVERSAMPLING, ("dopri",)), (default, 2, ("dopri",)),
                                                  (band, OVERSAMPLING, ("dopri", "rodas"))):
            synth = synthesis_cpu(STATUE, bed, STATUE_MOTION, n, cutoff, oversampling)
            for integrator in integrators:
                ds, c = timed(STATUE, bed, STATUE_MOTION, n, integrator=integrator, cutoff=cutoff,
                              oversampling=oversampling)
                record(ratios, f"statue k={k:g} {integrator} band {cutoff:.0f} x{oversampling}", ds, "coupled", n,
                       STATUE, bed, c, oversampling=oversampling)
                h = ds.attrs["dt_integration_mean"]
                print(f"| {k:.0e} | {w_v:,.0f} | {cutoff:,.0f} | {oversampling} | {integrator} | {1e3 * synth:.2f} "
                      f"| {1e3 * (c / n - synth):.2f} | {float(ds.n_steps.mean()):,.0f} | {rejected_fraction(ds):.1%} "
                      f"| {h * w_v:.2f} | {bound:.2f} | {float(np.nanmax(ds.var_theta)):.3e} |", flush=True)


def peak_var(ds):
    i = int(np.nanargmax(ds.var_theta.values))
    return float(ds.var_theta[i]), float(ds.var_theta_se[i])


def stiff_table(n, ratios):
    print(f"\n== 1. statue block, lam = 30 k, Kanai-Tajimi S0 = {STATUE_MOTION.S0:g}; {n} samples x {T_END:g} s; "
          f"default rtol (auto) {auto_rtol('coupled', n):g}; reference: dopri rtol 1e-10")
    print("| k [N/m2] | dopri ms/sample | dopri steps | rodas ms/sample | rodas steps | rodas/dopri CPU "
          "| cost vs k=1e8 (dopri) | dopri: d peak var / SE | dopri: sample peak err med / max "
          "| rodas: d peak var / SE | rodas: sample peak err med / max |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    base = None
    for k in (1e8, 1e9, 1e10, 1e11):
        bed = Foundation(k=k, lam=30.0 * k, eps=0.0)
        ref, _ = timed(STATUE, bed, STATUE_MOTION, n, repeat=1, rtol=1e-10)
        ref_v, ref_se = peak_var(ref)
        row, cpu = [], {}
        for integrator in ("dopri", "rodas"):
            ds, c = timed(STATUE, bed, STATUE_MOTION, n, integrator=integrator)
            cpu[integrator] = c
            record(ratios, f"statue k={k:g} {integrator}", ds, "coupled", n, STATUE, bed, c)
            v, _ = peak_var(ds)
            err = np.abs(ds.peak_abs_theta.values / ref.peak_abs_theta.values - 1.0)
            row.append((1e3 * c / n, float(ds.n_steps.mean()), (v - ref_v) / ref_se, np.nanmedian(err),
                        np.nanmax(err)))
        base = base or row[0][0]
        (dm, ds_, dv, de, dx), (rm, rs, rv, re_, rx) = row
        print(f"| {k:.0e} | {dm:.1f} | {ds_:,.0f} | {rm:.1f} | {rs:,.0f} | {cpu['rodas'] / cpu['dopri']:.1f} "
              f"| {dm / base:.1f} | {dv:+.2f} | {de:.1e} / {dx:.1e} | {rv:+.2f} | {re_:.1e} / {rx:.1e} |", flush=True)


@numba.njit(cache=True)
def _loop_hermite(acc, acc_dot, dt, n):
    total = 0.0
    t_span = dt * (acc.shape[1] - 1)
    t = 0.0
    for _ in range(n):                   # marching through the record, as the stages do
        t += 0.37 * dt
        if t >= t_span:
            t -= t_span
        total += ground_input(0, acc, acc_dot, dt, t)
    return total


@numba.njit(cache=True)
def _loop_rhs(models, theta, z_cb, n):
    total = 0.0
    for i in range(n):
        a1, a3 = kern.coupled_accelerations(theta * (1.0 + 1e-9 * i), 0.01, z_cb, 1e-4, 0.5, models[0])
        total += a1 + a3
    return total


@numba.njit(cache=True)
def _loop_trig(theta, n):
    total = 0.0
    for i in range(n):
        x = theta * (1.0 + 1e-9 * i)
        total += math.sin(x) + math.cos(x)
    return total


def per_call_ns(fn, *args, n=2_000_000):
    """CPU nanoseconds per iteration of a compiled loop of ``n`` calls (median of ``REPEAT``; compiled first)."""
    fn(*args, 10)
    cpu = []
    for _ in range(REPEAT[0]):
        t0 = time.process_time()
        fn(*args, n)
        cpu.append(time.process_time() - t0)
    return 1e9 * float(np.median(cpu)) / n


def profile_table():
    """Per-part cost of one evaluation of the coupled right-hand side on the paper block."""
    plan = spectral_plan(PAPER_MOTION, T_END, default_cutoff(PAPER, PAPER_BED))
    acc, acc_dot = stationary_samples(plan, 0, np.arange(1))
    models = kern.model_record(PAPER, PAPER_BED, get_condensation("paper"))[None]
    theta_ul = float(models[0]["theta_ul"])
    contact = (0.3 * theta_ul, quasi_static_indentation(PAPER, PAPER_BED, 0.3 * theta_ul))
    uplift = (3.0 * theta_ul, quasi_static_indentation(PAPER, PAPER_BED, 3.0 * theta_ul))
    parts = {"cubic Hermite input": per_call_ns(_loop_hermite, acc, acc_dot, plan.dt),
             "coupled right-hand side, full contact (sin, cos, resultants, equations)":
                 per_call_ns(_loop_rhs, models, *contact),
             "coupled right-hand side, uplift": per_call_ns(_loop_rhs, models, *uplift),
             "of which sin + cos": per_call_ns(_loop_trig, contact[0])}
    print("\n== 2a. per-part profile (paper block; ns per call, compiled loops of 2 M calls)")
    print("| part | ns |")
    print("|---|---|")
    for name, ns in parts.items():
        print(f"| {name} | {ns:.1f} |")
    return parts


def paper_table(n, ratios):
    print(f"\n== 2. paper block on the paper bed (eps = 6e7), white noise S0 = {PAPER_MOTION.S0:g}; {n} samples; "
          f"CPU s per 1000 samples x {T_END:g} s")
    print("| model | integrator | CPU s / 1000 | synthesis s / 1000 | integration s / 1000 | steps/sample "
          "| us / step | peak var_theta (SE) |")
    print("|---|---|---|---|---|---|---|---|")
    synth = synthesis_cpu(PAPER, PAPER_BED, PAPER_MOTION, n)
    for model in ("coupled", "condensed"):
        for integrator in ("dopri", "rodas"):
            ds, c = timed(PAPER, PAPER_BED, PAPER_MOTION, n, model=model, integrator=integrator)
            record(ratios, f"paper bed {model} {integrator}", ds, model, n, PAPER, PAPER_BED, c)
            steps = float(ds.n_steps.mean())
            v, se = peak_var(ds)
            per = 1e3 * c / n
            print(f"| {model} | {integrator} | {per:.2f} | {1e3 * synth:.2f} | {per - 1e3 * synth:.2f} | {steps:,.0f} "
                  f"| {1e6 * (c / n - synth) / steps:.3f} | {v:.4e} ({se:.1e}) |", flush=True)


def calibration_table(n, ratios):
    for name, (block, bed, motion) in CALIBRATION.items():
        for model in ("coupled", "condensed"):
            ds, c = timed(block, bed, motion, n, model=model)
            record(ratios, f"calibration: {name} {model}", ds, model, n, block, bed, c, calibration=True)
    print(f"\n== 3. cost model: STEP_COST_S {dict((m.name, v) for m, v in esc.STEP_COST_S.items())}, "
          f"RODAS_STEP_FACTOR {esc.RODAS_STEP_FACTOR:g}, GRID_COST_S {esc.GRID_COST_S:g} s "
          f"+ GRID_DOUBLING_COST_S {esc.GRID_DOUBLING_COST_S:g} s per doubling of {esc.GRID_REFERENCE_POINTS} points")
    print("| run | steps | grid points | measured CPU s | predicted s | measured / predicted "
          "| measured / steps term alone |")
    print("|---|---|---|---|---|---|---|")
    for r in ratios:
        print(f"| {r['name']} | {r['steps']:.3g} | {r['grid']:.3g} | {r['cpu']:.2f} | {r['pred']:.2f} "
              f"| {r['cpu'] / r['pred']:.2f} | {r['cpu'] / r['old']:.2f} |")
    for label, rows in (("all runs", ratios), ("calibration beds", [r for r in ratios if r["calibration"]])):
        ratio = np.array([r["cpu"] / r["pred"] for r in rows])
        print(f"measured / predicted, {label}: {ratio.min():.2f} .. {ratio.max():.2f} over {ratio.size} runs "
              f"({np.sum(np.abs(ratio - 1) <= 0.25)} within +-25 %)")
    # least squares on the relative error: cpu = a_coupled steps_c + a_condensed steps_k
    #   + grid (g + g2 log2(grid per sample / reference)), RODAS steps x RODAS_STEP_FACTOR
    f = esc.RODAS_STEP_FACTOR
    x = np.array([[r["steps"] * (r["model"] == "coupled") * (f if r["rodas"] else 1.0),
                   r["steps"] * (r["model"] == "condensed") * (f if r["rodas"] else 1.0), r["grid"],
                   r["grid"] * np.log2(r["grid"] / r["samples"] / esc.GRID_REFERENCE_POINTS)] for r in ratios])
    y = np.array([r["cpu"] for r in ratios])
    coef, *_ = np.linalg.lstsq(x / y[:, None], np.ones_like(y), rcond=None)
    print(f"relative least-squares fit (RODAS step = {f:g} explicit steps): coupled {coef[0]:.3g} s/step, "
          f"condensed {coef[1]:.3g} s/step, grid {coef[2]:.3g} s/point + {coef[3]:.3g} s/point per doubling")


#: Multiples of each bed's intensity (bench_stiff_bed_cost.beds) in the stiff-bed table: no uplift to near toppling.
STIFF_SCALES = (0.003, 0.03, 0.1, 0.3, 1.0, 3.0)


def stiff_bed_cost_table(n_samples, sampler="stiff_bed"):
    """The stiff-bed model's cost model against measured CPU over intensity (module docstring), for the
    reference kernel (``sampler="stiff_bed"``) or the exact-contact sampler (``"stiff_bed_fast"``: the
    constants ``FAST_*``, and the grid term fitted too, its synthesis being the batched real FFT)."""
    import warnings

    from bench_stiff_bed_cost import beds

    from screening.solvers import stiff_bed

    rows = []
    fast = sampler == "stiff_bed_fast"
    print(f"\n== stiff-bed cost model ({sampler}): {n_samples} samples x {T_END:g} s per run "
          f"(and {max(n_samples // 8, 1)} at two intensities), output dt 0.05 s, seed {SEED[0]}, "
          f"median CPU of {REPEAT[0]}; STIFF_BED_EXACT_COST_S "
          f"{esc.STIFF_BED_EXACT_COST_S:g} s, STIFF_BED_ADAPTIVE_COST_S {esc.STIFF_BED_ADAPTIVE_COST_S:g} s, "
          f"STIFF_BED_RUN_COST_S {esc.STIFF_BED_RUN_COST_S:g} s, grid term of the coupled model; exact-contact "
          f"sampler: {esc.FAST_COSTS_S}")
    print("| bed | S0 [m2/s3] | samples | steps/sample | grid intervals/sample | full-contact share | overturned "
          "| measured ms/sample | predicted ms/sample | measured / predicted | single cost: measured / predicted |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                   # validity warnings: not the subject here
        t0 = time.perf_counter()
        _, block, bed, s0 = beds()[0]
        monte_carlo(block, bed, KanaiTajimi(S0=s0, omega_g=15.6, zeta_g=0.6, envelope=ENVELOPE), n_samples=2,
                    t_end=0.2, model=sampler, progress=False)
        print(f"numba threads {numba.get_num_threads()}; JIT warm-up {time.perf_counter() - t0:.1f} s")
        for label, block, bed, s0 in beds():
            stiff_bed.transfer_table(block, bed)           # once per bed, as a worker's cache does
            for scale, n in [(s, n_samples) for s in STIFF_SCALES] + [(STIFF_SCALES[0], max(n_samples // 8, 1)),
                                                                         (STIFF_SCALES[-2], max(n_samples // 8, 1))]:
                motion = KanaiTajimi(S0=s0 * scale, omega_g=15.6, zeta_g=0.6, envelope=ENVELOPE)
                ds, cpu = timed(block, bed, motion, n, model=sampler, dt=0.05)
                steps, grid = float(ds["n_steps"].sum()), float(n * int(ds.attrs["input_grid_points"]))
                n_used = n - int(ds["n_overturned"]) - int(ds["n_diverged"])
                share = esc.full_contact_share(ds["p_uplift"].values, n_used, n)
                code = int(EscalationModel.stiff_bed)
                pred = esc.estimated_cost(steps, code, grid, False, n, full_contact=share, exact=fast)
                single = esc.estimated_cost(steps, code, grid, False, n)
                rows.append(dict(steps=steps, grid=grid, share=share, cpu=cpu, n=n, runs=1.0,
                                 synth=grid * esc.grid_point_cost(grid / n)))
                print(f"| {label} | {s0 * scale:.3g} | {n} | {steps / n:,.0f} | {grid / n - 1:,.0f} | {share:.3f} "
                      f"| {int(ds['n_overturned'])} | {1e3 * cpu / n:.2f} | {1e3 * pred / n:.2f} | {cpu / pred:.2f} "
                      f"| {cpu / single:.2f} |", flush=True)
    ratio = np.array([r["cpu"] for r in rows]) / np.array(
        [esc.estimated_cost(r["steps"], int(EscalationModel.stiff_bed), r["grid"], False, r["n"],
                            full_contact=r["share"], exact=fast) for r in rows])
    print(f"measured / predicted: {ratio.min():.2f} .. {ratio.max():.2f} over {ratio.size} runs "
          f"({np.sum(np.abs(ratio - 1) <= 0.25)} within +-25 %)")
    exact = np.array([min(r["share"] * (r["grid"] - r["n"]), r["steps"]) for r in rows])
    cpu = np.array([r["cpu"] for r in rows])
    cols = [exact, np.array([r["steps"] for r in rows]) - exact, np.ones(len(rows))]
    if fast:                                  # its own synthesis: the grid term is fitted too
        cols.append(np.array([r["grid"] for r in rows]))
        y = cpu
    else:
        y = cpu - np.array([r["synth"] for r in rows])
    x = np.c_[tuple(cols)]
    coef, *_ = np.linalg.lstsq(x / cpu[:, None], y / cpu, rcond=None)
    print(f"relative least-squares fit{'' if fast else ' (grid term fixed)'}: exact interval {coef[0]:.3g} s, "
          f"adaptive step {coef[1]:.3g} s, run {coef[2]:.3g} s" + (f", grid point {coef[3]:.3g} s" if fast else ""))
    fitted = x @ coef
    print(f"with the fit: measured / predicted {np.min(cpu / fitted):.2f} .. {np.max(cpu / fitted):.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=24, help="samples per run (the stiff-bed table)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cost-only", action="store_true", help="only the calibration beds of the cost model")
    ap.add_argument("--stiff-bed", action="store_true", help="only the stiff-bed model's cost model over intensity")
    ap.add_argument("--repeat", type=int, default=3, help="identical runs per timing (the median is taken)")
    ap.add_argument("--sampler", default="stiff_bed", choices=("stiff_bed", "stiff_bed_fast"),
                    help="with --stiff-bed: the reference kernel or the exact-contact sampler")
    args = ap.parse_args()
    SEED[0] = args.seed
    REPEAT[0] = args.repeat
    import numba

    if args.stiff_bed:
        stiff_bed_cost_table(args.samples, args.sampler)
        return
    t0 = time.perf_counter()
    for integrator in ("dopri", "rodas"):
        for model in ("coupled", "condensed"):
            monte_carlo(PAPER, PAPER_BED, PAPER_MOTION, n_samples=2, t_end=0.2, model=model, integrator=integrator,
                        progress=False)
    print(f"numba threads {numba.get_num_threads()}; JIT warm-up {time.perf_counter() - t0:.1f} s")
    ratios = []
    if not args.cost_only:
        step_table(args.samples, ratios)
        stiff_table(args.samples, ratios)
        profile_table()
        paper_table(4 * args.samples, ratios)
    calibration_table(args.samples, ratios)


if __name__ == "__main__":
    main()
