"""The planning pipeline: compile the task, search, replay the plan, and say what came of it."""

from __future__ import annotations

import time

from causalplan.causal.graph import goal_holds
from causalplan.errors import CausalPlanError
from causalplan.pddl.task import PlanningTask
from causalplan.pddl.writer import compile_task
from causalplan.planners import fast_downward
from causalplan.planners.replay import replay
from causalplan.planners.result import PlanResult, PlanStatus, PlanStep

PLANNERS = tuple(fast_downward.CONFIGS)
"""The planner names ``plan`` accepts."""

PRECHECK = "precheck"
"""``planner_used`` when the answer was decided before any search."""


class UnknownPlannerError(CausalPlanError):
    """A planner name that is not in the registry."""

    code = "unknown_planner"


def goal_reachable(task: PlanningTask) -> bool:
    """Return whether the goal would hold if every part carrying a function were assembled."""
    return goal_holds(task.carriers(), task.rules, task.goal_key)


def plan_task(
    task: PlanningTask,
    planner: str = "fd",
    time_limit: float = fast_downward.DEFAULT_TIME_LIMIT,
    include_pddl: bool = False,
) -> PlanResult:
    """Return a replayed plan for ``task`` (or the status saying why there is none)."""
    config = fast_downward.CONFIGS.get(planner)
    if config is None:
        raise UnknownPlannerError(
            f"Unknown planner '{planner}'; choose one of: {', '.join(PLANNERS)}.", details={"planner": planner}
        )
    started = time.perf_counter()
    compiled = compile_task(task)
    timing = {"compile": time.perf_counter() - started}
    pddl = {"domain": compiled.domain, "problem": compiled.problem} if include_pddl else None
    obj = task.obj
    if not goal_reachable(task):
        timing["total"] = time.perf_counter() - started
        return PlanResult(
            PlanStatus.UNSOLVABLE,
            PRECHECK,
            obj.id,
            timing=timing,
            pddl=pddl,
            message=f"Even with every part of the {obj.name} assembled, the model's rules do not "
            f"produce '{task.goal}': no part carries some function the rules need.",
        )
    outcome = fast_downward.solve(compiled.domain, compiled.problem, config, time_limit)
    timing.update(outcome.timing)
    if outcome.status is not PlanStatus.SOLVED:
        timing["total"] = time.perf_counter() - started
        message = outcome.message or {
            PlanStatus.UNSOLVABLE: f"No sequence of connections of the {obj.name}'s parts produces '{task.goal}' "
            "under the model.",
            PlanStatus.TIMEOUT: f"The planner did not finish within {time_limit:g} s.",
            PlanStatus.OUT_OF_MEMORY: "The planner ran out of memory.",
        }.get(outcome.status, "The planner failed.")
        return PlanResult(outcome.status, config.name, obj.id, timing=timing, message=message, pddl=pddl)
    replay_started = time.perf_counter()
    checked = replay(task, outcome.actions)
    timing["replay"] = time.perf_counter() - replay_started
    timing["total"] = time.perf_counter() - started
    if not (checked.executable and checked.valid_under_model):
        why = checked.failure or "the goal does not hold under the model after the last step"
        return PlanResult(
            PlanStatus.ERROR,
            config.name,
            obj.id,
            timing=timing,
            pddl=pddl,
            message=f"The planner's plan failed replay ({why}); it is not returned.",
        )
    fits = {fit.id: fit for fit in obj.fits}
    steps = tuple(PlanStep(action, args[:2], args[2], obj.step_text(fits[args[2]])) for action, args in outcome.actions)
    message = (
        ""
        if checked.valid_under_true_mechanism
        else (
            f"The plan satisfies the model, but the real {obj.name} would not produce {obj.goal}; it also needs: "
            + "; ".join(checked.unmet_requirements)
            + "."
        )
    )
    return PlanResult(
        PlanStatus.SOLVED,
        config.name,
        obj.id,
        steps,
        True,
        checked.valid_under_true_mechanism,
        checked.unmet_requirements,
        timing,
        message,
        pddl,
    )
