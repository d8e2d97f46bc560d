"""What the commands of the ``screening`` parser share: the click group, the option types, the
one-line errors and the files a fragility writes (:mod:`screening.cli` and :mod:`screening.cli_records`
register their commands on :data:`cli`)."""

from __future__ import annotations

import sys

import click
import numpy as np

from screening import __version__
from screening.atomicfile import publish as _publish
from screening.atomicfile import temporary_beside

__all__ = ["EXIT_OK", "EXIT_USAGE", "EXIT_INTERRUPTED", "CommandError", "MAX_WORKERS", "POSITIVE_INT",
           "WORKER_COUNT", "POSITIVE_FLOAT", "ZLIB_LEVEL", "cli", "announce_compilation", "stamp_fragility",
           "lognormal_fit_text", "write_file_set", "fragility_figures", "fit_files", "write_fragility_files"]

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


class _Choice(click.Choice):
    """``click.Choice`` with argparse's words: ``invalid choice: 'x' (choose from 'a', 'b')``."""

    def convert(self, value, param, ctx):
        if value not in self.choices:
            self.fail(f"invalid choice: {value!r} (choose from {', '.join(map(repr, self.choices))})", param, ctx)
        return value


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


def _zlib_level(text):
    if text not in [str(i) for i in range(10)]:
        raise ValueError(f"must be an integer in 0..9 (got {text!r})")
    return int(text)


#: Most local worker processes a command starts.
MAX_WORKERS = 256
POSITIVE_INT = _Checked("integer", _integer_in(1))
WORKER_COUNT = _Checked("integer", _integer_in(0, MAX_WORKERS))
POSITIVE_FLOAT = _Checked("number", _positive_float)
ZLIB_LEVEL = _Checked("0..9", _zlib_level)


def _not_with(other):
    """Callback refusing an option given after ``--<other>`` (options processed in command-line order)."""
    def callback(ctx, param, value):
        if value is not None and ctx.params.get(other) is not None:
            raise click.UsageError(f"argument {param.opts[0]}: not allowed with argument --{other.replace('_', '-')}",
                                   ctx)
        return value
    return callback


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


def _usage_message(exc):
    """argparse's wording for a click usage error, with where to get help."""
    param = getattr(exc, "param", None)
    name = (param.opts[0] if isinstance(param, click.Option) else param.name) if param is not None else None
    if isinstance(exc, click.MissingParameter) and name:
        message = f"the following arguments are required: {name}"
    elif isinstance(exc, click.BadParameter) and name:
        message = f"argument {name}: {exc.message}"
    elif isinstance(exc, click.NoSuchOption):
        message = f"unrecognized arguments: {exc.option_name}"
    elif isinstance(exc, click.BadOptionUsage) and "requires an argument" in exc.message:
        message = f"argument {exc.option_name}: expected one argument"
    else:
        message = exc.format_message()
    where = exc.ctx.command_path if exc.ctx is not None else "screening"
    return f"{message} (see '{where} --help')"


@click.group(cls=_Group, no_args_is_help=False,
             help="Stochastic screening of rocking blocks on flexible nonlinear foundations.")
@click.version_option(__version__, "--version", prog_name="screening", message="%(prog)s %(version)s")
def cli():
    pass


def announce_compilation(quiet=False):
    """One line on stderr before a command that computes, if numba will compile the solvers first
    (a fresh clone: a minute or two that would otherwise look like a hang); nothing with ``quiet``."""
    if not quiet:
        from screening.kernels.cache import announce_compilation as announce

        announce()


def _say(msg):
    print(msg, file=sys.stderr, flush=True)


def _temporary_for(out, suffix=""):
    """A new empty file next to ``out`` (never a planted link) to write ``out`` into; its name ends in
    ``.tmp`` and ``suffix`` (writers that read the format from the name)
    (:func:`screening.atomicfile.temporary_beside`; a failure as a one-line error)."""
    try:
        return temporary_beside(out, suffix)
    except OSError as exc:
        raise _write_error(out, exc) from None


def _stem(result):
    """The name of a result without ``.nc`` / ``.zarr`` (for the names of its figures)."""
    return result.stem if result.suffix in (".nc", ".zarr") else result.name


def _write_error(path, exc):
    from screening.workflow.errors import SweepError, write_failure_reason

    return SweepError(f"cannot write {getattr(exc, 'filename', None) or path}: {write_failure_reason(exc, path)}")


