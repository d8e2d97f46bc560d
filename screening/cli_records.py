"""Commands of the engineer-facing record tools, registered on :data:`screening.cli.cli`.

``screening simulate RECORD --study STUDY.toml --out RESULT.nc`` — deterministic response of the
study's block on its bed to one record (netCDF + PNG).
"""

from __future__ import annotations

from pathlib import Path

import click

from screening.cli import (EXIT_OK, WORKER_COUNT, CommandError, _Choice, _not_with, _say, _write_error,
                           _stem, announce_compilation, cli, lognormal_fit_text, stamp_fragility,
                           write_fragility_files)

#: Largest record set a cloud analysis runs in process by default (larger sets: 2 local workers).
SERIAL_RECORDS = 4


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


def _fit_files(frag, out):
    """The fits of ``frag`` as CSV and (where OpenQuake knows the IM) NRML next to ``out``."""
    from screening.analysis.im_fragility import write_csv, write_nrml

    return [("CSV", out.with_suffix(".csv"), lambda path: write_csv(frag, path)),
            ("NRML", out.with_suffix(".xml"), lambda path: write_nrml(frag, path))]


def _read(record, dt, units):
    from screening.records import read_record

    try:
        return read_record(record, dt=dt, units=units)
    except (ValueError, OSError) as exc:
        raise CommandError(f"cannot read record {record}: {exc}") from None


@cli.command("simulate", help="response of the study's block and bed to one ground-motion record "
                              "(netCDF + PNG)")
@click.argument("record")
@click.option("--study", required=True, help="study file (TOML) giving the block and the bed (its excitation, "
                                             "if any, is not used)")
@click.option("--out", help="netCDF file (default <record-stem>_simulation.nc in the current folder; its folder "
                            "must exist); the PNG goes next to it")
@click.option("--model", type=_Choice(["coupled", "condensed"]), default="coupled",
              help="coupled (eqs. 7-8, default) or condensed (eq. 22, the study's condensation)")
@click.option("--dt", type=float, help="time step [s] of a one-column record")
@click.option("--units", type=_Choice(["g", "m/s2", "cm/s2"]),
              help="acceleration units of a text record (default m/s2; AT2 files: from the header)")
@click.option("--scale", type=float, default=1.0, help="factor on the record's accelerations (default 1)")
@click.option("--case", help="case of the study (required when it has several)")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE",
              help="value of a swept block/bed parameter (repeatable)")
@click.option("--theta0", type=float, default=0.0, help="initial rotation [rad]")
@click.option("--theta-dot0", type=float, default=0.0, help="initial angular velocity [rad/s]")
@click.option("--t-end", type=float, help="end time [s] (default: the record's duration)")
@click.option("--no-plots", is_flag=True, help="do not write the PNG")
def cmd_simulate(record, study, out, model, dt, units, scale, case, sets, theta0, theta_dot0, t_end, no_plots):
    from screening.records import Record
    from screening.report.record_figures import plot_simulation
    from screening.solvers.simulate import simulate
    from screening.workflow.records_study import block_and_foundation, load_record_study
    from screening.workflow.writer import check_output_path

    rec = _read(record, dt, units)
    if scale != 1.0:
        rec = Record(rec.acceleration * scale, rec.dt, rec.name, rec.source, rec.units_in)
    st, _ = load_record_study(study)
    block, foundation, chosen = block_and_foundation(st, case, _overrides(sets))
    out = check_output_path(out or Path(f"{rec.name}_simulation.nc"))
    announce_compilation()
    try:
        ds = simulate(block, foundation, rec, model=model, theta0=theta0, theta_dot0=theta_dot0,
                      condensation=chosen.condensation if model == "condensed" else "paper", t_end=t_end)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    ds.attrs.update(study=str(study), record_scale=scale,
                    history=f"screening simulate {record} --study {study} --model {model}")
    tmp = out.with_name(out.name + ".tmp")
    png_path = out.with_suffix(".png")
    try:
        ds.to_netcdf(tmp, engine="netcdf4", encoding={c: {"_FillValue": None} for c in ds.coords})
        if not no_plots:
            plot_simulation(ds, png_path)
        tmp.replace(out)
    except (OSError, RuntimeError) as exc:
        tmp.unlink(missing_ok=True)
        raise _write_error(out, exc) from None
    print(out)
    if not no_plots:
        print(png_path)
    over = (f"overturned at t = {float(ds['overturning_time']):.3f} s" if bool(ds["overturned"])
            else f"peak |theta| = {float(ds['peak_abs_theta']):.4g} rad "
                 f"({float(ds['peak_abs_theta']) / float(ds['slenderness']):.3f} of atan(b/h))")
    _say(f"{rec.name}: PGA {rec.pga / 9.80665:.3f} g, {model} model: {ds.attrs['status']}; {over}")
    return EXIT_OK


