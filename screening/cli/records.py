"""Commands of the engineer-facing record tools, registered on the group :data:`screening.cli.base.cli`.

``screening simulate RECORD --study STUDY.toml --out RESULT.nc`` — deterministic response of the
study's block on its bed to one record (netCDF + PNG).
"""

from __future__ import annotations

from pathlib import Path

import click

from screening.core.atomicfile import atomic_path
from screening.solvers import mc_registry
from screening.cli._common import Choice, not_with, result_stem, say, write_error
from screening.cli.base import (EXIT_OK, POSITIVE_FLOAT, WORKER_COUNT, CommandError, announce_compilation, cli,
                                fragility_figures, lognormal_fit_text, fit_files, stamp_fragility, write_file_set,
                                write_fragility_files, fragility_outputs, refuse_collisions)

__all__ = []

#: Largest record set a cloud analysis runs in process by default (larger sets: 2 local workers).
SERIAL_RECORDS = 4
UNITS_HELP = ("acceleration units of the record (required for a text record unless a header line states them, "
              "e.g. 'units: g' or 'acc [g]'; AT2: from its header, must agree)")


def _overrides(pairs):
    out = {}
    for text in pairs:
        key, sep, value = text.partition("=")
        if not sep:
            raise CommandError(f"--set {text!r}: expected NAME=VALUE")
        try:
            out[key.strip()] = float(value)
        except ValueError:
            raise CommandError(f"--set {text!r}: {value!r} is not a number") from None
    return out


def _output_folder(out):
    """Create the default output folder (``outputs/``) of ``out``; one line if it cannot be."""
    try:
        out.parent.mkdir(exist_ok=True)
    except OSError as exc:
        raise CommandError(f"cannot create the output folder {out.parent}: {exc.strerror or exc}") from None


def _read(record, dt, units):
    from screening.core.records import read_record

    try:
        return read_record(record, dt=dt, units=units, option="--units")
    except (ValueError, OSError) as exc:
        raise CommandError(_record_error(record, exc)) from None


def _record_error(record, exc):
    """One line for a record that cannot be read, naming its file once (the reader's message may already
    name it, as a ``path: ...`` prefix or inside the text)."""
    text = str(exc)
    for spelling in dict.fromkeys((str(record), str(Path(record)))):
        if text.startswith(f"{spelling}: "):
            return f"cannot read record {spelling}: {text[len(spelling) + 2:]}"
        if spelling in text:
            return f"cannot read record: {text}"
    return f"cannot read record {record}: {text}"


@cli.command("simulate", help="response of the study's block and bed to one ground-motion record "
                              "(netCDF + PNG)")
@click.argument("record")
@click.option("--study", required=True, help="study file (TOML) giving the block and the bed (its excitation, "
                                             "if any, is not used)")
@click.option("--out", help="netCDF file (default outputs/<record-stem>_simulation.nc, folder created if missing; "
                            "the folder of an explicit path must exist); the PNG goes next to it")
@click.option("--model", type=Choice(mc_registry.names), default="coupled",
              help="coupled (eqs. 7-8, default), condensed (eq. 22, the study's condensation) or stiff_bed "
                   "(rigid block on the quasi-static contact, docs/stiff_bed.md)")
@click.option("--dt", type=float, help="time step [s] of a one-column record (checked against a time column "
                                      "or an AT2 header)")
@click.option("--units", type=Choice(["g", "m/s2", "cm/s2"]), help=UNITS_HELP)
@click.option("--scale", type=float, default=1.0, help="factor on the record's accelerations (default 1)")
@click.option("--case", help="case of the study (required when it has several)")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE",
              help="value of a swept block/bed parameter (repeatable)")
@click.option("--theta0", type=float, default=0.0, help="initial rotation [rad]")
@click.option("--theta-dot0", type=float, default=0.0, help="initial angular velocity [rad/s]")
@click.option("--t-end", type=float, help="end time [s] (default: the record's duration)")
@click.option("--no-plots", is_flag=True, help="do not write the PNG")
@click.option("--no-vertical", is_flag=True, help="leave out the record's vertical component (default: a "
                                                   "two-component record drives the block with both)")
