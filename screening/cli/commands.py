"""Command line: ``screening run | export | plot | info | fragility | tradeoff | simulate |
fit-excitation | cloud`` (one click parser).

The record commands (``simulate``, ``fit-excitation``, ``cloud``) and ``fragility --im`` live in
:mod:`screening.cli.records`.

``screening run STUDY.toml [--out PATH] [--workers N | --scheduler ADDRESS]`` runs a study on
dask (:func:`screening.sweep.run.run_sweep`; ``--workers 0``, the default for small
studies, in this process) and writes ``PATH`` (default
``outputs/<study-stem>.nc``) plus PNG figures next to it.  An interrupted run restarted
with the same command resumes; an unchanged study reuses its finished result.

``--out PATH.zarr`` writes a zarr store instead, in place from the workers (large runs);
``screening export RESULT.zarr RESULT.nc`` converts it to the netCDF file a direct run writes;
``screening export RESULT OUT.nc --layout cdo [--select DIM=VALUE]`` writes the form CDO reads
(:mod:`screening.io.cdofile`).

``screening plot RESULT.nc [--out-dir DIR] [--response var|sigma|fraction]`` writes the figures;
``screening info RESULT.nc`` prints the dimensions, swept parameters, status counts and summary statistics
(and describes the files of ``simulate``, ``cloud`` and ``fragility``).
``screening fragility RESULT.nc --threshold X [--threshold Y ...] [--relative-to slenderness|theta_ul]`` writes
the probability of exceeding the rotation over the grid (netCDF) and fragility curves (PNG), one limit
state per threshold, all files as one set (docs/fragility.md).
``screening tradeoff STUDY.toml`` runs the speed-accuracy trade study (:mod:`screening.report.tradeoff`).

User errors (bad options, bad study file, missing output folder, unreadable result file,
unreachable scheduler) print one line ``screening: error: ...`` on stderr and exit with status 2,
without writing anything.  Ctrl-C exits with 130 and keeps the finished batches.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click
import numpy as np

from screening._version import __version__
from screening.core.atomicfile import publish as _publish
from screening.cli._common import Choice, not_with, result_stem, say, temporary_for, usage_message, write_error
from screening.cli.base import (EXIT_OK, EXIT_USAGE, EXIT_INTERRUPTED, CommandError, POSITIVE_INT,
                                WORKER_COUNT, POSITIVE_FLOAT, ZLIB_LEVEL, cli, announce_compilation, stamp_fragility,
                                lognormal_fit_text, write_file_set, fragility_figures, fit_files,
                                write_fragility_files, DISPERSION, fragility_outputs, refuse_collisions)
from screening import __version__

__all__ = []

def main(argv=None):
    """Entry point of the ``screening`` console script; returns the exit status.

    Parses and runs like ``cli.main(standalone_mode=False)``, without click's own handling of
    Ctrl-C (a blank line on stderr): every failure is mapped here to one line and a status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: :data:`EXIT_OK` (0), :data:`EXIT_USAGE` (2: a user error, one line
        ``screening: error: ...`` on stderr, nothing written) or :data:`EXIT_INTERRUPTED` (130: Ctrl-C).

    """
    from screening.io.errors import SweepError
    from screening.sweep.interrupt import interrupt_guard
    from screening.sweep.study import StudyError
    from screening.kernels.cache import announcing_compiles

    argv = sys.argv[1:] if argv is None else list(argv)

    try:
        with interrupt_guard(), announcing_compiles(quiet="--quiet" in argv), \
                cli.make_context("screening", argv) as ctx:
            status = cli.invoke(ctx)
        sys.stdout.flush()                      # a closed pipe shows here, not at interpreter exit
        return status
    except BrokenPipeError:                     # `screening info R.nc | head -1`: the reader has enough
        _silence_stdout()
        return EXIT_OK
    except click.exceptions.Exit as exc:            # --help / --version
        return exc.exit_code
    except click.UsageError as exc:
        return _error(usage_message(exc))
    except (CommandError, StudyError, SweepError) as exc:
        return _error(str(exc))
    except KeyboardInterrupt:
        print(f"screening: interrupted; {interrupted_note(argv)}", file=sys.stderr)
        return EXIT_INTERRUPTED


#: Commands that keep their finished work when interrupted and resume from it.
RESUMING_COMMANDS = ("run",)


def interrupted_note(argv):
    """What an interrupted command leaves: ``run`` keeps its finished batches; the others keep nothing
    to resume from (their files are written whole, each at its end).

    Parameters
    ----------
    argv : list of str
        The command line after the program name.

    Returns
    -------
    str
        The words printed after ``interrupted`` when Ctrl-C stops the command.

    """
    command = next((a for a in argv if not a.startswith("-")), "")
    if command in RESUMING_COMMANDS:
        return "finished batches are kept, re-run the same command to resume"
    return "nothing is kept to resume from, re-run the command to start again"


def _silence_stdout():
    """Point stdout at /dev/null so that Python's final flush does not complain about the closed pipe."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):   # no real file descriptor (captured output)
        pass


