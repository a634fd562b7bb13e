"""The consensus graph as a picture: edge thickness is a rule's support, beside the members' models.

The layout is ``causal.render``'s (functions left, goal right, AND junctions); the left panel
is the consensus, the small panels on the right are the first members' own models.
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.causal.render import COLORS, DRAW_LOCK, drawing_graph, layers
from causalplan.consensus.build import Consensus

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from causalplan.causal.model import CausalModel

SMALL_MULTIPLES = 6
"""How many members' models are drawn beside the consensus."""


def _draw_model(axes: Axes, model: CausalModel, widths: dict[int, float], title: str, font: float) -> None:
    """Draw one model on ``axes``; ``widths`` gives each rule's (by index) line width."""
    from matplotlib.patches import FancyArrowPatch

    graph = drawing_graph(model)
    column = layers(graph)
    goal = f"n:{model.goal_key}"
    if goal in column:
        column[goal] = max(column.values())
    for node in graph.nodes:  # a function stands just left of what it feeds, so no arrow crosses a junction
        if graph.nodes[node]["kind"] == "function" and graph.out_degree(node):
            column[node] = min(column[successor] for successor in graph.successors(node)) - 1
    rows: dict[int, list[str]] = {}
    for node in sorted(graph.nodes, key=lambda n: (column[n], str(n))):
        rows.setdefault(column[node], []).append(node)
    position = {
        node: (col * 3.2, ((len(nodes) - 1) / 2 - index) * 1.4)
        for col, nodes in rows.items()
        for index, node in enumerate(nodes)
    }
    rule_of = {}
    for rule in model.rules:
        if len(rule.cause_keys) == 1:
            rule_of[(f"n:{next(iter(rule.cause_keys))}", f"n:{rule.effect_key}")] = rule.index
        else:
            rule_of.update({(f"n:{c}", f"r:{rule.index}"): rule.index for c in rule.cause_keys})
            rule_of[(f"r:{rule.index}", f"n:{rule.effect_key}")] = rule.index
    for source, target in graph.edges:
        axes.add_patch(
            FancyArrowPatch(
                position[source],
                position[target],
                arrowstyle="-|>",
                mutation_scale=10 + font,
                shrinkA=5 if graph.nodes[source]["kind"] == "rule" else 4 * font,
                shrinkB=5 if graph.nodes[target]["kind"] == "rule" else 4 * font,
                color="#444444",
                linewidth=widths.get(rule_of.get((source, target), -1), 1.2),
            )
        )
    for node, data in graph.nodes(data=True):
        x, y = position[node]
        is_rule = data["kind"] == "rule"
        axes.text(
            x,
            y,
            "AND" if is_rule else textwrap.fill(data["label"], 16),
            ha="center",
            va="center",
            fontsize=font * (0.75 if is_rule else 1.0),
            color="white" if is_rule else "black",
            bbox={
                "boxstyle": "circle,pad=0.3" if is_rule else "round,pad=0.4",
                "facecolor": COLORS[data["kind"]],
                "edgecolor": "none" if is_rule else "#666666",
            },
        )
    xs = [x for x, _ in position.values()] or [0.0]
    ys = [y for _, y in position.values()] or [0.0]
    axes.set_xlim(min(xs) - 1.6, max(xs) + 1.6)
    axes.set_ylim(min(ys) - 0.9, max(ys) + 0.9)
    axes.set_axis_off()
    axes.set_title(title, fontsize=font + 1)


def draw_consensus(consensus: Consensus, members: dict[str, CausalModel], folder: Path) -> list[Path]:
    """Write ``consensus_graph.png`` and ``.svg`` to ``folder``; return their paths."""
    from matplotlib.figure import Figure

    model = consensus.loaded.model
    entered = [rule for rule in consensus.rules if rule.entered]
    shown = list(members.items())[:SMALL_MULTIPLES]
    columns = 2 if shown else 0
    figure = Figure(figsize=(9 + 3.2 * columns, 5.5))
    grid = figure.add_gridspec(max(1, (len(shown) + 1) // 2), 2 + columns, width_ratios=[1.5, 1.5] + [1] * columns)
    main = figure.add_subplot(grid[:, :2])
    if model is not None:
        # Rules keep their order, so rule i of the model is the i-th entered rule.
        widths = {index: 1.0 + 7.0 * rule.share for index, rule in enumerate(entered, start=1)}
        joined = len(consensus.members)
        title = f"Consensus of {joined} participant{'s' if joined != 1 else ''}' models (line width = support)"
        if consensus.left_out:
            # How many, not who or why: the reasons name participants (the CLI's report lists them).
            title += f"\n{len(consensus.left_out)} left out (no model to read, or another training object)"
        if len(members) > len(shown):
            title += f"\n{len(shown)} of the {len(members)} models shown on the right"
        _draw_model(main, model, widths, title, 9)
    else:
        main.set_axis_off()
        main.set_title("No consensus model could be read")
    for number, (person, member) in enumerate(shown):
        axes = figure.add_subplot(grid[number // 2, 2 + number % 2])
        _draw_model(axes, member, {}, person, 5)
    figure.text(
        0.01,
        0.01,
        "blue: function   orange: intermediate effect   green: goal   AND: all causes needed; "
        "thicker arrows: held by more of the crowd",
        fontsize=7,
        color="#555555",
    )
    paths = [folder / "consensus_graph.png", folder / "consensus_graph.svg"]
    with DRAW_LOCK:
        for path in paths:
            figure.savefig(path, bbox_inches="tight", dpi=120)
    return paths
