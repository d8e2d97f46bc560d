"""Where the stiff-bed model departs from the coupled model on the collection's stiffest beds (issue 40, item 3).

A research script, not a test: on one case of ``benchmarks/stiff_bed_validity.py`` (the same blocks, beds,
intensities and ground band) it measures, on the same ground motions for both models (seed 1):

``--profile WORK``
    the paired exceedance profile ``P(|theta| > x atan(b/h))`` of the two models from the validity benchmark's
    work folder (its per-sample peaks), x from 1e-3 to 1: at which amplitude the two part;
``--transfers N``
    the energy balance of every corner-to-corner transfer and of every half cycle between transfers in ``N``
    forced runs of each model (``screening.simulate`` on the benchmark's samples, output every 0.5 ms): the
    rocking energy ``E = m_eff(theta) theta'^2 / 2 + V(theta)`` of the stiff-bed model's constraint
    (``rocking_coefficients``, ``potential``) and the work of the ground ``W = int m h cos(theta) x_g'' theta' dt``
    (``x_g'' = -a_g``); a transfer keeps ``E(t_c + tau) / (E(t_c - tau) + W)`` (``tau`` = 15 ms about the zero
    crossing ``t_c``), against the transfer table's ``eta(A)`` (``A`` the half cycle's amplitude); a half cycle
    dissipates ``E_start + W - E_end``;
``--sensitivity``
    the stiff-bed model's probabilities (1,000 samples) with its transfer table scaled by a factor from an
    amplitude on (a diagnostic variant, never a model): how much a bias of the transfer loss moves them;
``--table-points``
    the same with the transfer table on more amplitudes (``TABLE_POINTS``): the spread of a chaotic system's
    probabilities under a change of the model far below its tolerance.

Nothing here is fitted or shipped; the figures are quoted in ``docs/stiff_bed_validity.md``.

    nice -n 10 env NUMBA_NUM_THREADS=1 PYTHONPATH=. python benchmarks/stiff_bed_departure.py \
        --case bust_on_mortar_k_3.51e_10_kanai_tajimi_strong --profile outputs/sbv25 --transfers 300 \
        --sensitivity --table-points
"""
import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import stiff_bed_validity as sbv  # noqa: E402

from screening import monte_carlo, simulate  # noqa: E402
from screening.core.condensation import cubic  # noqa: E402
from screening.kernels.stiff_bed_contact import potential, rocking_coefficients  # noqa: E402
from screening.solvers import stiff_bed  # noqa: E402
from screening.solvers.synthesis import ground_acceleration, synthesis_cutoff  # noqa: E402

OUTPUT_DT = 5e-4     # output step of the forced runs [s]
TAU = 0.015          # half width of a transfer's window [s]
BINS = (1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.2, 0.35, 0.5, 0.7, 0.95)   # A / atan(b/h)


def the_case(text, band):
    found = [c for c in sbv.cases(band) if text in c["id"]]
    if not found:
        raise SystemExit(f"--case: no case of benchmarks/stiff_bed_validity.py contains {text!r}")
    return found[0]


def profile(case, work):
    path = sbv.case_path(work, case)
    record = json.loads(path.read_text())
    ref, mod = record["models"]["coupled"], record["models"]["stiff_bed"]
    alpha = math.atan(case["block_params"]["b"] / case["block_params"]["h"])
    peaks = []
    for r in (ref, mod):
        p = np.array(r["peak"], dtype=float) / alpha
        p[np.asarray(r["overturned"], dtype=bool)] = np.inf
        peaks.append(p)
    n = min(len(peaks[0]), len(peaks[1]))
    print(f"paired exceedance profile, {n} samples ({path})")
    for x in (1e-3, 1e-2, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.0):
        a, b = peaks[0][:n] > x, peaks[1][:n] > x
        d = b.astype(float) - a
        label = "overturn" if x == 1.0 else f"> {x:g} alpha"
        print(f"  P({label}): coupled {a.mean():.3f}, stiff_bed {b.mean():.3f}, difference {d.mean():+.3f} "
              f"+- {d.std(ddof=1) / math.sqrt(n):.3f} (only coupled {int(np.sum(a & ~b))}, only stiff_bed "
              f"{int(np.sum(b & ~a))})")


