"""Independent sub-problems of the MDP: parts and fits that share no connector, holder, block or goal term.

The goal is a monotone formula over the parts' functions. Flattening the rules from the goal
node while a node has exactly one rule (an AND) and no carrier gives its *conjuncts*: nodes
that must all hold, each a leaf function or an OR (several rules or carriers). A conjunct
carried by the base (always attached) always holds and is left out.

Two parts are *coupled* when a fit joins them (a holder other than the base), when fits of
theirs exclude each other (a shared connector, or a fit that blocks the other's connector:
what ``taken_on_success`` and ``taken_on_failure`` say), or when one conjunct depends on both.
The base couples nothing: it is always there, and fits onto distinct connectors of it are
independent. The connected components of the coupling graph (networkx) are independent
sub-problems: each is the MDP over its own fits whose goal is its own conjuncts, a success
or failure in one changes nothing in another, and the object's goal holds exactly when every
component's goal does. A component with no conjunct never matters and is dropped.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

from causalplan.planners.mdp.model import CompiledMdp


@dataclass(frozen=True)
class Component:
    """One independent sub-problem: its fits (indices into the whole MDP's) and the goal nodes it must make."""

    fits: tuple[int, ...]
    goal_keys: tuple[str, ...]


def goal_conjuncts(compiled: CompiledMdp) -> dict[str, frozenset[str]] | None:
    """Return the goal's conjuncts with the parts each depends on; None when the rules are not a tree of ANDs to ORs."""
    task = compiled.task
    carriers = task.carriers()
    rules_of: dict[str, list[frozenset[str]]] = {}
    for rule in task.rules:
        rules_of.setdefault(rule.effect_key, []).append(rule.cause_keys)
    base = task.obj.base
    support: dict[str, frozenset[str]] = {}
    visiting: set[str] = set()

    def parts_under(key: str) -> frozenset[str] | None:
        if key in support:
            return support[key]
        if key in visiting:
            return None  # a cycle in the rules: no decomposition
        visiting.add(key)
        found: set[str] = set(carriers.get(key, ()))
        for causes in rules_of.get(key, ()):
            for cause in causes:
                below = parts_under(cause)
                if below is None:
                    return None
                found |= below
        visiting.discard(key)
        support[key] = frozenset(found)
        return support[key]

    conjuncts: dict[str, frozenset[str]] = {}

    def flatten(key: str) -> bool:
        if base in carriers.get(key, ()):
            return True  # always holds
        rules = rules_of.get(key, [])
        if len(rules) == 1 and not carriers.get(key):
            return all(flatten(cause) for cause in rules[0])
        below = parts_under(key)
        if below is None:
            return False
        conjuncts[key] = below
        return True

    return conjuncts if flatten(task.goal_key) else None


def independent_components(compiled: CompiledMdp) -> list[Component]:
    """Return the MDP's independent sub-problems, in the order of their first fit (one when nothing splits)."""
    import networkx as nx

    whole = [Component(tuple(range(len(compiled.fits))), ())]
    conjuncts = goal_conjuncts(compiled)
    if conjuncts is None:
        return whole
    base = compiled.task.obj.base
    graph: nx.Graph[str] = nx.Graph()
    fits = compiled.fits
    for index, fit in enumerate(fits):
        graph.add_node(fit.moving_part)
        if fit.fixed_part != base:
            graph.add_edge(fit.moving_part, fit.fixed_part)
        excluded = compiled.taken_on_success[index] | compiled.taken_on_failure[index]
        for other in range(len(fits)):
            if excluded >> other & 1:
                graph.add_edge(fit.moving_part, fits[other].moving_part)
    from_base = compiled.active(compiled.base)
    for key, parts in list(conjuncts.items()):
        inside = sorted(part for part in parts if part in graph)
        if not inside:
            if key not in from_base:
                return whole  # a conjunct no relevant fit can make: let the search say so
            del conjuncts[key]
            continue
        graph.add_nodes_from(inside)
        for first, second in itertools.pairwise(inside):
            graph.add_edge(first, second)
    components: list[Component] = []
    for parts in nx.connected_components(graph):
        keys = tuple(sorted(key for key, under in conjuncts.items() if under & parts))
        if keys:
            members = tuple(index for index, fit in enumerate(fits) if fit.moving_part in parts)
            components.append(Component(members, keys))
    return sorted(components, key=lambda component: component.fits[0])
