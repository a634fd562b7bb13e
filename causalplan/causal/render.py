"""Pictures of a causal model: left to right from functions to the goal, as DOT, PNG or SVG.

Rules with several causes get a small AND junction, so the picture shows what the planner
reads: causes joined at a junction are all needed; arrows meeting at a node are alternatives.
"""

from __future__ import annotations

import textwrap
import threading
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.causal.graph import causal_graph

if TYPE_CHECKING:
    import networkx as nx

    from causalplan.causal.model import CausalModel

COLORS = {"function": "#cfe2f3", "effect": "#fde9c8", "goal": "#c9ecc4", "unknown": "#f8c9c4", "rule": "#555555"}
PICTURE_SUFFIXES = (".png", ".svg", ".pdf")
DRAW_LOCK = threading.Lock()
"""Held by a program's threads around any matplotlib drawing: its font cache and text layout are not thread-safe."""


def drawing_graph(model: CausalModel) -> nx.DiGraph:
    """Return the graph to draw: nodes ``n:<label>``, and ``r:<index>`` AND junctions of 2+ causes."""
    import networkx as nx

    drawing = nx.DiGraph()
    for key, data in causal_graph(model).nodes(data=True):
        drawing.add_node(f"n:{key}", **data)
    for rule in model.rules:
        effect = f"n:{rule.effect_key}"
        if len(rule.cause_keys) == 1:
            (cause,) = rule.cause_keys
            drawing.add_edge(f"n:{cause}", effect)
            continue
        junction = f"r:{rule.index}"
        drawing.add_node(junction, label="AND", kind="rule")
        drawing.add_edges_from((f"n:{cause}", junction) for cause in rule.cause_keys)
        drawing.add_edge(junction, effect)
    return drawing


def layers(graph: nx.DiGraph) -> dict[str, int]:
    """Return each node's column: the longest path reaching it (cycles are collapsed first)."""
    import networkx as nx

    condensed = nx.condensation(graph)
    column: dict[int, int] = {}
    for component in nx.topological_sort(condensed):
        column[component] = max((column[p] + 1 for p in condensed.predecessors(component)), default=0)
    mapping = condensed.graph["mapping"]
    return {node: column[mapping[node]] for node in graph.nodes}


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def to_dot(model: CausalModel) -> str:
    """Return the model as Graphviz DOT text (labels quoted, so any label is safe)."""
    graph = drawing_graph(model)
    lines = ["digraph causal_model {", "  rankdir=LR;", '  node [fontname="Helvetica", style=filled];']
    for node, data in sorted(graph.nodes(data=True)):
        shape = "point" if data["kind"] == "rule" else ("doubleoctagon" if data["kind"] == "goal" else "box")
        lines.append(
            f"  {_quote(node)} [label={_quote(data['label'])}, shape={shape}, "
            f"fillcolor={_quote(COLORS[data['kind']])}];"
        )
    for source, target in sorted(graph.edges):
        lines.append(f"  {_quote(source)} -> {_quote(target)};")
    lines.append("}")
    return "\n".join(lines) + "\n"


def to_json(model: CausalModel) -> dict[str, object]:
    """Return the drawing graph as nodes (id, label, kind, column) and edges (source, target)."""
    graph = drawing_graph(model)
    column = layers(graph)
    return {
        "nodes": [
            {"id": node, "label": data["label"], "kind": data["kind"], "column": column[node]}
            for node, data in sorted(graph.nodes(data=True))
        ],
        "edges": [{"source": source, "target": target} for source, target in sorted(graph.edges)],
    }


def draw(model: CausalModel, path: Path) -> None:
    """Draw the model to ``path`` (PNG, SVG or PDF by suffix) with matplotlib, no display needed."""
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyArrowPatch

    graph = drawing_graph(model)
    carriers = model.labelling.carriers()
    column = layers(graph)
    goal_column = max(column.values(), default=0)
    if f"n:{model.goal_key}" in column:
        column[f"n:{model.goal_key}"] = goal_column  # the goal always stands at the right
    rows: dict[int, list[str]] = {}
    for node in sorted(graph.nodes, key=lambda n: (column[n], str(n))):
        rows.setdefault(column[node], []).append(node)
    height = max((len(nodes) for nodes in rows.values()), default=1)
    position: dict[str, tuple[float, float]] = {}
    for col, nodes in rows.items():  # centre each column vertically
        for index, node in enumerate(nodes):
            position[node] = (col * 3.2, ((len(nodes) - 1) / 2 - index) * 1.4)
    figure = Figure(figsize=(max(4.0, 3.0 * (goal_column + 1)), max(2.5, 1.3 * height + 0.8)))
    axes = figure.add_subplot()
    axes.set_axis_off()
    for source, target in graph.edges:
        axes.add_patch(
            FancyArrowPatch(
                position[source],
                position[target],
                arrowstyle="-|>",
                mutation_scale=14,
                shrinkA=42 if graph.nodes[source]["kind"] != "rule" else 5,
                shrinkB=42 if graph.nodes[target]["kind"] != "rule" else 5,
                color="#444444",
                linewidth=1.2,
            )
        )
    for node, data in graph.nodes(data=True):
        x, y = position[node]
        if data["kind"] == "rule":
            axes.text(
                x,
                y,
                "AND",
                ha="center",
                va="center",
                fontsize=7,
                color="white",
                bbox={"boxstyle": "circle,pad=0.3", "facecolor": COLORS["rule"], "edgecolor": "none"},
            )
            continue
        text = textwrap.fill(data["label"], 18)
        if node[2:] in carriers:
            text += "\n(" + textwrap.fill(", ".join(p.replace("_", " ") for p in carriers[node[2:]]), 22) + ")"
        axes.text(
            x,
            y,
            text,
            ha="center",
            va="center",
            fontsize=9,
            fontweight="bold" if data["kind"] == "goal" else "normal",
            bbox={"boxstyle": "round,pad=0.5", "facecolor": COLORS[data["kind"]], "edgecolor": "#666666"},
        )
    xs = [x for x, _ in position.values()] or [0.0]
    ys = [y for _, y in position.values()] or [0.0]
    axes.set_xlim(min(xs) - 1.6, max(xs) + 1.6)
    axes.set_ylim(min(ys) - 0.9, max(ys) + 0.9)
    axes.set_title(f"How the {model.object_id.replace('_', ' ')} produces {model.goal}", fontsize=10)
    figure.text(
        0.01,
        0.01,
        "blue: a part's function (part in brackets)   orange: intermediate effect   "
        "green: goal   red: nothing produces it   AND: all causes needed; arrows meeting at a box are "
        "alternatives",
        fontsize=7,
        color="#555555",
    )
    figure.savefig(path, bbox_inches="tight", dpi=120)
