"""A troubleshooting episode's last test, in physics: the object rebuilt as the episode left it.

The episode's moves change the order in which the parts sit on the object: a part detached
and attached again comes after the parts that stayed. This rebuilds the object in that order
in PyBullet (parts move themselves, with every physics check: blocked path, contact,
alignment, stability), lights it where it has something to light it with (each ``ignite`` fit
once its part is in place and the fits it must come after are made, before anything covers
it), and judges the true mechanism on what was built. The object gives its goal when physics
says so *and* the broken part was swapped for a spare: a broken part looks whole to the
simulator.

This is ``troubleshoot --physics``: a check of where the episode ends, not of its actions.
The Franka Panda carrying out the episode itself, action by action (detach, set aside, take
the spare, attach, light), is ``sim.robot_episode`` (``troubleshoot --robot``).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.sim.executor import simulate_plan
from causalplan.sim.outcomes import RenderMode
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.report import SimulationReport
from causalplan.troubleshoot.assembly import ATTACH, DETACH, assembly_graph
from causalplan.troubleshoot.episode import Episode
from causalplan.troubleshoot.solver import REPLACE, TEST
from causalplan.troubleshoot.structure import structure_of


@dataclass(frozen=True)
class RepairInPhysics:
    """The last test of an episode in physics: the simulation of the rebuilt object, and the verdict."""

    order: tuple[str, ...]
    """The parts in the order they sit on the object at the last test (the base first)."""
    fits: tuple[str, ...]
    """The fits of the rebuild, in order (lighting included): the 3D player plays them (``POST /research/playback``)."""
    report: SimulationReport
    broken_part_replaced: bool

    @property
    def produces_goal(self) -> bool:
        """Return whether the rebuilt object gives its goal: physics says so, and the broken part is a spare."""
        return self.report.passed and self.broken_part_replaced

    def as_dict(self) -> dict[str, object]:
        return {
            "order": list(self.order),
            "fits": list(self.fits),
            "produces_goal": self.produces_goal,
            "broken_part_replaced": self.broken_part_replaced,
            "simulation": self.report.summary(),
        }


def first_build_order(obj: AssemblyObject) -> list[str]:
    """Return ``obj``'s body parts in an order that builds it from the bare base (fewest attaches)."""
    structure = structure_of(obj)
    graph, parts = assembly_graph(structure), structure.parts
    came_from: dict[int, tuple[int, str]] = {}
    queue = deque([0])
    seen = {0}
    while queue:
        state = queue.popleft()
        for move in graph.moves[state]:
            if move.kind == ATTACH and move.target not in seen:
                seen.add(move.target)
                came_from[move.target] = (state, parts[move.part])
                queue.append(move.target)
    order: list[str] = []
    state = graph.assembled
    while state != 0:
        state, part = came_from[state]
        order.append(part)
    return order[::-1]


def rebuild_steps(obj: AssemblyObject, order: list[str]) -> list[StepRequest]:
    """Return the steps that attach ``order`` and light the object, in an order the object allows.

    Each ignite fit is made as soon as its part is in place and the fits its requirement must
    come ``after`` are made (a lantern's mantle is lit once the valve is open), and before a
    part covers it. So the parts a light waits for go on first, and a part that would cover a
    light still waiting goes on after it; otherwise the parts keep the episode's order.
    """
    fit_of = {fit.moving_part: fit for fit in obj.fits if fit.primitive != "ignite"}
    lights = [fit for fit in obj.fits if fit.primitive == "ignite"]
    steps: list[StepRequest] = []
    in_place = {obj.base}
    made: set[str] = set()
    covered: set[tuple[str, str]] = set()

    def after(fit: Fit) -> tuple[str, ...]:
        requirement = obj.requirement_of(fit.id)
        return requirement.after if requirement is not None else ()

    def make(fit: Fit) -> None:
        steps.append(StepRequest(fit.primitive, fit.moving_part, fit.fixed_part, fit.id))
        made.add(fit.id)
        covered.update(fit.blocks)

    def light_what_can_be() -> None:
        for fit in [fit for fit in lights if fit.fixed_part in in_place and made.issuperset(after(fit))]:
            if (fit.fixed_part, fit.fixed_connector) not in covered:
                make(fit)
                lights.remove(fit)

    light_what_can_be()
    remaining = list(order)
    while remaining:
        doable = [part for part in remaining if fit_of[part].fixed_part in in_place]
        if not doable:  # the episode's order is the object's: keep it as it is
            doable = remaining[:1]
        waited_for = {fit_id for light in lights for fit_id in after(light)}
        waiting = {(light.fixed_part, light.fixed_connector) for light in lights}
        part = next(
            (part for part in doable if fit_of[part].id in waited_for),
            next((part for part in doable if not waiting & set(fit_of[part].blocks)), doable[0]),
        )
        remaining.remove(part)
        make(fit_of[part])
        in_place.add(part)
        light_what_can_be()
    return steps


def repair_in_physics(obj: AssemblyObject, episode: Episode) -> RepairInPhysics:
    """Rebuild ``obj`` as ``episode`` left it at its last test, in physics, and judge whether it gives its goal."""
    order = first_build_order(obj)
    last_test = max(index for index, step in enumerate(episode.steps) if step.kind == TEST)
    replaced = False
    for step in episode.steps[:last_test]:
        if step.kind == DETACH and step.part in order:
            order.remove(step.part)
        elif step.kind == ATTACH and step.part is not None:
            order.append(step.part)
        elif step.kind == TEST:
            replaced = False  # an earlier test showed no goal: the spares so far were not the answer
        elif step.kind == REPLACE and step.part == episode.fault:
            replaced = True
    steps = rebuild_steps(obj, order)
    report = simulate_plan(obj, steps, render=RenderMode.NONE)
    fits = tuple(step.fit for step in steps if step.fit is not None)
    return RepairInPhysics((obj.base, *order), fits, report, replaced)
