"""One comparison run in its own process: ``python -m causalplan.comparison.worker`` (JSON in, a file out).

It reads its request from stdin, rebuilds the task, imports the planner's libraries *before*
the clock starts (so the time is the planner's, not Python's imports), plans, then validates
the plan with unified-planning's plan validator and, when asked, VAL, outside the timed
section. The record goes to ``RECORD_FILE`` in its working directory (stdout is left to
whatever the planners print).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from causalplan.errors import CausalPlanError

RECORD_FILE = "record.json"


def run(request: dict[str, object]) -> dict[str, object]:
    """Return the record of one planner run on one task."""
    from causalplan.comparison.tasks import build
    from causalplan.planners.pipeline import plan_task

    planner = str(request["planner"])
    time_limit = float(str(request["time_limit"]))
    task = build(request["task"])  # type: ignore[arg-type]
    if planner.startswith("up:"):
        from causalplan.planners.up_problem import engine_problem

        engine_problem(planner.removeprefix("up:"))  # imports and loads the engine, untimed
    started = time.perf_counter()
    result = plan_task(task, planner, time_limit)
    seconds = time.perf_counter() - started
    validated = None
    validated_by: dict[str, str] | None = None
    message = result.message
    if result.has_plan:
        from causalplan.pddl.writer import compile_task
        from causalplan.planners import val
        from causalplan.planners.up_problem import validate_with_up

        actions = tuple((step.action, (*step.args, step.fit)) for step in result.steps)
        validated = validate_with_up(task, actions)
        validated_by = {**result.validated_by, "up": "valid" if validated else "invalid"}
        if request.get("val"):
            readable = compile_task(task)
            report = val.validate(readable.domain, readable.problem, actions)
            validated_by["val"] = report.verdict.value
            message = message or report.words
    return {
        "status": result.status.value,
        "planner_used": result.planner_used,
        "plan_length": len(result.steps) if result.has_plan else None,
        "seconds": seconds,
        "success_probability": result.success_probability,
        "valid_under_model": result.valid_under_model,
        "valid_under_true_mechanism": result.valid_under_true_mechanism,
        "validated_by_up": validated,
        "validated_by": validated_by,
        "message": message,
    }


def main() -> None:
    """Read one request from stdin, write its record to ``RECORD_FILE``."""
    request = json.loads(sys.stdin.read())
    try:
        record = run(request)
    except CausalPlanError as exc:
        record = {"status": "error", "message": f"{exc.code}: {exc.message}"}
    Path(RECORD_FILE).write_text(json.dumps(record), encoding="utf-8")


if __name__ == "__main__":
    main()
