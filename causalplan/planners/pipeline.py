"""The planning pipeline: choose a planner, search, check the plan, and say what came of it.

Planners (a plain registry, ``SEARCHES``): ``fd`` and ``fd-opt`` run Fast Downward on our PDDL
with derived predicates; ``mdp`` solves the paper's probabilistic MDP by heuristic search
(improved LAO*) and ``mdp-exact`` over every reachable state, to the same optimum;
``up:<engine>`` solves the axiom-free unified-planning formulation with that engine; ``auto``
(the default) runs FD when every fit that matters is certain, the MDP otherwise (FD's plans are
blind to risk), and falls back to the other when the first ends with an error, a timeout or
is unavailable. Every plan, whatever its route, is
replayed on the object before it is returned, and checked by VAL on the readable PDDL when
asked (``val=True``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial

from causalplan.causal.graph import goal_holds
from causalplan.errors import CausalPlanError
from causalplan.pddl.canonical import canonical_pddl, plan_actions
from causalplan.pddl.task import PlanningTask
from causalplan.pddl.writer import compile_task
from causalplan.planners import fd
from causalplan.planners.ordering import mechanism_order
from causalplan.planners.replay import replay
from causalplan.planners.result import PlanResult, PlanStatus, PlanStep, SearchOutcome

UP_ENGINES = ("fast-downward", "fast-downward-opt", "pyperplan", "pyperplan-opt", "tamer", "enhsp", "enhsp-opt")
"""unified-planning engines installed with causalplan (``up-*`` packages)."""

Actions = tuple[tuple[str, tuple[str, ...]], ...]


@dataclass(frozen=True)
class Objective:
    """What the MDP planners optimise (classical planners ignore it): see ``mdp.objective``."""

    name: str = "probability"
    required_success: float | None = None


Search = Callable[[PlanningTask, float, dict[str, float], Objective], SearchOutcome]
"""A planner: the task, its time limit, a dict for stage times and the objective in; its outcome out."""


def _fd_search(
    config: fd.SearchConfig, task: PlanningTask, time_limit: float, timing: dict[str, float], _: Objective
) -> SearchOutcome:
    started = time.perf_counter()
    # FD solves the label-free canonical form: equal problems give identical runs and plans,
    # and one cached solve serves them all. Too big a goal function: the readable form.
    canonical = canonical_pddl(task)
    compiled = canonical or compile_task(task)
    timing["compile"] = time.perf_counter() - started
    outcome = fd.solve(compiled.domain, compiled.problem, config, time_limit)
    return replace(outcome, actions=plan_actions(outcome.actions)) if canonical is not None else outcome


def _mdp_search(
    exact: bool, task: PlanningTask, time_limit: float, timing: dict[str, float], objective: Objective
) -> SearchOutcome:
    from causalplan.planners.mdp import search_outcome
    from causalplan.planners.mdp.objective import check_objective, solve_for

    started = time.perf_counter()
    chosen = check_objective(objective.name, objective.required_success)
    solution = solve_for(task, time_limit, chosen, objective.required_success, exact=exact)
    return search_outcome(solution, time.perf_counter() - started)


def _up_search(
    engine: str, task: PlanningTask, time_limit: float, timing: dict[str, float], _: Objective
) -> SearchOutcome:
    from causalplan.planners.up_problem import solve_with_up

    return solve_with_up(task, engine, time_limit)


SEARCHES: dict[str, Search] = {
    **{name: partial(_fd_search, config) for name, config in fd.CONFIGS.items()},
    "mdp": partial(_mdp_search, False),
    "mdp-exact": partial(_mdp_search, True),
    **{f"up:{engine}": partial(_up_search, engine) for engine in UP_ENGINES},
}
"""Every planner by name (``auto`` is not one: it chooses among them)."""

PLANNERS: tuple[str, ...] = ("auto", *SEARCHES)
"""Every planner name ``plan_task`` accepts."""

DESCRIPTIONS: dict[str, str] = {
    "auto": "Fast Downward when every fit that matters is certain, else the MDP (the default)",
    **{name: config.description for name, config in fd.CONFIGS.items()},
    "mdp": "the paper's probabilistic MDP by heuristic search (improved LAO*), independent components and "
    "splitting: the optimal policy, or the best so far with bounds at the time limit",
    "mdp-exact": "the same MDP solved over every reachable state: the reference; too_large on big tasks",
    **{f"up:{engine}": f"unified-planning engine '{engine}' on the axiom-free formulation" for engine in UP_ENGINES},
}

PRECHECK = "precheck"
"""``planner_used`` when the answer was decided before any search."""

MDP_TIME_LIMIT = 10.0
FALLBACK_STATUSES = (PlanStatus.ERROR, PlanStatus.TIMEOUT, PlanStatus.OUT_OF_MEMORY)


class UnknownPlannerError(CausalPlanError):
    """A planner name that is not in the registry."""

    code = "unknown_planner"


def goal_reachable(task: PlanningTask) -> bool:
    """Return whether the goal would hold if every part carrying a function were assembled."""
    return goal_holds(task.carriers(), task.rules, task.goal_key)


def planner_availability() -> dict[str, str | None]:
    """Return each planner with None when it can run here, or why it cannot."""
    result: dict[str, str | None] = {}
    try:
        fd.search_binary()
        fd_problem = None if fd.translator_available() else "fast-downward.translate is not installed"
    except CausalPlanError as exc:
        fd_problem = exc.message
    for name in PLANNERS:
        result[name] = fd_problem if name in fd.CONFIGS else None
    try:
        from causalplan.planners.up_problem import engine_problem
    except ImportError as exc:  # pragma: no cover - unified-planning is a dependency
        return {**result, **{f"up:{engine}": str(exc) for engine in UP_ENGINES}}
    for engine in UP_ENGINES:
        result[f"up:{engine}"] = engine_problem(engine)
    return result


def _failure_message(status: PlanStatus, task: PlanningTask, time_limit: float) -> str:
    return {
        PlanStatus.UNSOLVABLE: f"No sequence of connections of the {task.obj.name}'s parts produces '{task.goal}' "
        "under the model.",
        PlanStatus.TIMEOUT: f"The planner did not finish within {time_limit:g} s.",
        PlanStatus.OUT_OF_MEMORY: "The planner ran out of memory.",
        PlanStatus.TOO_LARGE: "The task is too large for the exact MDP (mdp-exact); try mdp.",
    }.get(status, "The planner failed.")


@dataclass(frozen=True)
class _Asked:
    """What the caller asked for beyond a replayed plan."""

    include_pddl: bool
    validate_up: bool
    val: bool
    objective: Objective = Objective()


def _validations(
    task: PlanningTask, planner: str, actions: Actions, asked: _Asked, timing: dict[str, float]
) -> dict[str, str]:
    """Return each validator's verdict on a replayed plan (replay's is "valid"); raise if VAL rejects it."""
    validated_by = {"replay": "valid"}
    if asked.val:
        from causalplan.planners import val

        started = time.perf_counter()
        # Named by its canonical form (the answer cache's key): one VAL run per distinct plan.
        canonical = canonical_pddl(task)
        task_key = (canonical.domain, canonical.problem) if canonical is not None else None
        readable = compile_task(task)  # the person's rules as written: one derived clause per rule
        validated_by["val"] = val.check(readable.domain, readable.problem, actions, task_key).value
        timing["val"] = time.perf_counter() - started
    if asked.validate_up or planner.startswith("up:"):
        from causalplan.planners.up_problem import validate_with_up

        started = time.perf_counter()
        validated_by["up"] = "valid" if validate_with_up(task, actions) else "invalid"
        timing["up_validate"] = time.perf_counter() - started
    return validated_by


def _run(task: PlanningTask, planner: str, time_limit: float, asked: _Asked) -> PlanResult:
    started = time.perf_counter()
    obj = task.obj
    timing: dict[str, float] = {}
    pddl = None
    if asked.include_pddl:
        compiled = compile_task(task)
        pddl = {"domain": compiled.domain, "problem": compiled.problem}

    def without_plan(
        status: PlanStatus, planner_used: str, message: str, probability: float | None = None
    ) -> PlanResult:
        timing["total"] = time.perf_counter() - started
        return PlanResult(
            status, planner_used, obj.id, timing=timing, pddl=pddl, success_probability=probability, message=message
        )

    if not goal_reachable(task):
        return without_plan(
            PlanStatus.UNSOLVABLE,
            PRECHECK,
            f"Even with every part of the {obj.name} assembled, the model's rules do not "
            f"produce '{task.goal}': no part carries some function the rules need.",
            probability=0.0,
        )
    outcome = SEARCHES[planner](task, time_limit, timing, asked.objective)
    timing.update(outcome.timing)
    timing.pop("total", None)
    if outcome.status is not PlanStatus.SOLVED:
        failed = without_plan(
            outcome.status, planner, outcome.message or _failure_message(outcome.status, task, time_limit)
        )
        return replace(failed, mdp=_mdp_figures(outcome))
    if not outcome.policy:  # an open-loop plan: its steps in the order the true mechanism needs
        outcome = replace(outcome, actions=mechanism_order(task, outcome.actions))
    replay_started = time.perf_counter()
    checked = replay(task, outcome.actions)
    timing["replay"] = time.perf_counter() - replay_started
    if not (checked.executable and checked.valid_under_model):
        why = checked.failure or "the goal does not hold under the model after the last step"
        return without_plan(PlanStatus.ERROR, planner, f"The planner's plan failed replay ({why}); it is not returned.")
    validated_by = _validations(task, planner, outcome.actions, asked, timing)
    timing["total"] = time.perf_counter() - started
    fits = {fit.id: fit for fit in obj.fits}
    steps = tuple(PlanStep(action, args[:2], args[2], obj.step_text(fits[args[2]])) for action, args in outcome.actions)
    probability = outcome.success_probability
    if probability is None:  # an open-loop plan works only if every step does
        probability = math.prod(fits[step.fit].probability for step in steps)
    message = (
        ""
        if checked.valid_under_true_mechanism
        else (
            f"The plan satisfies the model, but the real {obj.name} would not produce {obj.goal}; it also needs: "
            + "; ".join(checked.unmet_requirements)
            + "."
        )
    )
    if outcome.message:  # what the planner says about its answer, e.g. an anytime MDP's bounds
        message = f"{outcome.message} {message}".strip()
    return PlanResult(
        PlanStatus.SOLVED,
        planner,
        obj.id,
        steps,
        True,
        checked.valid_under_true_mechanism,
        checked.unmet_requirements,
        timing,
        message,
        pddl,
        probability,
        outcome.expected_actions
        if outcome.expected_actions is not None or outcome.optimality == "bounded"
        else float(len(steps)),
        outcome.policy,
        None,
        validated_by["up"] == "valid" if "up" in validated_by else None,
        validated_by,
        _mdp_figures(outcome),
    )


def _mdp_figures(outcome: SearchOutcome) -> dict[str, object] | None:
    """Return what the MDP says beyond a plan: the objective solved, what is proved, the bounds."""
    if outcome.objective is None:
        return None
    figures: dict[str, object] = {
        "objective": outcome.objective,
        "required_success": outcome.required_success,
        "optimality": outcome.optimality,
        "states": outcome.states,
        "fewest_attempts": outcome.fewest_attempts,
    }
    if outcome.success_bounds is not None:
        low, high = outcome.success_bounds
        figures["success_probability_bounds"] = [round(low, 6), round(high, 6)]
        figures["bound_gap"] = round(high - low, 6)
    return figures


def _with_fallback(result: PlanResult, reason: str, started: float, first: PlanResult | None = None) -> PlanResult:
    timing = dict(result.timing)
    if first is not None:
        timing.update({f"{first.planner_used}_{stage}": seconds for stage, seconds in first.timing.items()})
    timing["total"] = time.perf_counter() - started
    return replace(result, fallback_reason=reason, timing=timing)


def _auto(task: PlanningTask, time_limit: float, asked: _Asked) -> PlanResult:
    from causalplan.planners.mdp import relevant_fits  # here: what never plans need not import the MDP

    started = time.perf_counter()
    risky = sorted(fit.id for fit in relevant_fits(task) if fit.probability < 1.0)
    if risky:
        mdp = _run(task, "mdp", min(time_limit, MDP_TIME_LIMIT), asked)
        if mdp.status.is_final():
            return _with_fallback(
                mdp,
                f"fit(s) {', '.join(risky)} may fail (probability below 1); Fast Downward's plans are blind to risk",
                started,
            )
        first = _run(task, "fd", time_limit, asked)
        return _with_fallback(
            first,
            f"the MDP could not be used ({mdp.status.value}: {mdp.message}); this classical "
            f"plan ignores that fit(s) {', '.join(risky)} may fail",
            started,
            mdp,
        )
    first = _run(task, "fd", time_limit, asked)
    if first.status not in FALLBACK_STATUSES:
        return first
    mdp = _run(task, "mdp", min(time_limit, MDP_TIME_LIMIT), asked)
    if not mdp.status.is_final():
        return first
    return _with_fallback(mdp, f"Fast Downward ended with '{first.status.value}': {first.message}", started, first)


def plan_task(
    task: PlanningTask,
    planner: str = "auto",
    time_limit: float = fd.DEFAULT_TIME_LIMIT,
    include_pddl: bool = False,
    validate_up: bool = False,
    val: bool = False,
    objective: str = "probability",
    required_success: float | None = None,
) -> PlanResult:
    """Return a replayed plan for ``task`` (or the status saying why there is none).

    ``val`` also checks the plan with VAL on the readable PDDL (one derived clause per rule);
    a plan VAL rejects raises ``PlanRejectedError`` with VAL's words. ``validate_up`` also
    checks it with unified-planning's sequential plan validator (always done for ``up:``
    planners). ``validated_by`` in the result has each validator's verdict. ``objective``
    (``probability`` or ``attempts`` with ``required_success``) is what the MDP planners
    optimise; ``ObjectiveError`` (``invalid_objective``) says what is wrong with it.
    """
    if planner not in PLANNERS:
        raise UnknownPlannerError(
            f"Unknown planner '{planner}'; choose one of: {', '.join(PLANNERS)}.", details={"planner": planner}
        )
    if not task.constraints.is_empty and planner not in fd.CONFIGS:
        # Only the PDDL route compiles a question's constraints; the MDP and UP would ignore them.
        raise UnknownPlannerError(
            f"A task with constraints is planned by {' or '.join(fd.CONFIGS)}, not '{planner}'.",
            details={"planner": planner},
        )
    if objective != "probability" or required_success is not None:
        from causalplan.planners.mdp.objective import check_objective

        check_objective(objective, required_success)
    asked = _Asked(include_pddl, validate_up, val, Objective(objective, required_success))
    if planner == "auto":
        return _auto(task, time_limit, asked)
    return _run(task, planner, time_limit, asked)
