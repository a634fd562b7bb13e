"""One explanation request: plan the task, then answer "why this step?" and "why not …?" about that plan."""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.explain.chains import StepExplanation, explain_step
from causalplan.explain.contrast import Contrast, PlanUnavailableError, why_not
from causalplan.explain.questions import UnknownStepError, parse_question, resolve_part, resolve_step
from causalplan.pddl.task import PlanningTask
from causalplan.planners.fd import DEFAULT_TIME_LIMIT
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult, PlanStep

EVERY_STEP = "all"
"""``why`` for every step of the plan."""


@dataclass(frozen=True)
class Explanation:
    """A replayed plan, why each asked step is in it, and the answer to a why-not question if one was asked."""

    plan: PlanResult
    steps: tuple[StepExplanation, ...]
    contrast: Contrast | None

    def as_dict(self) -> dict[str, object]:
        """Return the explanation as a JSON-ready dict (the plan once, as ``causalplan plan --json``)."""
        contrast = self.contrast.as_dict() if self.contrast is not None else None
        return {"plan": self.plan.as_dict(), "why": [step.as_dict() for step in self.steps], "why_not": contrast}


def step_numbers(steps: tuple[PlanStep, ...], task: PlanningTask, which: str) -> list[int]:
    """Return the step numbers ``which`` names: ``all``, a number, or the part a step attaches."""
    if which.strip().lower() == EVERY_STEP:
        return list(range(1, len(steps) + 1))
    if which.strip().isdigit():
        resolve_step(steps, int(which))
        return [int(which)]
    part = resolve_part(task.obj, which)
    for number, step in enumerate(steps, start=1):
        if step.args[0] == part:
            return [number]
    raise UnknownStepError(
        f"No step of the plan attaches the {task.obj.part(part).name}; ask 'attach {part}' to see why not.",
        details={"part": part},
    )


def explain_plan(
    task: PlanningTask,
    why: str | None = None,
    why_not_question: str | None = None,
    planner: str = "fd",
    time_limit: float = DEFAULT_TIME_LIMIT,
    val: bool = True,
    simulate: bool = False,
) -> Explanation:
    """Plan ``task`` and explain the plan: ``why`` (a step number, a part, or ``all``) and ``why_not_question``.

    With neither, every step is explained. Questions are checked against the object and the
    plan before any planning beyond the plan itself (``QuestionError`` and its codes).
    """
    plan = plan_task(task, planner, time_limit, val=val)
    if not plan.has_plan:
        raise PlanUnavailableError(
            f"There is no plan to explain ({plan.status.value}): {plan.message}", details={"status": plan.status.value}
        )
    question = parse_question(why_not_question, task.obj, plan.steps) if why_not_question is not None else None
    asked_why = why if why is not None else (EVERY_STEP if question is None else None)
    numbers = step_numbers(plan.steps, task, asked_why) if asked_why is not None else []
    steps = tuple(explain_step(task, plan.steps, number) for number in numbers)
    contrast = why_not(task, question, plan, time_limit, val, simulate) if question is not None else None
    return Explanation(plan, steps, contrast)