def cmd_simulate(record, study, out, model, dt, units, scale, case, sets, theta0, theta_dot0, t_end, no_plots,
                 no_vertical):
    from screening.core.records import check_scale
    from screening.report.record_figures import plot_simulation
    from screening.solvers.simulate import simulate, simulation_times
    from screening.applications.records_study import block_and_foundation, load_record_study
    from screening.io.writer import check_output_path

    try:
        scale = check_scale(scale, "--scale", signed=True)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    rec = _read(record, dt, units)
    if scale != 1.0:
        rec = rec.scaled(scale)
    try:
        simulation_times(rec, t_end, None, "--t-end")
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    st, _ = load_record_study(study)
    block, foundation, chosen = block_and_foundation(st, case, _overrides(sets))
    if out is None:                         # like run and cloud: outputs/, created if missing
        out = Path("outputs") / f"{rec.name}_simulation.nc"
        _output_folder(out)
    out = check_output_path(out, inputs=(record, study))
    if not no_plots:
        refuse_collisions(out, [("PNG", out.with_suffix(".png"))])
    announce_compilation()
    try:
        ds = simulate(block, foundation, rec, model=model, theta0=theta0, theta_dot0=theta_dot0,
                      condensation=chosen.condensation if mc_registry.get(model).uses_condensation else "paper",
                      t_end=t_end, vertical=not no_vertical)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    ds.attrs.update(study=str(study), record_scale=scale,
                    history=f"screening simulate {record} --study {study} --model {model}"
                            + (" --no-vertical" if no_vertical else ""))
    png_path = out.with_suffix(".png")
    try:
        with atomic_path(out) as tmp:                   # never through a link planted at out or beside it
            ds.to_netcdf(tmp, engine="netcdf4", encoding={c: {"_FillValue": None} for c in ds.coords})
            if not no_plots:
                plot_simulation(ds, png_path)
    except (OSError, RuntimeError) as exc:
        raise write_error(out, exc) from None
    print(out)
    if not no_plots:
        print(png_path)
    over = (f"overturned at t = {float(ds['overturning_time']):.3f} s" if bool(ds["overturned"])
            else f"peak |theta| = {float(ds['peak_abs_theta']):.4g} rad "
                 f"({float(ds['peak_abs_theta']) / float(ds['slenderness']):.3f} of atan(b/h))")
    say(f"{rec.name}: PGA {rec.pga / 9.80665:.3f} g, {model} model: {ds.attrs['status']}; {over}")
    if rec.vertical is not None:
        lift = " (g + a_v < 0: the block lifts off)" if bool(ds.get("lift_off", False)) else ""
        say(f"vertical component: {ds.attrs['vertical_ground_motion']}{lift}")
    return EXIT_OK


