"""The default policy: where a search stopped early, how the returned policy goes on.

From a state it follows an *all-success completion*: a sequence of attempts that reaches the
goal if every one of them succeeds, preferring necessary parts (by their most reliable fit),
then the most reliable fit. The completion is found by depth-first search with backtracking,
pruned by the relaxed test (the goal stays reachable if every usable fit succeeded). A
one-step look-ahead on that test alone is not enough: the relaxation lets two parts count on
one socket, so parts that share sockets in a cycle can be attached half-way round the wrong
way and strand the last part; the plan then ends without the goal (issue 44). Backtracking
finds the way round, or proves that there is none (the state can never reach the goal).

The completion's chance (every attempt succeeds) bounds the default policy's success from
below; its expected attempts, counting a stop at the first failure, are exact whenever
failures on it leave no completion. ``evaluate_policy`` gives the figures of a searched
policy completed by this default, exactly as ``search.decide`` rolls it out.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from causalplan.planners.mdp.bounds import bound
from causalplan.planners.mdp.model import STEP_COST, CompiledMdp, Completion, State, single_bits

NODES_PER_FIT = 4
"""The depth-first search's budget: this many states per relevant fit; beyond it, no completion."""


NO_COMPLETION = Completion((), 0.0, 0.0)


class _OutOfNodes(Exception):
    """Raised when the depth-first search has used its budget."""


def _sockets_suffice(compiled: CompiledMdp, necessary: int, unusable: int) -> bool:
    """Return whether the necessary parts can each take a usable fit onto a different connector.

    Two parts cannot both take one connector, which the relaxed test overlooks: a matching of
    parts to connectors (Kuhn's augmenting paths) sees a cycle of shared sockets at once.
    """
    options: dict[int, list[tuple[int, str]]] = {}
    for bit in single_bits(necessary):
        options[bit] = [
            (compiled.fixed[index], compiled.fits[index].fixed_connector)
            for index in compiled.fits_of_part.get(bit, ())
            if not unusable >> index & 1
        ]
    holder: dict[tuple[int, str], int] = {}

    def place(bit: int, tried: set[tuple[int, str]]) -> bool:
        for connector in options[bit]:
            if connector in tried:
                continue
            tried.add(connector)
            if connector not in holder or place(holder[connector], tried):
                holder[connector] = bit
                return True
        return False

    return all(place(bit, set()) for bit in options)


def _search(compiled: CompiledMdp, parts: int, unusable: int, step_cost: float) -> tuple[int, ...] | None:
    """Return the fits of an all-success completion from (parts, unusable); None when there is none."""
    dead: set[tuple[int, int]] = compiled.completion_dead_ends
    budget = [NODES_PER_FIT * max(1, len(compiled.fits))]

    def complete(parts: int, unusable: int) -> list[int] | None:
        if compiled.goal_holds(parts):
            return []
        if (parts, unusable) in dead:
            return None
        budget[0] -= 1
        if budget[0] < 0:
            raise _OutOfNodes
        here = bound(compiled, parts, unusable, 0, step_cost)
        if here.dead_end or not _sockets_suffice(compiled, here.necessary & ~parts, unusable):
            dead.add((parts, unusable))
            return None
        options = sorted(
            compiled.applicable(parts, unusable),
            key=lambda index: (not compiled.moving[index] & here.necessary, -compiled.probability[index], index),
        )
        for index in options:
            rest = complete(parts | compiled.moving[index], unusable | compiled.taken_on_success[index])
            if rest is not None:
                return [index, *rest]
        dead.add((parts, unusable))
        return None

    try:
        found = complete(parts, unusable)
    except _OutOfNodes:
        return None
    return None if found is None else tuple(found)


def completion(compiled: CompiledMdp, state: State, step_cost: float = STEP_COST) -> Completion:
    """Return the default policy's all-success completion from ``state`` (``NO_COMPLETION`` when none is found).

    Kept per state on the compiled MDP: a rollout asks for the states of one path again and again.
    """
    known = compiled.completions.get(state)
    if known is not None:
        return known
    parts, unusable = compiled.parts_of(state)
    fits = _search(compiled, parts, unusable, step_cost)
    if fits is None:
        compiled.completions[state] = NO_COMPLETION
        return NO_COMPLETION
    made, failed = state
    for position in range(len(fits)):  # every state on the way has the rest of it as its own
        rest = [compiled.probability[index] for index in fits[position:]]
        attempts = sum(math.prod(rest[:count]) for count in range(len(rest)))
        compiled.completions.setdefault((made, failed), Completion(fits[position:], math.prod(rest), attempts))
        made |= 1 << fits[position]
    compiled.completions.setdefault((made, failed), Completion((), 1.0, 0.0))
    return compiled.completions[state]


def default_attempt(compiled: CompiledMdp, state: State, step_cost: float = STEP_COST) -> int:
    """Return the default policy's attempt in ``state``: the first of its completion; -1 when there is none."""
    found = completion(compiled, state, step_cost)
    return found.fits[0] if found.fits else -1


MAX_EVALUATED_STATES = 200_000
"""Beyond this many states, the returned policy's figures count the rest as failures (a lower bound)."""


@dataclass
class Evaluation:
    """The returned policy's figures: success probability and expected attempts, its table and successes.

    ``exact`` says that every state the policy reaches was evaluated (within the deadline and
    ``MAX_EVALUATED_STATES``): the figures are the policy's own, not bounds.
    """

    success: float
    attempts: float
    table: dict[State, int]
    successes: dict[State, float]
    exact: bool


def evaluate_policy(
    compiled: CompiledMdp, step_cost: float, table: dict[State, int], start: tuple[State, int, int], deadline: float
) -> Evaluation:
    """Return the figures of the policy ``decide`` follows: ``table`` where it has the state, else the default.

    Elsewhere than the table the policy is the default one (``completion.py``), so the figures
    are those of exactly the policy that is returned and rolled out. States beyond the deadline
    or the budget count as failures, and the figures are then lower bounds.
    """
    c = compiled
    success: dict[State, float] = {}
    attempts: dict[State, float] = {}
    exact = [True]

    def value(state: State, parts: int, unusable: int) -> tuple[float, float]:
        known = success.get(state)
        if known is not None:
            return known, attempts[state]
        if c.goal_holds(parts):
            result = (1.0, 0.0)
        elif len(success) >= MAX_EVALUATED_STATES or time.monotonic() > deadline:
            exact[0] = False
            return 0.0, 0.0
        else:
            index = table[state] if state in table else default_attempt(c, state, step_cost)
            if index < 0:
                result = (0.0, 0.0)
            else:
                made, failed = state
                bit, p = 1 << index, c.probability[index]
                s_success, a_success = value(
                    (made | bit, failed), parts | c.moving[index], unusable | c.taken_on_success[index]
                )
                s_failure, a_failure = (
                    value((made, failed | bit), parts, unusable | c.taken_on_failure[index]) if p < 1.0 else (0.0, 0.0)
                )
                result = (p * s_success + (1 - p) * s_failure, 1 + p * a_success + (1 - p) * a_failure)
        success[state], attempts[state] = result
        return result

    root_success, root_attempts = value(*start)
    return Evaluation(root_success, root_attempts, table, success, exact[0])
