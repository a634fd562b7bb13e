"""The paper's MDP solved exactly over every reachable state (``mdp-exact``).

Every attempt adds a fit to the made or failed ones, so the reachable state graph is acyclic
and one memoised backward pass (value iteration in topological order) gives the exact optimal
values. Beyond ``MAX_RELEVANT_FITS`` relevant fits or ``MAX_STATES`` states it stops at once
with status ``too_large``, and at the time limit with ``timeout``; it never hangs. The heuristic search
(``search.py``) finds the same optimum from the start state over far fewer states; this
solver is the reference it is tested against.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.model import (
    STEP_COST,
    CompiledMdp,
    MdpSolution,
    State,
    all_success_path,
    compile_mdp,
    policy_entries,
    relevant_fits,
)
from causalplan.planners.result import PlanStatus

MAX_RELEVANT_FITS = 40
MAX_STATES = 600_000


class _TooLarge(Exception):
    """Raised inside the search when the state budget is exhausted."""


class _OutOfTime(Exception):
    """Raised inside the search when the time limit has passed."""


@dataclass(frozen=True)
class _Value:
    value: float
    success: float  # probability of reaching the goal under the policy
    attempts: float  # expected number of attempts
    action: int  # index of the fit to attempt; -1 in terminal states


class _Solver:
    def __init__(self, compiled: CompiledMdp, deadline: float, step_cost: float) -> None:
        self.c = compiled
        self.deadline = deadline
        self.step_cost = step_cost
        self.values: dict[State, _Value] = {}

    def solve(self, state: State, parts: int, unusable: int) -> _Value:
        """Return the value of ``state``; ``parts`` and ``unusable`` are derived from it (passed down)."""
        known = self.values.get(state)
        if known is not None:
            return known
        if len(self.values) >= MAX_STATES:
            raise _TooLarge
        if time.monotonic() > self.deadline:
            raise _OutOfTime
        if self.c.goal_holds(parts):
            result = _Value(1.0, 1.0, 0.0, -1)
        elif not self.c.goal_holds(self.c.reachable_parts(parts, unusable)):
            result = _Value(-1.0, 0.0, 0.0, -1)
        else:
            result = self._best_attempt(state, parts, unusable)
        self.values[state] = result
        return result

    def _best_attempt(self, state: State, parts: int, unusable: int) -> _Value:
        made, failed = state
        c = self.c
        best: _Value | None = None
        for index in c.applicable(parts, unusable):
            p, bit = c.probability[index], 1 << index
            success = self.solve((made | bit, failed), parts | c.moving[index], unusable | c.taken_on_success[index])
            failure = (
                self.solve((made, failed | bit), parts, unusable | c.taken_on_failure[index]) if p < 1.0 else success
            )
            q = -self.step_cost + p * success.value + (1 - p) * failure.value
            if best is None or q > best.value + 1e-12:
                best = _Value(
                    q,
                    p * success.success + (1 - p) * failure.success,
                    1 + p * success.attempts + (1 - p) * failure.attempts,
                    index,
                )
        if best is None:  # unreachable in practice: the relaxed check found a way forward
            return _Value(-1.0, 0.0, 0.0, -1)
        return best


def solve_mdp(task: PlanningTask, time_limit: float = 10.0, step_cost: float = STEP_COST) -> MdpSolution:
    """Solve the task's MDP exactly; ``too_large`` (quickly) beyond its size limits, ``timeout`` at ``time_limit``."""
    return solve_compiled_mdp(compile_mdp(task, relevant_fits(task)), time_limit, step_cost)


def solve_compiled_mdp(compiled: CompiledMdp, time_limit: float, step_cost: float) -> MdpSolution:
    """Solve a compiled MDP exactly (``solve_mdp``'s work, for callers that solve it more than once)."""
    fits = compiled.fits
    if len(fits) > MAX_RELEVANT_FITS:
        return MdpSolution(
            PlanStatus.TOO_LARGE,
            relevant_fits=len(fits),
            message=f"{len(fits)} fits matter for this model; the exact MDP stops at {MAX_RELEVANT_FITS}.",
        )
    solver = _Solver(compiled, time.monotonic() + time_limit, step_cost)

    def stopped(status: PlanStatus, message: str) -> MdpSolution:
        return MdpSolution(status, states=len(solver.values), relevant_fits=len(fits), message=message)

    start: State = (0, 0)
    # No RecursionError to catch: each level of the recursion (two frames) attempts one more
    # fit, so it is at most MAX_RELEVANT_FITS levels deep.
    try:
        root = solver.solve(start, compiled.base, 0)
    except _OutOfTime:
        return stopped(
            PlanStatus.TIMEOUT,
            f"The exact MDP did not finish within {time_limit:g} s "
            f"({len(solver.values):,} states solved over {len(fits)} relevant fits).",
        )
    except _TooLarge:
        return stopped(
            PlanStatus.TOO_LARGE,
            f"The exact MDP over {len(fits)} relevant fits passed {len(solver.values):,} states; it was stopped.",
        )
    if root.success == 0.0:
        return MdpSolution(
            PlanStatus.UNSOLVABLE,
            success_probability=0.0,
            expected_actions=0.0,
            states=len(solver.values),
            relevant_fits=len(fits),
            message="No policy reaches the goal: even if every attempt succeeded.",
        )
    table = {state: value.action for state, value in solver.values.items() if value.action >= 0}
    successes = {state: value.success for state, value in solver.values.items()}
    return MdpSolution(
        PlanStatus.SOLVED,
        all_success_path(fits, lambda state: solver.values[state].action)[0],
        root.success,
        root.attempts,
        policy_entries(compiled, lambda state: table.get(state, -1), lambda state: successes.get(state, 0.0)),
        len(solver.values),
        len(fits),
        success_upper=root.success,
        fits=fits,
        policy_table=table,
        state_success=successes,
    )
