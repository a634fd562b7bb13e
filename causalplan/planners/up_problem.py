"""The same planning task as a unified-planning problem without axioms (the comparison route).

unified-planning 1.3.0 has no derived predicates, so the causal graph cannot be written as
axioms the way ``pddl.writer`` does. Instead every fit becomes one grounded action whose
effects also switch on ``active(f)`` for each function its moving part carries, and the goal
node is expanded into a formula over those fluents: rules with the same effect become an
``Or``, the causes of one rule an ``And`` (the paper's eq. 1, unrolled).

unified-planning is slow to import, so it is imported inside the functions that need it.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from causalplan.pddl.identifiers import slug
from causalplan.pddl.task import PlanningTask
from causalplan.planners.result import PlanStatus, SearchOutcome

if TYPE_CHECKING:
    from unified_planning.model import Problem

PlanAction = tuple[str, tuple[str, ...]]
"""One plan step as the rest of causalplan writes it: (primitive, (moving, fixed, fit))."""

ActionMap = dict[str, tuple[str, tuple[str, str, str]]]
"""UP action name -> (primitive, (moving part, fixed part, fit id))."""

DEFAULT_UP_TIME_LIMIT = 30.0
VALIDATOR = "sequential_plan_validator"

Formula = tuple[Any, ...]
"""A goal formula over function nodes: ``("true",)``, ``("false",)``, ``("fn", key)``,
``("and", [formula, ...])`` or ``("or", [formula, ...])``."""

TRUE_FORMULA: Formula = ("true",)
FALSE_FORMULA: Formula = ("false",)


@dataclass
class _Names:
    """Hands out distinct UP names, so ids and labels can never clash with each other."""

    taken: set[str] = field(default_factory=set)

    def get(self, wanted: str) -> str:
        base = wanted or "x"
        name, counter = base, 1
        while name in self.taken:
            counter += 1
            name = f"{base}_{counter}"
        self.taken.add(name)
        return name


def goal_structure(task: PlanningTask) -> Formula:
    """Return the goal node as a nested formula over function nodes (no UP objects involved).

    A node is a function node when some part carries it, and/or the effect of
    rules; a node on a cycle back to itself contributes false (least fixpoint), a node that is
    neither a function nor an effect is false.
    """
    carried = set(task.carriers())
    by_effect: dict[str, list[frozenset[str]]] = {}
    for rule in task.rules:
        by_effect.setdefault(rule.effect_key, []).append(rule.cause_keys)
    memo: dict[str, Formula] = {}

    def expand(key: str, path: frozenset[str]) -> tuple[Formula, bool]:
        """Return the node's formula and whether it depends on ``path`` (a cycle was cut)."""
        if key in memo:
            return memo[key], False
        if key in path:
            return FALSE_FORMULA, True
        inner = path | {key}
        alternatives: list[Formula] = [("fn", key)] if key in carried else []
        cut = False
        for causes in by_effect.get(key, []):
            parts: list[Formula] = []
            for cause in sorted(causes):
                formula, cause_cut = expand(cause, inner)
                cut = cut or cause_cut
                parts.append(formula)
            alternatives.append(_combine("and", parts))
        result = _combine("or", alternatives)
        if not cut:
            memo[key] = result
        return result, cut

    return expand(task.goal_key, frozenset())[0]


def _combine(kind: str, parts: list[Formula]) -> Formula:
    """Return ``(kind, parts)`` simplified: one false part decides an "and", one true part an "or"."""
    decides, neutral = (FALSE_FORMULA, TRUE_FORMULA) if kind == "and" else (TRUE_FORMULA, FALSE_FORMULA)
    if decides in parts:
        return decides
    parts = [part for part in parts if part != neutral]
    if not parts:
        return neutral
    return parts[0] if len(parts) == 1 else (kind, parts)


