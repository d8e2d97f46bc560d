"""What the commands of the ``screening`` parser share: the click group, the option types, the
one-line errors and the files a fragility writes (:mod:`screening.cli` and :mod:`screening.cli.records`
register their commands on :data:`cli`)."""

from __future__ import annotations

import os
from pathlib import Path

import click
import numpy as np

from screening._version import __version__
from screening.core.atomicfile import publish as _publish
from screening.cli._common import say, temporary_for, write_error
from screening import __version__
from screening.core.limits import MAX_MODELLING_DISPERSION

__all__ = []

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class CommandError(Exception):
    """A user error found by a command (not by the parser): one line, exit status 2."""


# ----------------------------------------------------------------------------- option types
class _Checked(click.ParamType):
    """An option type from a function ``parse(text)`` raising ``ValueError(message)``."""

    def __init__(self, name, parse):
        self.name, self.parse = name, parse

    def convert(self, value, param, ctx):
        try:
            return self.parse(str(value))
        except ValueError as exc:
            self.fail(str(exc), param, ctx)


def _integer_in(low, high=None):
    """Parser of an integer ``>= low`` (and ``<= high``) for :class:`_Checked`."""
    allowed = f"an integer >= {low}" if high is None else f"an integer in {low}..{high}"

    def parse(text):
        try:
            value = int(text)
        except ValueError:
            value = low - 1
        if value < low or (high is not None and value > high):
            raise ValueError(f"must be {allowed} (got {text!r})")
        return value
    return parse


def _positive_float(text):
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"must be a finite number > 0 (got {text!r})")
    return value


def _dispersion(text):
    value = _positive_float(text)
    if value > MAX_MODELLING_DISPERSION:
        raise ValueError(f"must be a number > 0 and <= {MAX_MODELLING_DISPERSION:g} (got {text!r})")
    return value


def _zlib_level(text):
    if text not in [str(i) for i in range(10)]:
        raise ValueError(f"must be an integer in 0..9 (got {text!r})")
    return int(text)


#: Most local worker processes a command starts.
MAX_WORKERS = 256
POSITIVE_INT = _Checked("integer", _integer_in(1))
WORKER_COUNT = _Checked("integer", _integer_in(0, MAX_WORKERS))
POSITIVE_FLOAT = _Checked("number", _positive_float)
DISPERSION = _Checked("number", _dispersion)
ZLIB_LEVEL = _Checked("0..9", _zlib_level)


