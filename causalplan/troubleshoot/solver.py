"""The exact troubleshooting policy: dynamic programming over the belief and the assembly.

The belief is two sets of parts: ``suspects`` (not yet cleared) and ``replaced`` (swapped for
a spare since the last test, so the object may already be repaired). The broken part is one of
them; the strategy's prior (``Suspicion``) weighs them. Every action costs 1:

- ``test`` (the object assembled): the goal when the broken part was replaced (the episode
  ends), else every replaced part is cleared;
- ``inspect PART`` (a suspect whose fault shows, within reach): broken, or cleared;
- ``replace PART`` (a suspect off the object): it moves from the suspects to the replaced;
- ``detach PART`` / ``attach PART``: change the assembly, not the belief.

Each informative action (test, inspect, replace) makes the belief strictly smaller (fewer
suspects and replaced together, or fewer suspects), so the beliefs form an acyclic graph and
are solved from the smallest up. Between two informative actions only moves happen, and the
best moves are a shortest path in the assembly graph, so for one belief the value of state
``A`` is ``min over A' of distance(A, A') + acting(A')``, where ``acting`` is the best
informative action's value in each state. The result is the minimum expected number of
actions under the strategy's own prior, and a policy that reaches it, for every belief and
assembly state.

Two reductions keep it exact: beliefs whose replaced parts have the same weights share one
table (the replaced parts matter only through the chance that the object is repaired
already), and no action is tried on a part with no chance of being the broken one under the
current belief (it costs an action and changes no outcome's probability). The tests compare
the values with value iteration over every action in every state.

Ties go to acting before moving, then to the test, then to inspections and replacements in
the catalog's part order, then to moves in the assembly graph's order, so a policy is the same
on every run.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Iterable
from dataclasses import dataclass, field
from operator import add
from typing import TYPE_CHECKING

from causalplan.troubleshoot.assembly import AssemblyGraph, Move, assembly_graph
from causalplan.troubleshoot.errors import TooLargeError
from causalplan.troubleshoot.priors import Suspicion
from causalplan.troubleshoot.structure import NO_PART, Structure, bits

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

TEST, INSPECT, REPLACE = "test", "inspect", "replace"
MAX_STATES = 10_000_000
"""The (belief, assembly state) pairs the solver may hold: about 18 bytes each, 180 MB in all."""
SMALL_GRAPH = 32
"""Up to this many assembly states, a belief's values are summed in Python; above, with numpy."""
TOLERANCE = 1e-9
"""Values closer than this are equal (sums of the same numbers in another order differ in the last bits)."""


@dataclass(frozen=True)
class Act:
    """An informative action: ``kind`` is test, inspect or replace; ``part`` its part's number (-1 for test)."""

    kind: str
    part: int = NO_PART


Choice = Act | Move
Belief = tuple[int, int]
"""(suspects, replaced), each a mask of parts."""


@dataclass(frozen=True)
class _BeliefTable:
    values: array[float]
    """The value of each assembly state."""
    acting: array[float]
    """The value of the best informative action in each state (inf: none there)."""
    acts: tuple[Act, ...]
    which: array[int]
    """The index in ``acts`` of that action, per state."""


