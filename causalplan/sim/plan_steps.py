"""The steps a simulation runs: from a planner's result, or read (and checked) from a plan file.

A plan file is the ``plan`` list of ``causalplan plan --json`` (or that whole output): steps
with ``action``, ``args`` (moving part, fixed part) and ``fit``. A step may leave out ``fit``:
the simulator then looks for a free pair of connectors with the same spec, which is how a
plan can try to join parts that do not fit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from causalplan.errors import CausalPlanError
from causalplan.objects.model import PRIMITIVE_TEXTS, AssemblyObject
from causalplan.planners.result import PlanStep


class PlanInputError(CausalPlanError):
    """A plan to simulate is malformed or does not match the object."""

    code = "invalid_plan"


@dataclass(frozen=True)
class StepRequest:
    """One step to simulate: the primitive, the part that moves, the part it joins, and the fit if known."""

    action: str
    moving: str
    fixed: str
    fit: str | None = None

    @classmethod
    def from_plan_step(cls, step: PlanStep) -> StepRequest:
        """Return the request for a planner's step."""
        return cls(step.action, step.args[0], step.args[1], step.fit or None)

    def text(self, obj: AssemblyObject) -> str:
        """Return the sentence describing this step."""
        if self.fit is not None:
            return obj.step_text(obj.fit(self.fit))
        return PRIMITIVE_TEXTS[self.action].format(moving=obj.part(self.moving).name, fixed=obj.part(self.fixed).name)


def _problem(request: StepRequest, obj: AssemblyObject) -> str | None:
    """Return what is wrong with one step for ``obj``, or None."""
    if request.action not in PRIMITIVE_TEXTS:
        return f"unknown action '{request.action}'; use one of: {', '.join(PRIMITIVE_TEXTS)}"
    for role, part in (("moving", request.moving), ("fixed", request.fixed)):
        if part not in obj.part_ids:
            return f"the {role} part '{part}' is not a part of the {obj.name} ({', '.join(obj.part_ids)})"
    if request.moving == request.fixed:
        return f"it joins the part '{request.moving}' to itself"
    if request.fit is None:
        return None
    fits = {fit.id: fit for fit in obj.fits}
    fit = fits.get(request.fit)
    if fit is None:
        return f"unknown fit '{request.fit}'; the {obj.name}'s fits are: {', '.join(fits) or 'none'}"
    expected = (fit.primitive, fit.moving_part, fit.fixed_part)
    if (request.action, request.moving, request.fixed) != expected:
        return (
            f"the fit '{fit.id}' is '{fit.primitive}' with args [{fit.moving_part}, {fit.fixed_part}], "
            f"not '{request.action}' with [{request.moving}, {request.fixed}]"
        )
    return None


def check_steps(steps: Sequence[StepRequest | PlanStep], obj: AssemblyObject) -> tuple[StepRequest, ...]:
    """Return the steps as requests, checked against ``obj``; PlanInputError names the first bad one."""
    requests = tuple(step if isinstance(step, StepRequest) else StepRequest.from_plan_step(step) for step in steps)
    for number, request in enumerate(requests, start=1):
        problem = _problem(request, obj)
        if problem is not None:
            raise PlanInputError(f"Plan step {number}: {problem}.", details={"step": number})
    return requests


def _read_step(number: int, item: object) -> StepRequest:
    if not isinstance(item, dict):
        raise PlanInputError(f"Plan step {number} is not an object with 'action', 'args' and 'fit'.")
    unknown = sorted(set(item) - {"action", "args", "fit", "text"})
    if unknown:
        raise PlanInputError(f"Plan step {number} has unknown field(s): {', '.join(map(str, unknown))}.")
    action, args, fit = item.get("action"), item.get("args"), item.get("fit")
    if not isinstance(action, str):
        raise PlanInputError(f"Plan step {number} needs 'action', a primitive such as 'screw'.")
    if not (isinstance(args, list) and len(args) == 2 and all(isinstance(arg, str) for arg in args)):
        raise PlanInputError(f"Plan step {number}: 'args' must be two part ids, [moving part, fixed part].")
    if fit is not None and not isinstance(fit, str):
        raise PlanInputError(f"Plan step {number}: 'fit' must be a fit id (text).")
    return StepRequest(action, args[0], args[1], fit or None)


def read_plan_steps(data: object, obj: AssemblyObject) -> tuple[StepRequest, ...]:
    """Return the checked steps of a plan file's data: a list of steps, or ``plan --json`` output."""
    if isinstance(data, dict):
        named = data.get("object")
        if named is not None and named != obj.id:
            raise PlanInputError(f"The plan is for the object '{named}', not the {obj.name} ('{obj.id}').")
        if "plan" not in data:
            raise PlanInputError("The plan file has no 'plan' list of steps.")
        if data["plan"] is None:
            raise PlanInputError(f"The plan file holds no plan (status: {data.get('status', 'unknown')}).")
        data = data["plan"]
    if not isinstance(data, list):
        raise PlanInputError("A plan is a list of steps, each with 'action', 'args' and 'fit'.")
    return check_steps([_read_step(number, item) for number, item in enumerate(data, start=1)], obj)