_CONTROL = {c: f"\\x{c:02x}" for c in [*range(0x00, 0x09), *range(0x0b, 0x20), 0x7f, *range(0x80, 0xa0)]}


def printable(text):
    """``text`` with terminal control characters (escape sequences, carriage returns, C1 codes) shown
    as ``\\xNN``: a result file's title or attributes must not drive the user's terminal.

    Parameters
    ----------
    text : object
        What to print (converted with ``str``).

    Returns
    -------
    str
        The text with the C0 control characters but tab and newline, DEL and the C1 codes
        (U+0080-U+009F) replaced by ``\\xNN``.

    """
    return str(text).translate(_CONTROL)


def _error(message):
    _quiet_abandoned_reads()
    print(f"screening: error: {printable(' '.join(str(message).split()))}", file=sys.stderr)
    return EXIT_USAGE


def _quiet_abandoned_reads():
    """After a failed read of a zarr store, its other chunk reads (tasks of zarr's event loop) are
    abandoned; asyncio would report each of them at exit ("Task was destroyed but it is pending",
    "Future exception was never retrieved", "coroutine ... was never awaited", "Event loop is closed"
    through the unraisable hook): the one-line error
    already said what failed."""
    import logging
    import warnings

    logging.getLogger("asyncio").setLevel(logging.CRITICAL + 1)
    warnings.filterwarnings("ignore", message="coroutine .* was never awaited", category=RuntimeWarning)

    def on_unraisable(unraisable, default=sys.unraisablehook):
        # an abandoned read closed after zarr's loop: "Exception ignored in <coroutine ...>: Event loop is closed"
        if isinstance(unraisable.exc_value, RuntimeError) and "Event loop is closed" in str(unraisable.exc_value):
            return
        default(unraisable)

    sys.unraisablehook = on_unraisable


# ----------------------------------------------------------------------------- commands
@cli.command("run", help="run a study file (TOML) and write a netCDF result + PNG figures")
@click.argument("study")
@click.option("--out", help="result file (default outputs/<study-stem>.nc, folder created if missing; "
                            "the folder of an explicit path must exist); a path ending in .zarr is a zarr store "
                            "written in place by the workers (large runs; 'screening export' converts it)")
@click.option("--workers", type=WORKER_COUNT, callback=not_with("scheduler"),
              help="worker processes of the local dask cluster; 0 = in this process, no cluster (default: "
                   "the study's [cluster] table if it has one, else 0 for at most 500 points and at most one Monte "
                   "Carlo spot check, else 2)")
@click.option("--scheduler", metavar="ADDRESS", callback=not_with("workers"),
              help="use an existing dask cluster: scheduler address or scheduler JSON file (docs/distributed.md)")
