"""Cost of the stiff-bed Monte Carlo model against the coupled model, before and after its cheaper numerics.

Per bed (the statue on k = 1e8, 1e10 and 1e11, the cabinet on its hardening pads) and on the same samples
(same seed, same synthesis), one run each of:

* ``coupled``: the coupled model at its defaults (the judge);
* ``auto``: ``model = "auto"`` (the stiff-bed model on these beds: the name that ran is printed);
* ``stiff_bed first``: the stiff-bed model's first kernel (``StiffBedModel(locate=False)``, ``rtol = 1e-7``,
  ``h_max = 5 ms``: the transfer applied at the end of the step that crossed zero);
* ``stiff_bed 5 ms``: the defaults of 2026-11-25 (the transfer located at the crossing, ``rtol = 1e-5``,
  ``h_max = 5 ms``, the largest step of every model then);
* ``stiff_bed after``: the stiff-bed model at its defaults (as ``5 ms`` with the model's own largest step,
  ``StiffBedModel.default_h_max = 10 ms``);
* ``stiff_bed reference``: the located kernel at ``rtol = 1e-9``, ``h_max = 5 ms`` (the model's converged
  statistics).

It prints the CPU time per sample (synthesis and integration, one numba thread: the script sets
``NUMBA_NUM_THREADS=1`` unless it is set), the coupled / model cost ratio, and two accuracy checks:

* against the coupled model, the tolerances of the scene: ``P(|theta| > a atan(b/h))`` for
  ``a = 0.05, 0.1, 0.3, 0.5`` and ``P(overturn)`` within ``max(0.03, 2.5 SE)`` (SE the paired standard
  error of the difference), peak var_theta within 15 % where no coupled sample overturns;
* against the reference: the largest ``|dP| / SE`` over those five probabilities (SE the binomial standard
  error of the estimate, ``sqrt(p (1 - p) / n)``), the same in units of the paired standard error of the
  difference (the sample paths of this model are sensitive at every tolerance, so the paired error is as
  large as the sampling error: see docs/stiff_bed.md, "Numerics"), and the relative difference of the
  peak var_theta with its standard error.

Run (about 10 minutes at 300 samples on an idle core)::

    flock /work/bench.lock nice -n 10 env PYTHONPATH=. python benchmarks/bench_stiff_bed_cost.py --samples 300

``--profile`` prints instead where one sample's time goes on the statue's k = 1e10 bed (``--only`` another) at
the defaults and at ``h_max = 5 ms``: CPU
per sample of the synthesis of the low-passed samples (with their modulation) against the whole run, and the
kernel's steps per sample by phase (``stiff_bed_kernels.COUNT_ROWS``, counted by the kernel itself)::

    flock /work/bench.lock nice -n 10 env PYTHONPATH=. python benchmarks/bench_stiff_bed_cost.py --profile --samples 200
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.analysis.beds import lam_from_vertical_damping  # noqa: E402
from screening.core.model import Block, Foundation  # noqa: E402
from screening.core.excitations.kanai_tajimi import KanaiTajimi  # noqa: E402
from screening.solvers import stiff_bed  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402
from screening.kernels.stiff_bed_kernels import COUNT_ROWS  # noqa: E402
from screening.solvers.synthesis import (default_cutoff, envelope_rate, low_passed, spectral_plan,  # noqa: E402
                                         stationary_samples)

FRACTIONS = (0.05, 0.1, 0.3, 0.5)
FILTER = dict(omega_g=15.6, zeta_g=0.6)          # Kanai-Tajimi ground filter of the calibration's statue
BEFORE_RTOL = 1e-7
REFERENCE_RTOL = 1e-9
BEFORE_H_MAX = 0.005


def _bed(block, k, eps=0.0, zeta_v=0.05):
    return Foundation(k=k, eps=eps, lam=float(lam_from_vertical_damping(k, block.m, block.b, zeta_v)))


def beds():
    """``(label, block, bed, S0 [m2/s3])``: the beds and intensities of benchmarks/stiff_bed_validity.py."""
    statue, cabinet = Block(m=1200.0, b=0.25, h=0.9), Block(m=400.0, b=0.3, h=1.0)
    return [("statue k=1e8", statue, _bed(statue, 1e8), 0.01),
            ("statue k=1e10", statue, _bed(statue, 1e10), 0.015),
            ("statue k=1e11", statue, _bed(statue, 1e11), 0.015),
            ("cabinet pads k=2.1e9 eps=2e9", cabinet, _bed(cabinet, 2.1e9, eps=2e9), 0.02)]


def indicators(ds, slenderness):
    """``(5, n)`` 0/1 array: peak ``|theta|`` above each fraction of the slenderness (overturned samples
    count), then overturned."""
    peak, over = ds.peak_abs_theta.values, ds.overturned.values
    return np.array([(peak > a * slenderness) | over for a in FRACTIONS] + [over], dtype=float)


def peak_var(ds):
    """``(peak var_theta [rad2], its standard error)``."""
    i = int(np.nanargmax(ds.var_theta.values))
    return float(ds.var_theta.values[i]), float(ds.var_theta_se.values[i])


def paired_se(x, y):
    """Standard error of the mean of the paired differences ``x - y`` (rows: probabilities)."""
    d = np.asarray(x, float) - np.asarray(y, float)
    return np.std(d, axis=-1, ddof=1) / np.sqrt(d.shape[-1])


def against_coupled(ind, ref_ind, var, ref_var, coupled_overturned):
    """``(text, ok)``: the scene's tolerances against the coupled model (module docstring)."""
    diff = np.abs(ind.mean(1) - ref_ind.mean(1))
    tol = np.maximum(0.03, 2.5 * paired_se(ind, ref_ind))
    worst = int(np.argmax(diff / tol))
    ok = bool(np.all(diff <= tol))
    text = f"{diff[worst]:.3f} / {tol[worst]:.3f}"
    if coupled_overturned == 0:
        rel = var / ref_var - 1.0
        ok = ok and abs(rel) <= 0.15
        text += f", var {rel:+.0%}"
    return text + (" ok" if ok else " FAILS"), ok


