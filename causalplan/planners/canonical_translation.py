"""FD's translator on the canonical form, with the object's half parsed and grounded once.

A canonical task (``pddl.canonical``) is one object's PDDL with one action schema,
``assemble``, plus the goal clauses of one model. On the paper's objects, most of what FD's
translator does is the same for every model on the object:

- parsing and normalising the PDDL texts;
- grounding them with its Datalog exploration, which finds the relaxed-reachable atoms and action
  instances.

This module does the object's half once per object. It parses and normalises the texts without
the goal clauses. It then works out the relaxed reachability that the Datalog program would
compute: the parts that can join the assembly, and through which fits. For ``assemble`` this is
a walk over the fits from the parts already assembled.

For each model, only the goal clauses are parsed and normalised (FD's own functions), and the
clauses whose parts are all reachable are added to the relaxed model. From there FD's own code
runs on the result, unchanged: ``instantiate`` builds the ground actions and axioms, and
``pddl_to_sas`` does the rest (fact groups, the SAS translation, simplification, the order of
the variables). Tests check the SAS task byte for byte against the full translator, on every
example, on synthetic tasks and on random goals over the same objects.

The walk is only right for the action FD would ground the same way. ``sas_task`` returns None
(the caller then runs the full translator) unless the parsed object has exactly that shape:
- one ``assemble`` action, whose positive preconditions are ``fit-joins``, ``available`` and
  ``in-assembly`` of the fixed part, and whose only positive effect is ``in-assembly`` of the
  moving part;
- objects of the declared types;
- goal clauses that are ground conjunctions of ``in-assembly`` atoms.

Measured on the paper's four objects, the object's half already kept, both ways interleaved in
one process: 2.98 -> 1.36 ms per translation. Through the service, two servers interleaved
(1,000 new models each): cold p50 14.58 -> 12.76 ms.
"""

from __future__ import annotations

import copy
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from causalplan.objects.model import AssemblyObject
from causalplan.pddl.canonical import ASSEMBLE, ASSEMBLE_SCHEMA, GOAL_CLAUSE_START, canonical_texts

OBJECTS_KEPT = 32
"""How many objects' parsed halves are kept (least recently used first out)."""

GOAL = "goal"
IN_ASSEMBLY = "in-assembly"
_PARAMETER_TYPES = {"?kind": "kind", "?moving": "part", "?fixed": "part", "?fit": "fit"}
_POSITIVE_PRECONDITIONS = {
    ("fit-joins", ("?fit", "?kind", "?moving", "?fixed")),
    ("available", ("?fit",)),
    (IN_ASSEMBLY, ("?fixed",)),
}
_EXPLORED = "causalplan_explored"
"""The attribute of a task that carries its exploration to FD's ``instantiate.explore``."""


@dataclass(frozen=True)
class _ObjectHalf:
    """One object's parsed and normalised task (no goal clauses), and its relaxed reachability."""

    task: Any  # fast_downward.translate.pddl.Task
    model: tuple[Any, ...]  # the relaxed model's atoms: the initial ones, then actions and parts as reached
    reachable_parts: frozenset[str]
    types: dict[str, Any]
    predicates: dict[str, Any]
    constant_names: set[str]  # a set: FD's parser asserts that type


_halves: OrderedDict[tuple[str, str], _ObjectHalf | None] = OrderedDict()
_halves_lock = threading.Lock()


def sas_task(domain: str, problem: str) -> Any | None:
    """Return FD's SAS task of a canonical task, or None if the texts are not of that form.

    The translator's options must be set (``fast_downward._run_translator`` does it).
    Raises what FD's own parser raises for texts it cannot read.
    """
    from fast_downward.translate import main

    if ASSEMBLE_SCHEMA not in domain:
        return None
    lines = domain.split("\n")
    clauses = [line for line in lines if line.startswith(GOAL_CLAUSE_START)]
    half = _object_half("\n".join(line for line in lines if not line.startswith(GOAL_CLAUSE_START)), problem)
    if half is None:
        return None
    task = _with_goal_clauses(half, clauses)
    if task is None:
        return None
    _install_explore_hook()
    return main.pddl_to_sas(task)