@click.option("--batch-size", type=POSITIVE_INT, help="points per task (default: about 500)")
@click.option("--complevel", type=ZLIB_LEVEL, default="1",
              help="compression level (zlib; zstd for zarr): 1 (default, fastest) .. 9, 0 = uncompressed")
@click.option("--force", is_flag=True, help="recompute even if the result is up to date")
@click.option("--no-plots", is_flag=True, help="do not write the PNG figures")
@click.option("--quiet", is_flag=True, help="no progress bar")
@click.option("--inventory", type=click.Path(), help="a collection CSV (one row per object: name, m, b, h, depth, "
                                                     "bed) turned into named cases (docs/study.md)")
def cmd_run(study, out, workers, scheduler, batch_size, complevel, force, no_plots, quiet, inventory):
    from screening.io.errors import SweepError
    from screening.sweep.study import load_study
    from screening.sweep.run import run_sweep
    from screening.io.writer import check_output_path

    study = load_study(study, inventory=inventory)
    announce_compilation(quiet)
    if out:
        out = check_output_path(out, inputs=(study.source,))
    else:                                    # the default folder is created (the README's `make run`)
        out = Path("outputs") / f"{study.name}.nc"
        try:
            out.parent.mkdir(exist_ok=True)
        except OSError as exc:
            raise SweepError(f"cannot create the output folder {out.parent}: {exc.strerror or exc}") from None
        check_output_path(out, inputs=(study.source,))
    report = run_sweep(study, out, workers=workers, scheduler=scheduler, batch_size=batch_size,
                       force=force, progress=not quiet, log=say, complevel=complevel)
    if not report.reused:
        counts = ", ".join(f"{k} {v}" for k, v in report.status_counts.items())
        spots = f", {report.n_spots} spot check(s)" if report.n_spots else ""
        trust = ", ".join(f"{k} {v}" for k, v in report.trust_counts.items())
        say(f"wrote {out}: {report.n_points} points (status: {counts}; linearization against the coupled model: "
             f"{trust}){spots} in {report.timings['total']:.1f} s")
    if not no_plots:
        stem = result_stem(out)
        pngs = [out.parent / f"{stem}_{k}.png" for k in ("histories", "peaks")]
        if not report.reused or not all(p.exists() for p in pngs):
            try:
                paths = _plot(out, out.parent)
            except SweepError as exc:
                raise SweepError(f"{exc}; the result {out} is complete, re-run 'screening plot {out}' "
                                 "for the figures") from None
            for path in paths:
                say(f"wrote {path}")
    if report.n_failed_batches:
        say(f"warning: {report.n_failed_batches} batch(es) failed; their points have status task_failed "
             f"in {out}")
    return EXIT_OK


def _plot(result, out_dir, response="var"):
    """All figures of ``result`` into ``out_dir`` (none left behind on failure, one-line errors)."""
    from screening.report.figures import plot_result
    from screening.io.reader import damaged_data_error, open_result

    result = Path(result)
    with open_result(result) as ds:
        stem = result_stem(result)
        try:
            return plot_result(ds, stem, out_dir, response)
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(result, exc) from None
        except OSError as exc:                  # the PNG could not be written
            raise write_error(out_dir, exc) from None


@cli.command("plot", help="write PNG figures of a result file")
@click.argument("result")
@click.option("--out-dir", help="folder for the figures (default: next to the result; created if missing, "
                                "its parent must exist)")
@click.option("--response", type=Choice(["var", "sigma", "fraction"]), default="var",
              help="rotation drawn as its variance var_theta [rad2] (default), its standard deviation sigma_theta "
                   "[rad], or sigma_theta as a fraction of the slenderness angle atan(b/h)")
