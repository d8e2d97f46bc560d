"""Command line: ``screening run | plot | info | fragility | tradeoff``.

``screening run STUDY.toml [--out PATH] [--workers N | --scheduler ADDRESS]`` runs a study on
dask (:func:`screening.workflow.sweep.run_sweep`) and writes ``PATH`` (default
``outputs/<study-stem>.nc``) plus PNG figures next to it.  An interrupted run restarted
with the same command resumes; an unchanged study reuses its finished result.

``screening plot RESULT.nc [--out-dir DIR]`` writes the figures; ``screening info RESULT.nc``
prints the dimensions, swept parameters, status counts and summary statistics.
``screening fragility RESULT.nc --threshold X [--relative-to slenderness|theta_ul]`` writes
the probability of exceeding the rotation over the grid (netCDF) and fragility curves (PNG).
``screening tradeoff STUDY.toml`` runs the speed-accuracy trade study (:mod:`screening.analysis.tradeoff`).

User errors (bad study file, missing output folder, unreadable result file, unreachable
scheduler) print one line ``screening: error: ...`` on stderr and exit with status 2,
without writing anything.  Ctrl-C exits with 130 and keeps the finished batches.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from screening import __version__

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``screening: error: ...``)."""

    def error(self, message):
        raise _UsageError(f"{message} (see '{self.prog} --help')")


class _UsageError(Exception):
    pass


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1 (got {text!r})") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1 (got {text!r})")
    return value


def _positive_float(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0 (got {text!r})") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0 (got {text!r})")
    return value


def _zlib_level(text):
    if text not in [str(i) for i in range(10)]:
        raise argparse.ArgumentTypeError(f"must be an integer in 0..9 (got {text!r})")
    return int(text)


def build_parser():
    parser = _Parser(prog="screening", description="Stochastic screening of rocking blocks on flexible "
                                                   "nonlinear foundations.")
    parser.add_argument("--version", action="version", version=f"screening {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    run = sub.add_parser("run", help="run a study file (TOML) and write a netCDF result + PNG figures")
    run.add_argument("study", help="study file (TOML), e.g. studies/quick.toml")
    run.add_argument("--out", help="result file (default outputs/<study-stem>.nc, folder created if missing; "
                                   "the folder of an explicit path must exist)")
    where = run.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int,
                       help="worker processes of the local dask cluster (default 2)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="use an existing dask cluster: scheduler address or scheduler JSON file")
    run.add_argument("--batch-size", type=_positive_int, help="points per task (default: about 500)")
    run.add_argument("--complevel", type=_zlib_level, default=1,
                     help="zlib level of the netCDF file: 1 (default, fastest) .. 9, 0 = uncompressed")
    run.add_argument("--force", action="store_true", help="recompute even if the result is up to date")
    run.add_argument("--no-plots", action="store_true", help="do not write the PNG figures")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=cmd_run)

    plot = sub.add_parser("plot", help="write PNG figures of a result file")
    plot.add_argument("result", help="result file (netCDF)")
    plot.add_argument("--out-dir", help="folder for the figures (default: next to the result; must exist)")
    plot.set_defaults(func=cmd_plot)

    frag = sub.add_parser("fragility", help="probability of exceeding a rotation: netCDF + PNG fragility curves")
    frag.add_argument("result", help="result file (netCDF) of `screening run`")
    frag.add_argument("--threshold", type=_positive_float, required=True,
                      help="rotation threshold: in rad, or a fraction of the angle named by --relative-to")
    frag.add_argument("--relative-to", choices=["slenderness", "theta_ul"],
                      help="threshold as a fraction of the slenderness angle atan(b/h) or of theta_ul")
    frag.add_argument("--method", choices=["vanmarcke", "poisson"], default="vanmarcke",
                      help="up-crossing approximation (default vanmarcke)")
    frag.add_argument("--dim", help="swept intensity of the fragility curve and its lognormal fit "
                                    "(default S0 if swept)")
    frag.add_argument("--out", help="netCDF file (default <result-stem>_fragility.nc next to the result; "
                                    "its folder must exist); the PNG goes next to it")
    frag.set_defaults(func=cmd_fragility)

    sub.add_parser("tradeoff", add_help=False,
                   help="speed-accuracy trade study (screening.analysis.tradeoff; see 'screening tradeoff --help')")

    info = sub.add_parser("info", help="describe a result file")
    info.add_argument("result", help="result file (netCDF)")
    info.set_defaults(func=cmd_info)
    return parser