def _object_half(domain: str, problem: str) -> _ObjectHalf | None:
    key = (domain, problem)
    with _halves_lock:
        if key in _halves:
            _halves.move_to_end(key)
            return _halves[key]
    half = _read_object_half(domain, problem)
    with _halves_lock:
        _halves[key] = half
        while len(_halves) > OBJECTS_KEPT:
            _halves.popitem(last=False)
    return half


def _read_object_half(domain: str, problem: str) -> _ObjectHalf | None:
    from fast_downward.translate import normalize, pddl
    from fast_downward.translate.pddl_parser import parsing_functions

    from causalplan.planners.fast_downward import parse_pddl

    task = parsing_functions.parse_task(parse_pddl("domain", domain), parse_pddl("problem", problem))
    normalize.normalize(task)
    if not _has_canonical_shape(task):
        return None
    object_types = {obj.name: obj.type_name for obj in task.objects}
    action = task.actions[0]
    atoms = [fact for fact in task.init if isinstance(fact, pddl.Atom)]
    available = {atom.args[0] for atom in atoms if atom.predicate == "available"}
    joins_from: dict[str, list[tuple[str, ...]]] = {}
    for atom in dict.fromkeys(atom for atom in atoms if atom.predicate == "fit-joins"):
        fit, kind, moving, fixed = atom.args
        typed = (object_types.get(fit), object_types.get(kind), object_types.get(moving), object_types.get(fixed))
        if typed != ("fit", "kind", "part", "part"):
            return None  # FD would not ground it with these arguments: the walk would be wrong
        if fit in available:
            joins_from.setdefault(fixed, []).append((kind, moving, fixed, fit))
    # The Datalog program's model, as far as ``instantiate`` reads it: the initial atoms, then
    # each reachable action instance and each part it brings into the assembly.
    model: list[Any] = list(atoms)
    reached = list(dict.fromkeys(atom.args[0] for atom in atoms if atom.predicate == IN_ASSEMBLY))
    reachable = set(reached)
    for part in reached:  # grows while it is walked
        for arguments in joins_from.get(part, ()):
            model.append(pddl.Atom(action, arguments))
            moving = arguments[1]
            if moving not in reachable:
                reachable.add(moving)
                reached.append(moving)
                model.append(pddl.Atom(IN_ASSEMBLY, (moving,)))
    return _ObjectHalf(
        task,
        tuple(model),
        frozenset(reachable),
        {kind.name: kind for kind in task.types},
        {predicate.name: predicate for predicate in task.predicates},
        # The canonical domain's constants are its parts and kinds (the problem's objects are its
        # fits): the names a goal clause may use, as FD's parser of the whole domain would allow.
        {name for name, type_name in object_types.items() if type_name in ("part", "kind")},
    )


def _has_canonical_shape(task: Any) -> bool:
    """Return whether FD's Datalog grounding of ``task`` is the walk of ``_read_object_half``."""
    from fast_downward.translate import pddl

    if len(task.actions) != 1 or task.axioms or task.use_min_cost_metric:
        return False
    action = task.actions[0]
    if action.name != ASSEMBLE or action.cost is not None:
        return False
    if {parameter.name: parameter.type_name for parameter in action.parameters} != _PARAMETER_TYPES:
        return False
    if len(action.parameters) != len(_PARAMETER_TYPES) or action.num_external_parameters != len(_PARAMETER_TYPES):
        return False
    condition = action.precondition
    if not isinstance(condition, pddl.Conjunction):
        return False
    positive = {(part.predicate, tuple(part.args)) for part in condition.parts if isinstance(part, pddl.Atom)}
    if positive != _POSITIVE_PRECONDITIONS or not all(isinstance(part, pddl.Literal) for part in condition.parts):
        return False
    adds = [effect for effect in action.effects if not effect.literal.negated]
    if len(adds) != 1:
        return False
    (add,) = adds
    if add.parameters or not isinstance(add.condition, pddl.Truth):
        return False
    if (add.literal.predicate, tuple(add.literal.args)) != (IN_ASSEMBLY, ("?moving",)):
        return False
    goal = task.goal
    return isinstance(goal, pddl.Atom) and (goal.predicate, tuple(goal.args)) == (GOAL, ())