def cmd_plot(result, out_dir, response):
    from screening.io.errors import SweepError
    from screening.io.reader import open_result

    result = Path(result)
    open_result(result).close()                  # readable? (before touching the output folder)
    out_dir = Path(out_dir) if out_dir else result.parent
    if not out_dir.is_dir():
        if not out_dir.parent.is_dir() or out_dir.exists() or out_dir.is_symlink():
            raise SweepError(f"output folder {out_dir} does not exist and cannot be created here")
        try:
            out_dir.mkdir()
        except OSError as exc:
            raise SweepError(f"cannot create the output folder {out_dir}: {exc.strerror or exc}") from None
    if response == "fraction":
        with open_result(result) as ds:
            if "slenderness" not in ds.variables:
                raise SweepError(f"--response fraction: {result} does not store the slenderness angle")
    for path in _plot(result, out_dir, response):
        print(path)
    return EXIT_OK


@cli.command("fragility", help="probability of exceeding a rotation: netCDF + PNG fragility curves")
@click.argument("result")
@click.option("--threshold", type=POSITIVE_FLOAT, multiple=True,
              help="rotation threshold: in rad, or a fraction of the angle named by --relative-to; repeat it for "
                   "several limit states (one fragility model, a figure per limit state); required but with "
                   "--limit-state overturn")
@click.option("--relative-to", type=Choice(["slenderness", "theta_ul"]),
              help="threshold as a fraction of the slenderness angle atan(b/h) or of theta_ul")
@click.option("--method", type=Choice(["vanmarcke", "poisson"]), default="vanmarcke",
              help="up-crossing approximation (default vanmarcke)")
@click.option("--dim", help="swept intensity of the fragility curve and its lognormal fit (default: S0 or pga, "
                           "whichever is swept)")
@click.option("--out", help="netCDF file (default <result-stem>_fragility.nc next to the result; "
                            "its folder must exist); the PNG goes next to it")
@click.option("--im", type=Choice(["pga", "sa", "pgv", "avgsa", "rms", "arias", "s0"]),
              help="fit over an intensity measure of the input (RVT medians; screening.analysis.intensity) and "
                   "export the fits as CSV (a row per curve), pelicun CSV and OpenQuake NRML next to the netCDF "
                   "(docs/fragility.md)")
@click.option("--period", type=POSITIVE_FLOAT, help="oscillator period [s] of --im sa and --im avgsa")
@click.option("--modelling-dispersion", "modelling", type=DISPERSION,
              help="modelling dispersion beta_m [1], > 0 and <= 3, combined with each fitted beta by the square root of the sum of "
                   "squares (the fitted one kept as beta_fit)")
@click.option("--limit-state", type=Choice(["exceed", "overturn"]), default="exceed",
              help="exceed (default): |theta| beyond --threshold; overturn: the probability of overturning "
                   "(p_overturn of a study with [accuracy] or [fragility]), fitted over --im (default s0)")
