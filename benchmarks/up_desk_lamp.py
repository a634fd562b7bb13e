"""Reference: the same desk-lamp solve through unified-planning, as a whole process."""

from __future__ import annotations

from typing import TYPE_CHECKING

from unified_planning.shortcuts import (
    And,
    BoolType,
    Fluent,
    InstantaneousAction,
    Object,
    OneshotPlanner,
    Problem,
    UserType,
    get_environment,
)

if TYPE_CHECKING:
    from unified_planning.model import FNode

get_environment().credits_stream = None
Part, Fit = UserType("part"), UserType("fit")
in_assembly = Fluent("in_assembly", BoolType(), p=Part)
detached = Fluent("detached", BoolType(), p=Part)
available = Fluent("available", BoolType(), f=Fit)
provide, turn, close = (Fluent(n, BoolType()) for n in ("provide_electricity", "turn_into_light", "close_circuit"))
problem = Problem("desk_lamp")
for fluent in (in_assembly, detached, available, provide, turn, close):
    problem.add_fluent(fluent, default_initial_value=False)
base, bulb, shade = Object("base", Part), Object("bulb", Part), Object("shade", Part)
f1, f2 = Object("bulb_into_socket", Fit), Object("shade_onto_ring", Fit)
problem.add_objects([base, bulb, shade, f1, f2])


def attach(name: str, fit: Object, part: Object, *effects: tuple[FNode, bool]) -> InstantaneousAction:
    """Return the action attaching ``part`` to the base through ``fit``, with its further ``effects``."""
    action = InstantaneousAction(name)
    for precondition in (available(fit), in_assembly(base), detached(part)):
        action.add_precondition(precondition)
    for effect, value in ((in_assembly(part), True), (detached(part), False), *effects):
        action.add_effect(effect, value)
    return action


screw = attach("screw_bulb", f1, bulb, (turn(), True), (close(), True), (available(f1), False))
clip = attach("clip_shade", f2, shade, (available(f1), False), (available(f2), False))
problem.add_actions([screw, clip])
problem.set_initial_value(in_assembly(base), True)
problem.set_initial_value(provide(), True)
for part in (bulb, shade):
    problem.set_initial_value(detached(part), True)
for fit in (f1, f2):
    problem.set_initial_value(available(fit), True)
problem.add_goal(And(And(provide(), close()), turn()))
with OneshotPlanner(name="fast-downward") as planner:
    print(planner.solve(problem).plan)
