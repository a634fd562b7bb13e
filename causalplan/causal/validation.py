"""Checks a causal model's meaning: every finding has a stable code, plain words and a place.

Errors make a model invalid (the planner never sees it); warnings point at likely
misunderstandings, such as the paper's "diffuse light" and "hold things together".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from causalplan.causal.diagnostics import Diagnostic, Report, error, warning
from causalplan.causal.labels import closest, normalize_label
from causalplan.causal.model import CausalModel, Labelling

MAX_CYCLES_REPORTED = 5


@dataclass(frozen=True)
class ObjectSummary:
    """What validation needs to know of a catalog object."""

    id: str
    part_ids: tuple[str, ...]
    goal: str
    name: str = ""

    @property
    def title(self) -> str:
        """Return the object's display name (its id when it has none)."""
        return self.name or self.id


def check_labelling(labelling: Labelling, objects: Mapping[str, ObjectSummary]) -> list[Diagnostic]:
    """Return problems with the object id and part ids of a labelling."""
    source = labelling.source
    if not labelling.object_id:
        return []
    summary = objects.get(labelling.object_id)
    if summary is None:
        guess = closest(labelling.object_id, sorted(objects))
        hint = f"Did you mean '{guess}'?" if guess else f"Known objects: {', '.join(sorted(objects))}."
        return [
            error(
                "unknown_object",
                f"There is no object '{labelling.object_id}' in the catalog.",
                source.locate("object"),
                hint,
            )
        ]
    problems: list[Diagnostic] = []
    for part in labelling.functions:
        if part not in summary.part_ids:
            guess = closest(part, list(summary.part_ids))
            hint = f"Did you mean '{guess}'?" if guess else f"Its parts are: {', '.join(summary.part_ids)}."
            problems.append(
                error(
                    "unknown_part",
                    f"The {summary.title} ({summary.id}) has no part '{part}'.",
                    source.locate("functions", part, part=part),
                    hint,
                )
            )
    return problems


def _check_causes(model: CausalModel) -> list[Diagnostic]:
    functions = model.labelling.carriers()
    effects = {rule.effect_key for rule in model.rules}
    known = sorted(set(functions) | effects)
    labels = model.node_labels()
    problems: list[Diagnostic] = []
    reported: set[str] = set()
    for rule in model.rules:
        for cause in rule.causes:
            key = normalize_label(cause)
            if key in functions or key in effects or key in reported:
                continue
            reported.add(key)
            where = model.source.locate("rules", rule.index - 1, rule=rule.index)
            guess = closest(key, known, cutoff=0.75)
            if guess is not None:
                problems.append(
                    error(
                        "unknown_cause",
                        f"Rule {rule.index} uses '{cause}', which is neither a function of a part nor the effect "
                        "of another rule.",
                        where,
                        f"Did you mean '{labels[guess]}'?",
                    )
                )
            else:
                problems.append(
                    error(
                        "uncaused_effect",
                        f"Rule {rule.index} uses '{cause}' as a cause, but nothing produces it: no part has this "
                        "function and no rule causes it.",
                        where,
                        f"If it is an intermediate effect, add a rule that causes it: "
                        f"'FUNCTION AND FUNCTION CAUSES {cause}'. If it is what a part does, give that part "
                        "this function in step 1.",
                    )
                )
    return problems


def _check_goal(model: CausalModel) -> list[Diagnostic]:
    if any(rule.effect_key == model.goal_key for rule in model.rules):
        return []
    return [
        error(
            "goal_not_produced",
            f"No rule produces the goal '{model.goal}'.",
            model.source.locate("rules"),
            f"Add a rule of the form 'FUNCTION AND FUNCTION CAUSES {model.goal}', naming the functions "
            f"that together produce {model.goal}.",
        )
    ]


def _is_acyclic(model: CausalModel) -> bool:
    """Return whether the rules form no cycle (stdlib only: networkx is slow to import, and most models need none)."""
    from graphlib import CycleError, TopologicalSorter

    sorter: TopologicalSorter[str] = TopologicalSorter()
    for rule in model.rules:
        sorter.add(rule.effect_key, *rule.cause_keys)
    try:
        sorter.prepare()
    except CycleError:
        return False
    return True