def energy_balance(case, n, model):
    """Per transfer ``(A / alpha, kept, eta(A))`` and per half cycle ``(A / alpha, dissipated / V(A))``."""
    block, foundation, excitation = sbv.realize(case)
    alpha = float(block.slenderness)
    tu = float(cubic.uplift_threshold(block, foundation))
    log_amp, log_eta, *_ = stiff_bed.transfer_table(block, foundation)
    grid = np.geomspace(1e-3 * tu, alpha, 400)
    v_grid = np.array([potential(x, block, foundation) for x in grid])

    def v_of(theta):
        return np.interp(np.log(np.maximum(np.abs(theta), grid[0])), np.log(grid), v_grid)

    t, acc, _ = ground_acceleration(excitation, sbv.T_END, synthesis_cutoff(excitation, block, foundation), n, seed=1)
    k = int(round(TAU / OUTPUT_DT))
    transfers, halves = [], []
    for i in range(n):
        ds = simulate(block, foundation, acc[i], dt=t[1] - t[0], model=model, output_dt=OUTPUT_DT)
        ok = np.isfinite(ds.theta.values)
        th, thd, ag, tt = (ds.theta.values[ok], ds.theta_dot.values[ok], ds.ground_acceleration.values[ok],
                           ds.t.values[ok])
        m_eff = rocking_coefficients(th, block, foundation)[0]
        e = 0.5 * m_eff * thd**2 + v_of(th)
        power = -float(block.m * block.h) * np.cos(th) * ag * thd
        w = np.concatenate(([0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(tt))))
        crossings = np.flatnonzero(np.sign(th[1:]) * np.sign(th[:-1]) < 0)
        last, prev = 0, None
        for c in crossings:
            amp = np.abs(th[last:c + 1]).max()
            last = c + 1
            if prev is not None and c - k > prev + k:
                seg = slice(prev + k, c - k + 1)
                a_half = np.abs(th[seg]).max()
                halves.append((a_half / alpha, (e[prev + k] + w[c - k] - w[prev + k] - e[c - k]) / v_of(a_half)))
            prev = c
            if not 1e-3 * alpha <= amp <= 0.95 * alpha or c < k or c + k >= th.size:
                continue
            before = e[c - k] + w[c + k] - w[c - k]
            if before > 0:
                eta = math.exp(np.interp(math.log(amp), log_amp, log_eta))
                a_eq = math.exp(np.interp(before, v_grid, np.log(grid)))      # V(a_eq) = the energy at the impact
                eta_eq = math.exp(np.interp(math.log(a_eq), log_amp, log_eta))
                transfers.append((amp / alpha, e[c + k] / before, eta, before / v_of(amp), eta_eq))
    return np.array(transfers), np.array(halves)


def transfers(case, n):
    start = time.monotonic()
    got = {m: energy_balance(case, n, m) for m in ("coupled", "stiff_bed")}
    print(f"energy balance of {n} forced runs per model ({time.monotonic() - start:.0f} s): per transfer the energy "
          "kept (measured) and the table's eta(A), mean over the transfers of each amplitude bin")
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        cells = []
        diffs = []
        for m in ("coupled", "stiff_bed"):
            tr = got[m][0]
            sel = tr[(tr[:, 0] >= lo) & (tr[:, 0] < hi)]
            d = sel[:, 1] - sel[:, 2]
            diffs.append((d.mean(), d.std(ddof=1) / math.sqrt(len(d))))
            cells.append(f"{m} {len(sel)}: {sel[:, 1].mean():.4f} (table {sel[:, 2].mean():.4f})")
        net, se = diffs[0][0] - diffs[1][0], math.hypot(diffs[0][1], diffs[1][1])
        print(f"  A/alpha [{lo:g}, {hi:g}): " + "; ".join(cells)
              + f"; coupled - stiff_bed (each against the table) {net:+.4f} +- {se:.4f}")
    print("  above 0.1 alpha, by the energy at the impact over the half cycle's V(A): coupled - stiff_bed, and "
          "eta(A_eq) - eta(A) with V(A_eq) = E_impact (the table read at the impact's energy)")
    for lo, hi in ((0.0, 0.8), (0.8, 1.0), (1.0, 1.2), (1.2, 1.5), (1.5, 2.0), (2.0, 5.0)):
        sel = {}
        for m in ("coupled", "stiff_bed"):
            tr = got[m][0]
            sel[m] = tr[(tr[:, 0] >= 0.1) & (tr[:, 3] >= lo) & (tr[:, 3] < hi)]
        c, s = sel["coupled"], sel["stiff_bed"]
        net = np.mean(c[:, 1] - c[:, 2]) - np.mean(s[:, 1] - s[:, 2])
        print(f"    E_impact / V(A) [{lo:g}, {hi:g}): {len(c)} transfers, coupled - stiff_bed {net:+.4f}, "
              f"predicted {np.mean(c[:, 4] - c[:, 2]):+.4f}")
    for m in ("coupled", "stiff_bed"):
        h = got[m][1]
        h = h[h[:, 0] >= BINS[0]]
        print(f"  half cycles above {BINS[0]:g} alpha, {m}: {len(h)}, dissipated / V(A) mean {h[:, 1].mean():+.1e}, "
              f"largest |.| {np.abs(h[:, 1]).max():.1e}")


