"""The paper's MDP solved by heuristic search from the start state (``mdp``): improved LAO*.

Improved LAO* (Hansen and Zilberstein 2001) keeps the states expanded so far and, in each
pass, walks the current best policy depth first from the start, expands the unexpanded states
it meets, and backs the values up in post-order. A state's value is the optimum over its
expanded successors and, for the others, an admissible upper bound (``bounds.py``): so the
values never fall below the optimum. The state graph is acyclic (every attempt adds a fit to
the made or failed ones), so a state whose best attempt leads only to solved states has its
exact optimal value and is labelled *solved* (as in AO*); the search ends when the start is
solved, with the same optimal value as the exact solver over far fewer states.

When the time limit or the state budget comes first, the answer is anytime: the best policy
so far (its unexpanded states completed by the bound's greedy choice), a lower bound on its
success probability (those states counted as failures) and an upper bound on the success
probability of every policy (the bound's), never a hang.
"""

from __future__ import annotations

import sys
import time

from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.bounds import DEAD_END, Bound, bound
from causalplan.planners.mdp.model import (
    STEP_COST,
    CompiledMdp,
    MdpSolution,
    Optimality,
    State,
    compile_mdp,
    policy_entries,
    relevant_fits,
)
from causalplan.planners.result import PlanStatus

MAX_NODES = 1_000_000
SEARCH_SHARE = 0.9
MIN_SUCCESS_SCALE = 1e-9
TIE = 1e-12
"""A new best attempt must beat the old by more than this (the exact solver's rule: first index wins ties)."""


class _Node:
    """A state in the search graph with its bounds, and once expanded, its attempts."""

    __slots__ = ("action", "children", "necessary", "parts", "solved", "state", "success", "unusable", "value")

    def __init__(self, state: State, parts: int, unusable: int, estimate: Bound) -> None:
        self.state = state
        self.parts = parts
        self.unusable = unusable
        self.value = estimate.value
        self.success = estimate.success  # upper bound on the success probability of any policy
        self.necessary = estimate.necessary
        self.solved = estimate.goal or estimate.dead_end
        self.action = -1  # position in ``children`` of the best attempt
        self.children: list[tuple[int, _Node, _Node]] | None = None  # (fit, success, failure)


class _OutOfBudget(Exception):
    """Raised inside a pass when the time limit or the state budget is exhausted."""


class _Search:
    def __init__(self, compiled: CompiledMdp, step_cost: float, deadline: float) -> None:
        self.c = compiled
        self.step_cost = step_cost
        self.deadline = deadline
        self.nodes: dict[State, _Node] = {}
        self.expanded = 0

    def node(self, state: State, parts: int, unusable: int, necessary: int) -> _Node:
        known = self.nodes.get(state)
        if known is None:
            known = _Node(state, parts, unusable, bound(self.c, parts, unusable, necessary, self.step_cost))
            self.nodes[state] = known
        return known

    def expand(self, node: _Node) -> None:
        if len(self.nodes) >= MAX_NODES or time.monotonic() > self.deadline:
            raise _OutOfBudget
        c, (made, failed) = self.c, node.state
        children: list[tuple[int, _Node, _Node]] = []
        for index in c.applicable(node.parts, node.unusable):
            bit = 1 << index
            success = self.node(
                (made | bit, failed),
                node.parts | c.moving[index],
                node.unusable | c.taken_on_success[index],
                node.necessary,
            )
            failure = (
                self.node((made, failed | bit), node.parts, node.unusable | c.taken_on_failure[index], node.necessary)
                if c.probability[index] < 1.0
                else success
            )
            children.append((index, success, failure))
        node.children = children
        self.expanded += 1

    def backup(self, node: _Node) -> None:
        """Set the node's best attempt and bounds from its children; label it solved when exact."""
        assert node.children is not None
        best_value, best_success, best = -2.0, 0.0, -1
        for position, (index, success, failure) in enumerate(node.children):
            p = self.c.probability[index]
            q = -self.step_cost + p * success.value + (1 - p) * failure.value
            best_success = max(best_success, p * success.success + (1 - p) * failure.success)
            if best < 0 or q > best_value + TIE:
                best_value, best = q, position
        if best < 0:  # no attempt left: the bound's dead-end test rules this out, but be safe
            node.value, node.success, node.solved, node.action = DEAD_END.value, 0.0, True, -1
            return
        index, success, failure = node.children[best]
        solved = success.solved and failure.solved
        node.value, node.success, node.action, node.solved = best_value, best_success, best, solved

    def best_child_states(self, node: _Node) -> tuple[_Node, ...]:
        assert node.children is not None and node.action >= 0
        _, success, failure = node.children[node.action]
        return (success,) if success is failure else (success, failure)

    def run_pass(self, root: _Node) -> None:
        """One depth-first walk of the best partial policy: expand its tips, back up in post-order."""
        visited: set[State] = set()

        def visit(node: _Node) -> None:
            if node.solved or node.state in visited:
                return
            visited.add(node.state)
            if node.children is None:
                self.expand(node)
            else:
                for child in self.best_child_states(node):
                    visit(child)
            self.backup(node)

        visit(root)


