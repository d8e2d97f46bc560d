"""The error atlas campaign: linearization (every condensation) against reference Monte Carlo over a
Sobol design in dimensionless groups (:mod:`screening.analysis.atlas`), as a resumable dask job.

Run (regenerates ``screening/data/error_atlas.nc``)::

    nice -n 5 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/error_atlas.py \
        [--points 1024] [--samples 500] [--seed 0] [--workers 1 | --scheduler ADDRESS_OR_FILE] \
        [--work outputs/error_atlas] [--out screening/data/error_atlas.nc] [--pilot N] [--assemble-only]

Each point's result is written atomically to ``--work/point_NNNNN.json``; a re-run skips the points
already there (so an interrupted campaign resumes where it stopped, on this machine or a cluster),
then assembles every finished point into ``--out``.  ``--pilot N`` runs N points spread over the
design (every ``points // N``-th) and prints the CPU per point by reference model, to size a campaign.
Progress (points done, CPU per point, ETA) is printed as points complete.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "screening" / "data" / "error_atlas.nc"
DEFAULT_WORK = ROOT / "outputs" / "error_atlas"


def point_path(work, index):
    return Path(work) / f"point_{int(index):05d}.json"


def run_and_save(index, u, samples, seed, work):
    """Evaluate one point and write its JSON atomically (runs on a worker)."""
    from screening.analysis.atlas_run import evaluate_point
    from screening.atomicfile import atomic_open

    res = evaluate_point(index, u, samples=samples, seed=seed)
    with atomic_open(point_path(work, index)) as fh:
        json.dump(res, fh)
    return {"index": index, "cpu": res.get("cpu", float("nan")), "model": res.get("mc", {}).get("model", "-"),
            "error": res.get("error", "")}


def load(work, indices):
    out = []
    for i in indices:
        p = point_path(work, i)
        if p.exists():
            out.append(json.loads(p.read_text()))
    return out


def versions():
    import importlib.metadata as md

    names = ("numpy", "scipy", "numba", "xarray", "dask", "distributed")
    return "; ".join(f"{n} {md.version(n)}" for n in names)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=1024)
    ap.add_argument("--samples", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--scheduler", default=None)
    ap.add_argument("--work", default=str(DEFAULT_WORK))
    ap.add_argument("--out", default=str(DEFAULT_OUT))
    ap.add_argument("--pilot", type=int, default=0)
    ap.add_argument("--assemble-only", action="store_true")
    args = ap.parse_args(argv)
    if args.points < 1 or args.samples < 2:
        print("error: --points must be >= 1 and --samples >= 2", file=sys.stderr)
        return 2

    from screening.analysis import atlas

    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    u = atlas.design(args.points, seed=args.seed)
    indices = list(range(args.points))
    if args.pilot:
        indices = indices[:: max(1, args.points // args.pilot)][: args.pilot]
    todo = [i for i in indices if not point_path(work, i).exists()]
    print(f"error atlas: {len(indices)} points x {args.samples} samples; {len(indices) - len(todo)} already in "
          f"{work}, {len(todo)} to run", flush=True)
    t0 = time.time()
    if todo and not args.assemble_only:
        from distributed import as_completed

        from screening.workflow.execution import dask_client

        with dask_client(workers=args.workers, scheduler=args.scheduler) as client:
            print(f"dask: {client}", flush=True)
            futures = [client.submit(run_and_save, i, u[i], args.samples, args.seed, str(work), pure=False,
                                     key=f"atlas-point-{i}") for i in todo]
            cpu, done = [], 0
            for fut in as_completed(futures, loop=client.loop):
                r = fut.result()
                done += 1
                cpu.append(r["cpu"])
                el = time.time() - t0
                eta = el / done * (len(todo) - done)
                print(f"[{done}/{len(todo)}] point {r['index']} {r['model']:9s} cpu {r['cpu']:6.1f} s "
                      f"(mean {np.mean(cpu):.1f} s) elapsed {el / 60:.1f} min eta {eta / 60:.1f} min"
                      + (f" error: {r['error'][:80]}" if r["error"] else ""), flush=True)
    results = load(work, indices)
    if args.pilot:
        by = {}
        for r in results:
            by.setdefault(r.get("mc", {}).get("model", "none"), []).append(r["cpu"])
        for model, c in by.items():
            print(f"pilot: {model:9s} {len(c):4d} points, CPU per point mean {np.mean(c):.2f} s, max {np.max(c):.1f} s")
        allc = [r["cpu"] for r in results]
        print(f"pilot: all {len(allc)} points mean {np.mean(allc):.2f} s -> {args.points} points "
              f"{np.mean(allc) * args.points / 3600:.2f} CPU h")
        return 0
    from screening.analysis.atlas_run import assemble
    from screening.atomicfile import atomic_path

    cpu_h = sum(r.get("cpu", 0.0) for r in results) / 3600
    given = [a for a in (argv if argv is not None else sys.argv[1:]) if a != "--assemble-only"]
    command = ("benchmarks/error_atlas.py " + " ".join(given)).strip()
    ds = assemble(results, attrs={"command": command, "versions": versions(), "design_points": args.points,
                                  "design_seed": args.seed, "samples": args.samples,
                                  "points_finished": len(results), "cpu_hours": round(cpu_h, 3)})
    enc = {name: {"zlib": True, "complevel": 5} for name in ds.data_vars if ds[name].dtype != object}
    out = Path(args.out)
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp, encoding=enc)
    print(f"wrote {out}: {len(results)} of {args.points} points, {cpu_h:.2f} CPU h, "
          f"{out.stat().st_size / 1e6:.1f} MB", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
