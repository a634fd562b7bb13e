"""The paper's MDP solved by heuristic search from the start state (``mdp``): improved LAO*.

Improved LAO* (Hansen and Zilberstein 2001) keeps the states expanded so far and, in each
pass, walks the current best policy depth first from the start, expands the unexpanded states
it meets, and backs the values up in post-order. A state's value is the optimum over its
expanded successors and, for the others, an admissible upper bound (``bounds.py``): so the
values never fall below the optimum. The state graph is acyclic (every attempt adds a fit to
the made or failed ones), so a state whose best attempt leads only to solved states has its
exact optimal value and is labelled *solved* (as in AO*); the search ends when the start is
solved, with the same optimal value as the exact solver over far fewer states.

It also stops, ``optimal``, as soon as the returned policy's success probability, evaluated
exactly, meets the upper bound on every policy's (``PROOF_PRECISION``): the most reliable
policy is then proved, and its expected attempts are exact (those of this policy).

When the time limit or the state budget comes first, the answer is anytime: the best policy
so far (its unexpanded states completed by the default policy, ``completion.py``), a lower
bound on its success probability and an upper bound on the success probability of every
policy (the bound's), never a hang. Its plan (the path when every attempt succeeds) always
reaches the goal; when no such plan was found in time, the answer is ``timeout``, never a
plan that fails replay.
"""

from __future__ import annotations

import math
import sys
import time

from causalplan.pddl.canonical import Action
from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.bounds import DEAD_END, Bound, bound
from causalplan.planners.mdp.completion import Evaluation, completion, default_attempt, evaluate_policy
from causalplan.planners.mdp.model import (
    STEP_COST,
    CompiledMdp,
    MdpSolution,
    Optimality,
    State,
    all_success_path,
    compile_mdp,
    out_of_time,
    policy_entries,
    relevant_fits,
    unsolvable,
)
from causalplan.planners.result import PlanStatus

MAX_NODES = 1_000_000
SEARCH_SHARE = 0.9
"""The share of the time limit the search has; the rest evaluates the policy it returns."""
MIN_SUCCESS_SCALE = 1e-9
"""The least success probability ``tie_breaking_step_cost`` scales by (so the step cost never vanishes)."""
PROOF_PRECISION = 1e-9
"""The optimum is proved when the returned policy's success probability is within this share of the bound."""
FIRST_CHECK = 64
"""Expansions before the first check whether the bounds have met (then at doubling numbers)."""
CHECK_SHARE = 0.05
"""The most of the time limit one such check may take (beyond it, the check is inconclusive)."""
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


def tie_breaking_step_cost(compiled: CompiledMdp) -> float:
    """Return a step cost that only breaks ties between policies of (nearly) equal success probability.

    A fixed step cost outweighs the goal's reward where success is unlikely, and the value's
    optimum would then rush into a dead end. Scaled by a lower bound on the best success
    probability (the default policy's all-success path) over the number of relevant fits, all
    attempts together cost at most ``STEP_COST`` times that probability, so a policy is only
    preferred to a more reliable one when it is less reliable by under ``STEP_COST / 2`` of it.
    """
    reachable = completion(compiled, (0, 0), STEP_COST).chance
    return STEP_COST * max(reachable, MIN_SUCCESS_SCALE) / max(1, len(compiled.fits))


def _start(root: _Node) -> tuple[State, int, int]:
    return root.state, root.parts, root.unusable


def _policy_table(search: _Search, root: _Node) -> dict[State, int]:
    """Return the best policy's choice in every expanded state it reaches from the start."""
    c = search.c
    table: dict[State, int] = {}
    stack, seen = [root], {root.state}
    while stack:
        node = stack.pop()
        if node.children is None or node.action < 0 or c.goal_holds(node.parts):
            continue
        table[node.state] = node.children[node.action][0]
        for child in search.best_child_states(node):
            if child.state not in seen:
                seen.add(child.state)
                stack.append(child)
    return table


def decide(compiled: CompiledMdp, solution: MdpSolution, state: State, step_cost: float = STEP_COST) -> int:
    """Return the fit index the solution attempts in ``state``; -1 when the run is over.

    Inside the searched states, the policy's own choice; elsewhere (an anytime answer), the
    default policy's.
    """
    if solution.decider is not None:
        return solution.decider(state)
    if state in solution.policy_table:
        return solution.policy_table[state]
    return default_attempt(compiled, state, step_cost)


def _all_success_path(compiled: CompiledMdp, table: dict[State, int], step_cost: float) -> tuple[Action, ...] | None:
    """Return the policy's attempts (``table``, then the default) when all succeed; None unless the goal holds."""
    actions, made = all_success_path(
        compiled.fits,
        lambda state: table[state] if state in table else default_attempt(compiled, state, step_cost),
    )
    return actions if compiled.goal_holds(compiled.parts_of((made, 0))[0]) else None


def solve_mdp_search(task: PlanningTask, time_limit: float = 10.0, step_cost: float = STEP_COST) -> MdpSolution:
    """Solve the task's MDP by improved LAO* from the start; anytime (``bounded``) at the limit."""
    return search_compiled_mdp(compile_mdp(task, relevant_fits(task)), time_limit, step_cost)