class ScaledTable(stiff_bed.StiffBedModel):
    """Diagnostic variant: the bed's transfer table times ``factor`` from ``from_alpha atan(b/h)`` on."""

    def __init__(self, factor, from_alpha):
        super().__init__()
        self.factor, self.from_alpha = factor, from_alpha

    def table(self, block, foundation):
        log_amp, log_eta = super().table(block, foundation)
        x = np.linspace(log_amp[0], log_amp[-1], 400)
        y = np.interp(x, log_amp, log_eta)
        y = y + np.where(x >= math.log(self.from_alpha * float(block.slenderness)), math.log(self.factor), 0.0)
        return x, y


def probabilities(case, model, n=1000):
    block, foundation, excitation = sbv.realize(case)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = monte_carlo(block, foundation, excitation, n_samples=n, model=model, t_end=sbv.T_END, dt=sbv.DT,
                         seed=1, progress=False)
    alpha = float(block.slenderness)
    peak, over = ds.peak_abs_theta.values, ds.overturned.values.astype(bool)
    return [float(np.mean((peak > a * alpha) | over)) for a in sbv.FRACTIONS] + [float(over.mean())]


def _fmt(p):
    return " ".join(f"{x:.3f}" for x in p)


def sensitivity(case):
    print("P(> 0.05, 0.1, 0.3, 0.5 alpha), P(overturn) of the stiff-bed model, 1000 samples, transfer table scaled:")
    print(f"  as shipped: {_fmt(probabilities(case, 'stiff_bed'))}")
    for factor, from_alpha in ((1.0, 0.1), (0.95, 0.1), (1.05, 0.1), (0.95, 0.0)):
        p = probabilities(case, ScaledTable(factor, from_alpha))
        print(f"  eta x {factor:g} from {from_alpha:g} alpha (the table on 400 nodes): {_fmt(p)}")


def table_points(case):
    print("the same with the transfer table on more amplitudes (TABLE_POINTS, shipped 10):")
    shipped = stiff_bed.TABLE_POINTS
    try:
        for points in (10, 19, 37, 73):
            stiff_bed.TABLE_POINTS = points
            stiff_bed._transfer_table_cached.cache_clear()
            print(f"  {points} points: {_fmt(probabilities(case, 'stiff_bed'))}", flush=True)
    finally:
        stiff_bed.TABLE_POINTS = shipped
        stiff_bed._transfer_table_cached.cache_clear()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="bust_on_mortar_k_3.51e_10_kanai_tajimi_strong")
    parser.add_argument("--band-limit-hz", type=lambda v: v if v == "none" else float(v), default=25.0)
    parser.add_argument("--profile", metavar="WORK", help="the validity benchmark's work folder")
    parser.add_argument("--transfers", type=int, default=0, metavar="N")
    parser.add_argument("--sensitivity", action="store_true")
    parser.add_argument("--table-points", action="store_true")
    args = parser.parse_args()
    case = the_case(args.case, args.band_limit_hz)
    print(case["id"])
    if args.profile:
        profile(case, args.profile)
    if args.transfers:
        transfers(case, args.transfers)
    if args.sensitivity:
        sensitivity(case)
    if args.table_points:
        table_points(case)


if __name__ == "__main__":
    main()