def fragility_over_im_command(result, threshold, relative_to, method, dim, out, im, period, limit_state="exceed"):
    """``screening fragility RESULT --im IM``: netCDF, PNG, CSV and (where OpenQuake knows the IM) NRML;
    ``limit_state="overturn"``: of the probability of overturning."""
    from screening.analysis.im_fragility import fragility_over_im
    from screening.report.record_figures import plot_im_fragility
    from screening.workflow.reader import open_result
    from screening.workflow.writer import check_output_path

    result = Path(result)
    with open_result(result) as ds:
        stem = "overturn" if limit_state == "overturn" else "fragility"
        out = check_output_path(out or result.with_name(f"{_stem(result)}_{stem}_{im}.nc"))
        try:
            frag, warnings = fragility_over_im(ds.load(), threshold, im, dim, relative_to, method, period,
                                               limit_state=limit_state)
        except (ValueError, KeyError) as exc:
            raise CommandError(str(exc).strip("'\"")) from None
    stamp_fragility(frag, result, threshold=threshold, im=im, relative_to=relative_to, period=period,
                    limit_state=None if limit_state == "exceed" else limit_state)
    write_fragility_files(frag, out, lambda path: plot_im_fragility(frag, path), _fit_files(frag, out), warnings)
    fit = lognormal_fit_text(frag, frag.attrs["intensity_variable"], frag["median"].attrs["units"])
    if fit:
        _say(fit)
    return EXIT_OK


@cli.command("fit-excitation", help="estimate S0, omega_g, zeta_g, T1, T2 from a record and print the "
                                    "[excitation] table of a study")
@click.argument("record")
@click.option("--dt", type=float, help="time step [s] of a one-column record")
@click.option("--units", type=_Choice(["g", "m/s2", "cm/s2"]),
              help="acceleration units of a text record (default m/s2; AT2 files: from the header)")
@click.option("--kind", type=_Choice(["kanai_tajimi", "white"]), default="kanai_tajimi",
              help="excitation model (default kanai_tajimi)")
@click.option("--cutoff", type=float, help="band limit [rad/s] of the study's synthesis (required for white)")
def cmd_fit_excitation(record, dt, units, kind, cutoff):
    from screening.analysis.fit_excitation import excitation_table, fit_excitation

    rec = _read(record, dt, units)
    try:
        fit = fit_excitation(rec, kind=kind, cutoff=cutoff)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    print(excitation_table(fit))
    return EXIT_OK


@cli.command("cloud", help="cloud analysis: run the records of a study through the coupled model and fit a "
                           "fragility over an intensity measure (netCDF, PNG, CSV, NRML)")
@click.argument("study")
@click.option("--out", help="netCDF file (default outputs/<study-stem>.nc, folder created if missing)")
@click.option("--case", help="case of the study (required when it has several)")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE",
              help="value of a swept block/bed parameter (repeatable)")
@click.option("--workers", type=WORKER_COUNT, callback=_not_with("scheduler"),
              help=f"local dask worker processes, one task per record; 0: in this process (default: 0 up to "
                   f"{SERIAL_RECORDS} records, else 2)")
@click.option("--scheduler", metavar="ADDRESS", callback=_not_with("workers"),
              help="use an existing dask cluster: scheduler address or scheduler JSON file")
@click.option("--quiet", is_flag=True, help="no progress lines")
def cmd_cloud(study, out, case, sets, workers, scheduler, quiet):
    import contextlib

    from screening.workflow.cloud import load_cloud_study, plot_cloud, run_cloud
    from screening.workflow.execution import dask_client
    from screening.workflow.interrupt import shielded
    from screening.workflow.writer import check_output_path

    cloud = load_cloud_study(study)
    if out is None:
        out = Path("outputs") / f"{Path(study).stem}.nc"
        out.parent.mkdir(exist_ok=True)
    out = check_output_path(out)
    announce_compilation(quiet)
    if workers is None and not scheduler:
        workers = 0 if len(cloud.files) <= SERIAL_RECORDS else 2
    in_process = not scheduler and workers == 0
    with contextlib.ExitStack() as stack:
        client = None
        if not in_process:
            stack.enter_context(shielded())
            client = stack.enter_context(dask_client(workers, scheduler))
        ds, warnings = run_cloud(cloud, case, _overrides(sets), progress=None if quiet else _say, client=client)
    frag = ds[["median", "beta", "fit_flag", "threshold_rad", ds.attrs["intensity_variable"]]]
    write_fragility_files(ds, out, lambda path: plot_cloud(ds, path), _fit_files(frag, out), warnings)
    n = ds.sizes["record"]
    _say(f"{n} records: {int(ds['exceed'].sum())} exceed, {int(ds['overturned'].sum())} overturned; "
         f"fragility over {ds.attrs['intensity_variable']}: median {float(ds['median']):.4g} "
         f"{ds['median'].attrs['units']}, beta {float(ds['beta']):.3f}")
    return EXIT_OK