def main(argv=None):
    """Entry point of the ``screening`` console script; returns the exit status."""
    from screening.workflow.errors import SweepError
    from screening.workflow.study import StudyError

    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["tradeoff"]:                 # its own parser (screening.analysis.tradeoff.main)
        from screening.analysis.tradeoff import main as tradeoff_main

        return tradeoff_main(argv[1:])
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except (_UsageError, StudyError, SweepError) as exc:
        print(f"screening: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("screening: interrupted; finished batches are kept, re-run the same command to resume",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    except SystemExit as exc:               # --help / --version
        return exc.code if isinstance(exc.code, int) else EXIT_OK


# ----------------------------------------------------------------------------- commands
def _say(msg):
    print(msg, file=sys.stderr, flush=True)


def cmd_run(args):
    from screening.workflow.errors import SweepError
    from screening.workflow.study import load_study
    from screening.workflow.sweep import run_sweep
    from screening.workflow.writer import check_output_path

    study = load_study(args.study)
    if args.out:
        out = check_output_path(args.out)
    else:                                    # the default folder is created (the README's `make run`)
        out = Path("outputs") / f"{study.name}.nc"
        try:
            out.parent.mkdir(exist_ok=True)
        except OSError as exc:
            raise SweepError(f"cannot create the output folder {out.parent}: {exc.strerror or exc}") from None
        check_output_path(out)
    report = run_sweep(study, out, workers=args.workers or 2, scheduler=args.scheduler, batch_size=args.batch_size,
                       force=args.force, progress=not args.quiet, log=_say, complevel=args.complevel)
    if not report.reused:
        counts = ", ".join(f"{k} {v}" for k, v in report.status_counts.items())
        spots = f", {report.n_spots} spot check(s)" if report.n_spots else ""
        _say(f"wrote {out}: {report.n_points} points ({counts}){spots} in {report.timings['total']:.1f} s")
    if not args.no_plots:
        stem = out.name[:-3] if out.name.endswith(".nc") else out.name
        pngs = [out.parent / f"{stem}_{k}.png" for k in ("histories", "peaks")]
        if not report.reused or not all(p.exists() for p in pngs):
            try:
                paths = _plot(out, out.parent)
            except SweepError as exc:
                raise SweepError(f"{exc}; the result {out} is complete, re-run 'screening plot {out}' "
                                 "for the figures") from None
            for path in paths:
                _say(f"wrote {path}")
    if report.n_failed_batches:
        _say(f"warning: {report.n_failed_batches} batch(es) failed; their points have status task_failed "
             f"in {out}")
    return EXIT_OK


def _write_error(path, exc):
    from screening.workflow.errors import SweepError, write_failure_reason

    return SweepError(f"cannot write {getattr(exc, 'filename', None) or path}: {write_failure_reason(exc)}")


def _plot(result, out_dir):
    """All figures of ``result`` into ``out_dir`` (none left behind on failure, one-line errors)."""
    from screening.report.figures import plot_result
    from screening.workflow.reader import damaged_data_error, open_result

    result = Path(result)
    with open_result(result) as ds:
        stem = result.name[:-3] if result.name.endswith(".nc") else result.name
        try:
            return plot_result(ds, stem, out_dir)
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(result, exc) from None
        except OSError as exc:                  # the PNG could not be written
            raise _write_error(out_dir, exc) from None


def cmd_plot(args):
    from screening.workflow.errors import SweepError
    from screening.workflow.reader import open_result

    result = Path(args.result)
    open_result(result).close()                  # readable? (before touching the output folder)
    out_dir = Path(args.out_dir) if args.out_dir else result.parent
    if not out_dir.is_dir():
        raise SweepError(f"output folder {out_dir} does not exist")
    for path in _plot(result, out_dir):
        print(path)
    return EXIT_OK


def cmd_fragility(args):
    from screening.analysis.fragility import fragility_dataset
    from screening.report.figures import plot_fragility
    from screening.workflow.errors import SweepError
    from screening.workflow.reader import damaged_data_error, open_result
    from screening.workflow.writer import check_output_path

    result = Path(args.result)
    with open_result(result) as ds:
        grid = ds["status"].dims
        if args.dim is not None and args.dim not in grid:
            raise SweepError(f"--dim {args.dim!r} is not a swept dimension of {result} "
                             f"(swept: {', '.join(grid) or 'none'})")
        dim = args.dim or "S0"
        stem = result.name[:-3] if result.name.endswith(".nc") else result.name
        out = check_output_path(args.out or result.with_name(f"{stem}_fragility.nc"))
        try:
            frag = fragility_dataset(ds, args.threshold, args.relative_to, args.method, dim).load()
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(result, exc) from None
    frag.attrs.update(source_result=str(result), screening_version=__version__,
                      history=f"screening fragility {result} --threshold {args.threshold}"
                              + (f" --relative-to {args.relative_to}" if args.relative_to else ""))
    tmp = out.with_name(out.name + ".tmp")
    encoding = {name: {"_FillValue": None} for name in frag.coords}
    png_path = out.with_suffix(".png")
    png_existed = png_path.exists()
    try:
        frag.to_netcdf(tmp, engine="netcdf4", encoding=encoding)
        png = plot_fragility(frag, dim, png_path)
        tmp.replace(out)                         # the netCDF appears last: both or neither
    except (OSError, RuntimeError) as exc:      # netCDF reports a failed write as RuntimeError
        tmp.unlink(missing_ok=True)
        if not png_existed:
            png_path.unlink(missing_ok=True)
        raise _write_error(out, exc) from None
    print(out)
    if png is not None:
        print(png)
    p = frag["p_exceed"].values
    _say(f"P(exceed) over {p.size} point(s): min {np.nanmin(p):.3g}, max {np.nanmax(p):.3g}"
         + (f"; lognormal median {dim} {float(frag['median'].median()):.3g}, "
            f"beta {float(frag['beta'].median()):.2f} (medians over the other dims)" if "median" in frag else ""))
    return EXIT_OK


def cmd_info(args):
    from screening.workflow.reader import damaged_data_error, open_result

    with open_result(args.result) as ds:
        try:
            text = describe(ds, args.result)
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(args.result, exc) from None
    print(text)
    return EXIT_OK


# ----------------------------------------------------------------------------- info text
def _fmt(value):
    return f"{value:.4g}" if isinstance(value, (float, np.floating)) else str(value)


def describe(ds, path="result"):
    """Plain-text summary of a result dataset (what ``screening info`` prints)."""
    from screening.report.figures import grid_dims, grid_units, grid_values, point_label, spot_index

    dims = grid_dims(ds)
    lines = [f"{path}: {ds.attrs.get('title', '')}",
             f"  screening {ds.attrs.get('screening_version', '?')}, study {ds.attrs.get('study_file', '?')}, "
             f"created {ds.attrs.get('date_created', '?')}"]
    sizes = ", ".join(f"{d} ({n})" for d, n in ds.sizes.items())
    n_points = int(np.prod([ds.sizes[d] for d in dims], dtype=np.int64))
    lines.append(f"dimensions: {sizes}; {n_points} grid point(s)")
    lines.append("swept parameters:" if dims else "swept parameters: none")
    for d in dims:
        if d == "case":
            names = [str(s) for s in ds["case_name"].values]
            lines.append(f"  case     {len(names)} cases: {', '.join(names)}")
            continue
        v = grid_values(ds, d)
        units = grid_units(ds, d)
        lines.append(f"  {d:<8} {v.size} values, {_fmt(float(v.min()))} .. {_fmt(float(v.max()))} {units}")
    fixed = [n for n, var in ds.coords.items() if var.ndim == 0 and np.issubdtype(var.dtype, np.number)]
    if fixed:
        lines.append("fixed parameters: " + ", ".join(
            f"{n} = {_fmt(float(ds[n]))} {ds[n].attrs.get('units', '')}".rstrip() for n in fixed))
    per_case = [n for n, var in ds.coords.items() if var.dims == ("case",) and n not in ("case", "case_name")]
    if per_case:
        lines.append("per-case parameters: " + ", ".join(
            n + (f" ({', '.join(str(v) for v in ds[n].values)})" if ds[n].dtype.kind in "OUS" else "")
            for n in per_case))
    labels = [f"{k} = {ds.attrs[k]}" for k in ("contact", "condensation", "excitation", "envelope") if k in ds.attrs]
    if labels:
        lines.append("models: " + ", ".join(labels))
    t = ds["t"].values
    lines.append(f"time: {_fmt(float(t[0]))} .. {_fmt(float(t[-1]))} s, {t.size} output times")

    status = np.asarray(ds["status"].values).reshape(-1)
    codes = [int(c) for c in ds["status"].attrs["flag_values"]]
    meanings = str(ds["status"].attrs["flag_meanings"]).split()
    counts = ", ".join(f"{m} {int(np.sum(status == c))}" for c, m in zip(codes, meanings)
                       if np.any(status == c))
    lines.append(f"status: {counts}")
    ok = status == 0
    lines.append(f"summary over the {int(ok.sum())} status-ok point(s) (min / median / max):")
    for name in ("peak_var_theta", "t_peak_var_theta", "peak_p_uplift", "min_k_eq"):
        v = np.asarray(ds[name].values, dtype=float).reshape(-1)[ok]
        units = ds[name].attrs.get("units", "")
        if v.size:
            lines.append(f"  {name:<17} {_fmt(v.min())} / {_fmt(float(np.median(v)))} / {_fmt(v.max())} {units}")
    if "spot" in ds.dims and ds.sizes["spot"]:
        lines.append(f"Monte Carlo spot checks ({ds.attrs.get('mcs_model')}, {ds.attrs.get('mcs_samples')} "
                     f"samples, seed {ds.attrs.get('mcs_seed')}):")
        for i in range(ds.sizes["spot"]):
            index = spot_index(ds, i)
            rel = float(ds["mcs_rel_error_peak_var_theta"].values[i])
            rel_dot = float(ds["mcs_rel_error_peak_var_theta_dot"].values[i])
            over = int(ds["mcs_n_overturned"].values[i])
            div = int(ds["mcs_n_diverged"].values[i])
            lines.append(f"  {point_label(ds, index)}: " + _spot_summary(
                rel, rel_dot, over, div, int(ds["mcs_n_used"].values[i]),
                bool("mcs_status" in ds and int(ds["mcs_status"].values[i]) != 0)))
    return "\n".join(lines)


def _spot_summary(rel, rel_dot, n_overturned, n_diverged, n_used, failed):
    """One spot check in plain words: the relative errors, or why there are none."""
    n = n_overturned + n_diverged + n_used
    if failed:
        return "the Monte Carlo run failed (no statistics; see the run log)"
    if n_used == 0:
        if n_overturned == n:
            return f"all {n} samples overturned: no statistics (the block topples at this point)"
        if n_diverged == n:
            return f"all {n} samples diverged: no statistics"
        return f"no usable sample ({n_overturned} overturned, {n_diverged} diverged of {n}): no statistics"

    def pct(x):
        return f"{100 * x:+.1f} %" if np.isfinite(x) else "n/a (the linearization stopped)"

    return (f"peak var_theta rel. error {pct(rel)}, peak var_theta_dot {pct(rel_dot)}, "
            f"overturned {n_overturned}, diverged {n_diverged} of {n}")


if __name__ == "__main__":
    sys.exit(main())
