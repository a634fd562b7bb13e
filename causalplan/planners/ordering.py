"""The order the robot does a plan's steps in: the planner's, unless the object's true mechanism needs another.

The planner chooses *which* fits to make from the person's model alone; among the steps it
chose, the order is free wherever the object allows it. A real object can still care about
that order: a wick lit before the oil is in the bowl does not burn (a requirement's ``after``
in the catalog). So, before a plan is replayed and checked, its steps are put in the order
the mechanism needs, as far as the object (and a question's constraints) allow, keeping the
planner's order otherwise. No step is added or dropped: a model that leaves the fuel out
still gets a plan without it, which the true mechanism then rejects.

Only open-loop plans are reordered; an MDP's policy fixes its own order.
"""

from __future__ import annotations

from causalplan.pddl.task import PlanningTask
from causalplan.planners.replay import AssemblyState

Action = tuple[str, tuple[str, ...]]
"""A plan's action: the primitive and (moving part, fixed part, fit id)."""


def mechanism_order(task: PlanningTask, actions: tuple[Action, ...]) -> tuple[Action, ...]:
    """Return ``actions`` in an order that meets the true mechanism's ``after``, or as given when none does.

    Each next step is the planner's earliest remaining one that can be done now and whose
    ``after`` fits are made (or are not in the plan at all). When no step qualifies (the object
    or a question's constraints allow no such order), the planner's order is kept whole.
    """
    obj = task.obj
    fits = {fit.id: fit for fit in obj.fits}
    planned = {args[2] for _, args in actions if len(args) == 3}
    needs = {
        fit_id: {earlier for earlier in requirement.after if earlier in planned}
        for fit_id in planned
        if (requirement := obj.requirement_of(fit_id)) is not None
    }
    if not any(needs.values()):
        return actions
    state = AssemblyState.start(obj, task.constraints.forbidden_fits)
    remaining = list(actions)
    ordered: list[Action] = []
    while remaining:
        for action in remaining:
            fit = fits.get(action[1][2]) if len(action[1]) == 3 else None
            if fit is None:
                return actions
            if state.problem_with(obj, fit) is None and needs.get(fit.id, set()) <= set(state.made):
                break
        else:
            return actions
        remaining.remove(action)
        ordered.append(action)
        state.make(obj, fit)
        state.unavailable.update(task.constraints.excluded_after(obj, fit))
    return tuple(ordered)