def against_reference(ind, ref_ind, var, ref_var, var_se):
    """``|dP| / SE`` (binomial, worst of five), ``|dP| / paired SE`` (worst) and the peak var_theta's
    relative difference with its standard error in units of the reference's."""
    p, q = ind.mean(1), ref_ind.mean(1)
    n = ref_ind.shape[1]
    se = np.sqrt(np.maximum(q * (1.0 - q), 1.0 / n) / n)
    pse = np.maximum(paired_se(ind, ref_ind), 1.0 / n)
    d = np.abs(p - q)
    return (f"{np.max(d / se):.2f} | {np.max(d / pse):.2f} | {var / ref_var - 1.0:+.1%} "
            f"({abs(var - ref_var) / var_se:.1f} SE)")


def run_bed(label, block, bed, S0, samples, seed):
    excitation = KanaiTajimi(S0, FILTER["omega_g"], FILTER["zeta_g"])
    stiff_bed.transfer_table(block, bed)                       # once per bed, outside the timings
    alpha = float(block.slenderness)
    kw = dict(n_samples=samples, seed=seed, progress=False, t_end=20.0)
    runs = [("coupled", "coupled", {}), ("auto", "auto", {}),
            ("stiff_bed first", stiff_bed.StiffBedModel(locate=False), {"rtol": BEFORE_RTOL, "h_max": BEFORE_H_MAX}),
            ("stiff_bed 5 ms", stiff_bed.StiffBedModel(), {"h_max": BEFORE_H_MAX}),
            ("stiff_bed after", stiff_bed.StiffBedModel(), {}),
            ("stiff_bed reference", stiff_bed.StiffBedModel(), {"rtol": REFERENCE_RTOL, "h_max": BEFORE_H_MAX})]
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                        # validity warnings: not the subject here
        for name, model, extra in runs:
            start = time.process_time()
            ds = monte_carlo(block, bed, excitation, model=model, **kw, **extra)
            cpu = (time.process_time() - start) / samples
            out[name] = dict(ind=indicators(ds, alpha), var=peak_var(ds), cpu=cpu, model=ds.attrs["model"],
                             steps=float(ds.n_steps.mean()), over=int(ds.overturned.sum()))
    lines = []
    c = out["coupled"]
    r = out["stiff_bed reference"]
    for name, m in out.items():
        p = m["ind"].mean(1)
        cells = [label, f"{name} ({m['model']})" if name == "auto" else name,
                 " ".join(f"{x:.3f}" for x in p), f"{m['var'][0]:.3g}", f"{1e3 * m['cpu']:.2f}",
                 f"{m['steps']:.0f}", f"{c['cpu'] / m['cpu']:.1f}"]
        cells.append("" if name == "coupled" else against_coupled(m["ind"], c["ind"], m["var"][0], c["var"][0],
                                                                  c["over"])[0])
        cells.append(" | | " if name in ("coupled", "stiff_bed reference")
                     else against_reference(m["ind"], r["ind"], m["var"][0], r["var"][0], r["var"][1]))
        lines.append("| " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)
    return lines


class _Counting(stiff_bed.StiffBedModel):
    """The stiff-bed model whose integrators count their steps by phase (``step_counts``)."""

    def integrator(self, *args, **kwargs):
        integrate = super().integrator(*args, **kwargs)
        integrate.step_counts = np.zeros((len(COUNT_ROWS), 2), dtype=np.int64)
        self.last = integrate
        return integrate