def cmd_fragility(result, threshold, relative_to, method, dim, out, im, period, modelling, limit_state):
    if limit_state == "overturn":
        if threshold or relative_to is not None:
            raise click.UsageError("--threshold and --relative-to do not apply to --limit-state overturn "
                                   "(its threshold is atan(b/h))")
        return cli_records.fragility_over_im_command(result, (), None, method, dim, out,
                                                     im or ("sa" if period else "s0"), period, modelling, limit_state)
    if not threshold:
        raise click.UsageError("--threshold is required (unless --limit-state overturn)")
    threshold = sorted(threshold)
    if len(set(threshold)) < len(threshold):
        raise CommandError(f"--threshold: the same value given twice ({', '.join(f'{t:g}' for t in threshold)})")
    if im is not None or period is not None:
        return cli_records.fragility_over_im_command(result, threshold, relative_to, method, dim, out, im or "sa",
                                                     period, modelling)
    from screening.analysis.fragility import fragility_dataset, with_modelling_dispersion, STORED
    from screening.applications.im_fragility import default_dim, stack_limit_states, limit_state_name
    from screening.io.errors import SweepError
    from screening.io.reader import damaged_data_error, open_result
    from screening.io.writer import check_output_path

    result = Path(result)
    with open_result(result) as ds:
        grid = ds["status"].dims
        if dim is not None and dim not in grid:
            raise SweepError(f"--dim {dim!r} is not a swept dimension of {result} "
                             f"(swept: {', '.join(grid) or 'none'})")
        dim = dim or default_dim(grid) or "S0"
        out = check_output_path(out or result.with_name(f"{result_stem(result)}_fragility.nc"), inputs=(result,))
        refuse_collisions(out, fragility_outputs(out, [limit_state_name(t, relative_to) for t in threshold]
                                                 if len(threshold) > 1 else ()))
        try:
            frag = stack_limit_states([fragility_dataset(ds, t, relative_to, method, dim).load() for t in threshold],
                                      threshold, relative_to)
            flags = ds[[name for name in ("status", "sl_trust", "p_source") if name in ds.variables]].load()
            if frag.attrs.get("method") == STORED:          # the sweep's own answers: their p_source vouches
                flags = None
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(result, exc) from None
        except ValueError as exc:               # a threshold the result has no probabilities for
            raise CommandError(f"--threshold: {exc}") from None
    frag = with_modelling_dispersion(frag, modelling)
    stamp_fragility(frag, result, threshold=" --threshold ".join(f"{t:g}" for t in threshold),
                    relative_to=relative_to, modelling_dispersion=modelling)
    warnings = [] if dim in grid and frag.sizes[dim] >= 2 else [
        f"no fragility curve and no fit: {result} sweeps no intensity with two values or more (swept: "
        f"{', '.join(grid) or 'none'}); --dim names the swept intensity"]
    write_fragility_files(frag, out, fragility_figures(frag, out, dim, flags),
                          fit_files(frag, out) if "fit_median" in frag else (), warnings=warnings)
    p = frag["p_exceed"].values
    fit = lognormal_fit_text(frag, dim, frag["fit_median"].attrs.get("units", "") if "fit_median" in frag else "")
    say(f"P(exceed) over {p.size} point(s): min {np.nanmin(p):.3g}, max {np.nanmax(p):.3g}" + (f"; {fit}" if fit else ""))
    if "best_p_exceed" in frag:
        from screening.core.status import BestMethod

        source = frag["best_method"].values
        counts = ", ".join(f"{m.name} {int(np.sum(source == m))}" for m in BestMethod if np.any(source == m))
        best = frag["best_p_exceed"].values
        say(f"best estimates ([accuracy]): best_p_exceed min {np.nanmin(best):.3g}, max {np.nanmax(best):.3g}, "
             f"with the band best_p_exceed_low/high; from {counts}")
    return EXIT_OK


@cli.command("tradeoff", help="speed-accuracy trade study: SL vs condensed / coupled Monte Carlo "
                              "(screening.report.tradeoff)")
@click.argument("study")
@click.option("--out-dir", default="outputs", help="output directory (default: outputs)")
@click.option("--quiet", is_flag=True, help="no progress lines on stderr")
@click.option("--from-nc", is_flag=True, help="re-render reports from the saved netCDF instead of recomputing")
def cmd_tradeoff(study, out_dir, quiet, from_nc):
    from screening.report.tradeoff import rerender_reports, run_tradeoff
    from screening.applications.tradeoff_study import load_tradeoff_study
    from screening.report.tradeoff_text import summary_text
    from screening.sweep.config import StudyError

    try:
        parsed = load_tradeoff_study(study)
        announce_compilation(quiet or from_nc)
        if from_nc:
            ds, paths, rules = rerender_reports(parsed, out_dir)
        else:
            ds, paths, rules = run_tradeoff(parsed, out_dir, **({"progress": None} if quiet else {}))
    except StudyError as err:
        raise CommandError(str(err)) from None
    except FileNotFoundError as err:
        raise CommandError(f"--from-nc: {err}") from None
    except OSError as err:
        raise CommandError(f"cannot read the study file {study}: {err.strerror or err}") from None
    print(summary_text(parsed, ds, rules))
    print("wrote " + ", ".join(str(p) for p in paths.values()))
    return EXIT_OK