def build_up_problem(task: PlanningTask) -> tuple[Problem, ActionMap]:
    """Return the axiom-free UP problem of ``task`` and what each of its actions stands for."""
    from unified_planning.shortcuts import (
        FALSE,
        TRUE,
        And,
        BoolType,
        Fluent,
        InstantaneousAction,
        Object,
        Or,
        Problem,
        UserType,
    )

    obj = task.obj
    names = _Names()
    part_type = UserType(names.get("part"))
    fit_type = UserType(names.get("fit"))
    node_type = UserType(names.get("node"))
    in_assembly = Fluent(names.get("in_assembly"), BoolType(), part=part_type)
    # "not yet assembled" as its own fluent, so engines without negative conditions apply too.
    detached = Fluent(names.get("detached"), BoolType(), part=part_type)
    available = Fluent(names.get("available"), BoolType(), fit=fit_type)
    active = Fluent(names.get("active"), BoolType(), node=node_type)

    problem = Problem(names.get(f"causalplan_{obj.id}"))
    for fluent in (in_assembly, detached, available, active):
        problem.add_fluent(fluent, default_initial_value=False)
    parts = {part_id: Object(names.get(f"part_{part_id}"), part_type) for part_id in obj.part_ids}
    fits = {fit.id: Object(names.get(f"fit_{fit.id}"), fit_type) for fit in obj.fits}
    carriers = task.carriers()
    nodes = {key: Object(names.get("node_" + (slug(key).replace("-", "_") or "label")), node_type) for key in carriers}
    problem.add_objects([*parts.values(), *fits.values(), *nodes.values()])
    functions_of_part: dict[str, list[str]] = {}
    for key, carrying in carriers.items():
        for part_id in carrying:
            if part_id in parts:  # a mapping may name parts the object does not have
                functions_of_part.setdefault(part_id, []).append(key)

    actions: ActionMap = {}
    for fit in obj.fits:
        name = names.get(f"{fit.primitive}__{fit.moving_part}__{fit.fixed_part}__{fit.id}")
        action = InstantaneousAction(name)
        action.add_precondition(available(fits[fit.id]))
        action.add_precondition(in_assembly(parts[fit.fixed_part]))
        action.add_precondition(detached(parts[fit.moving_part]))
        action.add_effect(in_assembly(parts[fit.moving_part]), True)
        action.add_effect(detached(parts[fit.moving_part]), False)
        for key in functions_of_part.get(fit.moving_part, []):
            action.add_effect(active(nodes[key]), True)
        for other in obj.excluded_fits(fit):
            action.add_effect(available(fits[other]), False)
        problem.add_action(action)
        actions[name] = (fit.primitive, (fit.moving_part, fit.fixed_part, fit.id))

    problem.set_initial_value(in_assembly(parts[obj.base]), True)
    for part_id, part_object in parts.items():
        problem.set_initial_value(detached(part_object), part_id != obj.base)
    for key in functions_of_part.get(obj.base, []):
        problem.set_initial_value(active(nodes[key]), True)
    for fit_object in fits.values():
        problem.set_initial_value(available(fit_object), True)

    def to_up(formula: Formula) -> Any:
        kind = formula[0]
        if kind == "true":
            return TRUE()
        if kind == "false":
            return FALSE()
        if kind == "fn":
            return active(nodes[formula[1]])
        combine: Callable[..., Any] = And if kind == "and" else Or
        return combine(*(to_up(part) for part in formula[1]))

    goal = goal_structure(task)
    if goal == FALSE_FORMULA:  # PDDL has no "false": a fluent nothing ever sets says the same
        never = Fluent(names.get("goal_cannot_hold"), BoolType())
        problem.add_fluent(never, default_initial_value=False)
        problem.add_goal(never())
    elif goal != TRUE_FORMULA:  # true: no goal at all, the empty plan solves it
        problem.add_goal(to_up(goal))
    return problem, actions


_STATUS_NAMES: Mapping[str, PlanStatus] = {
    "SOLVED_SATISFICING": PlanStatus.SOLVED,
    "SOLVED_OPTIMALLY": PlanStatus.SOLVED,
    "UNSOLVABLE_PROVEN": PlanStatus.UNSOLVABLE,
    "UNSOLVABLE_INCOMPLETELY": PlanStatus.UNSOLVABLE,
    "TIMEOUT": PlanStatus.TIMEOUT,
    "MEMOUT": PlanStatus.OUT_OF_MEMORY,
}


def status_of_up_result(status_name: str) -> PlanStatus:
    """Return our status for the name of a UP ``PlanGenerationResultStatus`` (unknown: ERROR)."""
    return _STATUS_NAMES.get(status_name, PlanStatus.ERROR)


COMPILATIONS = ("DISJUNCTIVE_CONDITIONS_REMOVING", "NEGATIVE_CONDITIONS_REMOVING", "CONDITIONAL_EFFECTS_REMOVING")
"""UP compilations tried, in order, until an engine supports the problem (e.g. pyperplan: no ``or``)."""


def compile_for_engine(problem: Problem, engine: str) -> tuple[Problem, list[Callable[..., Any]]]:
    """Return ``problem`` compiled with UP's own compilers until ``engine`` supports it.

    Also returns the functions that map the compiled problem's actions back, last one first.
    An engine that supports nothing we can compile to gets the problem as it is (its own
    error then says why).
    """
    from unified_planning.shortcuts import CompilationKind, Compiler, get_environment

    engine_class = get_environment().factory.engine(engine)
    map_backs: list[Callable[..., Any]] = []
    for name in COMPILATIONS:
        if engine_class.supports(problem.kind):
            break
        kind = getattr(CompilationKind, name)
        with Compiler(problem_kind=problem.kind, compilation_kind=kind) as compiler:
            result = compiler.compile(problem, kind)
        problem = result.problem
        map_backs.append(result.map_back_action_instance)
    return problem, map_backs


ENGINE_PROGRAMS = {"enhsp": ("java", "a Java runtime, e.g. Debian's default-jre-headless")}
"""Programs an engine runs that no wheel ships (by the engine's name before any ``-opt``), and where to get them."""


def missing_program(engine: str) -> str | None:
    """Return why ``engine`` cannot run when a program it needs is not on PATH (UP loads it all the same)."""
    needed = ENGINE_PROGRAMS.get(engine.removesuffix("-opt"))
    if needed is None or shutil.which(needed[0]) is not None:
        return None
    program, source = needed
    return f"'{engine}' runs '{program}', which is not on PATH: install {source}."