def _with_goal_clauses(half: _ObjectHalf, clauses: list[str]) -> Any | None:
    """Return the object's task with ``clauses`` as its axioms, carrying its exploration; None if one does not fit."""
    from fast_downward.translate import instantiate, normalize, pddl
    from fast_downward.translate.pddl_parser import parsing_functions

    from causalplan.planners.fast_downward import parse_pddl

    entries = parse_pddl("domain", "(" + "\n".join(clauses) + ")")
    context = parsing_functions.Context()
    axioms = [
        parsing_functions.parse_axiom(context, entry, half.types, half.predicates, half.constant_names)
        for entry in entries
    ]
    base = half.task
    # Normalised as FD normalises a whole task, in a task of their own: the object's stays as it is.
    clauses_task = pddl.Task(
        base.domain_name,
        base.problem_name,
        base.requirements,
        base.types,
        base.objects,
        list(base.predicates),
        base.functions,
        base.init,
        base.goal,
        [],
        axioms,
        base.use_min_cost_metric,
    )
    normalize.normalize(clauses_task)
    model = list(half.model)
    goal_reachable = False
    for axiom in clauses_task.axioms:
        parts = _clause_parts(axiom)
        if parts is None:
            return None
        if parts <= half.reachable_parts:
            model.append(pddl.Atom(axiom, ()))
            goal_reachable = True
    if goal_reachable:
        model += [pddl.Atom(GOAL, ()), pddl.Atom("@goal-reachable", ())]
    task = copy.copy(base)
    task.axioms = clauses_task.axioms
    setattr(task, _EXPLORED, instantiate.instantiate(task, model))
    return task


def _clause_parts(axiom: Any) -> frozenset[str] | None:
    """Return the parts a normalised goal clause needs, or None if it is not a conjunction of them."""
    from fast_downward.translate import pddl

    if axiom.name != GOAL or axiom.parameters or axiom.num_external_parameters:
        return None
    condition = axiom.condition
    literals: Iterable[Any]
    if isinstance(condition, pddl.Truth):
        literals = ()
    elif isinstance(condition, pddl.Conjunction):
        literals = condition.parts
    else:
        literals = (condition,)
    parts = []
    for literal in literals:
        if not isinstance(literal, pddl.Atom) or literal.predicate != IN_ASSEMBLY or len(literal.args) != 1:
            return None
        parts.append(literal.args[0])
    return frozenset(parts)


_hook_lock = threading.Lock()


def _install_explore_hook() -> None:
    """Let FD's ``instantiate.explore`` return the exploration a task carries (once per process).

    ``main.pddl_to_sas`` calls ``instantiate.explore(task)`` first; a task from
    ``_with_goal_clauses`` carries its result, so FD's Datalog grounding does not run. Any other
    task is explored by FD's own function. The result travels with the task object, so threads
    and forked children never see another task's.
    """
    from fast_downward.translate import instantiate

    with _hook_lock:
        original: Callable[[Any], Any] = instantiate.explore
        if getattr(original, "carries_causalplan_exploration", False):
            return

        def explore(task: Any) -> Any:
            explored = task.__dict__.pop(_EXPLORED, None)
            return explored if explored is not None else original(task)

        explore.carries_causalplan_exploration = True  # type: ignore[attr-defined]
        instantiate.explore = explore


def keep_object(obj: AssemblyObject) -> None:
    """Parse and walk ``obj``'s half now, so that its first model is translated the short way too.

    A service worker does it for the catalog's objects while it starts.
    """
    from fast_downward.translate import options

    from causalplan.planners.fast_downward import translator_options

    options.options = translator_options()
    domain, problem = canonical_texts(obj, ())  # no goal clauses: the key ``sas_task`` looks up
    _object_half(domain, problem)


def clear() -> None:
    """Forget every object's parsed half (tests use it)."""
    with _halves_lock:
        _halves.clear()
