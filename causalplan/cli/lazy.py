"""A click group that imports a command's module only when that command runs (or help lists it).

``causalplan plan`` then loads the planning commands and nothing of ``compare``, ``consensus``
or ``serve``: every module a run imports costs it time, and a module that has no compiled copy
(an editable install with ``PYTHONDONTWRITEBYTECODE``) is compiled again on every run. This is
the pattern click's documentation gives for lazy subcommands.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any

import click


class LazyCommands(dict[str, click.Command]):
    """The commands by name; a command is imported from its ``module:attribute`` when first looked up."""

    def __init__(self, where: Mapping[str, str]) -> None:
        super().__init__()
        self.where = dict(where)

    def __missing__(self, name: str) -> click.Command:
        if name not in self.where:
            raise KeyError(name)
        module, attribute = self.where[name].split(":")
        command = getattr(importlib.import_module(f"causalplan.cli.{module}"), attribute)
        if not isinstance(command, click.Command) or command.name != name:
            raise TypeError(f"causalplan.cli.{self.where[name]} is not the click command '{name}'")
        self[name] = command
        return command


class LazyGroup(click.Group):
    """A group whose commands are named with where they live (``{"plan": "planning:plan"}``), imported when used."""

    def __init__(self, *args: Any, lazy_commands: Mapping[str, str], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.commands = LazyCommands(lazy_commands)

    def list_commands(self, ctx: click.Context) -> list[str]:
        """Return every command's name, sorted (as click lists them), without importing any."""
        commands = self.commands
        assert isinstance(commands, LazyCommands)
        return sorted({*commands.where, *commands})

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        """Return the command ``cmd_name``, importing its module now; None if there is none."""
        try:
            return self.commands[cmd_name]
        except KeyError:
            return None
