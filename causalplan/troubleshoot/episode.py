"""One troubleshooting episode: a policy carried out on an object whose broken part is known to the world.

Observations are perfect: a test shows the goal exactly when the broken part has been
replaced; inspecting a part whose fault shows says whether it is the broken one.
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.troubleshoot.assembly import ATTACH, DETACH, Move
from causalplan.troubleshoot.solver import INSPECT, REPLACE, TEST, Act, Policy

GOAL, NO_GOAL, BROKEN, WORKS = "goal", "no goal", "broken", "works"


@dataclass(frozen=True)
class Step:
    """One action of an episode: its kind, its part (None for a test) and what it showed (None: nothing)."""

    kind: str
    part: str | None
    observed: str | None = None

    def text(self, goal: str) -> str:
        """Return the action in words, with what it showed."""
        if self.kind == TEST:
            return f"test: {goal}" if self.observed == GOAL else f"test: no {goal}"
        shown = f": {self.observed}" if self.observed else ""
        return f"{self.kind} {self.part}{shown}"

    def as_dict(self) -> dict[str, str | None]:
        return {"action": self.kind, "part": self.part, "observed": self.observed}


@dataclass(frozen=True)
class Episode:
    """The actions taken on an object broken at ``fault``, until a test showed the goal."""

    fault: str
    steps: tuple[Step, ...]

    @property
    def actions(self) -> int:
        return len(self.steps)


def run_episode(policy: Policy, fault: str) -> Episode:
    """Carry out ``policy`` on the object broken at ``fault`` (a part id) and return every action taken."""
    structure, graph = policy.structure, policy.graph
    broken = structure.index(fault)
    suspects, replaced = policy.start
    state = graph.assembled
    steps: list[Step] = []
    limit = 4 * structure.size * (structure.size + 2) + 8  # far above any policy's longest episode
    while len(steps) < limit:
        chosen = policy.choice((suspects, replaced), state)
        if isinstance(chosen, Move):
            assert chosen.kind in (DETACH, ATTACH)
            steps.append(Step(chosen.kind, structure.parts[chosen.part]))
            state = chosen.target
            continue
        assert isinstance(chosen, Act)
        if chosen.kind == TEST:
            if replaced >> broken & 1:
                steps.append(Step(TEST, None, GOAL))
                return Episode(fault, tuple(steps))
            steps.append(Step(TEST, None, NO_GOAL))
            replaced = 0
        elif chosen.kind == INSPECT:
            is_broken = chosen.part == broken
            steps.append(Step(INSPECT, structure.parts[chosen.part], BROKEN if is_broken else WORKS))
            suspects = 1 << chosen.part if is_broken else suspects & ~(1 << chosen.part)
            replaced = 0 if is_broken else replaced
        else:
            assert chosen.kind == REPLACE
            steps.append(Step(REPLACE, structure.parts[chosen.part]))
            suspects &= ~(1 << chosen.part)
            replaced |= 1 << chosen.part
    raise RuntimeError(f"the policy did not repair {fault} in {limit} actions")
