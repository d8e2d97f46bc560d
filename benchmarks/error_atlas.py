"""The error atlas campaign: linearization (every condensation) against reference Monte Carlo over a
Sobol design in dimensionless groups (:mod:`screening.applications.atlas`), as a resumable dask job.

Run (regenerates ``screening/data/error_atlas.nc``)::

    nice -n 5 env NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD .venv/bin/python benchmarks/error_atlas.py \
        [--points 1024] [--samples 500] [--seed 0] [--workers 1 | --scheduler ADDRESS_OR_FILE] \
        [--work outputs/error_atlas] [--out screening/data/error_atlas.nc] [--pilot N] [--assemble-only] \
        [--resume-from screening/data/error_atlas.nc] [--redo POINTS] [--refit-model]

Each point's result is written atomically to ``--work/point_NNNNN.json``; a re-run skips the points
already there (so an interrupted campaign resumes where it stopped, on this machine or a cluster),
then assembles every finished point into ``--out``, with the error model fitted on them
(:func:`screening.analysis.error_model.fitted_variables`).  ``--resume-from FILE`` resumes from an assembled
atlas instead of (or besides) the JSON folder: the points already in FILE count as done and their rows
are kept as they are in the new ``--out`` (a point present both in FILE and as a JSON is taken from the
JSON); the CPU hours add up.  ``--redo POINTS`` (indices and ranges, ``"3,17,40-45"``) evaluates those points
again although FILE holds them (a JSON of theirs already in ``--work`` still counts as done, so a stopped redo
resumes): the way to give a point a new reference, e.g. where the reference model's validity rule changed.
``--pilot N`` runs N points spread over the
design (every ``points // N``-th) and prints the CPU per point by reference model, to size a campaign.
``--refit-model`` runs nothing: it refits the stored error model of the assembled ``--out`` in place (its
``em_*`` variables, :func:`screening.analysis.error_model.fitted_variables`), every other variable and
attribute kept, and records the command in ``attrs["error_model_command"]``.
Progress (points done, CPU per point, ETA) is printed as points complete.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # as a script only: a test importing this module leaves the environment alone
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))               # research/ (the campaign's points) lives beside the package
DEFAULT_OUT = ROOT / "screening" / "data" / "error_atlas.nc"
DEFAULT_WORK = ROOT / "outputs" / "error_atlas"


def point_path(work, index):
    return Path(work) / f"point_{int(index):05d}.json"


def run_and_save(index, u, samples, seed, work):
    """Evaluate one point and write its JSON atomically (runs on a worker)."""
    from research.atlas_run import _evaluate_point
    from screening.core.atomicfile import atomic_open

    res = _evaluate_point(index, u, samples=samples, seed=seed)
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


def resumed_rows(path, indices):
    """The points of the assembled atlas ``path`` whose index is in ``indices`` (``None`` if no path)."""
    if not path:
        return None
    import xarray as xr

    from research.atlas_run import REFERENCE_VALIDITY

    with xr.open_dataset(path) as ds:
        keep = np.isin(ds["point"].values, np.asarray(indices))
        ds = ds.drop_vars([name for name in ds.variables if name.startswith("em_")       # refitted at assembly
                           or name in REFERENCE_VALIDITY])                                 # judged again
        return ds.isel(point=np.flatnonzero(keep)).load()


def merge_rows(resumed, ds):
    """``ds`` (freshly assembled points) with the rows of ``resumed`` whose point it lacks, sorted by point."""
    import xarray as xr

    if resumed is None or resumed.sizes["point"] == 0:
        return ds
    old = resumed.isel(point=np.flatnonzero(~np.isin(resumed["point"].values, ds["point"].values)))
    if ds.sizes["point"] == 0:
        return old
    old = old.assign_coords(condensation=ds["condensation"].values, axis=ds["axis"].values)
    merged = xr.concat([old, ds], dim="point", data_vars="minimal", coords="minimal", compat="override",
                       join="override", combine_attrs="override").sortby("point")
    for name in merged.variables:
        src = ds if name in ds.variables else old
        merged[name].attrs = dict(src[name].attrs)
    return merged


def parse_points(text):
    """Sorted point indices from ``"3,17,40-45"`` (``ValueError`` naming ``--redo`` for anything else)."""
    out = set()
    for part in filter(None, (p.strip() for p in (text or "").split(","))):
        lo, sep, hi = part.partition("-")
        if not (lo.isdigit() and (not sep or hi.isdigit())) or (sep and int(hi) < int(lo)):
            raise ValueError(f"--redo must be point indices or ranges such as 3,17,40-45 (got {part!r})")
        out.update(range(int(lo), int(hi if sep else lo) + 1))
    return sorted(out)


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
    ap.add_argument("--resume-from", default=None)
    ap.add_argument("--redo", default="", help="points to evaluate again although --resume-from holds them")
    ap.add_argument("--refit-model", action="store_true",
                    help="only refit the stored error model of the assembled --out in place")
    args = ap.parse_args(argv)
    if args.refit_model:
        if not Path(args.out).is_file():
            print(f"error: --out must be an assembled atlas to refit (no file {args.out})", file=sys.stderr)
            return 2
        return refit_model(Path(args.out), "benchmarks/error_atlas.py " + " ".join(
            argv if argv is not None else sys.argv[1:]))
    if args.points < 1 or args.samples < 2:
        print("error: --points must be >= 1 and --samples >= 2", file=sys.stderr)
        return 2
    try:
        redo = parse_points(args.redo)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if redo and redo[-1] >= args.points:
        print(f"error: --redo must be point indices in 0..{args.points - 1} (got {redo[-1]})", file=sys.stderr)
        return 2

    from screening.applications import atlas

    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    u = atlas.design(args.points, seed=args.seed)
    indices = list(range(args.points))
    if args.pilot:
        indices = indices[:: max(1, args.points // args.pilot)][: args.pilot]
    resumed = resumed_rows(args.resume_from, indices)
    if resumed is not None and int(resumed.attrs.get("samples", args.samples)) != args.samples:
        print(f"error: --resume-from has {resumed.attrs['samples']} samples per point, not --samples "
              f"{args.samples}", file=sys.stderr)
        return 2
    in_file = (set() if resumed is None else {int(i) for i in resumed["point"].values}) - set(redo)
    todo = [i for i in indices if not point_path(work, i).exists() and i not in in_file]
    print(f"error atlas: {len(indices)} points x {args.samples} samples; {len(indices) - len(todo)} already in "
          f"{work}" + (f" or {args.resume_from}" if resumed is not None else "") + f", {len(todo)} to run",
          flush=True)
    t0 = time.time()
    if todo and not args.assemble_only:
        from distributed import as_completed

        from screening.sweep.execution import dask_client

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
    from research.atlas_run import REFERENCE_VALIDITY, assemble, reference_validity

    cpu_h = sum(r.get("cpu", 0.0) for r in results) / 3600
    given = [a for a in (argv if argv is not None else sys.argv[1:]) if a != "--assemble-only"]
    command = ("benchmarks/error_atlas.py " + " ".join(given)).strip()
    ds = assemble(results, attrs={}) if results else None
    if resumed is not None:
        fresh = {int(r["index"]) for r in results}
        kept = ~np.isin(resumed["point"].values, list(fresh))
        cpu_h += float(np.nansum(resumed["point_cpu"].values[kept])) / 3600
        ds = merge_rows(resumed, ds.drop_vars(list(REFERENCE_VALIDITY))) if ds is not None else resumed
    if ds is None:
        print("error: no finished point to assemble", file=sys.stderr)
        return 1
    ds = ds.assign(reference_validity(ds))        # every row judged by the validity rules as they stand now
    from screening.analysis.error_model import fitted_variables

    ds = ds.assign(fitted_variables(ds))          # the shipped error model, stored so that it is not refitted
    ds.attrs = {k: v for k, v in ds.attrs.items() if k in ("title", "Conventions", "levels_relative_to")}
    ds.attrs.update({"command": command, "versions": versions(), "design_points": args.points,
                     "design_seed": args.seed, "samples": args.samples,
                     "points_finished": int(ds.sizes["point"]), "cpu_hours": round(cpu_h, 3)})
    out = Path(args.out)
    write_atlas(ds, out)
    print(f"wrote {out}: {ds.sizes['point']} of {args.points} points, {cpu_h:.2f} CPU h, "
          f"{out.stat().st_size / 1e6:.1f} MB", flush=True)
    return 0


def write_atlas(ds, out):
    """Write the atlas ``ds`` to ``out`` atomically (numeric variables compressed)."""
    from screening.core.atomicfile import atomic_path

    enc = {name: {"zlib": True, "complevel": 5} for name in ds.data_vars if ds[name].dtype != object}
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp, encoding=enc)


def refit_model(path, command):
    """Replace the stored error model of the assembled atlas ``path`` by one fitted now; every other variable
    and attribute kept."""
    import xarray as xr

    from screening.analysis.error_model import STORED_FIT, fitted_variables

    with xr.open_dataset(path) as src:
        ds = src.load()
    ds = ds.drop_vars([name for name in STORED_FIT if name in ds.variables])
    ds = ds.assign(fitted_variables(ds))
    ds.attrs["error_model_command"] = command.strip()
    write_atlas(ds, path)
    print(f"refitted the error model of {path} ({ds.sizes['point']} points)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
