"""Benchmark: netCDF (the client writes) against zarr (the workers write) end to end.

The white-noise grid of ``bench_sweep.py`` (``n x n`` points, 20 s records, 401 output times) is run
with 2 local workers to a ``.nc`` and to a ``.zarr`` result, with ``[output] histories = "none"`` and
``"all"``, at each grid side given.  Prints points/s end to end, the peak RSS of the client and of
the largest worker process (psutil, sampled every 0.1 s), the client's share of CPU time, the size
on disk, and the zarr / netCDF ratios.  Every run is a fresh process (peak RSS is a high-water mark).

    .venv/bin/python benchmarks/bench_formats.py                       # 10,000 and 100,000 points
    .venv/bin/python benchmarks/bench_formats.py --sides 30 --histories none

The machine should be otherwise idle (2 cores): numbers on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_sweep import OUTPUT, STUDY, RssSampler  # noqa: E402


def _size(path):
    if path.is_dir():
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return path.stat().st_size


def run_once(side, histories, suffix, tmp):
    """One run; returns ``(points, wall [s], client RSS, worker RSS [bytes], client CPU [s], size [bytes])``."""
    from screening.sweep.study import parse_study
    from screening.sweep.run import run_sweep

    study = parse_study(STUDY.format(n=side, output=OUTPUT[histories]), name="bench")
    out = tmp / f"bench-{side}-{histories}{suffix}"
    cpu0 = time.process_time()
    with RssSampler() as rss:
        start = time.perf_counter()
        report = run_sweep(study, out, workers=2, force=True, progress=False, log=lambda *_: None)
        wall = time.perf_counter() - start
    cpu = time.process_time() - cpu0
    assert report.status_counts.get("ok", 0) > 0 and report.n_failed_batches == 0
    size = _size(out)
    shutil.rmtree(out) if out.is_dir() else out.unlink()
    return study.n_points, wall, rss.client, rss.worker, cpu, size


def run_in_a_process(side, histories, suffix, tmp):
    """:func:`run_once` in a new Python process (its own peak RSS)."""
    proc = subprocess.run([sys.executable, __file__, "--one", str(side), histories, suffix, str(tmp)],
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", default="100,316", help="grid sides (points = side**2), comma-separated")
    parser.add_argument("--histories", default="none,all", help="[output] histories, comma-separated")
    parser.add_argument("--one", nargs=4, metavar=("SIDE", "HISTORIES", "SUFFIX", "TMP"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        from screening.sweep.execution import warm_up

        warm_up()                                      # the numba cache is loaded before the clock starts
        side, histories, suffix, tmp = args.one
        print(json.dumps(run_once(int(side), histories, suffix, Path(tmp))))
        return
    tmp = Path(tempfile.mkdtemp(prefix="bench-formats-", dir=os.environ.get("TMPDIR")))
    try:
        print(f"{'points':>8} {'histories':>9} {'format':>6} {'points/s':>9} {'client MiB':>10} "
              f"{'worker MiB':>10} {'client CPU s':>12} {'size MiB':>9}", flush=True)
        for side in [int(s) for s in args.sides.split(",")]:
            for histories in args.histories.split(","):
                rows = {}
                for suffix in (".nc", ".zarr"):
                    n, wall, client, worker, cpu, size = rows[suffix] = run_in_a_process(side, histories, suffix, tmp)
                    print(f"{n:>8} {histories:>9} {suffix[1:]:>6} {n / wall:>9.0f} {client / 2**20:>10.1f} "
                          f"{worker / 2**20:>10.1f} {cpu:>12.1f} {size / 2**20:>9.1f}", flush=True)
                nc, zr = rows[".nc"], rows[".zarr"]
                print(f"{'':>8} {'':>9} {'zarr/nc':>6} {nc[1] / zr[1]:>8.2f}x {zr[2] / nc[2]:>9.2f}x "
                      f"{zr[3] / nc[3]:>9.2f}x {zr[4] / max(nc[4], 1e-9):>11.2f}x {zr[5] / nc[5]:>8.2f}x", flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