@cli.command("info", help="describe a result file (of run, simulate, cloud or fragility)")
@click.argument("result")
def cmd_info(result):
    from screening.report.text import describe
    from screening.io.reader import ResultError, damaged_data_error, open_result

    try:
        ds = open_result(result)
    except ResultError as exc:
        text = _describe_product(result)
        if text is None:
            raise exc from None
        print(printable(text))
        return EXIT_OK
    with ds:
        try:
            text = describe(ds, result)
        except RuntimeError as exc:             # netCDF/HDF5: damaged data chunks
            raise damaged_data_error(result, exc) from None
    print(printable(text))
    return EXIT_OK


def _describe_product(path):
    """:func:`~screening.report.text.describe_product` of the file at ``path`` (a file of ``simulate``,
    ``cloud`` or ``fragility``), or ``None`` when it is not one (or cannot be read)."""
    import xarray as xr

    from screening.report.text import describe_product

    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return describe_product(ds, path)
    except Exception:                               # noqa: BLE001 - not ours: the sweep reader's message stands
        return None


@cli.command("export", help="convert a zarr result (run --out RESULT.zarr) to the netCDF file a direct run writes, "
                             "or (--layout cdo) any result to a netCDF file laid out for CDO")
@click.argument("result")
@click.argument("out")
@click.option("--complevel", type=ZLIB_LEVEL, default="1",
              help="zlib level of the netCDF file: 1 (default, fastest) .. 9, 0 = uncompressed")
@click.option("--layout", type=Choice(["cf", "cdo"]), default="cf",
              help="cf (default): the netCDF file of a direct run, from a zarr result; cdo: time first, for CDO "
                   "(from a netCDF or zarr result; docs/outputs.md, 'Other tools')")
@click.option("--select", "selection", multiple=True, metavar="DIM=VALUE",
              help="--layout cdo: keep only the swept value of DIM nearest VALUE (a case by name or index); "
                   "repeatable; CDO reads at most 3 swept dimensions")
def cmd_export(result, out, complevel, layout, selection):
    import datetime as dt

    from screening.io import cdofile
    from screening.io.errors import ReadFailure, SweepError
    from screening.io.reader import open_result
    from screening.io.writer import check_output_path
    from screening.io.zarrfile import export_netcdf, is_zarr_store, store_problem

    result = Path(result)
    if layout == "cf" and selection:
        raise SweepError("--select applies to --layout cdo only")
    if layout == "cf" and not is_zarr_store(result):
        raise SweepError(f"{result}: not a zarr store (export converts the result of 'screening run --out "
                         "RESULT.zarr' to netCDF; --layout cdo converts any result)")
    # a screening result? (before writing anything; every chunk of a zarr store checked)
    problem = store_problem(result) if is_zarr_store(result) else None
    if problem:
        raise SweepError(f"cannot read {result}: {problem}; nothing written")
    ds = cdofile.open_source(result) if layout == "cdo" else open_result(result)
    try:
        selected = cdofile.parse_selection(selection, ds["status"].dims)
        out = check_output_path(out, inputs=(result,))
        tmp = temporary_for(out)
        now = dt.datetime.now(dt.timezone.utc).replace(microsecond=0).isoformat()
        options = "".join([" --layout cdo"] * (layout == "cdo") + [f" --select {item}" for item in selection])
        history = f"{now}: screening export {result} {out}{options} (screening {__version__})"
        try:
            if layout == "cdo":
                cdofile.export_cdo(ds, tmp, complevel, history, selected)
            else:
                export_netcdf(result, tmp, complevel, history)
            _publish(tmp, out)
        except BaseException as exc:
            tmp.unlink(missing_ok=True)
            if isinstance(exc, ReadFailure):
                raise SweepError(f"cannot read {result}: {exc}; nothing written") from None
            if isinstance(exc, (OSError, RuntimeError)):    # netCDF reports a failed write as RuntimeError
                raise write_error(out, exc) from None
            raise
    finally:
        ds.close()
    print(out)
    return EXIT_OK