def fragility_over_im_command(result, threshold, relative_to, method, dim, out, im, period, modelling=None,
                              limit_state="exceed"):
    """``screening fragility RESULT --im IM``: netCDF, PNG, CSV and (where OpenQuake knows the IM) NRML;
    ``limit_state="overturn"``: of the probability of overturning (``threshold`` is then empty).

    The options are checked before the result is read; the files are written as one set
    (:func:`~screening.cli.base.write_fragility_files`), the paths printed on stdout and the
    lognormal fit summarised on stderr.

    Parameters
    ----------
    result : str or path-like
        The result file (netCDF or zarr) of a sweep.
    threshold : sequence of float
        The rotation thresholds [rad] (or fractions of the angle named by ``relative_to`` [-]), one
        limit state each; empty for ``limit_state="overturn"``.
    relative_to : {None, "slenderness", "theta_ul"}
        What ``threshold`` is a fraction of.
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation.
    dim : str or None
        The swept intensity dimension (default: ``S0`` or ``pga``, whichever is swept).
    out : str or None
        The netCDF file (default ``<result-stem>_fragility_<im>.nc`` next to the result).
    im : {"pga", "sa", "pgv", "avgsa", "rms", "arias", "s0"}
        The intensity measure the curves are fitted over (``pga`` [m s-2], ``pgv`` [m s-1], ...).
    period : float or None
        The oscillator period [s] of ``sa`` and ``avgsa``, in ``SA_PERIOD_RANGE`` (1e-3..100 s) of
        :mod:`screening.core.limits`.
    modelling : float, optional
        A modelling dispersion ``beta_m`` [-] combined with each fitted ``beta`` (square root of
        the sum of squares).
    limit_state : {"exceed", "overturn"}, default "exceed"
        Exceeding the thresholds, or overturning.

    Returns
    -------
    int
        :data:`~screening.cli.base.EXIT_OK` (0).

    Raises
    ------
    screening.cli.base.CommandError
        A bad option or a result the fit cannot use (one line, exit status 2 in :func:`screening.cli.main`).

    References
    ----------
    .. [1] screening documentation, "Fragility: curves, formats, trust flags and multiple-stripe fits",
       docs/fragility.md.
    .. [2] [baker2015] in the bibliography, ``docs/bibliography.md``.
    """
    from screening.analysis.fragility import with_modelling_dispersion
    from screening.applications.im_fragility import fragility_over_im, stack_limit_states, limit_state_name
    from screening.io.reader import open_result
    from screening.io.writer import check_output_path

    if period is not None:
        from screening.core.validation import check_scalar
        from screening.core import limits

        low, high = limits.SA_PERIOD_RANGE
        try:
            check_scalar("--period", period, lower=low, lower_inclusive=True, upper=high, upper_inclusive=True)
        except ValueError as exc:
            raise CommandError(str(exc)) from None
    result = Path(result)
    with open_result(result) as ds:
        stem = "overturn" if limit_state == "overturn" else "fragility"
        out = check_output_path(out or result.with_name(f"{result_stem(result)}_{stem}_{im}.nc"), inputs=(result,))
        refuse_collisions(out, fragility_outputs(out, [limit_state_name(t, relative_to) for t in threshold]
                                                 if len(threshold) > 1 else ()))
        try:
            ds = ds.load()
            frags, warnings = [], []
            for t in (threshold if limit_state == "exceed" else (None,)):
                one, said = fragility_over_im(ds, t, im, dim, relative_to, method, period, limit_state=limit_state)
                frags.append(one)
                warnings += [w for w in said if w not in warnings]
            frag = stack_limit_states(frags, threshold, relative_to) if limit_state == "exceed" else frags[0]
        except (ValueError, KeyError) as exc:
            raise CommandError(str(exc).strip("'\"")) from None
        flags = ds[[name for name in ("status", "sl_trust", "p_source") if name in ds.variables]].load() \
            if "status" in ds.variables else None
    frag = with_modelling_dispersion(frag, modelling)
    stamp_fragility(frag, result, threshold=" --threshold ".join(f"{t:g}" for t in threshold) or None, im=im,
                    relative_to=relative_to, period=period, modelling_dispersion=modelling,
                    limit_state=None if limit_state == "exceed" else limit_state)
    write_fragility_files(frag, out, fragility_figures(frag, out, frag.attrs["intensity_dim"], flags),
                          fit_files(frag, out), warnings)
    fit = lognormal_fit_text(frag, frag.attrs["intensity_variable"], frag["fit_median"].attrs["units"])
    if fit:
        say(fit)
    return EXIT_OK


@cli.command("fit-excitation", help="estimate S0, omega_g, zeta_g, T1, T2 from a record and print the "
                                    "[excitation] table of a study")
@click.argument("record")
@click.option("--dt", type=float, help="time step [s] of a one-column record (checked against a time column "
                                      "or an AT2 header)")
@click.option("--units", type=Choice(["g", "m/s2", "cm/s2"]), help=UNITS_HELP)
@click.option("--kind", type=Choice(["kanai_tajimi", "white"]), default="kanai_tajimi",
              help="excitation model (default kanai_tajimi)")
@click.option("--cutoff", type=POSITIVE_FLOAT, help="band limit [rad/s] of the study's synthesis (required for white)")
@click.option("--figure", help="PNG of the fit: the record's Husid curve and spectrum against the fitted model's "
                               "(its folder must exist)")
def cmd_fit_excitation(record, dt, units, kind, cutoff, figure):
    from screening.applications.fit_excitation import excitation_table, fit_excitation
    from screening.io.writer import check_output_path

    if figure is not None:
        figure = check_output_path(figure, inputs=(record,))
    rec = _read(record, dt, units)
    try:
        fit = fit_excitation(rec, kind=kind, cutoff=cutoff)
    except (ValueError, ArithmeticError) as exc:
        raise CommandError(f"cannot fit {record}: {exc}") from None
    if figure is not None:
        from screening.report.record_figures import plot_excitation_fit

        write_file_set([("PNG", figure, lambda path: plot_excitation_fit(rec, fit, path))])
    print(excitation_table(fit))
    for flag in fit["flags"]:
        say(f"warning: {flag}")
    return EXIT_OK


