"""What the band's extra filter states cost the moment solver, and how sharp each order is.

The paper block (``m = 8.67 kg``, ``b = 0.035 m``, ``h = 0.21 m``) on three beds (the paper's ``k = 2.89e7``, and
``1e9``, ``1e10`` with proportional damping), 8 intensities ``S0`` 1e-5..1e-3 per call, 20-s records: the wall time
of :func:`screening.solvers.moments.solve_moments` (best of two, after compiling) and its steps, for the idealized
spectrum (order 0) and the 25-Hz band with a Butterworth low-pass of order 2 and 4
(:data:`screening.core.excitations.base.BAND_ORDER`, patched for the measurement), with the largest peak ``var_theta``
of each.  Speed as ratios within one run.

Run::

    NUMBA_NUM_THREADS=1 PYTHONPATH=. nice -n 10 python benchmarks/band_order_cost.py
"""

import time

import numpy as np

import screening.core.excitations.base as base
from screening import Block, Foundation
from screening.core.excitations import CloughPenzien, KanaiTajimi, WhiteNoise
from screening.solvers.moments import solve_moments
from screening.solvers.timegrid import output_times

S0 = np.geomspace(1e-5, 1e-3, 8)
INPUTS = {"white": lambda band: WhiteNoise(S0, band_limit_hz=band),
          "kanai_tajimi": lambda band: KanaiTajimi(S0, 15.7, 0.6, band_limit_hz=band),
          "clough_penzien": lambda band: CloughPenzien(S0, 15.7, 0.6, 1.5, 0.8, band_limit_hz=band)}


def main():
    t_out = output_times(20.0, 0.05)
    block = Block(m=8.67, b=0.035, h=0.21)
    default = base.BAND_ORDER
    print("bed | input | order: wall [ms], steps, largest peak var_theta [rad2] | cost order 4 / order 2")
    for k in (2.89e7, 1e9, 1e10):
        bed = Foundation(k=k, lam=8.95e8 * k / 2.89e7)
        for name, make in INPUTS.items():
            row = []
            for order, band in ((0, None), (2, 25.0), (4, 25.0)):
                base.BAND_ORDER = order or default
                exc = make(band)
                solve_moments(block, bed, exc, t_out[:3], condensation="paper")          # compile
                best = np.inf
                for _ in range(2):
                    start = time.perf_counter()
                    res = solve_moments(block, bed, exc, t_out, condensation="paper", histories=False)
                    best = min(best, time.perf_counter() - start)
                row.append((order, best, int(res["n_steps"].sum()), float(np.nanmax(res["peak_var_theta"]))))
            base.BAND_ORDER = default
            cells = "  ".join(f"{o}: {w * 1e3:.1f} ms, {s} steps, {p:.3e}" for o, w, s, p in row)
            print(f"k={k:.3g} | {name} | {cells} | {row[2][1] / row[1][1]:.2f}x", flush=True)


if __name__ == "__main__":
    main()