# registers simulate, fit-excitation, cloud on the group, after the commands above (their order in --help)
@cli.command("risk", help="annual frequency and probability over a time span of overturning and of each limit "
                           "state at a site: each object's fragility convolved with the site's hazard curve")
@click.argument("result", type=click.Path())
@click.option("--hazard", required=True, type=click.Path(),
              help="the site's hazard curve: OpenQuake's hazard-curve CSV, or a table 'PGA [g], annual_rate [1/yr]'")
@click.option("--years", type=POSITIVE_FLOAT, default=50.0, show_default=True,
              help="time span [yr] of the probabilities (Poisson occurrences)")
@click.option("--site", type=click.IntRange(min=0), help="the row of an OpenQuake hazard file with several sites")
@click.option("--threshold", type=float, multiple=True,
              help="with a sweep result: a limit state |theta| > X besides overturning (repeatable)")
@click.option("--relative-to", type=Choice(["slenderness", "theta_ul"]), default=None,
              help="--threshold is a fraction of this angle")
@click.option("--im", type=Choice(["pga", "sa"]), default="pga", show_default=True,
              help="with a sweep result: the intensity measure the fragilities are fitted over")
@click.option("--period", type=POSITIVE_FLOAT, help="oscillator period [s] of --im sa")
@click.option("--out", type=click.Path(), help="the risk CSV (default RESULT_risk.csv; the figure beside it)")
def cmd_risk(result, hazard, years, site, threshold, relative_to, im, period, out):
    import xarray as xr

    from screening.applications.im_fragility import IMS
    from screening.applications.risk import (HazardError, hazard_levels, limit_state_fragilities, read_hazard,
                                             risk_table, write_risk_csv)
    from screening.report.risk_figures import plot_risk
    from screening.io.reader import ResultError, open_result
    from screening.io.writer import check_output_path

    result = Path(result)
    try:
        curve = read_hazard(hazard, site)
    except HazardError as exc:
        raise CommandError(str(exc)) from None
    out = check_output_path(Path(out) if out else result.with_name(f"{result_stem(result)}_risk.csv"),
                            inputs=(result, Path(hazard)))
    try:
        opened = open_result(result)
    except ResultError as exc:          # not a sweep: a fragility file (of fragility or cloud) then
        try:
            opened = xr.open_dataset(result, engine="netcdf4")
        except Exception:               # noqa: BLE001 - neither: the sweep reader's message stands
            raise exc from None
        if "fit_median" not in opened:
            opened.close()
            raise CommandError(f"{result}: neither a sweep result nor a fragility file (no fit_median)") from None
    with opened as ds:
        is_fragility = "fit_median" in ds
        try:        # the hazard's IMT and units against the fragility's, before any work
            if is_fragility:
                name = ds["fit_median"].attrs.get("intensity", "")
                period_of = ds[name].attrs.get("period", "") if name in ds else ""
                hazard_levels(curve, name, ds["fit_median"].attrs.get("units", ""), period_of, hazard)
            else:
                if im == "sa" and period is None:
                    raise CommandError("--im sa needs --period SECONDS")
                hazard_levels(curve, IMS[im][0], IMS[im][1], period if im == "sa" else "", hazard)
        except HazardError as exc:
            raise CommandError(str(exc)) from None
        if is_fragility:
            frags = [ds.load()]
        else:
            frags = limit_state_fragilities(ds.load(), im, period, threshold, relative_to)
            if not frags:
                raise CommandError(f"{result}: no p_overturn stored (run the study with [accuracy] or [fragility]) "
                                   "and no --threshold: nothing to convolve")
    rows = []
    for frag in frags:
        rows += risk_table(frag, curve, years, hazard)
    rows.sort(key=lambda row: (not np.isfinite(row["annual_rate"]), -np.nan_to_num(row["annual_rate"])))
    for rank, row in enumerate(rows, start=1):
        row["rank"] = rank if np.isfinite(row["annual_rate"]) else ""
    rated = [r for r in rows if np.isfinite(r["annual_rate"])]
    figure = out.with_suffix(".png")
    write_file_set([("risk CSV", out, lambda path: write_risk_csv(rows, path))]
                   + ([("risk figure", figure, lambda path: plot_risk(rows, path, f"{result.name} at {curve.source}",
                                                                      years))] if rated else []))
    say(f"risk of {len(rated)} of {len(rows)} object/limit-state pair(s) over {curve.source}" + (
        f"; highest: {rated[0]['object']} {rated[0]['limit_state']} {rated[0]['annual_rate']:.3g} /yr, "
        f"P({years:g} yr) = {rated[0]['probability']:.3g} ({100 * rated[0]['share_outside_vouched']:.0f} % of it "
        "from outside the vouched range)" if rated else ""))
    return EXIT_OK


