"""One comparison run, in a process of its own forked from a warm parent (see ``runner``).

Everything a run needs is imported here, at module level, so the fork server that preloads
this module hands every run a process where no import is left to do: the clock times the
planner, not Python. The run limits its own memory, plans, and returns its record; checks
that need no planner libraries (VAL) are left to the parent, which runs each distinct plan
once. unified-planning's validator runs only for ``up:`` planners, whose run has it loaded.
"""

from __future__ import annotations

import os
import resource
import time
from pathlib import Path

# Imported for their side effect: the fork server loads them once, so no run imports them.
import fast_downward.translate.main  # noqa: F401 - FD's translator runs in the run's process

import causalplan.planners.mdp  # noqa: F401 - the MDP planner is imported when first used
from causalplan.errors import CausalPlanError
from causalplan.pddl.task import PlanningTask
from causalplan.planners import processes
from causalplan.planners.pipeline import plan_task

OUTPUT_FILE = "output.log"
"""Where a run's stdout and stderr go, in its folder (what planners print would garble the progress bar)."""


def _limit_memory(megabytes: int) -> None:
    limit = processes.memory_limit(megabytes)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _output_to(folder: Path) -> None:
    """Send this process's stdout and stderr (file descriptors 1 and 2) to ``OUTPUT_FILE`` in ``folder``."""
    descriptor = os.open(folder / OUTPUT_FILE, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(descriptor, 1)
    os.dup2(descriptor, 2)
    os.close(descriptor)


def run(task: PlanningTask, planner: str, time_limit: float, memory_mb: int, folder: Path) -> dict[str, object]:
    """Return the record of one planner run on ``task`` (in this process; ``folder`` is its own)."""
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