def stamp_fragility(frag, result, **options):
    """Record in ``frag``'s attributes where it comes from: the result file, the package version and the
    ``screening fragility`` command line (options that are ``None`` left out)."""
    flags = "".join(f" --{name.replace('_', '-')} {value}" for name, value in options.items() if value is not None)
    frag.attrs.update(source_result=str(result), screening_version=__version__,
                      history=f"screening fragility {result}{flags}")


def lognormal_fit_text(frag, over, units=""):
    """``"lognormal fit over <over>: 3 of 5 curve(s) fitted (...); median <m> [units], beta <b> (medians
    over the fitted curves)"``, or ``""`` where ``frag`` has no fit (no swept intensity)."""
    from screening.analysis.im_fragility import curve_count_text

    if "fit_median" not in frag:
        return ""
    text = f"lognormal fit over {over}: {curve_count_text(frag)}"
    if not np.isfinite(frag["fit_median"].values).any():
        return text
    return (f"{text}; median {float(frag['fit_median'].median()):.4g}{' ' + units if units else ''}, "
            f"beta {float(frag['beta'].median()):.3f} (medians over the fitted curves)")


def write_file_set(files, warnings=()):
    """Write a set of files that belong together, all or none: ``files`` is a list of ``(name, path,
    write)`` and ``write(tmp)`` writes the file into the new temporary ``tmp`` (a
    :class:`~screening.analysis.im_fragility.NoExport` there means this file has no content: the warning
    "no <name> file: ..." and, so that the folder holds only what this command produced, an older file at ``path`` is removed).  Every file is written to a
    temporary next to its path first; only when all are written are they renamed into place (the first
    of ``files`` last).  On any failure (or Ctrl-C) every temporary is removed and nothing is published;
    a write error becomes the one-line error.  Prints the paths written and the warnings."""
    from screening.analysis.im_fragility import NoExport

    warnings = list(warnings)
    done, drop = [], []
    try:
        for name, path, write in files:
            tmp = _temporary_for(path, suffix=path.suffix)
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
            raise _write_error(files[0][1], exc) from None
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
        _say(f"warning: {w}")


def _drawn(path):
    """The path a figure function returned; :class:`~screening.analysis.im_fragility.NoExport` (no figure
    file) where it drew none."""
    from screening.analysis.im_fragility import NoExport

    if path is None:
        raise NoExport("nothing to draw")
    return path


def fragility_figures(frag, out, dim, flags=None):
    """The PNG entries of :func:`write_file_set` for a fragility dataset: ``<out>.png``, or with several
    limit states one ``<out-stem>_<limit state>.png`` each
    (:func:`~screening.report.fragility_figures.plot_fragility`)."""
    from screening.report.fragility_figures import plot_fragility

    def draw(one):
        return lambda path: _drawn(plot_fragility(one, dim, path, flags=flags))

    if "limit_state" not in frag.dims:
        return [("PNG", out.with_suffix(".png"), draw(frag))]
    entries = []
    for i, name in enumerate(frag["limit_state"].values):
        one = frag.isel(limit_state=i).assign_attrs(threshold=float(frag["threshold"].values[i]))
        entries.append((f"PNG of {name}", out.with_name(f"{out.stem}_{name}.png"), draw(one)))
    return entries


def fit_files(frag, out):
    """The entries of :func:`write_file_set` for the fits of ``frag``: CSV (a row per curve), pelicun CSV
    and (where OpenQuake knows the intensity) NRML next to ``out``."""
    from screening.analysis.im_fragility import write_csv, write_nrml, write_pelicun_csv

    return [("CSV", out.with_suffix(".csv"), lambda path: write_csv(frag, path)),
            ("pelicun CSV", out.with_name(f"{out.stem}_pelicun.csv"), lambda path: write_pelicun_csv(frag, path)),
            ("NRML", out.with_suffix(".xml"), lambda path: write_nrml(frag, path))]


def write_fragility_files(ds, out, figures, extras=(), warnings=()):
    """Write ``ds`` as netCDF at ``out``, its ``figures`` and each of ``extras`` (entries ``(name, path,
    write)``) as one set (:func:`write_file_set`)."""
    def netcdf(path):
        ds.to_netcdf(path, engine="netcdf4", encoding={c: {"_FillValue": None} for c in ds.coords})

    write_file_set([("netCDF", out, netcdf), *figures, *extras], warnings)
