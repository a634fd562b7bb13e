"""The causal graph: nodes are functions and effects, edges go from cause to effect.

``goal_holds`` is the paper's eq. 1: function nodes are 1 when a part carrying them is in the
assembly, and every other node is computed from its parents; a node is produced when *any*
of its rules has *all* its causes (OR over rules, AND within one).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

from causalplan.causal.rules import Rule

if TYPE_CHECKING:
    import networkx as nx

    from causalplan.causal.model import CausalModel


def active_nodes(functions: Iterable[str], rules: Sequence[Rule]) -> set[str]:
    """Return the normalised nodes that hold when exactly ``functions`` hold (least fixpoint)."""
    active = set(functions)
    changed = True
    while changed:
        changed = False
        for rule in rules:
            if rule.effect_key not in active and rule.cause_keys <= active:
                active.add(rule.effect_key)
                changed = True
    return active


def goal_holds(functions: Iterable[str], rules: Sequence[Rule], goal_key: str) -> bool:
    """Return whether the goal node is produced when exactly ``functions`` hold."""
    return goal_key in active_nodes(functions, rules)


def causal_graph(model: CausalModel) -> nx.DiGraph:
    """Return the model as a DiGraph: node attributes ``label`` and ``kind``, edges with ``rules``."""
    import networkx as nx

    graph = nx.DiGraph()
    labels = model.node_labels()
    functions = set(model.labelling.carriers())
    effects = {rule.effect_key for rule in model.rules}
    for key, label in labels.items():
        if key == model.goal_key:
            kind = "goal"
        elif key in functions:
            kind = "function"
        elif key in effects:
            kind = "effect"
        else:
            kind = "unknown"
        graph.add_node(key, label=label, kind=kind)
    for rule in model.rules:
        for cause in rule.cause_keys:
            if graph.has_edge(cause, rule.effect_key):
                graph.edges[cause, rule.effect_key]["rules"].append(rule.index)
            else:
                graph.add_edge(cause, rule.effect_key, rules=[rule.index])
    return graph
