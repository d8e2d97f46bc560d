"""What the ground motion's band changes: 25 Hz against "none" on the validity beds (coupled Monte Carlo).

Per case (the statue on mortar, ``k = 1e10`` and ``1e11``; the cabinet on hardening pads; Kanai-Tajimi firm
soil, two spectral intensities ``S0`` each) the coupled model runs ``--samples`` samples (seed fixed) with the
excitation's ``band_limit_hz = 25`` (the default: an order-4 Butterworth low-pass, synthesized to its top) and
with ``band_limit_hz = None`` (the idealized spectrum, synthesized to 3 x the bed's vertical frequency), at the
SAME ``S0``: the two inputs have the same spectrum below ~15 Hz and differ only above, so the differences are
the band's.  Printed per case and band: ``P(|theta| > a atan(b/h))`` for ``a`` in :data:`FRACTIONS` (overturned
samples count), ``P(overturn)``, the coupled model's peak ``var_theta`` (surviving samples), the linearization's
peak ``var_theta`` (``virtual_work``) under the same input, the median PGA of each input (random-vibration
theory, each to its own band: the idealized one's to a sharp 25 Hz) and the coupled model's CPU per sample; then
the difference 25 Hz - none with its standard error (independent runs: the two syntheses have different
frequency grids, so their samples are not paired).

Run (about 15 minutes of CPU with 300 samples)::

    NUMBA_NUM_THREADS=1 PYTHONPATH=. nice -n 10 python benchmarks/band_effect.py --samples 300
"""

from __future__ import annotations

import argparse
import math
import time
import warnings

import numpy as np

from screening.analysis.intensity import pga_median
from screening.analysis.beds import lam_from_vertical_damping
from screening.core.model import Block, Foundation
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.timegrid import output_times

FRACTIONS = (0.05, 0.1, 0.3)
T_END, DT, SEED = 20.0, 0.05, 2026
STATUE = dict(m=1200.0, b=0.25, h=0.9)
CABINET = dict(m=400.0, b=0.3, h=1.0)
#: ``(label, block, k [N m-2], eps [m-2], S0 levels [m2 s-3])``: vertical damping ratio 0.05; the levels span
#: the onset of rocking to strong rocking at the ground's band (the statue's 0.015 is the scene's intensity).
CASES = (
    ("statue on mortar k=1e10", STATUE, 1e10, 0.0, (0.008, 0.015)),
    ("statue on mortar k=1e11", STATUE, 1e11, 0.0, (0.008, 0.015)),
    ("cabinet on pads k=2.1e9 eps=2e9", CABINET, 2.1e9, 2e9, (0.012, 0.02)),
)
KT = dict(omega_g=15.6, zeta_g=0.6)
BANDS = (25.0, None)


def run(block, bed, excitation, samples):
    """Coupled Monte Carlo: exceedance and overturning probabilities with binomial SEs, peak var_theta and its
    SE, CPU per sample."""
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = monte_carlo(block, bed, excitation, n_samples=samples, model="coupled", t_end=T_END, dt=DT,
                         seed=SEED, progress=False, condensation="paper")
    cpu = (time.process_time() - start) / samples
    slender = math.atan(block.b / block.h)
    peak, over = ds.peak_abs_theta.values, ds.overturned.values.astype(bool)
    out = {}
    for a in FRACTIONS:
        p = float(np.mean(over | (peak > a * slender)))
        out[f"p_exceed_{a:g}"] = (p, math.sqrt(max(p * (1 - p), 1.0 / samples) / samples))
    p = float(np.mean(over))
    out["p_overturn"] = (p, math.sqrt(max(p * (1 - p), 1.0 / samples) / samples))
    v = ds.var_theta.values
    i = int(np.nanargmax(v))
    out["peak_var_theta"] = (float(v[i]), float(ds.var_theta_se.values[i]))
    out["cpu_ms"] = cpu * 1e3
    out["cutoff"] = float(ds.attrs["cutoff_rad_s"])
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=300)
    args = parser.parse_args()
    keys = [*(f"p_exceed_{a:g}" for a in FRACTIONS), "p_overturn", "peak_var_theta"]
    t = output_times(T_END, DT)
    print(f"coupled model, {args.samples} samples per run, seed {SEED}, Kanai-Tajimi omega_g {KT['omega_g']} rad/s "
          f"zeta_g {KT['zeta_g']}, {T_END:g} s; same S0 for both bands", flush=True)
    print("case | S0 | band | " + " | ".join(keys) + " | SL peak var (virtual_work) | median PGA [m/s2] | "
          "synthesis cutoff [rad/s] | CPU/sample [ms]")
    diffs = []
    for label, params, k, eps, levels in CASES:
        block = Block(**params)
        bed = Foundation(k=k, eps=eps, lam=float(lam_from_vertical_damping(k, block.m, block.b, 0.05)))
        for s0 in levels:
            rows = {}
            for band in BANDS:
                exc = KanaiTajimi(s0, **KT, band_limit_hz=band)
                r = run(block, bed, exc, args.samples)
                sl = solve_moments(block, bed, exc, t, condensation="virtual_work", histories=False)
                pga = pga_median(exc, T_END, exc.reference_cutoff())
                rows[band] = r
                name = "none" if band is None else f"{band:g} Hz"
                print(f"{label} | {s0:g} | {name} | " + " | ".join(f"{r[k_][0]:.3g} +- {r[k_][1]:.2g}" for k_ in keys)
                      + f" | {float(sl['peak_var_theta']):.3g} | {pga:.3f} | {r['cutoff']:.0f} | {r['cpu_ms']:.1f}",
                      flush=True)
            a, b = rows[25.0], rows[None]
            d = {k_: (a[k_][0] - b[k_][0], math.hypot(a[k_][1], b[k_][1])) for k_ in keys}
            d["peak_var_theta"] = (a["peak_var_theta"][0] / b["peak_var_theta"][0] - 1.0,
                                   math.hypot(a["peak_var_theta"][1] / b["peak_var_theta"][0],
                                              a["peak_var_theta"][0] * b["peak_var_theta"][1] / b["peak_var_theta"][0] ** 2))
            d["cost"] = b["cpu_ms"] / a["cpu_ms"]
            diffs.append((label, s0, d))
    print("\ndifference 25 Hz - none (+- the SE of the difference) | peak var_theta: 25 Hz / none - 1 | "
          "coupled CPU none / 25 Hz")
    for label, s0, d in diffs:
        print(f"{label} | {s0:g} | " + " | ".join(f"{d[k_][0]:+.3f} +- {d[k_][1]:.3f}" for k_ in keys[:-1])
              + f" | {d['peak_var_theta'][0]:+.2f} +- {d['peak_var_theta'][1]:.2f} | {d['cost']:.2f}x", flush=True)


if __name__ == "__main__":
    main()
