"""The probabilistic MDP planner of the paper, solved exactly over the reachable states.

The model (paper, "Planner"): a state is the assembly state, an action attempts one fit, the
transition probability is the fit's success probability from the catalog, and the reward
comes from the person's causal model.

* **Outcomes.** An attempt succeeds with the fit's probability ``p``: the moving part joins the
  assembly and the fit's connectors (and the connectors it ``blocks``) are taken. With
  ``1 - p`` it fails: the parts stay apart and *that connector pair is unusable* afterwards,
  i.e. both connectors of the failed fit can take no other fit (a cross-threaded bulb strips
  the socket's thread and its own). We chose this over "only this exact fit is lost" because
  a failure then costs something real: with harmless failures, trying the riskiest fit first
  is always at least as good, and risk would never change a plan.
* **Reward.** +1 when the goal node of the model holds (absorbing); -1 at a dead end: the goal
  does not hold and cannot be reached any more (not even if every remaining usable fit
  succeeded), which includes "no applicable action"; and a step cost of ``STEP_COST`` per
  attempt so that, among equally reliable plans, shorter ones win.
* **Exact solution.** Every attempt adds a fit to the made or failed ones, so the reachable
  state graph is acyclic and one memoised backward pass (value iteration in topological order)
  gives the exact optimal values. The search is restricted soundly to the fits that matter:
  parts carrying a function the model uses, and the parts needed to connect them to the base;
  attaching anything else can only take connectors away.
* **Limits.** Beyond ``MAX_RELEVANT_FITS`` relevant fits or ``MAX_STATES`` states the planner
  stops at once with status ``too_large``, and at the time limit with ``timeout``; it never hangs.

It returns the policy, the plan the policy follows when every attempt succeeds, the success
probability of the policy (closed loop: after a failure it takes the best remaining route)
and the expected number of attempts.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from causalplan.causal.graph import active_nodes
from causalplan.objects.model import Fit
from causalplan.pddl.task import PlanningTask
from causalplan.planners.result import PlanStatus, SearchOutcome

STEP_COST = 1e-3
MAX_RELEVANT_FITS = 40
MAX_STATES = 600_000
MAX_POLICY_ENTRIES = 200

State = tuple[int, int]
"""(made fits, failed fits) as bit masks over the relevant fits."""


class _TooLarge(Exception):
    """Raised inside the search when the state budget is exhausted."""


class _OutOfTime(Exception):
    """Raised inside the search when the time limit has passed."""


def relevant_fits(task: PlanningTask) -> tuple[Fit, ...]:
    """Return the fits that can matter: attaching parts that carry a used function, or lead to them."""
    obj = task.obj
    used = {key for rule in task.rules for key in rule.cause_keys} | {task.goal_key}
    relevant = {part for key, parts in task.carriers().items() if key in used for part in parts}
    changed = True
    while changed:
        changed = False
        for fit in obj.fits:
            if fit.moving_part in relevant and fit.fixed_part not in relevant:
                relevant.add(fit.fixed_part)
                changed = True
    return tuple(fit for fit in obj.fits if fit.moving_part in relevant and fit.fixed_part in relevant)


@dataclass
class _Compiled:
    """The restricted MDP as bit masks: everything the inner loop needs, nothing else."""

    fits: tuple[Fit, ...]
    probability: list[float]
    moving: list[int]  # part bit of each fit's moving part
    fixed: list[int]
    taken_on_success: list[int]  # fits made unusable when the fit succeeds (itself included)
    taken_on_failure: list[int]  # fits made unusable when it fails (those sharing a connector)
    base: int
    functions_of_part: dict[int, frozenset[str]]


def _compile(task: PlanningTask, fits: tuple[Fit, ...]) -> _Compiled:
    obj = task.obj
    part_bit = {part_id: 1 << index for index, part_id in enumerate(obj.part_ids)}
    fit_bit = {fit.id: 1 << index for index, fit in enumerate(fits)}

    def mask(fit_ids: tuple[str, ...] | list[str]) -> int:
        return sum(fit_bit[fit_id] for fit_id in set(fit_ids) if fit_id in fit_bit)

    functions: dict[int, set[str]] = {}
    for key, parts in task.carriers().items():
        for part in parts:
            if part in part_bit:
                functions.setdefault(part_bit[part], set()).add(key)
    return _Compiled(
        fits=fits,
        probability=[fit.probability for fit in fits],
        moving=[part_bit[fit.moving_part] for fit in fits],
        fixed=[part_bit[fit.fixed_part] for fit in fits],
        taken_on_success=[mask(obj.excluded_fits(fit)) for fit in fits],
        taken_on_failure=[
            mask([other.id for other in fits if set(other.connectors()) & set(fit.connectors())]) for fit in fits
        ],
        base=part_bit[obj.base],
        functions_of_part={bit: frozenset(keys) for bit, keys in functions.items()},
    )


@dataclass(frozen=True)
class _Value:
    value: float
    success: float  # probability of reaching the goal under the policy
    attempts: float  # expected number of attempts
    action: int  # index of the fit to attempt; -1 in terminal states


class _Solver:
    def __init__(self, task: PlanningTask, compiled: _Compiled, deadline: float) -> None:
        self.task = task
        self.c = compiled
        self.deadline = deadline
        self.values: dict[State, _Value] = {}
        self.goal_cache: dict[int, bool] = {}

    def goal_holds(self, parts: int) -> bool:
        cached = self.goal_cache.get(parts)
        if cached is None:
            functions: set[str] = set()
            for bit, keys in self.c.functions_of_part.items():
                if parts & bit:
                    functions |= keys
            cached = self.task.goal_key in active_nodes(functions, self.task.rules)
            self.goal_cache[parts] = cached
        return cached

    def reachable_parts(self, parts: int, unusable: int) -> int:
        """Return the parts that could still join if every usable fit succeeded (relaxed)."""
        changed = True
        while changed:
            changed = False
            for index, moving in enumerate(self.c.moving):
                if not unusable >> index & 1 and parts & self.c.fixed[index] and not parts & moving:
                    parts |= moving
                    changed = True
        return parts

    def solve(self, state: State, parts: int, unusable: int) -> _Value:
        """Return the value of ``state``; ``parts`` and ``unusable`` are derived from it (passed down)."""
        known = self.values.get(state)
        if known is not None:
            return known
        if len(self.values) >= MAX_STATES:
            raise _TooLarge
        if time.monotonic() > self.deadline:
            raise _OutOfTime
        if self.goal_holds(parts):
            result = _Value(1.0, 1.0, 0.0, -1)
        elif not self.goal_holds(self.reachable_parts(parts, unusable)):
            result = _Value(-1.0, 0.0, 0.0, -1)
        else:
            result = self._best_attempt(state, parts, unusable)
        self.values[state] = result
        return result

    def _best_attempt(self, state: State, parts: int, unusable: int) -> _Value:
        made, failed = state
        c = self.c
        best: _Value | None = None
        for index, p in enumerate(c.probability):
            if unusable >> index & 1 or not parts & c.fixed[index] or parts & c.moving[index]:
                continue
            bit = 1 << index
            success = self.solve((made | bit, failed), parts | c.moving[index], unusable | c.taken_on_success[index])
            failure = (
                self.solve((made, failed | bit), parts, unusable | c.taken_on_failure[index]) if p < 1.0 else success
            )
            q = -STEP_COST + p * success.value + (1 - p) * failure.value
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


@dataclass(frozen=True)
class MdpSolution:
    """The solved MDP: its values at the start, the policy and the all-success path."""

    status: PlanStatus
    actions: tuple[tuple[str, tuple[str, ...]], ...] = ()
    success_probability: float | None = None
    expected_actions: float | None = None
    policy: tuple[dict[str, object], ...] = ()
    states: int = 0
    relevant_fits: int = 0
    message: str = ""


def _policy_entries(solver: _Solver, start: State) -> tuple[dict[str, object], ...]:
    """Return the policy in the states it can reach from ``start`` (at most MAX_POLICY_ENTRIES)."""
    obj, fits = solver.task.obj, solver.c.fits
    entries: list[dict[str, object]] = []
    frontier, seen = [start], {start}
    while frontier and len(entries) < MAX_POLICY_ENTRIES:
        made, failed = frontier.pop(0)
        value = solver.values[(made, failed)]
        if value.action < 0:
            continue
        fit = fits[value.action]
        entries.append(
            {
                "made": [f.id for i, f in enumerate(fits) if made >> i & 1],
                "failed": [f.id for i, f in enumerate(fits) if failed >> i & 1],
                "attempt": fit.id,
                "text": obj.step_text(fit),
                "success_probability": round(value.success, 6),
            }
        )
        bit = 1 << value.action
        for child in ((made | bit, failed), (made, failed | bit)):
            if child in solver.values and child not in seen:
                seen.add(child)
                frontier.append(child)
    return tuple(entries)


def solve_mdp(task: PlanningTask, time_limit: float = 10.0) -> MdpSolution:
    """Solve the task's MDP exactly; ``too_large`` (quickly) beyond its size limits, ``timeout`` at ``time_limit``."""
    fits = relevant_fits(task)
    if len(fits) > MAX_RELEVANT_FITS:
        return MdpSolution(
            PlanStatus.TOO_LARGE,
            relevant_fits=len(fits),
            message=f"{len(fits)} fits matter for this model; the exact MDP stops at {MAX_RELEVANT_FITS}.",
        )
    solver = _Solver(task, _compile(task, fits), time.monotonic() + time_limit)
    start: State = (0, 0)
    try:
        root = solver.solve(start, solver.c.base, 0)
    except _OutOfTime:
        message = (
            f"The exact MDP did not finish within {time_limit:g} s "
            f"({len(solver.values):,} states solved over {len(fits)} relevant fits)."
        )
        return MdpSolution(PlanStatus.TIMEOUT, states=len(solver.values), relevant_fits=len(fits), message=message)
    except (_TooLarge, RecursionError) as exc:
        message = (
            "The MDP's plans are too long to solve exactly."
            if isinstance(exc, RecursionError)
            else f"The exact MDP over {len(fits)} relevant fits passed {len(solver.values):,} states; it was stopped."
        )
        return MdpSolution(PlanStatus.TOO_LARGE, states=len(solver.values), relevant_fits=len(fits), message=message)
    if root.success == 0.0:
        return MdpSolution(
            PlanStatus.UNSOLVABLE,
            success_probability=0.0,
            expected_actions=0.0,
            states=len(solver.values),
            relevant_fits=len(fits),
            message="No policy reaches the goal: even if every attempt succeeded.",
        )
    actions: list[tuple[str, tuple[str, ...]]] = []
    made, failed = start
    while (value := solver.values[(made, failed)]).action >= 0:
        fit = fits[value.action]
        actions.append((fit.primitive, (fit.moving_part, fit.fixed_part, fit.id)))
        made |= 1 << value.action
    return MdpSolution(
        PlanStatus.SOLVED,
        tuple(actions),
        root.success,
        root.attempts,
        _policy_entries(solver, start),
        len(solver.values),
        len(fits),
    )


def search_outcome(solution: MdpSolution, seconds: float) -> SearchOutcome:
    """Return the solution in the planners' common outcome form."""
    return SearchOutcome(
        solution.status,
        solution.actions,
        {"search": seconds},
        solution.message,
        solution.success_probability,
        solution.expected_actions,
        solution.policy,
    )