def default_attempt(compiled: CompiledMdp, state: State, step_cost: float = STEP_COST) -> int:
    """Return the attempt of the default policy, used where the search stopped early; -1 when over.

    It attaches a necessary part if it can (the most reliable such fit), else the most
    reliable fit whose success keeps the goal reachable.
    """
    parts, unusable = compiled.parts_of(state)
    here = bound(compiled, parts, unusable, 0, step_cost)
    if here.goal or here.dead_end:
        return -1
    best, best_key = -1, (False, -1.0)
    for index in compiled.applicable(parts, unusable):
        after = compiled.reachable_parts(parts | compiled.moving[index], unusable | compiled.taken_on_success[index])
        if not compiled.goal_holds(after):
            continue
        key = (bool(compiled.moving[index] & here.necessary), compiled.probability[index])
        if best < 0 or key > best_key:
            best, best_key = index, key
    return best


def _default_success(compiled: CompiledMdp, state: State, step_cost: float) -> float:
    """Return a lower bound on the default policy's success from ``state``: its all-success path's chance."""
    made, failed = state
    chance = 1.0
    while (index := default_attempt(compiled, (made, failed), step_cost)) >= 0:
        chance *= compiled.probability[index]
        made |= 1 << index
    return chance if compiled.goal_holds(compiled.parts_of((made, failed))[0]) else 0.0


def tie_breaking_step_cost(compiled: CompiledMdp) -> float:
    """Return a step cost that only breaks ties between policies of (nearly) equal success probability.

    A fixed step cost outweighs the goal's reward where success is unlikely, and the value's
    optimum would then rush into a dead end. Scaled by a lower bound on the best success
    probability (the default policy's all-success path) over the number of relevant fits, all
    attempts together cost at most ``STEP_COST`` times that probability, so a policy is only
    preferred to a more reliable one when it is less reliable by under ``STEP_COST / 2`` of it.
    """
    reachable = _default_success(compiled, (0, 0), STEP_COST)
    return STEP_COST * max(reachable, MIN_SUCCESS_SCALE) / max(1, len(compiled.fits))


def _evaluate(
    search: _Search, root: _Node, deadline: float
) -> tuple[float, float, dict[State, int], dict[State, float]]:
    """Return the best policy's success probability, expected attempts, its table and successes.

    Where the search stopped early, the policy goes on with ``default_attempt``: its success
    there is bounded below by its all-success path's chance (0 once ``deadline`` has passed),
    so the first figure is a lower bound (and the attempts are counted up to there).
    """
    success: dict[State, float] = {}
    attempts: dict[State, float] = {}
    table: dict[State, int] = {}
    c = search.c

    def value(node: _Node) -> tuple[float, float]:
        known = success.get(node.state)
        if known is not None:
            return known, attempts[node.state]
        if c.goal_holds(node.parts):
            result = (1.0, 0.0)
        elif node.solved and node.action < 0:
            result = (0.0, 0.0)
        elif node.children is None:
            tip = _default_success(c, node.state, search.step_cost) if time.monotonic() < deadline else 0.0
            result = (tip, 0.0)
        else:
            index, on_success, on_failure = node.children[node.action]
            table[node.state] = index
            p = c.probability[index]
            s_success, a_success = value(on_success)
            s_failure, a_failure = value(on_failure)
            result = (p * s_success + (1 - p) * s_failure, 1 + p * a_success + (1 - p) * a_failure)
        success[node.state], attempts[node.state] = result
        return result

    root_success, root_attempts = value(root)
    return root_success, root_attempts, table, success