def _check_cycles(model: CausalModel) -> list[Diagnostic]:
    if _is_acyclic(model):
        return []
    import networkx as nx

    from causalplan.causal.graph import causal_graph

    graph = causal_graph(model)
    labels = model.node_labels()
    problems: list[Diagnostic] = []
    for cycle in nx.simple_cycles(graph):
        if len(problems) >= MAX_CYCLES_REPORTED:
            break
        names = " → ".join(labels[node] for node in [*cycle, cycle[0]])
        edges = zip(cycle, [*cycle[1:], cycle[0]], strict=True)
        rule_indexes = sorted({index for a, b in edges for index in graph.edges[a, b]["rules"]})
        where = model.source.locate("rules", rule_indexes[0] - 1, rule=rule_indexes[0])
        which = (
            f"rule {rule_indexes[0]}" if len(rule_indexes) == 1 else "one of rules " + ", ".join(map(str, rule_indexes))
        )
        problems.append(
            error(
                "cycle",
                f"The rules go round in a circle: {names}.",
                where,
                f"Something cannot cause itself. Remove or change {which}.",
            )
        )
    return problems


def _check_duplicates(model: CausalModel) -> list[Diagnostic]:
    first_seen: dict[str, int] = {}
    problems: list[Diagnostic] = []
    for rule in model.rules:
        canonical = rule.canonical()
        if canonical in first_seen:
            problems.append(
                warning(
                    "duplicate_rule",
                    f"Rule {rule.index} says the same as rule {first_seen[canonical]}.",
                    model.source.locate("rules", rule.index - 1, rule=rule.index),
                    "Delete one of them.",
                )
            )
        else:
            first_seen[canonical] = rule.index
    return problems


def _check_unused(model: CausalModel) -> list[Diagnostic]:
    carriers = model.labelling.carriers()
    labels = model.labelling.labels()
    causes = set().union(*(rule.cause_keys for rule in model.rules)) if model.rules else set()
    effects = {rule.effect_key for rule in model.rules}
    problems: list[Diagnostic] = []
    for key, parts in carriers.items():
        if key in effects:
            problems.append(
                warning(
                    "effect_is_function",
                    f"'{labels[key]}' is both a function of {', '.join(parts)} and the effect of a rule.",
                    model.source.locate("functions", parts[0], part=parts[0]),
                    "A node is usually one or the other: a part's function, or an effect.",
                )
            )
        if key not in causes and key != model.goal_key:
            problems.append(
                warning(
                    "unused_function",
                    f"The function '{labels[key]}' (of {', '.join(parts)}) is not used by any rule, so it does not "
                    f"help produce {model.goal}.",
                    model.source.locate("functions", parts[0], part=parts[0]),
                    f"If it is needed for {model.goal}, use it in a rule; if not (like 'hold things together'), "
                    "you can leave it out.",
                )
            )
    for rule in model.rules:
        if rule.effect_key != model.goal_key and rule.effect_key not in causes:
            problems.append(
                warning(
                    "unused_effect",
                    f"The effect '{rule.effect}' of rule {rule.index} does not lead to "
                    f"{model.goal}: no rule uses it as a cause.",
                    model.source.locate("rules", rule.index - 1, rule=rule.index),
                    f"Use it as a cause in the rule that produces {model.goal}, or remove the rule.",
                )
            )
    return problems


def check_goal_matches_object(model: CausalModel, objects: Mapping[str, ObjectSummary]) -> list[Diagnostic]:
    """Warn when the model's goal is not the goal the object really produces."""
    summary = objects.get(model.object_id)
    if summary is None or normalize_label(summary.goal) == model.goal_key:
        return []
    return [
        warning(
            "goal_differs_from_object",
            f"The model's goal is '{model.goal}' but the {summary.title} produces '{summary.goal}'.",
            model.source.locate("goal"),
            f"Set 'goal: {summary.goal}' unless you mean something else.",
        )
    ]


def validate_model(
    model: CausalModel, objects: Mapping[str, ObjectSummary], earlier: list[Diagnostic] | None = None
) -> Report:
    """Return every problem with the model, after ``earlier`` ones (e.g. from reading it)."""
    diagnostics = list(earlier or [])
    diagnostics += check_labelling(model.labelling, objects)
    diagnostics += check_goal_matches_object(model, objects)
    diagnostics += _check_causes(model)
    diagnostics += _check_goal(model)
    diagnostics += _check_cycles(model)
    diagnostics += _check_duplicates(model)
    diagnostics += _check_unused(model)
    return Report(tuple(diagnostics))


def validate_mapping(
    labelling: Labelling, objects: Mapping[str, ObjectSummary], earlier: list[Diagnostic] | None = None
) -> Report:
    """Return every problem with a step-3 mapping that does not depend on the model."""
    return Report(tuple([*(earlier or []), *check_labelling(labelling, objects)]))
