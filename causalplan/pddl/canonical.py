"""The canonical form of a planning task: the goal as its minimal sets of parts.

Whatever the labels and however the rules are written, a causal model's goal is a monotone
Boolean function of which parts are in the assembly: it holds exactly when the assembly
contains one of a few *minimal part sets*. Two models with the same minimal sets on the same
object are the same planning problem. ``canonical_pddl`` writes that problem with one
``(goal)`` derived predicate, one clause per minimal set, and nothing that depends on labels.

The planners solve this form (when it is small), so equal problems give byte-identical
PDDL, hence identical Fast Downward runs and plans, and one cached solve can answer them all.
People still see the readable compilation (``writer.compile_task``), which is equivalent.

Its assembly steps are one action schema, ``assemble``, whose first parameter is the fit's kind
(a constant ``kind-screw``, ``kind-clip``...; a hyphen is never in a part's or fit's id), where
the readable form has one schema per primitive. FD's translator does its work per schema, so
one schema translates faster than several. The translated task is the same, operator for
operator and in the same order, but for the operators' names (tests check it byte for byte),
so FD's searches are too; ``plan_actions`` gives the plan back in the per-primitive names.
"""

from __future__ import annotations

from collections.abc import Iterable

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.pddl.constraints import NO_CONSTRAINTS, PlanConstraints
from causalplan.pddl.task import PlanningTask
from causalplan.pddl.writer import CompiledTask, assembly_action, problem_text, requirements_line

MAX_MINIMAL_SETS = 64
"""Beyond this many minimal part sets the canonical form is not written (DNF would grow)."""


ASSEMBLE = "assemble"
"""The one action schema of the canonical form."""
KIND_PREFIX = "kind-"

ASSEMBLE_SCHEMA = assembly_action(
    ASSEMBLE, "?kind - kind ?moving - part ?fixed - part ?fit - fit", "(fit-joins ?fit ?kind ?moving ?fixed)"
)
"""The text of the ``assemble`` schema: a domain that contains it is in the canonical form."""

GOAL_CLAUSE_START = "  (:derived (goal) "
"""How each line of the domain that holds one goal clause (one minimal part set) starts."""

Action = tuple[str, tuple[str, ...]]


def _fit_facts(fit: Fit) -> list[str]:
    return [f"(fit-joins {fit.id} {KIND_PREFIX}{fit.primitive} {fit.moving_part} {fit.fixed_part})"]


def plan_actions(actions: tuple[Action, ...]) -> tuple[Action, ...]:
    """Return a plan of the canonical form in per-primitive actions.

    ``(assemble kind-screw a b f)`` becomes ``(screw a b f)``; other actions stay as they are.
    """
    return tuple(
        (args[0].removeprefix(KIND_PREFIX), args[1:])
        if name == ASSEMBLE and args and args[0].startswith(KIND_PREFIX)
        else (name, args)
        for name, args in actions
    )


class _TooMany(Exception):
    pass


def _minimize(sets: set[frozenset[str]]) -> set[frozenset[str]]:
    """Return the sets that contain no other set of ``sets``."""
    return {candidate for candidate in sets if not any(other < candidate for other in sets)}


def minimal_part_sets(task: PlanningTask) -> frozenset[frozenset[str]] | None:
    """Return the minimal sets of parts whose assembly makes the goal hold, or None if too many.

    The empty set means the goal already holds with no part; no set means it never holds.
    The base part is always assembled, so it is left out of every set.
    """
    carriers = task.carriers()
    by_effect: dict[str, list[frozenset[str]]] = {}
    for rule in task.rules:
        by_effect.setdefault(rule.effect_key, []).append(rule.cause_keys)
    memo: dict[str, set[frozenset[str]]] = {}
    cycles_cut = 0
    base = task.obj.base

    def sets_of(key: str, path: frozenset[str]) -> set[frozenset[str]]:
        nonlocal cycles_cut
        if key in memo:
            return memo[key]
        if key in path:  # a cycle contributes nothing (least fixpoint)
            cycles_cut += 1
            return set()
        cut_before = cycles_cut
        result = {frozenset() if part == base else frozenset({part}) for part in carriers.get(key, ())}
        for causes in by_effect.get(key, []):
            combined: set[frozenset[str]] = {frozenset()}
            for cause in sorted(causes):
                options = sets_of(cause, path | {key})
                combined = _minimize({left | right for left in combined for right in options})
                if len(combined) > MAX_MINIMAL_SETS:
                    raise _TooMany
            result |= combined
        result = _minimize(result)
        if len(result) > MAX_MINIMAL_SETS:
            raise _TooMany
        # Without a cycle below it, a node's sets do not depend on the path that reached it, so
        # they are worked out once: effects shared by many rules would otherwise cost 2**depth.
        if cycles_cut == cut_before:
            memo[key] = result
        return result

    try:
        return frozenset(sets_of(task.goal_key, frozenset()))
    except _TooMany:
        return None


def canonical_pddl(task: PlanningTask) -> CompiledTask | None:
    """Return the label-free PDDL of ``task``, or None when its goal has too many minimal sets."""
    sets = minimal_part_sets(task)
    if sets is None:
        return None
    domain, problem = canonical_texts(task.obj, sets, task.constraints)
    return CompiledTask(domain, problem, {task.goal_key: "goal"})


def canonical_texts(
    obj: AssemblyObject, sets: Iterable[Iterable[str]], constraints: PlanConstraints = NO_CONSTRAINTS
) -> tuple[str, str]:
    """Return the domain and problem whose goal holds once the assembly of ``obj`` contains one of ``sets``.

    ``constraints`` go into the problem as in the readable form (``writer.problem_text``).
    """
    clauses = []
    for parts in sorted(sorted(group) for group in sets):
        body = " ".join(f"(in-assembly {part})" for part in parts)
        clauses.append(f"{GOAL_CLAUSE_START}{body if len(parts) == 1 else f'(and {body})' if parts else '(and)'})")
    kinds = " ".join(f"{KIND_PREFIX}{primitive}" for primitive in sorted({fit.primitive for fit in obj.fits}))
    domain = (
        "\n".join(
            [
                f"(define (domain causalplan-{obj.id})",
                requirements_line(),
                "  (:types part fit kind)",
                f"  (:constants {' '.join(obj.part_ids)} - part{f' {kinds} - kind' if kinds else ''})",
                "  (:predicates (in-assembly ?p - part) (available ?f - fit) (excludes ?f - fit ?g - fit)",
                "               (fit-joins ?f - fit ?k - kind ?moving - part ?fixed - part) (goal))",
                *clauses,
                ASSEMBLE_SCHEMA,
                ")",
            ]
        )
        + "\n"
    )
    return domain, problem_text(obj, "goal", comments=False, static_facts=_fit_facts, constraints=constraints)