def decide(compiled: CompiledMdp, solution: MdpSolution, state: State, step_cost: float = STEP_COST) -> int:
    """Return the fit index the solution attempts in ``state``; -1 when the run is over.

    Inside the searched states, the policy's own choice; elsewhere (an anytime answer), the
    default policy's.
    """
    if state in solution.policy_table:
        return solution.policy_table[state]
    return default_attempt(compiled, state, step_cost)


def _all_success_path(
    compiled: CompiledMdp, solution: MdpSolution, step_cost: float
) -> tuple[tuple[str, tuple[str, ...]], ...]:
    actions: list[tuple[str, tuple[str, ...]]] = []
    made = 0
    while (index := decide(compiled, solution, (made, 0), step_cost)) >= 0:
        fit = compiled.fits[index]
        actions.append((fit.primitive, (fit.moving_part, fit.fixed_part, fit.id)))
        made |= 1 << index
    return tuple(actions)


def solve_mdp_search(task: PlanningTask, time_limit: float = 10.0, step_cost: float = STEP_COST) -> MdpSolution:
    """Solve the task's MDP by improved LAO* from the start; anytime (``bounded``) at the limit."""
    return search_compiled_mdp(compile_mdp(task, relevant_fits(task)), time_limit, step_cost)


def search_compiled_mdp(compiled: CompiledMdp, time_limit: float, step_cost: float) -> MdpSolution:
    """Solve a compiled MDP by improved LAO* (``solve_mdp_search``'s work, for callers that solve it more than once)."""
    fits = compiled.fits
    started = time.monotonic()
    # The last tenth of the time goes to bounding the policy where the search stopped.
    search = _Search(compiled, step_cost, started + SEARCH_SHARE * time_limit)
    root = search.node((0, 0), compiled.base, 0, 0)
    optimality = Optimality.OPTIMAL
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 4 * len(fits) + 200))  # one frame per attempt on a path, twice
    try:
        while not root.solved:
            search.run_pass(root)
    except _OutOfBudget:
        optimality = Optimality.BOUNDED
    try:
        return _solution(search, root, optimality, time_limit, started + time_limit)
    finally:
        sys.setrecursionlimit(limit)


def _solution(search: _Search, root: _Node, optimality: Optimality, time_limit: float, deadline: float) -> MdpSolution:
    compiled, fits, step_cost = search.c, search.c.fits, search.step_cost
    if root.solved and root.success == 0.0:
        return MdpSolution(
            PlanStatus.UNSOLVABLE,
            success_probability=0.0,
            expected_actions=0.0,
            states=search.expanded,
            relevant_fits=len(fits),
            message="No policy reaches the goal: even if every attempt succeeded.",
            success_upper=0.0,
            fits=fits,
        )
    success, attempts, table, successes = _evaluate(search, root, deadline)
    message = ""
    if optimality is Optimality.BOUNDED:
        fallback = _default_success(compiled, (0, 0), step_cost)
        if fallback > success:  # the default policy alone is provably better than what was bounded
            success, table, successes = fallback, {}, {}
        message = (
            f"The time limit ({time_limit:g} s) or the state budget came first after {search.expanded:,} expansions: "
            f"this is the best policy so far; it succeeds with probability at least {success:.4f}, and no policy "
            f"does better than {root.success:.4f}."
        )
    draft = MdpSolution(PlanStatus.SOLVED, fits=fits, policy_table=table)
    return MdpSolution(
        PlanStatus.SOLVED,
        _all_success_path(compiled, draft, step_cost),
        success,
        attempts if optimality is Optimality.OPTIMAL else None,
        policy_entries(compiled, table, successes),
        search.expanded,
        len(fits),
        message,
        optimality,
        root.success if optimality is Optimality.BOUNDED else success,
        fits=fits,
        policy_table=table,
    )
