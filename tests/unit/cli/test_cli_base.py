"""What the commands of the parser share (screening.cli.base): option types, the group's usage errors."""

import click
import pytest

from screening.cli import base as cli_base
from screening.cli.base import MAX_WORKERS, POSITIVE_FLOAT, POSITIVE_INT, WORKER_COUNT, ZLIB_LEVEL, cli


@pytest.mark.parametrize("kind, text, value", [(POSITIVE_FLOAT, "2.5", 2.5), (POSITIVE_INT, "3", 3),
                                               (WORKER_COUNT, "0", 0), (WORKER_COUNT, str(MAX_WORKERS), MAX_WORKERS),
                                               (ZLIB_LEVEL, "9", 9)])
def test_the_option_types_accept_their_range(kind, text, value):
    assert kind.convert(text, None, None) == value


@pytest.mark.parametrize("kind, text", [(POSITIVE_FLOAT, "0"), (POSITIVE_FLOAT, "nan"), (POSITIVE_FLOAT, "x"),
                                        (POSITIVE_INT, "0"), (POSITIVE_INT, "1.5"),
                                        (WORKER_COUNT, str(MAX_WORKERS + 1)), (ZLIB_LEVEL, "10")])
def test_the_option_types_refuse_the_rest_with_the_allowed_range(kind, text):
    with pytest.raises(click.BadParameter, match=f"got '{text}'"):
        kind.convert(text, None, None)


def test_the_group_refuses_a_missing_or_unknown_command_in_one_usage_line():
    with pytest.raises(click.UsageError, match="the following arguments are required: command"):
        cli.make_context("screening", [])
    ctx = cli.make_context("screening", ["run", "x.toml"])
    with pytest.raises(click.UsageError, match="invalid choice: 'runn'"):
        cli.resolve_command(ctx, ["runn"])


def test_every_command_of_both_modules_is_on_the_one_group():
    import screening.cli  # noqa: F401 - registers the commands (and the record commands after them)

    names = list(cli.commands)
    assert names[:6] == ["run", "plot", "fragility", "tradeoff", "info", "export"]
    assert {"simulate", "fit-excitation", "cloud"} <= set(names[6:])
    assert screening.cli.commands.cli is cli_base.cli
