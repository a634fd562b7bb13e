"""One comparison run in its own process: ``python -m causalplan.comparison.worker`` (JSON in, JSON out).

It rebuilds the task, imports the planner's libraries *before* the clock starts (so the
time is the planner's, not Python's imports), plans, then validates the plan with
unified-planning's plan validator outside the timed section.
"""

from __future__ import annotations

import json
import sys
import time

from causalplan.errors import CausalPlanError


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
    if result.has_plan:
        from causalplan.planners.up_problem import validate_with_up

        validated = validate_with_up(task, tuple((s.action, (*s.args, s.fit)) for s in result.steps))
    return {
        "status": result.status.value,
        "planner_used": result.planner_used,
        "plan_length": len(result.steps) if result.has_plan else None,
        "seconds": seconds,
        "success_probability": result.success_probability,
        "valid_under_model": result.valid_under_model,
        "valid_under_true_mechanism": result.valid_under_true_mechanism,
        "validated_by_up": validated,
        "message": result.message,
    }


def main() -> None:
    """Read one request from stdin, write its record to stdout."""
    request = json.loads(sys.stdin.read())
    try:
        record = run(request)
    except CausalPlanError as exc:
        record = {"status": "error", "message": f"{exc.code}: {exc.message}"}
    sys.stdout.write(json.dumps(record))


if __name__ == "__main__":
    main()
