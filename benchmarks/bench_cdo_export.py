"""Benchmark: ``screening export R.nc R_cdo.nc --layout cdo`` (the CDO form of a result) at growing grids.

The white-noise grid of ``bench_sweep.py`` (``n x n`` points, 20 s records, 401 output times, all six
histories) is run once per side given (2 local workers), then exported in a fresh process.  Prints
the points, the export's wall time and peak RSS (its memory must not grow with the grid: blocks of
at most 4 Mi values, netCDF chunk caches of a few MiB) and the sizes on disk.

    .venv/bin/python benchmarks/bench_cdo_export.py                 # 2,500 and 10,000 points
    .venv/bin/python benchmarks/bench_cdo_export.py --sides 30 60

The machine should be otherwise idle (2 cores): numbers on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_sweep import OUTPUT, STUDY  # noqa: E402

EXPORT = """
import resource, sys
from screening.cli import main
code = main(["export", sys.argv[1], sys.argv[2], "--layout", "cdo"])
print(code, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""


def export_once(result, out):
    """Wall time [s] and peak RSS [bytes] of the export in a fresh process."""
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", EXPORT, str(result), str(out)], capture_output=True, text=True,
                          check=True)
    wall = time.perf_counter() - start
    code, rss = proc.stdout.split()[-2:]
    if code != "0":
        raise SystemExit(f"export failed: {proc.stderr}")
    return wall, int(rss)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", type=int, nargs="+", default=[50, 100], help="values per swept parameter")
    args = parser.parse_args(argv)
    from screening.sweep.study import parse_study
    from screening.sweep.run import run_sweep

    print(f"{'points':>8} {'export [s]':>11} {'peak RSS [MiB]':>15} {'result [MB]':>12} {'CDO form [MB]':>14}")
    with tempfile.TemporaryDirectory() as tmp:
        for side in args.sides:
            result, out = Path(tmp) / f"r{side}.nc", Path(tmp) / f"r{side}_cdo.nc"
            run_sweep(parse_study(STUDY.format(n=side, output=OUTPUT["all"])), result, workers=2, progress=False, log=lambda *_: None)
            wall, rss = export_once(result, out)
            print(f"{side * side:>8} {wall:>11.2f} {rss / 2**20:>15.0f} {result.stat().st_size / 1e6:>12.1f} "
                  f"{out.stat().st_size / 1e6:>14.1f}")


if __name__ == "__main__":
    main()