# ----------------------------------------------------------------------------- parser
class _Command(click.Command):
    """A subcommand that reports extra positional arguments the way argparse did."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("context_settings", {})["allow_extra_args"] = True
        super().__init__(*args, **kwargs)

    def parse_args(self, ctx, args):
        try:
            rest = super().parse_args(ctx, args)
        except click.UsageError as exc:
            exc.ctx = exc.ctx or ctx            # click's parser leaves some without (missing values)
            raise
        if ctx.args:
            raise click.UsageError(f"unrecognized arguments: {' '.join(ctx.args)}", ctx)
        return rest


class _Group(click.Group):
    """The ``screening`` group: a missing or unknown subcommand is a one-line usage error."""

    command_class = _Command

    def parse_args(self, ctx, args):
        if not args:
            raise click.UsageError("the following arguments are required: command", ctx)
        return super().parse_args(ctx, args)

    def resolve_command(self, ctx, args):
        if not args[0].startswith("-") and self.get_command(ctx, args[0]) is None:
            raise click.UsageError(f"argument command: invalid choice: {args[0]!r} (choose from "
                                   f"{', '.join(map(repr, self.commands))})", ctx)
        return super().resolve_command(ctx, args)


@click.group(cls=_Group, no_args_is_help=False,
             help="Stochastic screening of rocking blocks on flexible nonlinear foundations.")
@click.version_option(__version__, "--version", prog_name="screening", message="%(prog)s %(version)s")
def cli():
    pass


def announce_compilation(quiet=False):
    """One line on stderr before a command that computes, if numba will compile the solvers first
    (a fresh clone: a minute or two that would otherwise look like a hang); nothing with ``quiet``.

    Parameters
    ----------
    quiet : bool, default False
        The command's ``--quiet``: say nothing.

    Returns
    -------
    None
        The line (if due) goes to stderr (:func:`screening.kernels.cache.announce_compilation`).

    """
    if not quiet:
        from screening.kernels.cache import announce_compilation as announce

        announce()


def stamp_fragility(frag, result, **options):
    """Record in ``frag``'s attributes where it comes from: the result file, the package version and the
    ``screening fragility`` command line (options that are ``None`` left out).

    Parameters
    ----------
    frag : xarray.Dataset
        The fragility dataset; its ``attrs`` are updated in place.
    result : str or pathlib.Path
        The result file it was computed from.
    **options
        The command's options, ``name=value`` (``relative_to`` is written ``--relative-to``).

    Returns
    -------
    None
        ``frag.attrs`` gains ``source_result``, ``screening_version`` and ``history``.

    """
    flags = "".join(f" --{name.replace('_', '-')} {value}" for name, value in options.items() if value is not None)
    frag.attrs.update(source_result=str(result), screening_version=__version__,
                      history=f"screening fragility {result}{flags}")


def lognormal_fit_text(frag, over, units=""):
    """``"lognormal fit over <over>: 3 of 5 curve(s) fitted (...); median <m> [units], beta <b> (medians
    over the fitted curves)"``, or ``""`` where ``frag`` has no fit (no swept intensity).

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset (``fit_median``, ``beta``, ``fit_flag``, ``threshold_rad`` where fitted).
    over : str
        The intensity the curves are fitted over (``"pga_median"``, ``"S0"``).
    units : str, default ""
        The units of the median (``"m s-2"``), printed after it.

    Returns
    -------
    str
        The line ``screening fragility`` prints: the count of fitted curves (with the reasons of the
        others), the median of the fitted medians [units] and of the dispersions ``beta`` [-].

    References
    ----------
    .. [1] screening documentation, "Fragility: curves, formats, trust flags and multiple-stripe fits",
       docs/fragility.md, section "The files (written as a set: all or none)".
    .. [2] [baker2015] in the bibliography, ``docs/bibliography.md``.
    """
    from screening.applications.im_fragility import curve_count_text

    if "fit_median" not in frag:
        return ""
    text = f"lognormal fit over {over}: {curve_count_text(frag)}"
    if not np.isfinite(frag["fit_median"].values).any():
        return text
    return (f"{text}; median {float(frag['fit_median'].median()):.4g}{' ' + units if units else ''}, "
            f"beta {float(frag['beta'].median()):.3f} (medians over the fitted curves)")


def write_file_set(files, warnings=()):
    """Write a set of files that belong together, all or none.

    ``files`` is a list of ``(name, path, write)`` and ``write(tmp)`` writes the file into the new
    temporary ``tmp`` (a :class:`~screening.applications.im_fragility.NoExport` there means this file has
    no content: the warning "no <name> file: ..." and, so that the folder holds only what this
    command produced, an older file at ``path`` is removed).  Every file is written to a temporary
    next to its path first; only when all are written are they renamed into place (the first of
    ``files`` last).  On any failure (or Ctrl-C) every temporary is removed and nothing is
    published; a write error becomes the one-line error.  Prints the paths written and the warnings.

    Parameters
    ----------
    files : list of tuple
        ``(name, path, write)``: a name for messages, the ``pathlib.Path`` to write and a function
        ``write(tmp)`` that writes the file into ``tmp``.
    warnings : iterable of str, default ()
        Warnings to print (on stderr, ``warning: ...``) after the paths.

    Returns
    -------
    None
        The paths written are printed on stdout, in the order of ``files``.

    Raises
    ------
    screening.io.errors.SweepError
        A write failed (``OSError`` or netCDF's ``RuntimeError``): nothing was published.

    """
    from screening.applications.im_fragility import NoExport

    warnings = list(warnings)
    done, drop = [], []
    try:
        for name, path, write in files:
            tmp = temporary_for(path, suffix=path.suffix)
            done.append((tmp, path))
            try:
                write(tmp)
            except NoExport as exc:
                warnings.append(f"no {name} file: {exc}")
                done.pop()
                tmp.unlink(missing_ok=True)
                drop.append(path)
    except BaseException as exc:
        for tmp, _ in done:
            tmp.unlink(missing_ok=True)
        if isinstance(exc, (OSError, RuntimeError)):    # netCDF reports a failed write as RuntimeError
            raise write_error(files[0][1], exc) from None
        raise
    for tmp, path in done[::-1]:
        _publish(tmp, path)
    for path in drop:
        if path.is_file() and not path.is_symlink():
            path.unlink()
            warnings.append(f"removed {path} of an earlier run (this run has no such file)")
    for _, path in done:
        print(path)
    for w in warnings:
        say(f"warning: {w}")


def refuse_collisions(out, others, option="--out"):
    """Refuse an output path that is also one of the command's other outputs (before any work).

    Parameters
    ----------
    out : path-like
        The path the user gave.
    others : iterable of tuple
        ``(name, path)`` of the other files the command writes next to it.
    option : str, default "--out"
        The option named in the message.

    Returns
    -------
    None

    Raises
    ------
    CommandError
        One line naming the clash (exit status 2).

    """
    def key(path):
        return os.path.normcase(os.path.abspath(os.fspath(path)))

    for name, path in others:
        if key(path) == key(out):
            raise CommandError(f"{option} {out}: the command also writes its {name} there; give the netCDF file "
                               f"another name (e.g. {Path(out).with_suffix('.nc')})")


def fragility_outputs(out, limit_states=()):
    """``(name, path)`` of every file ``screening fragility`` writes beside the netCDF file ``out``: the PNG
    (one per limit state with several), the CSV, pelicun CSV and NRML of the fits (:func:`fragility_figures`,
    :func:`fit_files`).

    Parameters
    ----------
    out : pathlib.Path
        The fragility netCDF file.
    limit_states : sequence of str, default ()
        The limit-state names where there are several (a ``limit_state`` dimension).

    Returns
    -------
    list of tuple
        ``(name, path)``.

    """
    out = Path(out)
    figures = ([(f"PNG of {name}", out.with_name(f"{out.stem}_{name}.png")) for name in limit_states]
               if limit_states else [("PNG", out.with_suffix(".png"))])
    return figures + [("CSV", out.with_suffix(".csv")), ("pelicun CSV", out.with_name(f"{out.stem}_pelicun.csv")),
                      ("NRML", out.with_suffix(".xml"))]


def _drawn(path):
    """The path a figure function returned; :class:`~screening.applications.im_fragility.NoExport` (no figure
    file) where it drew none."""
    from screening.applications.im_fragility import NoExport

    if path is None:
        raise NoExport("nothing to draw")
    return path


def fragility_figures(frag, out, dim, flags=None):
    """The PNG entries of :func:`write_file_set` for a fragility dataset: ``<out>.png``, or with several
    limit states one ``<out-stem>_<limit state>.png`` each
    (:func:`~screening.report.fragility_figures.plot_fragility`).

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset, with or without a ``limit_state`` dimension.
    out : pathlib.Path
        The fragility netCDF file; the figures are named after it.
    dim : str
        The intensity dimension on the x axis.
    flags : xarray.Dataset, optional
        ``status`` (and ``sl_trust``) of the result, to mark flagged points.

    Returns
    -------
    list of tuple
        ``(name, path, write)`` entries; ``write`` draws the figure when called (nothing is drawn here).

    """
    from screening.report.fragility_figures import plot_fragility

    def draw(one):
        return lambda path: _drawn(plot_fragility(one, dim, path, flags=flags))

    if "limit_state" not in frag.dims:
        return [("PNG", fragility_outputs(out)[0][1], draw(frag))]
    names = [str(name) for name in frag["limit_state"].values]
    return [(label, path, draw(frag.isel(limit_state=i).assign_attrs(threshold=float(frag["threshold"].values[i]))))
            for i, (label, path) in enumerate(fragility_outputs(out, names)[:len(names)])]


def fit_files(frag, out):
    """The entries of :func:`write_file_set` for the fits of ``frag``: CSV (a row per curve), pelicun CSV
    and (where OpenQuake knows the intensity) NRML next to ``out``.

    Parameters
    ----------
    frag : xarray.Dataset
        A fragility dataset with lognormal fits (:func:`screening.applications.im_fragility.fragility_over_im`).
    out : pathlib.Path
        The fragility netCDF file; the others are named after it.

    Returns
    -------
    list of tuple
        ``(name, path, write)`` entries: ``<stem>.csv``, ``<stem>_pelicun.csv``, ``<stem>_pelicun.json``,
        ``<stem>.xml``.

    References
    ----------
    .. [1] screening documentation, "Fragility: curves, formats, trust flags and multiple-stripe fits",
       docs/fragility.md, section "The files (written as a set: all or none)".
    .. [2] [baker2015] in the bibliography, ``docs/bibliography.md``.
    .. [3] M. Pagani et al., "OpenQuake engine: an open hazard (and risk) software for the Global
       Earthquake Model", Seismological Research Letters 85(3) (2014) 692-702.
    """
    from screening.applications.im_fragility import write_csv, write_nrml, write_pelicun_csv, write_pelicun_json

    return [("CSV", out.with_suffix(".csv"), lambda path: write_csv(frag, path)),
            ("pelicun CSV", out.with_name(f"{out.stem}_pelicun.csv"), lambda path: write_pelicun_csv(frag, path)),
            ("pelicun JSON", out.with_name(f"{out.stem}_pelicun.json"), lambda path: write_pelicun_json(frag, path)),
            ("NRML", out.with_suffix(".xml"), lambda path: write_nrml(frag, path))]


def write_fragility_files(ds, out, figures, extras=(), warnings=()):
    """Write ``ds`` as netCDF at ``out``, its ``figures`` and each of ``extras`` (entries ``(name, path,
    write)``) as one set (:func:`write_file_set`).

    Parameters
    ----------
    ds : xarray.Dataset
        The fragility dataset, written as netCDF-4 (no fill value on the coordinates).
    out : pathlib.Path
        The netCDF file.
    figures : list of tuple
        ``(name, path, write)`` entries of the figures (:func:`fragility_figures`).
    extras : iterable of tuple, default ()
        More entries (:func:`fit_files`).
    warnings : iterable of str, default ()
        Warnings to print after the paths.

    Returns
    -------
    None
        The paths written are printed on stdout.

    """
    def netcdf(path):
        ds.to_netcdf(path, engine="netcdf4", encoding={c: {"_FillValue": None} for c in ds.coords})

    write_file_set([("netCDF", out, netcdf), *figures, *extras], warnings)
