"""The paper's MDP as bit masks, shared by its two solvers: fits, outcomes, goal and dead ends.

* **Outcomes.** An attempt succeeds with the fit's probability ``p``: the moving part joins the
  assembly and the fit's connectors (and the connectors it ``blocks``) are taken. With
  ``1 - p`` it fails: the parts stay apart and *that connector pair is unusable* afterwards,
  i.e. both connectors of the failed fit can take no other fit (a cross-threaded bulb strips
  the socket's thread and its own). We chose this over "only this exact fit is lost" because
  a failure then costs something real: with harmless failures, trying the riskiest fit first
  is always at least as good, and risk would never change a plan.
* **Reward.** +1 when the goal node of the model holds (absorbing); -1 at a dead end: the goal
  does not hold and cannot be reached any more (not even if every remaining usable fit
  succeeded), which includes "no applicable action"; and a step cost per attempt
  (``STEP_COST`` by default) so that, among equally reliable plans, shorter ones win. Every
  run ends in the goal or a dead end, so a policy's value is ``2 P(success) - 1 - cost E[attempts]``.
* **Restriction.** The search is restricted soundly to the fits that matter: parts carrying a
  function the model uses, and the parts needed to connect them to the base; attaching
  anything else can only take connectors away.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum

from causalplan.causal.graph import active_nodes
from causalplan.objects.model import Fit
from causalplan.pddl.canonical import Action
from causalplan.pddl.task import PlanningTask
from causalplan.planners.result import PlanStatus, SearchOutcome

STEP_COST = 1e-3
MAX_POLICY_ENTRIES = 200

State = tuple[int, int]
"""(made fits, failed fits) as bit masks over the relevant fits."""


class Objective(StrEnum):
    """What the MDP optimises."""

    PROBABILITY = "probability"  # the highest success probability (the paper's), ties by fewer attempts
    ATTEMPTS = "attempts"  # the fewest expected attempts that still reach a required success probability


class Optimality(StrEnum):
    """What is proved about an MDP answer."""

    OPTIMAL = "optimal"  # the optimum of the objective, proved (exact values over the policy's states)
    BOUNDED = "bounded"  # the limit came first: the best policy so far, its success probability bounded


def single_bits(mask: int) -> list[int]:
    """Return the set bits of ``mask`` as one-bit masks, lowest first."""
    bits = []
    while mask:
        low = mask & -mask
        bits.append(low)
        mask ^= low
    return bits


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


@dataclass(frozen=True)
class Completion:
    """An all-success completion from a state: its attempts, their joint chance, expected attempts.

    The expected attempts count a stop at the first failure (see ``completion.py``).
    """

    fits: tuple[int, ...]
    chance: float
    attempts: float


@dataclass
class CompiledMdp:
    """The restricted MDP as bit masks: everything the inner loops need, nothing else."""

    task: PlanningTask
    fits: tuple[Fit, ...]
    probability: list[float]
    moving: list[int]  # part bit of each fit's moving part
    fixed: list[int]
    taken_on_success: list[int]  # fits made unusable when the fit succeeds (itself included)
    taken_on_failure: list[int]  # fits made unusable when it fails (those sharing a connector)
    base: int
    functions_of_part: dict[int, frozenset[str]]
    fits_of_part: dict[int, list[int]]  # part bit -> the fits that attach it
    moving_connector: list[str]  # each fit's connector on its moving part
    fits_onto_part: dict[int, list[int]]  # part bit -> the fits that attach something to it
    goal_keys: tuple[str, ...] = ()  # the nodes that must all hold; () means the model's goal
    goal_cache: dict[int, bool] = field(default_factory=dict)
    cutting_pairs: list[tuple[int, int]] | None = None  # worked out once by ``bounds``
    completions: dict[State, Completion] = field(default_factory=dict)  # kept by ``completion``
    completion_dead_ends: set[tuple[int, int]] = field(default_factory=set)  # (parts, unusable) with none
    holders_counted_once: bool = True  # False: the earlier, looser bound (shared holders counted nowhere)

    def active(self, parts: int) -> set[str]:
        """Return the model's nodes that hold with ``parts`` assembled (their functions, and what they cause)."""
        functions: set[str] = set()
        for bit, keys in self.functions_of_part.items():
            if parts & bit:
                functions |= keys
        return active_nodes(functions, self.task.rules)

    def goal_holds(self, parts: int) -> bool:
        """Return whether the goal (the model's, or every one of ``goal_keys``) holds with ``parts`` assembled."""
        cached = self.goal_cache.get(parts)
        if cached is None:
            active = self.active(parts)
            cached = all(key in active for key in self.goal_keys or (self.task.goal_key,))
            self.goal_cache[parts] = cached
        return cached

    def reachable_parts(self, parts: int, unusable: int, without: int = 0) -> int:
        """Return the parts that could still join if every usable fit succeeded (relaxed).

        ``without`` is a part bit kept out (to ask whether a part is necessary). A worklist
        over the fits leaving each newly reached part: every fit is looked at once.
        """
        reached, frontier = parts, parts
        while frontier:
            new = 0
            while frontier:
                low = frontier & -frontier
                frontier ^= low
                for index in self.fits_onto_part.get(low, ()):
                    moving = self.moving[index]
                    if not unusable >> index & 1 and not (reached | new | without) & moving:
                        new |= moving
            reached |= new
            frontier = new
        return reached

    def applicable(self, parts: int, unusable: int) -> list[int]:
        """Return the fits that can be attempted now, in index order."""
        return [
            index
            for index in range(len(self.fits))
            if not unusable >> index & 1 and parts & self.fixed[index] and not parts & self.moving[index]
        ]

    def parts_of(self, state: State) -> tuple[int, int]:
        """Return the assembled parts and the unusable fits of a state."""
        made, failed = state
        parts, unusable = self.base, 0
        for index in range(len(self.fits)):
            if made >> index & 1:
                parts |= self.moving[index]
                unusable |= self.taken_on_success[index]
            elif failed >> index & 1:
                unusable |= self.taken_on_failure[index]
        return parts, unusable


