"""What the command modules share below the click group (package-internal; used by
:mod:`screening.cli.base`, :mod:`screening.cli` and :mod:`screening.cli.records`): argparse's wording for
choices and usage errors, an option refused after another, the stderr line, a temporary file beside an
output and the one-line error of a failed write, the stem of a result's name.
"""

from __future__ import annotations

import sys

import click

from screening.core.atomicfile import temporary_beside


class Choice(click.Choice):
    """``click.Choice`` with argparse's words: ``invalid choice: 'x' (choose from 'a', 'b')``; ``choices`` may be
    a function, called when used (a registry's names)."""

    def __init__(self, choices, case_sensitive=True):
        self._read = choices if callable(choices) else None
        super().__init__(() if self._read else choices, case_sensitive)

    @property
    def choices(self):
        return tuple(self._read()) if self._read else self._choices

    @choices.setter
    def choices(self, value):
        self._choices = value

    def convert(self, value, param, ctx):
        if value not in self.choices:
            self.fail(f"invalid choice: {value!r} (choose from {', '.join(map(repr, self.choices))})", param, ctx)
        return value


def not_with(other):
    """Callback refusing an option given after ``--<other>`` (options processed in command-line order)."""
    def callback(ctx, param, value):
        if value is not None and ctx.params.get(other) is not None:
            raise click.UsageError(f"argument {param.opts[0]}: not allowed with argument --{other.replace('_', '-')}",
                                   ctx)
        return value
    return callback


def usage_message(exc):
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


def say(msg):
    print(msg, file=sys.stderr, flush=True)


def temporary_for(out, suffix=""):
    """A new empty file next to ``out`` (never a planted link) to write ``out`` into; its name ends in
    ``.tmp`` and ``suffix`` (writers that read the format from the name)
    (:func:`screening.core.atomicfile.temporary_beside`; a failure as a one-line error)."""
    try:
        return temporary_beside(out, suffix)
    except OSError as exc:
        raise write_error(out, exc) from None


def result_stem(result):
    """The name of a result without ``.nc`` / ``.zarr`` (for the names of its figures)."""
    return result.stem if result.suffix in (".nc", ".zarr") else result.name


def write_error(path, exc):
    from screening.io.errors import SweepError, write_failure_reason

    return SweepError(f"cannot write {getattr(exc, 'filename', None) or path}: {write_failure_reason(exc, path)}")
