"""The canonical form of a planning task: the goal as its minimal sets of parts.

Whatever the labels and however the rules are written, a causal model's goal is a monotone
Boolean function of which parts are in the assembly: it holds exactly when the assembly
contains one of a few *minimal part sets*. Two models with the same minimal sets on the same
object are the same planning problem. ``canonical_pddl`` writes that problem with one
``(goal)`` derived predicate, one clause per minimal set, and nothing that depends on labels.

The planners solve this form (when it is small), so equal problems give byte-identical
PDDL, hence identical Fast Downward runs and plans, and one cached solve can answer them all.
People still see the readable compilation (``writer.compile_task``), which is equivalent.
"""

from __future__ import annotations

from causalplan.pddl.task import PlanningTask
from causalplan.pddl.writer import CompiledTask, actions_text, problem_text, requirements_line

MAX_MINIMAL_SETS = 64
"""Beyond this many minimal part sets the canonical form is not written (DNF would grow)."""


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
    obj = task.obj
    clauses = []
    for parts in sorted(sorted(group) for group in sets):
        body = " ".join(f"(in-assembly {part})" for part in parts)
        clauses.append(f"  (:derived (goal) {body if len(parts) == 1 else f'(and {body})' if parts else '(and)'})")
    primitives = sorted({fit.primitive for fit in obj.fits})
    domain = (
        "\n".join(
            [
                f"(define (domain causalplan-{obj.id})",
                requirements_line(),
                "  (:types part fit)",
                f"  (:constants {' '.join(obj.part_ids)} - part)",
                "  (:predicates (in-assembly ?p - part) (available ?f - fit) (moves ?f - fit ?p - part)",
                "               (attaches-to ?f - fit ?p - part) (excludes ?f - fit ?g - fit)",
                *(f"               ({primitive}-fit ?f - fit)" for primitive in primitives),
                "               (goal))",
                *clauses,
                actions_text(primitives),
                ")",
            ]
        )
        + "\n"
    )
    return CompiledTask(domain, problem_text(obj, "goal", comments=False), {task.goal_key: "goal"})
