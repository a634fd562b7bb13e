"""Jobs for the planner workers in the pool tests: module-level and light, so a worker imports them fast."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Any

from causalplan.service.work.batches import TrialsArguments

STARTED_MARK = "slow-job-started"
"""The file a slow job leaves in its worker's temp folder when it begins (tests wait for it)."""


RELEASE_VARIABLE = "CAUSALPLAN_TEST_RELEASE_FILE"
"""The environment variable naming the file whose creation lets ``plan_when_released`` go on."""
RELEASE_SECONDS = 120.0
"""A bound on the wait for the release file, so a test that fails before releasing leaves no worker stuck."""


def plan_when_released(*args: Any) -> dict[str, object]:
    """Leave STARTED_MARK in the worker's temp folder, then plan once the file named by ``RELEASE_VARIABLE`` exists.

    A solve that lasts as long as the test needs it to, however slow the machine is.
    """
    import tempfile
    from pathlib import Path

    from causalplan.service.work.planning import plan

    (Path(tempfile.gettempdir()) / STARTED_MARK).touch()
    release = Path(os.environ[RELEASE_VARIABLE])
    deadline = time.monotonic() + RELEASE_SECONDS
    while not release.exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    return plan(*args)


def crash_with_exception(*_: Any) -> dict[str, object]:
    """Fail the way a bug would."""
    raise RuntimeError("a bug in a planner")


def sleep_forever(*_: Any) -> dict[str, object]:
    """Hang, as a planner stuck outside Fast Downward's own limits would."""
    time.sleep(3600)
    return {}


def allocate_too_much(*_: Any) -> dict[str, object]:
    """Ask for more memory than the worker's address-space limit allows."""
    return {"size": len(bytearray(64 * 1024**3))}


def timed_sleep(seconds: float) -> tuple[float, float, int]:
    """Sleep ``seconds``; return when the job began and ended (the system-wide monotonic clock) and the worker's pid."""

    began = time.monotonic()
    time.sleep(seconds)
    return began, time.monotonic(), os.getpid()


def temp_folders() -> tuple[str, str]:
    """Make a folder in the worker's temp folder, as a search does; return both."""
    import tempfile

    return tempfile.gettempdir(), tempfile.mkdtemp(prefix="causalplan-fd-")


def start_a_session_then_hang(pid_file: str) -> dict[str, object]:
    """Start a long-lived child in a session of its own (as search processes are), write its pid, hang."""
    import subprocess

    child = subprocess.Popen(["sleep", "600"], start_new_session=True)
    with open(pid_file, "w", encoding="utf-8") as handle:
        handle.write(str(child.pid))
    time.sleep(3600)
    return {}


@dataclass(frozen=True)
class DyingTrials(TrialsArguments):
    """A chunk of trials whose worker dies for a trial named to (see ``judge_or_die``)."""

    marker: str = ""


def judge_or_die(arguments: DyingTrials, catalog: Any) -> list[Any]:
    """Judge a batch chunk as the jobs' ``JUDGED_TRIALS`` does, but kill this worker first for a trial named to.

    Trial id ``die``: always; ``die-once``: only while the marker file is absent, which the
    first death leaves behind.
    """
    import signal
    from pathlib import Path

    from causalplan.service.work.batches import judged_trials

    ids = {trial.id for trial in arguments.trials}
    if "die" in ids or ("die-once" in ids and not Path(arguments.marker).exists()):
        Path(arguments.marker).touch()
        os.kill(os.getpid(), signal.SIGKILL)
    return judged_trials(arguments, catalog)


@dataclass(frozen=True)
class DieOnce:
    """``die_once``'s arguments: the marker file its first death leaves ('': always die), and what it returns."""

    marker: str
    value: str


def die_once(arguments: DieOnce, catalog: Any) -> str:
    """Kill this worker the first time (leaving the marker), return the value after; marker '': always die."""
    import signal
    from pathlib import Path

    if not arguments.marker or not Path(arguments.marker).exists():
        if arguments.marker:
            Path(arguments.marker).touch()
        os.kill(os.getpid(), signal.SIGKILL)
    return arguments.value
