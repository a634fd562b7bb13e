"""One comparison run, in a process of its own forked from a warm parent (see ``runner``).

The fork server preloads the planners (``runner.PRELOADED``), so a run forked from it has no
import left to do: the clock times the planner, not Python. This module itself stays light
(the parent imports it to name ``serve``). The run limits its own memory, plans, and sends its
record; checks that need no planner libraries (VAL) are left to the parent, which runs each
distinct plan once. unified-planning's validator runs only for ``up:`` planners, whose run has
it loaded.
"""

from __future__ import annotations

import os
import resource
import time
from multiprocessing.connection import Connection
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.errors import CausalPlanError
from causalplan.planners import processes

if TYPE_CHECKING:
    from causalplan.pddl.task import PlanningTask


def _limit_memory(megabytes: int) -> None:
    limit = processes.memory_limit(megabytes)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _output_to(folder: Path) -> None:
    """Send this process's stdout and stderr (file descriptors 1 and 2) to ``processes.OUTPUT_FILE`` in ``folder``.

    What planners print would garble the parent's progress bar; the parent reads the file when the run dies.
    """
    descriptor = os.open(folder / processes.OUTPUT_FILE, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(descriptor, 1)
    os.dup2(descriptor, 2)
    os.close(descriptor)


def run(task: PlanningTask, planner: str, time_limit: float, memory_mb: int, folder: Path) -> dict[str, object]:
    """Return the record of one planner run on ``task`` (in this process; ``folder`` is its own)."""
    from causalplan.planners.pipeline import plan_task  # preloaded by the fork server: no import is left here

    _output_to(folder)
    os.chdir(folder)
    _limit_memory(memory_mb)
    if planner.startswith("up:"):
        from causalplan.planners.up_problem import engine_problem  # only up: runs pay for unified-planning

        engine_problem(planner.removeprefix("up:"))  # imports and loads the engine, untimed
    try:
        started = time.perf_counter()
        result = plan_task(task, planner, time_limit)
        seconds = time.perf_counter() - started
    except CausalPlanError as exc:
        return {"status": "error", "message": f"{exc.code}: {exc.message}"}
    return {
        "status": result.status.value,
        "planner_used": result.planner_used,
        "plan_length": len(result.steps) if result.has_plan else None,
        "seconds": seconds,
        "success_probability": result.success_probability,
        "valid_under_model": result.valid_under_model,
        "valid_under_true_mechanism": result.valid_under_true_mechanism,
        "validated_by": dict(result.validated_by) if result.has_plan else None,
        "actions": [[step.action, [*step.args, step.fit]] for step in result.steps] if result.has_plan else None,
        "message": result.message,
    }


def serve(
    answer: Connection, task: PlanningTask, planner: str, time_limit: float, memory_mb: int, folder: Path
) -> None:
    """Run one planner run (``run``) in this process and send its record through ``answer``.

    An exception becomes an error record, so the parent learns what went wrong; a process that
    dies sends nothing, and the parent reports its exit code.
    """
    try:
        record = run(task, planner, time_limit, memory_mb, folder)
    except MemoryError:
        record = {"status": "out_of_memory", "message": "the worker failed: MemoryError"}
    except Exception as exc:  # noqa: BLE001 - whatever ended the run is its row's message
        record = {"status": "error", "message": f"the worker failed: {type(exc).__name__}: {exc}"}
    answer.send(record)
    answer.close()
