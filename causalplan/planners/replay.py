"""Replays a plan on the object, step by step: every plan is checked before it is returned.

Replay is independent of the planner: it applies the catalog's own fit semantics, then
evaluates the goal twice, under the person's model (eq. 1) and under the object's true
mechanism (the catalog's requirements).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from causalplan.causal.graph import goal_holds
from causalplan.objects.model import AssemblyObject, Fit
from causalplan.pddl.task import PlanningTask


@dataclass
class AssemblyState:
    """Which parts are in the assembly, which fits are made and which can no longer be made."""

    in_assembly: set[str]
    made: list[str] = field(default_factory=list)
    unavailable: set[str] = field(default_factory=set)

    @classmethod
    def start(cls, obj: AssemblyObject, forbidden: frozenset[str] = frozenset()) -> AssemblyState:
        """Return the starting state: only the base part is in the assembly; ``forbidden`` fits cannot be made."""
        return cls(in_assembly={obj.base}, unavailable=set(forbidden))

    def problem_with(self, obj: AssemblyObject, fit: Fit) -> str | None:
        """Return why ``fit`` cannot be made now, or None when it can."""
        if fit.fixed_part not in self.in_assembly:
            return f"the {obj.part(fit.fixed_part).name} is not in the assembly yet"
        if fit.moving_part in self.in_assembly:
            return f"the {obj.part(fit.moving_part).name} is already in the assembly"
        if fit.id in self.unavailable:
            return "a connector it needs is already taken or covered"
        return None

    def make(self, obj: AssemblyObject, fit: Fit) -> None:
        """Make ``fit`` (the caller has checked ``problem_with``)."""
        self.in_assembly.add(fit.moving_part)
        self.made.append(fit.id)
        self.unavailable.update(obj.excluded_fits(fit))


def unmet_requirements(obj: AssemblyObject, made: Sequence[str]) -> tuple[str, ...]:
    """Return the true mechanism's requirements (in words) that the fits ``made``, in their order, do not meet.

    A requirement whose fit was made, but before a fit its ``after`` names (the wick lit before
    the oil is in the bowl), is not met: its words then say the order it needs.
    """
    unmet = []
    for requirement in obj.mechanism:
        if requirement.is_met_by(made):
            continue
        was_made = set(made) & set(requirement.any_of)
        unmet.append(obj.order_words(requirement) if was_made else requirement.says)
    return tuple(unmet)


@dataclass(frozen=True)
class Replay:
    """The outcome of replaying a plan."""

    executable: bool
    failure: str | None
    valid_under_model: bool
    valid_under_true_mechanism: bool
    unmet_requirements: tuple[str, ...]


def replay(task: PlanningTask, actions: tuple[tuple[str, tuple[str, ...]], ...]) -> Replay:
    """Apply ``actions`` (primitive, (moving, fixed, fit)) to the object and check the goals.

    A task with constraints (a question's) also needs the plan to meet them: a plan that does
    not counts as not valid under the model (the constraints are part of its goal).
    """
    obj = task.obj
    constraints = task.constraints
    state = AssemblyState.start(obj, constraints.forbidden_fits)
    fits = {fit.id: fit for fit in obj.fits}
    for number, (primitive, args) in enumerate(actions, start=1):
        fit = fits.get(args[2]) if len(args) == 3 else None
        failure: str | None
        if fit is None or (fit.primitive, fit.moving_part, fit.fixed_part) != (primitive, args[0], args[1]):
            failure = f"step {number} ({primitive} {' '.join(args)}) is not an assembly step of the {obj.name}"
        else:
            reason = state.problem_with(obj, fit)
            failure = f"step {number} ({obj.step_text(fit)}) cannot be done: {reason}" if reason else None
        if failure is not None:
            return Replay(False, failure, False, False, unmet_requirements(obj, state.made))
        assert fit is not None
        state.make(obj, fit)
        state.unavailable.update(constraints.excluded_after(obj, fit))
    functions = task.functions_of(frozenset(state.in_assembly))
    unmet = unmet_requirements(obj, state.made)
    holds = goal_holds(functions, task.rules, task.goal_key) and not constraints.violations(obj, state.made)
    return Replay(True, None, holds, not unmet, unmet)