@cli.command("cloud", help="cloud analysis: run the records of a study through the coupled model and fit a "
                           "fragility over an intensity measure (netCDF, PNG, CSV, NRML)")
@click.argument("study")
@click.option("--out", help="netCDF file (default outputs/<study-stem>.nc, folder created if missing)")
@click.option("--case", help="case of the study (required when it has several)")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE",
              help="value of a swept block/bed parameter (repeatable)")
@click.option("--workers", type=WORKER_COUNT, callback=not_with("scheduler"),
              help=f"local dask worker processes, one task per record; 0: in this process (default: 0 up to "
                   f"{SERIAL_RECORDS} records, else 2)")
@click.option("--scheduler", metavar="ADDRESS", callback=not_with("workers"),
              help="use an existing dask cluster: scheduler address or scheduler JSON file")
@click.option("--units", type=Choice(["g", "m/s2", "cm/s2"]),
              help="acceleration units of the study's text records (as [records] units; both given: must agree)")
@click.option("--quiet", is_flag=True, help="no progress lines")
@click.option("--no-vertical", is_flag=True, help="leave out the records' vertical components (as [records] "
                                                   "vertical = false)")
def cmd_cloud(study, out, case, sets, workers, scheduler, units, quiet, no_vertical):
    import contextlib

    from screening.report.record_figures import plot_cloud, plot_stripes
    from screening.applications.cloud import (load_cloud_study, read_cloud_records, run_cloud, run_stripes,
                                              write_demand_csv)
    from screening.sweep.execution import dask_client
    from screening.sweep.interrupt import shielded
    from screening.io.writer import check_output_path

    cloud = load_cloud_study(study, units, vertical=not no_vertical)
    records = read_cloud_records(cloud)                # every record checked before any work
    if out is None:
        out = Path("outputs") / f"{Path(study).stem}.nc"
        _output_folder(out)
    out = check_output_path(out, inputs=(study, *cloud.files))
    refuse_collisions(out, [("PNG", out.with_suffix(".png")), ("demand CSV", out.with_name(f"{out.stem}_demand.csv")),
                            *fragility_outputs(out)[1:]])
    announce_compilation(quiet)
    if workers is None and not scheduler:
        workers = 0 if len(cloud.files) * max(len(cloud.levels), 1) <= SERIAL_RECORDS else 2
    in_process = not scheduler and workers == 0
    run = run_stripes if cloud.levels else run_cloud
    with contextlib.ExitStack() as stack:
        client = None
        if not in_process:
            stack.enter_context(shielded())
            client = stack.enter_context(dask_client(workers, scheduler))
        ds, warnings = run(cloud, case, _overrides(sets), progress=None if quiet else say, client=client,
                           records=records)
    frag = ds[["fit_median", "beta", "fit_flag", "threshold_rad", ds.attrs["intensity_variable"]]]
    demand = ("demand CSV", out.with_name(f"{out.stem}_demand.csv"), lambda path: write_demand_csv(ds, path))
    if cloud.levels:
        write_fragility_files(ds, out, [("PNG", out.with_suffix(".png"), lambda path: plot_stripes(ds, path))],
                              [demand, *fit_files(frag, out)], warnings)
        say(f"{ds.sizes['level']} stripes x {ds.sizes['record']} records: {int(ds['n_exceed'].sum())} of "
             f"{int(ds['n_used'].sum())} runs exceed; fragility over {ds.attrs['intensity_variable']}: median "
             f"{float(ds['fit_median']):.4g} +- {float(ds['fit_median_se']):.2g} {ds['fit_median'].attrs['units']}, "
             f"beta {float(ds['beta']):.3f} +- {float(ds['beta_se']):.3f} (standard errors)")
        return EXIT_OK
    write_fragility_files(ds, out, [("PNG", out.with_suffix(".png"), lambda path: plot_cloud(ds, path))],
                          [demand, *fit_files(frag, out)], warnings)
    n = ds.sizes["record"]
    say(f"{n} records: {int(ds['exceed'].sum())} exceed, {int(ds['overturned'].sum())} overturned; "
         f"fragility over {ds.attrs['intensity_variable']}: median {float(ds['fit_median']):.4g} "
         f"{ds['fit_median'].attrs['units']}, beta {float(ds['beta']):.3f}")
    return EXIT_OK