def compile_mdp(task: PlanningTask, fits: tuple[Fit, ...], goal_keys: tuple[str, ...] = ()) -> CompiledMdp:
    """Return the MDP over ``fits`` (the relevant ones) as bit masks; ``goal_keys``: see ``CompiledMdp``."""
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
    return CompiledMdp(
        task=task,
        fits=fits,
        probability=[fit.probability for fit in fits],
        moving=[part_bit[fit.moving_part] for fit in fits],
        fixed=[part_bit[fit.fixed_part] for fit in fits],
        taken_on_success=[mask(obj.excluded_fits(fit)) for fit in fits],
        taken_on_failure=[
            mask([other.id for other in fits if set(other.connectors()) & set(fit.connectors())]) for fit in fits
        ],
        base=part_bit[obj.base],
        goal_keys=goal_keys,
        functions_of_part={bit: frozenset(keys) for bit, keys in functions.items()},
        moving_connector=[fit.moving_connector for fit in fits],
        fits_onto_part={
            bit: [index for index, fit in enumerate(fits) if part_bit[fit.fixed_part] == bit]
            for bit in {part_bit[fit.fixed_part] for fit in fits}
        },
        fits_of_part={
            bit: [index for index, fit in enumerate(fits) if part_bit[fit.moving_part] == bit]
            for bit in {part_bit[fit.moving_part] for fit in fits}
        },
    )