def synthesis_cpu(block, bed, excitation, model, samples, seed, chunk=64):
    """CPU seconds per sample [s] of synthesizing and modulating the samples ``model`` reads, as
    ``monte_carlo`` does (same plan, same chunks)."""
    plan = spectral_plan(excitation, 20.0, default_cutoff(block, bed))
    low = low_passed(plan, model.input_band(block, bed))[0]
    q, q_dot = excitation.envelope(low.times), envelope_rate(excitation.envelope, low.times)
    start = time.process_time()
    for lo in range(0, samples, chunk):
        acc, acc_dot = stationary_samples(low, seed, np.arange(lo, min(lo + chunk, samples)))
        acc_dot *= q
        acc_dot += q_dot * acc
        acc *= q
    return (time.process_time() - start) / samples, low


def profile(samples, seed, only="statue k=1e10"):
    """Print where one sample's time goes (module docstring, ``--profile``) on the first bed whose label
    contains ``only``."""
    label, block, bed, S0 = next(b for b in beds() if only in b[0])
    excitation = KanaiTajimi(S0, FILTER["omega_g"], FILTER["zeta_g"])
    stiff_bed.transfer_table(block, bed)
    kw = dict(n_samples=samples, seed=seed, progress=False, t_end=20.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = time.process_time()
        ds = monte_carlo(block, bed, excitation, model=stiff_bed.StiffBedModel(), **kw)
        total = (time.process_time() - start) / samples
        counting = _Counting()
        monte_carlo(block, bed, excitation, model=counting, **kw)
        capped = _Counting()
        monte_carlo(block, bed, excitation, model=capped, h_max=BEFORE_H_MAX, **kw)
    synth, low = synthesis_cpu(block, bed, excitation, stiff_bed.StiffBedModel(), samples, seed)
    counts = counting.last.step_counts / samples
    before = capped.last.step_counts / samples
    print(f"{label}, Kanai-Tajimi S0 = {S0} m2/s3, {samples} samples, seed {seed}, defaults "
          f"(rtol {stiff_bed.StiffBedModel.default_rtol:g}, h_max {stiff_bed.StiffBedModel.default_h_max:g} s)")
    print(f"CPU per sample: {1e3 * total:.2f} ms, of which synthesis of the low-passed samples {1e3 * synth:.2f} ms "
          f"({low.n_fft}-point FFT, {low.n_frequencies} components, grid {1e3 * low.dt:.3f} ms) and the rest "
          f"{1e3 * (total - synth):.2f} ms (kernel and bookkeeping); {float(ds.n_steps.mean()):.0f} steps per sample")
    print(f"| phase | accepted per sample | rejected per sample | at h_max = {BEFORE_H_MAX:g} s: accepted | rejected |"
          "\n|---|---|---|---|---|")
    for name, (acc, rej), (acc5, rej5) in zip(COUNT_ROWS, counts, before):
        print(f"| {name} | {acc:.0f} | {rej:.0f} | {acc5:.0f} | {rej5:.0f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--only", help="run only the beds whose label contains one of these comma-separated texts")
    parser.add_argument("--profile", action="store_true", help="where the time goes on the statue's k = 1e10 bed")
    args = parser.parse_args()
    if args.profile:
        return profile(args.samples, args.seed, *([args.only] if args.only else []))
    statue = Block(m=1200.0, b=0.25, h=0.9)
    for model in ("coupled", stiff_bed.StiffBedModel(), stiff_bed.StiffBedModel(locate=False)):  # compile
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            monte_carlo(statue, _bed(statue, 1e10), KanaiTajimi(1e-3, 15.6, 0.6), n_samples=2, t_end=0.2, dt=0.1,
                        progress=False, model=model)
    head = ("| bed | model | P(>0.05, 0.1, 0.3, 0.5 alpha), P(overturn) | peak var_theta [rad2] | CPU per sample [ms] "
            "| steps per sample | coupled / model | vs coupled: worst dP / tol | vs reference: worst dP / SE "
            "| worst dP / paired SE | peak var_theta |")
    print(head + "\n|" + "---|" * (head.count("|") - 1), flush=True)
    for label, block, bed, S0 in beds():
        if args.only is None or any(t in label for t in args.only.split(",")):
            run_bed(label, block, bed, S0, args.samples, args.seed)
    print(f"\n{args.samples} samples per row, seed {args.seed}, NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']}; "
          f"Kanai-Tajimi omega_g = {FILTER['omega_g']} rad/s, zeta_g = {FILTER['zeta_g']}, t_end = 20 s; first: "
          f"locate=False, rtol {BEFORE_RTOL:g}, h_max {BEFORE_H_MAX:g} s; 5 ms: h_max {BEFORE_H_MAX:g} s; reference: "
          f"rtol {REFERENCE_RTOL:g}, h_max {BEFORE_H_MAX:g} s.")


if __name__ == "__main__":
    main()
