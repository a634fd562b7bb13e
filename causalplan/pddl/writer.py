"""Writes a planning task as a PDDL 2.2 domain and problem (pure: values in, text out).

Design: parts and fits are typed objects; the assembly grows from the object's base part.
Each node of the causal graph is a 0-ary derived predicate. A function node is derived from
each part that carries it (``(in-assembly part)``); each rule becomes one ``(:derived ...)``
clause of its effect, the conjunction of its causes. Several clauses of one predicate are
alternatives, exactly the semantics of the rule language. The goal is the goal node.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.pddl.constraints import NO_CONSTRAINTS, PlanConstraints
from causalplan.pddl.identifiers import comment, node_identifiers
from causalplan.pddl.task import PlanningTask
from causalplan.version import __version__

REQUIREMENTS = ":strips :typing :negative-preconditions :conditional-effects :derived-predicates"


@dataclass(frozen=True)
class CompiledTask:
    """PDDL texts of one task, and the predicate name of every node label."""

    domain: str
    problem: str
    node_names: dict[str, str]


def _fit_predicate(primitive: str) -> str:
    return f"{primitive}-fit"


def assembly_action(name: str, parameters: str, fit_conditions: str) -> str:
    """Return an action schema that attaches ``?moving`` to ``?fixed`` through a free ``?fit``.

    ``fit_conditions``: the static facts that say the fit joins them (and how); the rest, the
    assembly's state and the fits it uses up, is the same in every form.
    """
    return f"""  (:action {name}
    :parameters ({parameters})
    :precondition (and {fit_conditions}
                       (available ?fit) (in-assembly ?fixed) (not (in-assembly ?moving)))
    :effect (and (in-assembly ?moving)
                 (forall (?other - fit) (when (excludes ?fit ?other) (not (available ?other))))))"""


def _action(primitive: str) -> str:
    return assembly_action(
        primitive,
        "?moving - part ?fixed - part ?fit - fit",
        f"({_fit_predicate(primitive)} ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)",
    )


def _names(names: list[str], indent: str, per_line: int = 6) -> str:
    rows = [" ".join(names[start : start + per_line]) for start in range(0, len(names), per_line)]
    return ("\n" + indent).join(rows)


def write_domain(task: PlanningTask, node_names: dict[str, str]) -> str:
    """Return the domain: types, the parts as constants, node predicates, axioms, actions."""
    labels = task.node_labels()
    primitives = sorted({fit.primitive for fit in task.obj.fits})
    node_declarations = "\n".join(f"    ({node_names[key]}) ; {comment(labels[key])}" for key in sorted(node_names))
    lines = [
        f";; causalplan {__version__}: the {comment(task.obj.name)} and a causal model of '{comment(task.goal)}'.",
        f"(define (domain causalplan-{task.obj.id})",
        requirements_line(),
        "  (:types part fit)",
        f"  (:constants {_names(list(task.obj.part_ids), '              ')} - part)",
        "  (:predicates",
        "    (in-assembly ?p - part)",
        "    (available ?f - fit)",
        "    (moves ?f - fit ?p - part)",
        "    (attaches-to ?f - fit ?p - part)",
        "    (excludes ?f - fit ?g - fit)",
        *(f"    ({_fit_predicate(primitive)} ?f - fit)" for primitive in primitives),
        "    ;; nodes of the causal graph",
        node_declarations,
        "  )",
        "",
        "  ;; Function nodes: true when a part carrying the function is in the assembly.",
    ]
    for key, parts in task.carriers().items():
        for part in parts:
            lines.append(f"  (:derived ({node_names[key]}) (in-assembly {part})) ; {comment(labels[key])}")
    lines += ["", "  ;; Rules: one clause per rule; rules with the same effect are alternatives."]
    for rule in task.rules:
        causes = " ".join(f"({node_names[cause]})" for cause in sorted(rule.cause_keys))
        body = causes if len(rule.cause_keys) == 1 else f"(and {causes})"
        lines.append(f"  ;; rule {rule.index}: {comment(rule.text)}")
        lines.append(f"  (:derived ({node_names[rule.effect_key]}) {body})")
    lines += ["", "  ;; Assembly primitives: attach a new part to the assembly through a free fit."]
    lines += [actions_text(primitives), ")"]
    return "\n".join(lines) + "\n"


def requirements_line() -> str:
    """Return the domain's ``:requirements`` line."""
    return f"  (:requirements {REQUIREMENTS})"


def actions_text(primitives: list[str]) -> str:
    """Return the action schemas of ``primitives``, one per primitive."""
    return "\n".join(_action(primitive) for primitive in primitives)


def fit_facts(fit: Fit) -> list[str]:
    """Return the static facts of ``fit`` that the per-primitive actions read: its kind, what it moves onto what."""
    return [
        f"({_fit_predicate(fit.primitive)} {fit.id})",
        f"(moves {fit.id} {fit.moving_part})",
        f"(attaches-to {fit.id} {fit.fixed_part})",
    ]


def problem_text(
    obj: AssemblyObject,
    goal: str,
    goal_comment: str | None = None,
    comments: bool = True,
    static_facts: Callable[[Fit], list[str]] = fit_facts,
    constraints: PlanConstraints = NO_CONSTRAINTS,
) -> str:
    """Return the problem: the fits as objects, the starting assembly, the goal predicate ``goal``.

    ``static_facts`` writes what the domain's actions read of a fit, besides ``available`` and ``excludes``.
    ``constraints`` (a question's: see ``constraints``) leave fits unavailable, add exclusions and goal facts.
    """
    constraints.check(obj)
    init = [f"    (in-assembly {obj.base})"]
    for fit in obj.fits:
        if comments:
            init.append(f"    ;; {fit.id}: {comment(obj.step_text(fit))}")
        facts = [f"(available {fit.id})"] if constraints.is_available(fit) else []
        facts += static_facts(fit)
        excluded = dict.fromkeys((*obj.excluded_fits(fit), *constraints.excluded_after(obj, fit)))
        facts += [f"(excludes {fit.id} {other})" for other in excluded]
        init.append("    " + " ".join(facts))
    fits = [fit.id for fit in obj.fits]
    objects = f"  (:objects {_names(fits, '            ')} - fit)" if fits else "  (:objects)"
    extra_goals = constraints.goal_facts()
    goal_formula = f"(and ({goal}) {' '.join(extra_goals)})" if extra_goals else f"({goal})"
    goal_line = f"  (:goal {goal_formula})" + (f" ; {comment(goal_comment)}" if goal_comment and comments else "")
    lines = [
        f"(define (problem {obj.id}-{goal})",
        f"  (:domain causalplan-{obj.id})",
        objects,
        "  (:init",
        *init,
        "  )",
        goal_line,
        ")",
    ]
    return "\n".join(lines) + "\n"


def write_problem(task: PlanningTask, node_names: dict[str, str]) -> str:
    """Return the problem: the fits as objects, the starting assembly, the goal node."""
    return problem_text(task.obj, node_names[task.goal_key], task.goal, constraints=task.constraints)


def compile_task(task: PlanningTask) -> CompiledTask:
    """Return the PDDL domain and problem of ``task``."""
    node_names = node_identifiers(task.node_labels())
    return CompiledTask(write_domain(task, node_names), write_problem(task, node_names), node_names)