@dataclass(frozen=True)
class MdpSolution:
    """A solved MDP: its figures at the start, the policy and the path when every attempt succeeds.

    ``success_probability`` is the success probability of the returned policy (a lower bound
    on it when ``optimality`` is ``bounded``); ``success_upper`` bounds the success probability
    of every policy from above. ``policy_table`` maps states to the fit index to attempt, for
    rolling the policy out (``decide`` completes it where the search stopped early), and
    ``state_success`` their success probabilities; a policy composed of independent
    components has ``decider`` instead (``composed.py``). ``states`` counts the states solved
    (exact solver) or expanded (heuristic search).
    """

    status: PlanStatus
    actions: tuple[Action, ...] = ()
    success_probability: float | None = None
    expected_actions: float | None = None
    policy: tuple[dict[str, object], ...] = ()
    states: int = 0
    relevant_fits: int = 0
    message: str = ""
    optimality: Optimality = Optimality.OPTIMAL
    success_upper: float | None = None
    objective: Objective = Objective.PROBABILITY
    required_success: float | None = None
    fits: tuple[Fit, ...] = field(default=(), repr=False)
    policy_table: dict[State, int] = field(default_factory=dict, repr=False, compare=False)
    state_success: dict[State, float] = field(default_factory=dict, repr=False, compare=False)
    fewest_attempts: bool = True  # the expected attempts are proved the fewest among the most reliable policies
    decider: Callable[[State], int] | None = field(default=None, repr=False, compare=False)


def unsolvable(fits: tuple[Fit, ...], states: int, message: str) -> MdpSolution:
    """Return the answer that no policy reaches the goal: success 0, proved (its upper bound is 0 too)."""
    return MdpSolution(
        PlanStatus.UNSOLVABLE,
        success_probability=0.0,
        expected_actions=0.0,
        states=states,
        relevant_fits=len(fits),
        message=message,
        success_upper=0.0,
        fits=fits,
    )


def out_of_time(fits: tuple[Fit, ...], states: int, message: str, upper: float) -> MdpSolution:
    """Return the answer that the limit came before a plan that reaches the goal; ``upper`` bounds every policy."""
    return MdpSolution(
        PlanStatus.TIMEOUT,
        states=states,
        relevant_fits=len(fits),
        message=message,
        optimality=Optimality.BOUNDED,
        success_upper=upper,
        fits=fits,
    )


def all_success_path(fits: tuple[Fit, ...], decide: Callable[[State], int]) -> tuple[tuple[Action, ...], int]:
    """Return the attempts ``decide`` makes from the start when every one succeeds, and the fits made then."""
    actions: list[Action] = []
    made = 0
    while (index := decide((made, 0))) >= 0:
        fit = fits[index]
        actions.append((fit.primitive, (fit.moving_part, fit.fixed_part, fit.id)))
        made |= 1 << index
    return tuple(actions), made


def policy_entries(
    compiled: CompiledMdp, decide: Callable[[State], int], success: Callable[[State], float]
) -> tuple[dict[str, object], ...]:
    """Return the policy (``decide``: a state's attempt, -1 when none) in the states it reaches (MAX_POLICY_ENTRIES)."""
    obj, fits = compiled.task.obj, compiled.fits
    entries: list[dict[str, object]] = []
    start: State = (0, 0)
    frontier, seen = deque([start]), {start}
    while frontier and len(entries) < MAX_POLICY_ENTRIES:
        made, failed = frontier.popleft()
        action = decide((made, failed))
        if action < 0:
            continue
        fit = fits[action]
        entries.append(
            {
                "made": [f.id for i, f in enumerate(fits) if made >> i & 1],
                "failed": [f.id for i, f in enumerate(fits) if failed >> i & 1],
                "attempt": fit.id,
                "text": obj.step_text(fit),
                "success_probability": round(success((made, failed)), 6),
            }
        )
        bit = 1 << action
        for child in ((made | bit, failed), (made, failed | bit)):
            if child not in seen:
                seen.add(child)
                frontier.append(child)
    return tuple(entries)


def search_outcome(solution: MdpSolution, seconds: float) -> SearchOutcome:
    """Return the solution in the planners' common outcome form."""
    bounds = None
    if solution.success_probability is not None and solution.success_upper is not None:
        bounds = (solution.success_probability, solution.success_upper)
    return SearchOutcome(
        solution.status,
        solution.actions,
        {"search": seconds},
        solution.message,
        solution.success_probability,
        solution.expected_actions,
        solution.policy,
        objective=solution.objective.value,
        optimality=solution.optimality.value,
        success_bounds=bounds,
        required_success=solution.required_success,
        states=solution.states,
        fewest_attempts=solution.fewest_attempts and solution.optimality is Optimality.OPTIMAL
        if solution.status is PlanStatus.SOLVED
        else None,
    )
