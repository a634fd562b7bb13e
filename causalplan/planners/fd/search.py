"""FD's search binary (the one shipped in ``up-fast-downward``'s wheel), one process per search.

The process is an idle one started ahead (``idle``) when this process asked for them, else a new one.
"""

from __future__ import annotations

import os
import re
from functools import cache
from importlib.util import find_spec
from pathlib import Path

from causalplan.errors import PlannerUnavailableError
from causalplan.planners import processes
from causalplan.planners.fd import idle
from causalplan.planners.processes import Finished

PLAN_FILE = "plan"
"""Where the search writes its plan, inside the solve's private folder."""
_PLAN_LINE = re.compile(r"^\(([^()\s]+)((?:\s+[^()\s]+)*)\)\s*$")

Action = tuple[str, tuple[str, ...]]


_chosen_binary: list[Path] = []
"""The binary ``use_search_binary`` chose, if any (a list: no ``global`` statement needed)."""


def use_search_binary(path: Path | None) -> None:
    """Use ``path`` as FD's search binary from now on (None: the wheel's again); settings call it."""
    _chosen_binary[:] = [path] if path is not None else []
    search_binary.cache_clear()


@cache
def search_binary() -> Path:
    """Return the path of FD's search binary: the one chosen, else the ``up-fast-downward`` wheel's."""
    if _chosen_binary:
        path = _chosen_binary[0]
    else:
        spec = find_spec("up_fast_downward")
        if spec is None or not spec.submodule_search_locations:
            raise PlannerUnavailableError("Fast Downward is not installed: pip install up-fast-downward")
        path = Path(next(iter(spec.submodule_search_locations))) / "downward/builds/release/bin/downward"
    if not os.access(path, os.X_OK):
        raise PlannerUnavailableError(f"Fast Downward's search binary is missing or not executable: {path}")
    return path


def search_command(search_options: str) -> list[str]:
    """Return the command line of a search with ``search_options``; it reads its task from stdin."""
    return [str(search_binary()), "--search", search_options, "--internal-plan-file", PLAN_FILE]


def search(
    sas: bytes, search_options: str, folder: Path, time_limit: float, memory_mb: int
) -> tuple[Finished, str | None]:
    """Run one search on the SAS task ``sas`` (its stdin); return how it ended and its plan file's text, if any.

    A new process runs in ``folder``; a prestarted one in its own folder, removed afterwards.
    """
    command = search_command(search_options)
    ready = idle.take(command)
    try:
        if ready is None:
            finished = processes.run_limited(
                command, folder=folder, time_limit=time_limit, memory_mb=memory_mb, stdin=sas
            )
            return finished, _read_plan(folder)
        if time_limit <= 0:
            return Finished(None, "", 0.0), None
        finished = processes.finish(
            ready.process, folder=ready.folder, time_limit=time_limit, memory_mb=memory_mb, stdin=sas
        )
        return finished, _read_plan(ready.folder)
    finally:
        if ready is not None:
            idle.discard(ready)
        idle.replace_used(command)  # also when none was ready (it died, or was not started yet)


def _read_plan(folder: Path) -> str | None:
    try:
        return (folder / PLAN_FILE).read_text(encoding="utf-8")
    except FileNotFoundError:
        return None


def parse_plan(text: str) -> tuple[Action, ...]:
    """Return the actions of an FD plan file, skipping its ``; cost`` comment."""
    actions = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith(";"):
            continue
        match = _PLAN_LINE.match(line)
        if match is None:
            raise ValueError(f"unexpected line in Fast Downward's plan: {line!r}")
        actions.append((match.group(1), tuple(match.group(2).split())))
    return tuple(actions)
