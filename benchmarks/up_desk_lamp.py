"""Reference: the same desk-lamp solve through unified-planning, as a whole process."""

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
screw = InstantaneousAction("screw_bulb")
screw.add_precondition(available(f1))
screw.add_precondition(in_assembly(base))
screw.add_precondition(detached(bulb))
for effect, value in (
    (in_assembly(bulb), True),
    (detached(bulb), False),
    (turn(), True),
    (close(), True),
    (available(f1), False),
):
    screw.add_effect(effect, value)
clip = InstantaneousAction("clip_shade")
clip.add_precondition(available(f2))
clip.add_precondition(in_assembly(base))
clip.add_precondition(detached(shade))
for effect, value in (
    (in_assembly(shade), True),
    (detached(shade), False),
    (available(f1), False),
    (available(f2), False),
):
    clip.add_effect(effect, value)
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