def engine_problem(engine: str) -> str | None:
    """Return None when the UP engine is installed, loads and has what it runs, else why it cannot be used."""
    missing = missing_program(engine)
    if missing is not None:
        return missing
    try:
        _quiet_environment()
        from unified_planning.shortcuts import get_environment

        get_environment().factory.engine(engine)
    except Exception as exc:  # noqa: BLE001 - UP raises assorted errors for missing engines
        return f"{type(exc).__name__}: {exc}"
    return None


def _quiet_environment() -> None:
    from unified_planning.shortcuts import get_environment

    get_environment().credits_stream = None


def solve_with_up(
    task: PlanningTask, engine: str = "fast-downward", time_limit: float = DEFAULT_UP_TIME_LIMIT
) -> SearchOutcome:
    """Build the axiom-free problem and solve it with a UP engine; never raises for failures.

    ``timing`` holds ``build`` (problem construction, the first time also importing UP),
    ``solve`` (the engine, all its processes included) and ``total``. The time limit covers
    the build and the engine's processes, but not UP's own PDDL writing before it starts them
    (seconds on the largest synthetic tasks), so a run can overshoot it by that much; UP stops its processes
    (SIGTERM to their process group) at the limit.
    """
    started = time.perf_counter()
    timing: dict[str, float] = {}
    missing = missing_program(engine)
    if missing is not None:  # else the engine's failure to start reads as "no plan"
        return SearchOutcome(PlanStatus.ERROR, timing={"total": 0.0}, message=missing)
    try:
        _quiet_environment()
        from unified_planning.shortcuts import OneshotPlanner

        problem, actions = build_up_problem(task)
        timing["build"] = time.perf_counter() - started
        remaining = time_limit - timing["build"]
        if remaining <= 0:
            timing["total"] = timing["build"]
            return SearchOutcome(
                PlanStatus.TIMEOUT, timing=timing, message=f"Building the problem took longer than {time_limit:g} s."
            )
        solve_started = time.perf_counter()
        with warnings.catch_warnings():  # "cannot establish whether X can solve": the status says it
            warnings.simplefilter("ignore")
            compiled, map_backs = compile_for_engine(problem, engine)
            # Fast Downward's driver writes its translated task (output.sas) in the working directory,
            # and UP starts it in ours: two runs from one directory would read each other's. The
            # directory is the process's, so a process runs one UP solve at a time (as its callers do).
            with (
                tempfile.TemporaryDirectory(prefix="causalplan-up-") as folder,
                contextlib.chdir(folder),
                OneshotPlanner(name=engine) as planner,
            ):
                result = planner.solve(compiled, timeout=remaining)
        plan = result.plan
        for map_back in reversed(map_backs):
            if plan is not None:
                plan = plan.replace_action_instances(map_back)
        timing["solve"] = time.perf_counter() - solve_started
    except Exception as exc:  # noqa: BLE001 - engine missing, problem unsupported, engine crash
        timing["total"] = time.perf_counter() - started
        return SearchOutcome(
            PlanStatus.ERROR,
            timing=timing,
            message=f"unified-planning engine '{engine}' failed: {type(exc).__name__}: {exc}",
        )
    timing["total"] = time.perf_counter() - started
    status = status_of_up_result(result.status.name)
    if status is not PlanStatus.SOLVED:
        message = {
            PlanStatus.TIMEOUT: f"The engine '{engine}' did not finish within {time_limit:g} s.",
            PlanStatus.ERROR: f"The engine '{engine}' ended with status {result.status.name}.",
        }.get(status, "")
        return SearchOutcome(status, timing=timing, message=message)
    if plan is None:
        return SearchOutcome(PlanStatus.ERROR, timing=timing, message=f"The engine '{engine}' returned no plan.")
    steps: list[PlanAction] = []
    for instance in plan.actions:
        mapped = actions.get(instance.action.name)
        if mapped is None:
            return SearchOutcome(
                PlanStatus.ERROR,
                timing=timing,
                message=f"The engine '{engine}' returned an unknown action '{instance.action.name}'.",
            )
        steps.append(mapped)
    return SearchOutcome(PlanStatus.SOLVED, tuple(steps), timing)


def validate_with_up(task: PlanningTask, actions: tuple[PlanAction, ...] | list[PlanAction]) -> bool:
    """Return whether UP's sequential plan validator accepts ``actions`` on the axiom-free problem."""
    _quiet_environment()
    from unified_planning.plans import ActionInstance, SequentialPlan
    from unified_planning.shortcuts import PlanValidator

    problem, action_map = build_up_problem(task)
    by_step: dict[PlanAction, str] = {(primitive, args): name for name, (primitive, args) in action_map.items()}
    instances = []
    for primitive, args in actions:
        name = by_step.get((primitive, tuple(args)))
        if name is None:
            return False
        instances.append(ActionInstance(problem.action(name)))
    with PlanValidator(name=VALIDATOR) as validator:
        result = validator.validate(problem, SequentialPlan(instances))
    return bool(result.status.name == "VALID")
