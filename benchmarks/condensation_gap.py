"""Does the "cubic" condensation close the gap between the condensed and the coupled model?

Run:  NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/condensation_gap.py [--samples 1000] [--seed 0]
      [--cases 1 3 5 7] [--markdown]

For the paper's eight cases (:mod:`screening.core.model.cases`, numbered 1–8 as in docs/validation.md: Figs. 2–9)
prints the peak over the 20 s record of ``var_theta`` and of ``var_theta_dot`` from

* ``coupled MCS``   — Monte Carlo of the full coupled model (eqs. 7–8), the reference;
* ``cond. MCS paper`` / ``cond. MCS cubic`` — Monte Carlo of the condensed SDOF (eq. 22) with
  the paper's condensation (eqs. 17–25) and with the cubic one (:mod:`screening.core.condensation.cubic`);
* ``SL paper`` / ``SL cubic`` — stochastic linearization + Lyapunov (:func:`screening.linearize`),

with each estimate's difference from the coupled MCS in percent (MCS peaks carry their
standard error; all MCS runs use the same samples: ``seed``, sample ``i`` seeded with
``default_rng([seed, i])``).  Intensity convention ``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``.
SL status 1 (``k_eq_negative``) means the linearized model lost stability (toppling); its
peak is then the value reached when the solver stopped.
"""

from __future__ import annotations

import argparse
import os
import time

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from screening.core.model.cases import PAPER_CASES, paper_case  # noqa: E402
from screening.solvers.montecarlo import monte_carlo  # noqa: E402
from screening.analysis.linearization import linearize  # noqa: E402

CASE_NAMES = list(PAPER_CASES)          # case n is CASE_NAMES[n - 1]
MCS_RUNS = (("coupled MCS", "coupled", "paper"), ("cond. MCS paper", "condensed", "paper"),
            ("cond. MCS cubic", "condensed", "cubic"))
SL_RUNS = (("SL paper", "paper"), ("SL cubic", "cubic"))


def mcs_peak(ds, name):
    """``(peak, its standard error)`` of an MCS time series (NaN if no usable samples)."""
    values = ds[name].values
    if not np.any(np.isfinite(values)):
        return np.nan, np.nan
    i = int(np.nanargmax(values))
    return float(values[i]), float(ds[name + "_se"].values[i])


def run_case(number, samples, seed):
    """All estimates of one case: ``{label: {"var_theta": (v, se), "var_theta_dot": (v, se), ...}}``."""
    block, foundation, excitation = paper_case(CASE_NAMES[number - 1])
    out = {}
    for label, model, condensation in MCS_RUNS:
        t0 = time.perf_counter()
        ds = monte_carlo(block, foundation, excitation, n_samples=samples, model=model, seed=seed,
                         condensation=condensation, progress=False)
        out[label] = {name: mcs_peak(ds, name) for name in ("var_theta", "var_theta_dot")}
        out[label].update(p_uplift=float(np.nanmax(ds.p_uplift.values)), n_overturned=int(ds.n_overturned),
                          n_diverged=int(ds.n_diverged), wall=time.perf_counter() - t0)
    for label, condensation in SL_RUNS:
        t0 = time.perf_counter()
        ds = linearize(block, foundation, excitation, t_end=20.0, dt=0.05, condensation=condensation)
        out[label] = {"var_theta": (float(ds.peak_var_theta), np.nan),
                      "var_theta_dot": (float(np.nanmax(ds.var_theta_dot.values)), np.nan),
                      "p_uplift": float(ds.peak_p_uplift), "status": int(ds.status),
                      "wall": time.perf_counter() - t0}
    return out


def percent(value, reference):
    return f"{100.0 * (value / reference - 1.0):+.0f} %" if np.isfinite(value) and reference > 0 else "n/a"


def table(results, name, markdown):
    """One table (rows: cases) for ``name`` in ``("var_theta", "var_theta_dot")``."""
    labels = [label for label, *_ in MCS_RUNS] + [label for label, _ in SL_RUNS]
    head = ["case", "eps", "S0", "input"] + [f"{label}" for label in labels] + \
           [f"{label} vs coupled" for label in labels[1:]]
    rows = []
    for number, res in results.items():
        _, foundation, excitation = paper_case(CASE_NAMES[number - 1])
        ref = res["coupled MCS"][name][0]
        cells = [str(number), f"{foundation.eps:.1e}", f"{excitation.S0:.2e}",
                 "white" if excitation.kind == "white" else "KT"]
        for label in labels:
            v, se = res[label][name]
            text = f"{v:.3e}" + (f" ± {se:.1e}" if np.isfinite(se) else "")
            if label.startswith("SL") and res[label]["status"] != 0:
                text += f" (status {res[label]['status']})"
            cells.append(text)
        cells += [percent(res[label][name][0], ref) for label in labels[1:]]
        rows.append(cells)
    print(f"\npeak {name} over 20 s")
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for cells in rows:
            print("| " + " | ".join(cells) + " |")
        return
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]
    print("  ".join(h.rjust(w) for h, w in zip(head, widths)))
    for cells in rows:
        print("  ".join(c.rjust(w) for c, w in zip(cells, widths)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cases", type=int, nargs="+", default=list(range(1, 9)), choices=range(1, 9))
    parser.add_argument("--markdown", action="store_true", help="print markdown tables")
    args = parser.parse_args(argv)
    block, foundation, excitation = paper_case(CASE_NAMES[0])
    for _, model, condensation in MCS_RUNS:                  # JIT warm-up
        monte_carlo(block, foundation, excitation, n_samples=2, t_end=0.5, model=model,
                    condensation=condensation, progress=False)
    print(f"{args.samples} samples per MCS run, seed {args.seed}, t_end 20 s, output dt 0.05 s, "
          f"NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']}")
    results = {}
    total = time.perf_counter()
    for number in args.cases:
        results[number] = run_case(number, args.samples, args.seed)
        res = results[number]
        print(f"case {number} ({CASE_NAMES[number - 1]}): "
              + ", ".join(f"{label} {res[label]['wall']:.1f} s" for label, *_ in MCS_RUNS + SL_RUNS)
              + "; peak p_uplift " + ", ".join(f"{label} {res[label]['p_uplift']:.3f}"
                                              for label, *_ in MCS_RUNS + SL_RUNS)
              + "; overturned/diverged " + ", ".join(f"{label} {res[label]['n_overturned']}/"
                                                     f"{res[label]['n_diverged']}" for label, *_ in MCS_RUNS),
              flush=True)
    for name in ("var_theta", "var_theta_dot"):
        table(results, name, args.markdown)
    print(f"\ntotal wall {time.perf_counter() - total:.0f} s")


if __name__ == "__main__":
    main()