@cli.command("report", help="one self-contained HTML page of a collection: ranked by risk at a site (--hazard) or by "
                             "median capacity, each object's curves with the points that vouch for them, which model "
                             "answered each point and how far to trust it, the inputs")
@click.argument("result", type=click.Path())
@click.option("--hazard", type=click.Path(),
              help="the site's hazard curve (as `risk`): OpenQuake's hazard-curve CSV, or 'PGA [g], annual_rate [1/yr]'")
@click.option("--years", type=POSITIVE_FLOAT, default=50.0, show_default=True,
              help="time span [yr] of the probabilities (Poisson occurrences)")
@click.option("--site", type=click.IntRange(min=0), help="the row of an OpenQuake hazard file with several sites")
@click.option("--im", type=Choice(["pga", "sa"]), default="pga", show_default=True,
              help="the intensity measure the fragilities are fitted over")
@click.option("--period", type=POSITIVE_FLOAT, help="oscillator period [s] of --im sa")
@click.option("--out", type=click.Path(), help="the HTML page (default RESULT_report.html)")
def cmd_report(result, hazard, years, site, im, period, out):
    from screening.applications.im_fragility import IMS
    from screening.applications.risk import HazardError, hazard_levels, limit_state_fragilities, read_hazard
    from screening.io.reader import ResultError, open_result
    from screening.io.writer import check_output_path
    from screening.report.collection_report import write_report

    result = Path(result)
    if im == "sa" and period is None:
        raise CommandError("--im sa needs --period SECONDS")
    try:
        curve = read_hazard(hazard, site) if hazard else None
        if curve is not None:
            hazard_levels(curve, IMS[im][0], IMS[im][1], period if im == "sa" else "", hazard)
    except HazardError as exc:
        raise CommandError(str(exc)) from None
    out = check_output_path(Path(out) if out else result.with_name(f"{result_stem(result)}_report.html"),
                            inputs=(result, *((Path(hazard),) if hazard else ())))
    try:
        opened = open_result(result)
    except ResultError as exc:
        raise CommandError(str(exc)) from None
    with opened as ds:
        ds = ds.load()
    thresholds = ds["threshold"].values.tolist() if "p_exceed" in ds and "threshold" in ds.coords else []
    relative_to = ds["p_exceed"].attrs.get("relative_to") or None if thresholds else None
    frags = limit_state_fragilities(ds, im, period, thresholds, relative_to)
    if not frags:
        raise CommandError(f"{result}: no p_overturn or p_exceed stored (run the study with [accuracy] or "
                           "[fragility]): nothing to report")
    objects = write_report(ds, out, result.name, curve, years, frags, hazard or "hazard")
    say(f"wrote {out}: {len(objects)} object(s)" + (f", highest risk: {objects[0]['name']}" if curve is not None
                                                     else f", lowest median capacity: {objects[0]['name']}"
                                                     if objects else ""))
    return EXIT_OK


from screening.cli import records as cli_records  # noqa: E402,I001


if __name__ == "__main__":               # python -m screening.cli: the commands live on the imported module
    from screening.cli import main as _main
    sys.exit(_main())
