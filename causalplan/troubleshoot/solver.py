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

Ties go to acting before moving, then to the test, then to inspections and replacements in
the catalog's part order, then to moves in the assembly graph's order, so a policy is the same
on every run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from causalplan.troubleshoot.assembly import AssemblyGraph, Move, assembly_graph
from causalplan.troubleshoot.errors import TooLargeError
from causalplan.troubleshoot.priors import Suspicion
from causalplan.troubleshoot.structure import Structure, bits

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

TEST, INSPECT, REPLACE = "test", "inspect", "replace"
MAX_STATES = 10_000_000
"""The (belief, assembly state) pairs the solver may hold: about 18 bytes each, 180 MB in all."""
NO_PART = -1
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
    values: npt.NDArray[np.float64]
    """The value of each assembly state."""
    acting: npt.NDArray[np.float64]
    """The value of the best informative action in each state (inf: none there)."""
    acts: tuple[Act, ...]
    which: npt.NDArray[np.int16]
    """The index in ``acts`` of that action, per state."""


@dataclass
class Policy:
    """The optimal policy of one strategy on one object: a value and a choice for every state it reaches."""

    structure: Structure
    graph: AssemblyGraph
    suspicion: Suspicion
    max_states: int = MAX_STATES
    _distances: npt.NDArray[np.float64] | None = field(default=None, repr=False)
    _tables: dict[Belief, _BeliefTable] = field(default_factory=dict, repr=False)
    _masks: dict[tuple[str, int], npt.NDArray[np.bool_]] = field(default_factory=dict, repr=False)

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

    def _table(self, belief: Belief) -> _BeliefTable:
        table = self._tables.get(belief)
        if table is None:
            if (len(self._tables) + 1) * len(self.graph.states) > self.max_states:
                raise TooLargeError(
                    f"Solving the {self.structure.object_id} exactly needs more than {self.max_states} "
                    "(belief, assembly) states.",
                    details={"object": self.structure.object_id, "limit": self.max_states},
                )
            table = self._solve(belief)
            self._tables[belief] = table
        return table

    def _solve(self, belief: Belief) -> _BeliefTable:
        import numpy as np

        structure, graph, suspicion = self.structure, self.graph, self.suspicion
        suspects, replaced = belief
        among = suspects | replaced
        count = len(graph.states)
        acts: list[Act] = []
        rows: list[npt.NDArray[np.float64]] = []
        if replaced:
            repaired = sum(suspicion.share(part, among) for part in bits(replaced))
            after = 0.0 if not suspects else (1.0 - repaired) * self.value((suspects, 0), graph.assembled)
            row = np.full(count, np.inf)
            row[graph.assembled] = 1.0 + after
            acts.append(Act(TEST))
            rows.append(row)
        if among.bit_count() >= 2:
            for part in bits(suspects & structure.visible):
                broken = suspicion.share(part, among)
                found = self._table((1 << part, 0)).values
                cleared = self._table((suspects & ~(1 << part), replaced)).values
                values = 1.0 + broken * found + (1.0 - broken) * cleared
                acts.append(Act(INSPECT, part))
                rows.append(np.where(self._allowed(INSPECT, part), values, np.inf))
        for part in bits(suspects):
            swapped = self._table((suspects & ~(1 << part), replaced | 1 << part)).values
            acts.append(Act(REPLACE, part))
            rows.append(np.where(self._allowed(REPLACE, part), 1.0 + swapped, np.inf))
        table = np.vstack(rows)
        which = np.argmin(table, axis=0).astype(np.int16)
        acting = table[which, np.arange(count)]
        values = np.min(self._all_distances() + acting[np.newaxis, :], axis=1)
        return _BeliefTable(values, acting, tuple(acts), which)

    def _allowed(self, kind: str, part: int) -> npt.NDArray[np.bool_]:
        """Return, per assembly state, whether ``part`` can be inspected (or replaced) there."""
        import numpy as np

        key = (kind, part)
        if key not in self._masks:
            allowed = self.structure.can_inspect if kind == INSPECT else self.structure.can_replace
            states = self.graph.states
            self._masks[key] = np.fromiter((allowed(part, attached) for attached in states), bool, len(states))
        return self._masks[key]

    def _all_distances(self) -> npt.NDArray[np.float64]:
        import numpy as np

        if self._distances is None:
            distances = self.graph.distances().astype(np.float64)
            distances[distances < 0] = np.inf
            self._distances = distances
        return self._distances


def solve(structure: Structure, suspicion: Suspicion, max_states: int = MAX_STATES) -> Policy:
    """Return the exact policy of ``suspicion`` on ``structure`` (solved as far as the start needs it)."""
    policy = Policy(structure, assembly_graph(structure), suspicion, max_states)
    policy.expected_actions()
    return policy
