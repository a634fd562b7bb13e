"""The order the robot does a plan's steps in: the planner's, unless the object's true mechanism needs another.

The planner chooses *which* fits to make from the person's model alone; among the steps it
chose, the order is free wherever the object allows it. A real object can still care about
that order: a wick lit before the oil is in the bowl does not burn (a requirement's ``after``
in the catalog). So, before a plan is replayed and checked, its steps are put in the order the
mechanism needs, as far as the object (and a question's constraints) allow; a plan already in
such an order is kept as the planner made it. No step is added or dropped: a model that leaves
the fuel out still gets a plan without it, which the true mechanism then rejects.

Only open-loop plans are reordered; an MDP's policy fixes its own order.
"""

from __future__ import annotations

from causalplan.pddl.canonical import Action
from causalplan.pddl.task import PlanningTask
from causalplan.planners.replay import AssemblyState


def _waits(task: PlanningTask, planned: list[str]) -> dict[str, list[str]]:
    """Return, per planned fit, the planned fits its requirement's ``after`` needs made first."""
    waits: dict[str, list[str]] = {}
    for fit_id in planned:
        requirement = task.obj.requirement_of(fit_id)
        if requirement is not None:
            waits[fit_id] = [earlier for earlier in requirement.after if earlier in planned]
    return waits


def mechanism_order(task: PlanningTask, actions: tuple[Action, ...]) -> tuple[Action, ...]:
    """Return ``actions`` in an order that meets the true mechanism's ``after``, or as given.

    A plan whose order already meets it is returned as it is. Otherwise the steps are redone
    one at a time, each one that can be done now and whose ``after`` fits are made: first the
    steps others wait for, in the order the mechanism lists them (the oil, then the wick, as a
    person fills a lamp before lighting it), then the rest in the planner's order. When no
    order qualifies (the object or a question's constraints allow none), the planner's order
    is kept whole.
    """
    obj = task.obj
    fits = {fit.id: fit for fit in obj.fits}
    if any(len(args) != 3 or args[2] not in fits for _, args in actions):
        return actions
    planned = [args[2] for _, args in actions]
    waits = _waits(task, planned)
    if all(planned.index(earlier) < planned.index(fit_id) for fit_id, wanted in waits.items() for earlier in wanted):
        return actions
    state = AssemblyState.start(obj, task.constraints.forbidden_fits)
    remaining = list(actions)
    ordered: list[Action] = []
    while remaining:
        waited_for = [earlier for _, args in remaining for earlier in waits.get(args[2], [])]
        ranks = {
            args[2]: (waited_for.index(args[2]), 0) if args[2] in waited_for else (len(waited_for), index)
            for index, (_, args) in enumerate(actions)
        }
        doable = [
            action
            for action in remaining
            if state.problem_with(obj, fits[action[1][2]]) is None
            and set(waits.get(action[1][2], [])) <= set(state.made)
        ]
        if not doable:
            return actions
        action = min(doable, key=lambda candidate: ranks[candidate[1][2]])
        fit = fits[action[1][2]]
        remaining.remove(action)
        ordered.append(action)
        state.make(obj, fit)
        state.unavailable.update(task.constraints.excluded_after(obj, fit))
    return tuple(ordered)
