"""The command line (``screening``): the click commands are in :mod:`screening.cli.commands`."""

from screening.cli.commands import main

__all__ = ["main"]
