"""What the command modules share below the click group (screening.cli._common): argparse's wording for choices
and usage errors, an option refused after another, the stem of a result's name, the temporary file beside an output
and the one-line error of a failed write."""

import errno
from pathlib import Path

import click
import pytest

from screening.cli import _common as common
from screening.io.errors import SweepError


def _command():
    @click.command()
    @click.option("--mode", type=common.Choice(["a", "b"]))
    @click.option("--first")
    @click.option("--second", callback=common.not_with("first"))
    def command(mode, first, second):
        pass
    return command


def test_a_bad_choice_is_said_the_way_argparse_says_it():
    with pytest.raises(click.BadParameter) as err:
        _command().make_context("command", ["--mode", "c"])
    assert err.value.message == "invalid choice: 'c' (choose from 'a', 'b')"
    assert common.usage_message(err.value) == "argument --mode: invalid choice: 'c' (choose from 'a', 'b') " \
                                              "(see 'command --help')"


def test_an_option_after_the_one_it_excludes_is_a_usage_error():
    with pytest.raises(click.UsageError, match="argument --second: not allowed with argument --first"):
        _command().make_context("command", ["--first", "x", "--second", "y"])
    assert _command().make_context("command", ["--second", "y"]).params["second"] == "y"


@pytest.mark.parametrize("args, message", [(["--mode"], "argument --mode: expected one argument (see 'screening --help')"),
                                           (["--bogus"], "unrecognized arguments: --bogus (see 'command --help')")])
def test_usage_errors_get_argparse_words_and_where_to_get_help(args, message):
    """Where click leaves the error without its command, help is pointed to on the whole parser."""
    with pytest.raises(click.UsageError) as err:
        _command().make_context("command", args)
    assert common.usage_message(err.value) == message


@pytest.mark.parametrize("name, stem", [("run.nc", "run"), ("run.zarr", "run"), ("run.v2.nc", "run.v2"),
                                        ("table.csv", "table.csv"), ("folder", "folder")])
def test_the_stem_of_a_result_drops_only_its_format_suffix(name, stem):
    assert common.result_stem(Path("outputs") / name) == stem


def test_a_temporary_file_is_created_beside_the_output_with_the_suffix(tmp_path):
    out = tmp_path / "result.nc"
    tmp = Path(common.temporary_for(out, ".nc"))
    assert tmp.parent == tmp_path and tmp.exists() and tmp.stat().st_size == 0 and tmp.name.endswith(".tmp.nc")
    assert not out.exists()


def test_a_failed_write_is_one_line_naming_the_file(tmp_path):
    err = common.write_error(tmp_path / "x.nc", PermissionError(errno.EACCES, "Permission denied", "/ro/x.nc"))
    assert isinstance(err, SweepError)
    assert str(err).startswith("cannot write /ro/x.nc: ") and "\n" not in str(err)
    with pytest.raises(SweepError, match="cannot write .*missing"):
        common.temporary_for(tmp_path / "missing" / "x.nc")


def test_say_writes_one_line_to_stderr(capsys):
    common.say("warning: something")
    assert capsys.readouterr() == ("", "warning: something\n")
