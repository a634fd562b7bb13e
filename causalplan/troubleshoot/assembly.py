"""The assembly states a troubleshooter can bring the object into, and the moves between them.

A state is the set of body parts attached (a bit mask). A move detaches or attaches one part
and costs one action; the two are each other's inverse, so the graph is undirected. Only the
states reachable from the bare base count, and the assembled object must be one of them.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from causalplan.troubleshoot.errors import NotTroubleshootableError, TooLargeError
from causalplan.troubleshoot.structure import Structure, bits

DETACH, ATTACH = "detach", "attach"
MAX_ASSEMBLY_STATES = 1 << 12
"""The all-pairs distances of this many states take 130 MB; beyond it the beliefs are too many anyway."""


@dataclass(frozen=True)
class Move:
    """One detach or attach: ``part`` (its number) and the state it leads to (its index)."""

    kind: str
    part: int
    target: int


@dataclass(frozen=True)
class AssemblyGraph:
    """Every reachable assembly state (``states[i]`` a mask) and each one's moves, in a fixed order."""

    states: tuple[int, ...]
    moves: tuple[tuple[Move, ...], ...]
    assembled: int
    """The index of the assembled object's state."""

    def index(self, attached: int) -> int:
        return self.states.index(attached)

    def distances(self) -> list[list[int]]:
        """Return the fewest moves between every two states (a breadth-first search from each; -1: none)."""
        count = len(self.states)
        result = [[-1] * count for _ in range(count)]
        for source in range(count):
            row = result[source]
            row[source] = 0
            frontier = [source]
            distance = 0
            while frontier:
                distance += 1
                ahead = []
                for state in frontier:
                    for move in self.moves[state]:
                        if row[move.target] < 0:
                            row[move.target] = distance
                            ahead.append(move.target)
                frontier = ahead
        return result


def assembly_graph(structure: Structure, max_states: int = MAX_ASSEMBLY_STATES) -> AssemblyGraph:
    """Return the states reachable from the bare base by detaching and attaching, and the moves.

    TooLargeError when there are more than ``max_states``; NotTroubleshootableError when the
    object cannot be assembled whole (its fits block each other whatever the order).
    """
    number: dict[int, int] = {0: 0}
    states = [0]
    queue = deque([0])
    edges: list[list[tuple[str, int, int]]] = [[]]
    while queue:
        attached = queue.popleft()
        here = number[attached]
        for part in bits(structure.body):
            if structure.can_detach(part, attached):
                kind, after = DETACH, attached & ~(1 << part)
            elif structure.can_attach(part, attached):
                kind, after = ATTACH, attached | 1 << part
            else:
                continue
            if after not in number:
                if len(states) >= max_states:
                    raise TooLargeError(
                        f"The {structure.object_id} has more than {max_states} assembly states.",
                        details={"object": structure.object_id, "limit": max_states},
                    )
                number[after] = len(states)
                states.append(after)
                edges.append([])
                queue.append(after)
            edges[here].append((kind, part, after))
    if structure.body not in number:
        raise NotTroubleshootableError(
            f"The {structure.object_id} cannot be assembled whole: its parts block each other in every order.",
            details={"object": structure.object_id},
        )
    moves = tuple(tuple(Move(kind, part, number[after]) for kind, part, after in edge) for edge in edges)
    return AssemblyGraph(tuple(states), moves, number[structure.body])