def search_compiled_mdp(compiled: CompiledMdp, time_limit: float, step_cost: float) -> MdpSolution:
    """Solve a compiled MDP by improved LAO* (``solve_mdp_search``'s work, for callers that solve it more than once)."""
    return ResumableSearch(compiled, step_cost).run(time_limit)


class ResumableSearch:
    """An improved LAO* search that can be given more time after it answered (``composed`` tries others between).

    It stops as soon as the optimum is proved: when the start is solved, or when the returned
    policy's success probability (evaluated exactly) meets the upper bound on every policy's
    to ``PROOF_PRECISION``; the checks come at doubling numbers of expansions, so they cost
    at most about as much as the last one.
    """

    def __init__(self, compiled: CompiledMdp, step_cost: float) -> None:
        self.search = _Search(compiled, step_cost, time.monotonic())
        self.root = self.search.node((0, 0), compiled.base, 0, 0)
        self.next_check = FIRST_CHECK

    def run(self, time_limit: float) -> MdpSolution:
        """Search on for ``time_limit`` seconds (the last tenth bounding the policy) and answer."""
        search, root = self.search, self.root
        started = time.monotonic()
        search.deadline = started + SEARCH_SHARE * time_limit
        optimality = Optimality.OPTIMAL
        proved: Evaluation | None = None
        limit = sys.getrecursionlimit()
        sys.setrecursionlimit(max(limit, 4 * len(search.c.fits) + 200))  # one frame per attempt on a path, twice
        try:
            while not root.solved:
                search.run_pass(root)
                if search.expanded >= self.next_check and not root.solved:
                    self.next_check = 2 * search.expanded
                    check = time.monotonic() + CHECK_SHARE * time_limit
                    evaluation = evaluate_policy(
                        search.c, search.step_cost, _policy_table(search, root), _start(root), check
                    )
                    if evaluation.exact and evaluation.success >= root.success * (1 - PROOF_PRECISION):
                        proved = evaluation
                        break
        except _OutOfBudget:
            optimality = Optimality.BOUNDED
        try:
            return _solution(search, root, optimality, time_limit, started, proved)
        finally:
            sys.setrecursionlimit(limit)


def _solution(
    search: _Search,
    root: _Node,
    optimality: Optimality,
    time_limit: float,
    started: float,
    proved: Evaluation | None,
) -> MdpSolution:
    compiled, fits, step_cost = search.c, search.c.fits, search.step_cost
    if root.solved and root.success == 0.0:
        return unsolvable(fits, search.expanded, "No policy reaches the goal: even if every attempt succeeded.")
    deadline = started + time_limit
    table = _policy_table(search, root)
    evaluation = proved or evaluate_policy(compiled, step_cost, table, _start(root), deadline)
    if optimality is Optimality.OPTIMAL and not evaluation.exact:
        # The search finished, so its policy is evaluated whole even past the deadline (the state
        # cap still bounds it): a deadline-cut evaluation would call a solvable task unsolvable.
        evaluation = evaluate_policy(compiled, step_cost, table, _start(root), math.inf)
    if optimality is Optimality.OPTIMAL and evaluation.exact and evaluation.success == 0.0:  # as mdp-exact says it
        return unsolvable(fits, search.expanded, "The optimal policy never reaches the goal.")
    path = _all_success_path(compiled, evaluation.table, step_cost)
    if path is None:  # an optimum that counts on a failure (never seen): not a plan to replay
        optimality = Optimality.BOUNDED
    if optimality is Optimality.BOUNDED:
        # The plan is the all-success path: it must reach the goal. A policy that counts on a
        # failure, or a table that ends where no completion is left, gives way to the default policy.
        default = completion(compiled, (0, 0), step_cost)
        if path is None or default.chance > evaluation.success:
            evaluation = evaluate_policy(compiled, step_cost, {}, _start(root), deadline)
            path = _all_success_path(compiled, {}, step_cost)
    upper = root.success
    if path is None:
        return out_of_time(
            fits,
            search.expanded,
            f"The time limit ({time_limit:g} s) or the state budget came first after {search.expanded:,} "
            f"expansions, before a plan that reaches the goal was found; no policy does better than {upper:.4f}.",
            upper,
        )
    success = evaluation.success
    message = ""
    if proved is not None:
        message = (
            f"Proved optimal after {search.expanded:,} expansions in {time.monotonic() - started:.2f} s: this "
            f"policy succeeds with probability {success:.6g}, and no policy does better than {upper:.6g}."
        )
    elif optimality is Optimality.BOUNDED:
        message = (
            f"The time limit ({time_limit:g} s) or the state budget came first after {search.expanded:,} expansions: "
            f"this is the best policy so far; it succeeds with probability at least {success:.4f}, and no policy "
            f"does better than {upper:.4f}."
        )
    known_attempts = optimality is Optimality.OPTIMAL and evaluation.exact
    return MdpSolution(
        PlanStatus.SOLVED,
        path,
        success,
        evaluation.attempts if known_attempts else None,
        policy_entries(
            compiled, lambda state: evaluation.table.get(state, -1), lambda state: evaluation.successes.get(state, 0.0)
        ),
        search.expanded,
        len(fits),
        message,
        optimality,
        upper if optimality is Optimality.BOUNDED else success,
        fits=fits,
        policy_table=evaluation.table,
        state_success=evaluation.successes,
        fewest_attempts=proved is None,
    )