@dataclass
class Policy:
    """The optimal policy of one strategy on one object: a value and a choice for every state it reaches."""

    structure: Structure
    graph: AssemblyGraph
    suspicion: Suspicion
    max_states: int = MAX_STATES
    _rows: list[list[float]] | None = field(default=None, repr=False)
    _matrix: npt.NDArray[np.float64] | None = field(default=None, repr=False)
    _tables: dict[tuple[int, tuple[float, ...]], _BeliefTable] = field(default_factory=dict, repr=False)
    _masses: dict[int, float] = field(default_factory=dict, repr=False)
    _weighed: dict[int, tuple[float, ...]] = field(default_factory=dict, repr=False)
    _places: dict[tuple[str, int], tuple[int, ...]] = field(default_factory=dict, repr=False)

    @property
    def start(self) -> Belief:
        """Return the belief of a broken object: every part suspected, nothing replaced."""
        return (self.structure.all_parts, 0)

    @property
    def beliefs_solved(self) -> int:
        return len(self._tables)

    def value(self, belief: Belief, state: int) -> float:
        """Return the minimum expected number of actions to the repair from ``belief`` in assembly ``state``."""
        return float(self._table(belief).values[state])

    def choice(self, belief: Belief, state: int) -> Choice:
        """Return what the policy does next in ``belief`` and assembly ``state`` (a move or an informative act)."""
        table = self._table(belief)
        value = table.values[state]
        if table.acting[state] <= value + TOLERANCE:
            return table.acts[int(table.which[state])]
        for move in self.graph.moves[state]:
            if abs(table.values[move.target] + 1.0 - value) <= TOLERANCE:
                return move
        raise ValueError(f"no action leads to the repair from {belief} in state {state}")

    def expected_actions(self) -> float:
        """Return the expected number of actions from the broken, assembled object, under the strategy's prior."""
        return self.value(self.start, self.graph.assembled)

    def _share(self, part: int, among: int) -> float:
        """Return ``Suspicion.share(part, among)``, with the masses of the sets of parts kept."""
        mass = self._masses.get(among)
        if mass is None:
            mass = self._masses[among] = self.suspicion.mass(among)
        if mass > 0:
            return self.suspicion.weights[part] / mass
        return 1.0 / among.bit_count()

    def _table(self, belief: Belief) -> _BeliefTable:
        # The replaced parts matter only through their weights (the chance that the object is
        # repaired already), never by name: beliefs whose replaced parts weigh alike share a table.
        suspects, replaced = belief
        weights = self._weighed.get(replaced)
        if weights is None:
            weights = self._weighed[replaced] = tuple(sorted(self.suspicion.weights[part] for part in bits(replaced)))
        key = (suspects, weights)
        table = self._tables.get(key)
        if table is None:
            if (len(self._tables) + 1) * len(self.graph.states) > self.max_states:
                raise TooLargeError(
                    f"Solving the {self.structure.object_id} exactly needs more than {self.max_states} "
                    "(belief, assembly) states.",
                    details={"object": self.structure.object_id, "limit": self.max_states},
                )
            table = self._solve(belief)
            self._tables[key] = table
        return table

    def _solve(self, belief: Belief) -> _BeliefTable:
        structure, graph = self.structure, self.graph
        suspects, replaced = belief
        among = suspects | replaced
        count = len(graph.states)
        acting = [math.inf] * count
        which = [0] * count
        acts: list[Act] = []

        def offer(act: Act, offers: Iterable[tuple[int, float]]) -> None:
            index = len(acts)
            acts.append(act)
            for state, value in offers:
                if value < acting[state]:
                    acting[state], which[state] = value, index

        if replaced:
            repaired = sum(self._share(part, among) for part in bits(replaced))
            after = 0.0 if not suspects else (1.0 - repaired) * self.value((suspects, 0), graph.assembled)
            offer(Act(TEST), ((graph.assembled, 1.0 + after),))
        if among.bit_count() >= 2:
            for part in bits(suspects & structure.visible):
                broken = self._share(part, among)
                if broken == 0.0:
                    continue  # it works, for sure: inspecting it costs an action and teaches nothing
                found = self._table((1 << part, 0)).values
                cleared = self._table((suspects & ~(1 << part), replaced)).values
                works = 1.0 - broken
                offers = (
                    (state, 1.0 + broken * found[state] + works * cleared[state])
                    for state in self._where(INSPECT, part)
                )
                offer(Act(INSPECT, part), offers)
        for part in bits(suspects):
            if self._share(part, among) == 0.0:
                continue  # replacing a part that works for sure costs an action and repairs nothing
            swapped = self._table((suspects & ~(1 << part), replaced | 1 << part)).values
            offer(Act(REPLACE, part), ((state, 1.0 + swapped[state]) for state in self._where(REPLACE, part)))
        return _BeliefTable(self._nearest(acting), array("d", acting), tuple(acts), array("h", which))

    def _where(self, kind: str, part: int) -> tuple[int, ...]:
        """Return the assembly states in which ``part`` can be inspected (or replaced)."""
        key = (kind, part)
        if key not in self._places:
            allowed = self.structure.can_inspect if kind == INSPECT else self.structure.can_replace
            self._places[key] = tuple(
                state for state, attached in enumerate(self.graph.states) if allowed(part, attached)
            )
        return self._places[key]

    def _nearest(self, acting: list[float]) -> array[float]:
        """Return, per state, the cheapest way to act: min over states S of distance to S + acting(S).

        In Python for small assembly graphs (numpy's call costs more than the sums), else with numpy.
        """
        if self._rows is None:
            distances = self.graph.distances()
            self._rows = [[math.inf if d < 0 else float(d) for d in row] for row in distances]
        if len(acting) <= SMALL_GRAPH:
            return array("d", [min(map(add, row, acting)) for row in self._rows])
        import numpy as np

        if self._matrix is None:
            self._matrix = np.array(self._rows, dtype=np.float64)
        return array("d", np.min(self._matrix + np.array(acting)[np.newaxis, :], axis=1).tolist())


def solve(structure: Structure, suspicion: Suspicion, max_states: int = MAX_STATES) -> Policy:
    """Return the exact policy of ``suspicion`` on ``structure`` (solved as far as the start needs it)."""
    policy = Policy(structure, assembly_graph(structure), suspicion, max_states)
    policy.expected_actions()
    return policy
