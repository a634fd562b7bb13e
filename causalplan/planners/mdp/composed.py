"""The MDP solved by its independent components, combined as a product, their attempts ordered as tests.

``components.py`` splits the MDP into sub-problems that share nothing. Each is solved exactly
on its own: by ``mdp-exact`` when it is small (its states are few), else by the heuristic
search, with a tie-breaking step cost scaled to the component and divided by the number of
components (so the product keeps the stated relative precision). Then:

* **Success probability.** The goal holds exactly when every component's goal does, outcomes
  in one component change nothing in another, so the best success probability is the product
  of the components' best (an induction over the acyclic states: at every state the value is
  at most the product, and running the components' optimal policies one after another, stopping
  at the first failure, reaches it). The product needs no particular order.
* **Attempts.** A component that fails ends the run, so the components are the tests of a
  series system: running them whole in increasing ``attempts / (1 - success)`` minimises the
  expected attempts among orders that run each whole (Smith's ratio rule; Mitten 1960). A
  component whose optimal policy is a chain (each failure on its all-success path ends it) is a
  chain of single tests under precedence; Sidney's decomposition splits it into initial
  segments of the highest ratio, and merging all segments by ratio is optimal among every
  interleaving of the chains (Monma and Sidney 1979; parallel chains are series-parallel). A
  component whose policy branches after a failure (a retry by another route) runs whole:
  there, interleaving could matter, and it is not searched (docs/planners.md).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from causalplan.planners.mdp.components import Component, independent_components
from causalplan.planners.mdp.exact import solve_compiled_mdp
from causalplan.planners.mdp.model import (
    CompiledMdp,
    MdpSolution,
    Optimality,
    State,
    all_success_path,
    compile_mdp,
    out_of_time,
    policy_entries,
    unsolvable,
)
from causalplan.planners.mdp.search import ResumableSearch, decide, tie_breaking_step_cost
from causalplan.planners.mdp.split_solve import solve_split
from causalplan.planners.result import PlanStatus

EXACT_FITS = 10
"""Components with at most this many fits are solved by ``mdp-exact`` (it stores every state, a few thousand)."""
EXACT_SHARE = 0.5
"""The share of such a component's time ``mdp-exact`` has; should it not finish, ``solve_one`` has the whole
share again (so the component can overrun its share by this much)."""


@dataclass(frozen=True)
class SolvedComponent:
    """A component with its own MDP, its solution, and its all-success path when that is a chain of tests."""

    component: Component
    compiled: CompiledMdp
    solution: MdpSolution
    step_cost: float
    chain: tuple[int, ...] | None

    def local(self, state: State) -> State:
        """Return the component's own state (its fits' bits) of a state of the whole MDP."""
        made, failed = state
        local_made = local_failed = 0
        for position, index in enumerate(self.component.fits):
            local_made |= (made >> index & 1) << position
            local_failed |= (failed >> index & 1) << position
        return local_made, local_failed


@dataclass(frozen=True)
class Module:
    """A stretch of one component's work in the schedule: the chain's steps up to ``end``, or all (``end`` -1)."""

    component: int
    end: int
    success: float
    attempts: float

    @property
    def ratio(self) -> float:
        """The chance of failing per expected attempt: the higher, the earlier (Smith's rule)."""
        return (1.0 - self.success) / self.attempts if self.attempts > 0 else 0.0


def sidney_modules(chances: list[float]) -> list[tuple[int, float, float]]:
    """Return a chain's Sidney decomposition: (end, success, expected attempts) of its initial segments.

    Each segment is the shortest initial one of the rest with the highest ratio
    ``(1 - success) / expected attempts``; the ratios do not increase along the chain.
    """
    segments: list[tuple[int, float, float]] = []
    start = 0
    while start < len(chances):
        best: tuple[float, int, float, float] | None = None
        success, attempts = 1.0, 0.0
        for end in range(start + 1, len(chances) + 1):
            attempts += success
            success *= chances[end - 1]
            ratio = (1.0 - success) / attempts
            if best is None or ratio > best[0] + 1e-15:
                best = (ratio, end, success, attempts)
        assert best is not None
        segments.append(best[1:])
        start = best[1]
    return segments


def schedule(solved: list[SolvedComponent]) -> list[Module]:
    """Return the order of the components' work: modules by decreasing ratio, each chain's in its order."""
    modules: list[Module] = []
    for number, part in enumerate(solved):
        if part.chain is not None:
            chances = [part.compiled.probability[index] for index in part.chain]
            modules += [Module(number, end, success, attempts) for end, success, attempts in sidney_modules(chances)]
        else:
            assert part.solution.success_probability is not None
            modules.append(Module(number, -1, part.solution.success_probability, part.solution.expected_actions or 0.0))
    return sorted(modules, key=lambda module: -module.ratio)  # stable: a chain's equal ratios keep their order


def expected_attempts(modules: list[Module]) -> float:
    """Return the expected attempts of running ``modules`` in order, stopping at the first that fails."""
    total, passing = 0.0, 1.0
    for module in modules:
        total += passing * module.attempts
        passing *= module.success
    return total


class ComposedPolicy:
    """The combined policy: the schedule's first unfinished module decides, by its component's own policy."""

    def __init__(self, solved: list[SolvedComponent], modules: list[Module]) -> None:
        self.solved = solved
        self.modules = modules

    def __call__(self, state: State) -> int:
        """Return the fit (an index of the whole MDP) to attempt in ``state``; -1 when the run is over."""
        for module in self.modules:
            part = self.solved[module.component]
            local = part.local(state)
            if part.compiled.goal_holds(part.compiled.parts_of(local)[0]):
                continue
            if module.end >= 0 and local[0].bit_count() >= module.end:
                continue
            index = decide(part.compiled, part.solution, local, part.step_cost)
            return part.component.fits[index] if index >= 0 else -1
        return -1


def _chain(compiled: CompiledMdp, solution: MdpSolution, step_cost: float) -> tuple[int, ...] | None:
    """Return the solution's all-success path when every failure on it ends the component's run, else None."""
    path: list[int] = []
    made = 0
    while (index := decide(compiled, solution, (made, 0), step_cost)) >= 0:
        if compiled.probability[index] < 1.0 and decide(compiled, solution, (made, 1 << index), step_cost) >= 0:
            return None
        path.append(index)
        made |= 1 << index
    return tuple(path)


FIRST_SEARCH_SHARE = 0.05
"""The share of a component's time the heuristic search has first (it proves small components quickly)."""
SPLIT_SHARE = 0.5
"""The share of what is left that the splitting solver has next, before the search has the rest."""


def solve_one(
    compiled: CompiledMdp, time_limit: float, step_cost: float, search: ResumableSearch | None = None
) -> MdpSolution:
    """Solve one MDP exactly if possible: the search briefly, then splitting after every attempt, then the search on.

    The heuristic search proves the optimum of the value (the most reliable policy, then the
    fewest attempts) on small problems within moments; the splitting solver (``split.py``)
    proves the most reliable policy where holders make the problem fall apart; whatever
    neither proves, the search (resumed where it stopped) answers with bounds in the time left.
    After a split answer the search has one more short share: where it closes, its answer
    (the fewest attempts proved too) is kept. ``search`` is one that already had its first share.
    """
    started = time.monotonic()
    if search is None:
        search = ResumableSearch(compiled, step_cost)
        first = search.run(FIRST_SEARCH_SHARE * time_limit)
        if first.status is not PlanStatus.SOLVED or first.optimality is Optimality.OPTIMAL:
            return first
    split = solve_split(compiled, SPLIT_SHARE * max(0.0, started + time_limit - time.monotonic()))
    if split is not None:
        # The split proves the reliability only; a search that closes a little later proves the fewest attempts too.
        later = search.run(min(FIRST_SEARCH_SHARE * time_limit, max(0.0, started + time_limit - time.monotonic())))
        closed = later.status is PlanStatus.SOLVED and later.optimality is Optimality.OPTIMAL
        return later if closed and later.fewest_attempts else split
    return search.run(max(0.0, started + time_limit - time.monotonic()))


def _solve_component(compiled: CompiledMdp, component: Component, count: int, time_limit: float) -> SolvedComponent:
    fits = tuple(compiled.fits[index] for index in component.fits)
    own = compile_mdp(compiled.task, fits, component.goal_keys)
    step_cost = tie_breaking_step_cost(own) / count
    solution: MdpSolution | None = None
    if len(fits) <= EXACT_FITS:
        solution = solve_compiled_mdp(own, EXACT_SHARE * time_limit, step_cost)
        if solution.status is not PlanStatus.SOLVED:
            solution = None
    if solution is None:
        solution = solve_one(own, time_limit, step_cost)
    optimal = solution.status is PlanStatus.SOLVED and solution.optimality is Optimality.OPTIMAL
    return SolvedComponent(component, own, solution, step_cost, _chain(own, solution, step_cost) if optimal else None)


def _better(first: MdpSolution, second: MdpSolution) -> MdpSolution:
    """Return the better of two answers: proved, then more reliable, then fewer expected attempts."""

    def rank(solution: MdpSolution) -> tuple[bool, bool, float, float]:
        solved = solution.status is PlanStatus.SOLVED
        success = solution.success_probability or 0.0
        return (
            solved and solution.optimality is Optimality.OPTIMAL,
            solved,
            round(success, 9),
            -(solution.expected_actions if solution.expected_actions is not None else math.inf),
        )

    return second if rank(second) > rank(first) else first


def solve_by_components(compiled: CompiledMdp, time_limit: float, step_cost: float) -> MdpSolution:
    """Solve the MDP: the heuristic search first (briefly), then by its independent components.

    Where the search closes (every state of its policy solved), its answer stands: the most
    reliable policy with the fewest attempts over every policy. Otherwise each component is
    solved on its own (``solve_one``) and they are combined; of two proved answers (equally
    reliable) the one with fewer expected attempts is kept.
    """
    started = time.monotonic()
    deadline = started + time_limit
    search = ResumableSearch(compiled, step_cost)
    first = search.run(FIRST_SEARCH_SHARE * time_limit)
    if first.status is not PlanStatus.SOLVED or (first.optimality is Optimality.OPTIMAL and first.fewest_attempts):
        return first
    components = independent_components(compiled)
    if len(components) == 1 and len(components[0].fits) == len(compiled.fits):
        if first.optimality is Optimality.OPTIMAL:
            return first
        return solve_one(compiled, max(0.0, deadline - time.monotonic()), step_cost, search)
    order = sorted(range(len(components)), key=lambda number: len(components[number].fits))
    solved: dict[int, SolvedComponent] = {}
    waiting = sum(len(component.fits) for component in components)
    for number in order:
        component = components[number]
        share = max(0.0, deadline - time.monotonic()) * len(component.fits) / max(1, waiting)
        solved[number] = _solve_component(compiled, component, len(components), share)
        waiting -= len(component.fits)
    combined = _combined(compiled, [solved[number] for number in range(len(components))], started, time_limit)
    return _better(first, combined)


def _combined(compiled: CompiledMdp, solved: list[SolvedComponent], started: float, time_limit: float) -> MdpSolution:
    fits = compiled.fits
    states = sum(part.solution.states for part in solved)
    statuses = {part.solution.status for part in solved}
    sizes = ", ".join(str(len(part.component.fits)) for part in solved)
    split = f"{len(solved)} independent components ({sizes} fits)"
    if PlanStatus.UNSOLVABLE in statuses:
        return unsolvable(fits, states, f"No policy reaches the goal: one of {split} cannot succeed.")
    upper = math.prod(part.solution.success_upper or 0.0 for part in solved)
    if statuses != {PlanStatus.SOLVED}:
        return out_of_time(
            fits,
            states,
            f"The time limit ({time_limit:g} s) came before every one of {split} had a plan; "
            f"no policy does better than {upper:.4f}.",
            upper,
        )
    success = math.prod(part.solution.success_probability or 0.0 for part in solved)
    optimal = all(part.solution.optimality is Optimality.OPTIMAL for part in solved)
    modules = schedule(solved) if optimal else [Module(number, -1, 0.0, 0.0) for number in range(len(solved))]
    policy = ComposedPolicy(solved, modules)
    actions, _ = all_success_path(fits, policy)

    def success_at(state: State) -> float:
        return math.prod(part.solution.state_success.get(part.local(state), 0.0) for part in solved)

    seconds = time.monotonic() - started
    chains = sum(part.chain is not None for part in solved)
    if optimal:
        message = (
            f"Proved optimal in {seconds:.2f} s as {split}: the success probability is the product of theirs; "
            f"their attempts are ordered by Smith's ratio rule, the {chains} chain(s) among them interleaved by "
            "Sidney's decomposition."
        )
    else:
        message = (
            f"The time limit ({time_limit:g} s) came first in one of {split}: this policy succeeds with probability "
            f"at least {success:.4f}, and no policy does better than {upper:.4f}."
        )
    return MdpSolution(
        PlanStatus.SOLVED,
        actions,
        success,
        expected_attempts(modules) if optimal else None,
        policy_entries(compiled, policy, success_at),
        states,
        len(fits),
        message,
        Optimality.OPTIMAL if optimal else Optimality.BOUNDED,
        success if optimal else upper,
        fits=fits,
        decider=policy,
        fewest_attempts=optimal and all(part.chain is not None and part.solution.fewest_attempts for part in solved),
    )
