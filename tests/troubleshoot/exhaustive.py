"""Brute force for the tests: finite-horizon value iteration over every action in every state.

No pruning, no shortcut through the assembly graph: every detach, attach, test, inspection and
replacement (useless ones too) is tried in every (suspects, replaced, assembly) state, for
every horizon up to ``horizon``. That is the minimum over all policies of at most
``horizon`` actions, and the exact solver must reach it.
"""

from __future__ import annotations

import math

from causalplan.troubleshoot.assembly import assembly_graph
from causalplan.troubleshoot.priors import Suspicion
from causalplan.troubleshoot.structure import Structure, bits

State = tuple[int, int, int]
Outcomes = list[list[tuple[float, State | None]]]
"""Each action's outcomes: (probability, next state; None when repaired)."""


def _outcomes(structure: Structure, suspicion: Suspicion, state: State, attached: int) -> Outcomes:
    """Return each action's outcomes from ``state``: (probability, next state; None when repaired)."""
    suspects, replaced, where = state
    among = suspects | replaced
    graph = assembly_graph(structure)
    options: Outcomes = []
    for move in graph.moves[where]:
        options.append([(1.0, (suspects, replaced, move.target))])
    if structure.is_assembled(attached):
        repaired = sum(suspicion.share(part, among) for part in bits(replaced))
        options.append([(repaired, None), (1.0 - repaired, (suspects, 0, where))])
    for part in range(structure.size):
        if structure.can_inspect(part, attached):
            if suspects >> part & 1:
                broken = suspicion.share(part, among)
                options.append(
                    [(broken, (1 << part, 0, where)), (1.0 - broken, (suspects & ~(1 << part), replaced, where))]
                )
            else:
                options.append([(1.0, state)])
        if structure.can_replace(part, attached):
            if suspects >> part & 1:
                options.append([(1.0, (suspects & ~(1 << part), replaced | 1 << part, where))])
            else:
                options.append([(1.0, state)])
    return options


def _value(values: dict[State, float], after: State | None) -> float:
    return 0.0 if after is None else values[after]


def _is_possible(probability: float, after: State | None) -> bool:
    """Return whether an outcome can happen: some probability, and a broken part still among the parts believed."""
    return probability > 0 and (after is None or bool(after[0] | after[1]))


def best_expected_actions(structure: Structure, suspicion: Suspicion, horizon: int) -> float:
    """Return the fewest expected actions to the repair over all policies of at most ``horizon`` actions."""
    graph = assembly_graph(structure)
    everything = structure.all_parts
    states = [
        (suspects, replaced, where)
        for suspects in range(everything + 1)
        for replaced in range(everything + 1)
        if not suspects & replaced and suspects | replaced
        for where in range(len(graph.states))
    ]
    outcomes = {state: _outcomes(structure, suspicion, state, graph.states[state[2]]) for state in states}
    values = dict.fromkeys(states, math.inf)
    for _ in range(horizon):
        values = {
            state: min(
                (
                    1.0
                    + sum(
                        p * (0.0 if after is None else values[after]) for p, after in option if _is_possible(p, after)
                    )
                    for option in outcomes[state]
                ),
                default=math.inf,
            )
            for state in states
        }
    return values[(everything, 0, graph.assembled)]
