"""The causal graph as a compact SVG for the pages, laid out from ``causalplan.causal.render.to_json``.

``render.draw`` makes print pictures (matplotlib, fixed sizes in inches): shrunk into a
column beside the rule box, their 9-point labels become unreadable. This draws the same
graph (the same nodes, AND junctions, columns and colours) at the page's own scale: labels
stay about as large as the text around them. Every label is XML-escaped.
"""

from __future__ import annotations

import textwrap
from collections import defaultdict
from xml.sax.saxutils import escape, quoteattr

from causalplan.causal.model import CausalModel
from causalplan.causal.render import COLORS, to_json

NODE_WIDTH = 168
JUNCTION_RADIUS = 15
LINE_HEIGHT = 16
FONT_SIZE = 13
PADDING = 8
GAP = 14
WRAP = 21
BOX_COLUMN = 218
JUNCTION_COLUMN = 64
MARGIN = 12
ROUTE_GAP = 7


def _edge(
    source: tuple[float, float, float, float],
    target: tuple[float, float, float, float],
    skips: bool,
    full_height: float,
    lanes: float,
    lane: int,
) -> str:
    """Return one arrow; an arrow that skips columns goes round above or below the nodes in between."""
    sx, sy = source[0] + source[2], source[1] + source[3] / 2
    tx, ty = target[0], target[1] + target[3] / 2
    if not skips:
        path = f"M {sx:.1f} {sy:.1f} L {tx:.1f} {ty:.1f}"
    else:
        above = (sy + ty) / 2 <= full_height / 2
        route = (lanes - ROUTE_GAP * lane) if above else (full_height - lanes + ROUTE_GAP * lane)
        bend = 16  # the climb stays within the gap before the next column
        path = (
            f"M {sx:.1f} {sy:.1f} C {sx + bend:.1f} {sy:.1f} {sx + bend:.1f} {route:.1f} "
            f"{sx + 2 * bend:.1f} {route:.1f} L {tx - 2 * bend:.1f} {route:.1f} "
            f"C {tx - bend:.1f} {route:.1f} {tx - bend:.1f} {ty:.1f} {tx:.1f} {ty:.1f}"
        )
    return f'<path d="{path}" fill="none" stroke="#444" stroke-width="1.4" marker-end="url(#arrow)"/>'


def _part_names(carriers: tuple[str, ...]) -> str:
    # Parts of a two-object model are named 'object.part'.
    return ", ".join(part.replace(".", ": ").replace("_", " ") for part in carriers)


def diagram_svg(model: CausalModel) -> bytes:
    """Return the model's causal graph as SVG: functions on the left, the goal on the right."""
    graph = to_json(model)
    nodes = {str(node["id"]): node for node in graph["nodes"]}  # type: ignore[attr-defined]
    edges = [(str(edge["source"]), str(edge["target"])) for edge in graph["edges"]]  # type: ignore[attr-defined]
    carriers = model.labelling.carriers()
    goal = f"n:{model.goal_key}"
    column = {node_id: int(node["column"]) for node_id, node in nodes.items()}
    if goal in column:
        column[goal] = max(column.values())  # the goal always stands at the right, as in render.draw
    lines: dict[str, list[str]] = {}
    for node_id, node in nodes.items():
        if node["kind"] == "rule":
            continue
        wrapped = textwrap.wrap(str(node["label"]), WRAP) or [""]
        if node_id[2:] in carriers:
            wrapped += textwrap.wrap(f"({_part_names(carriers[node_id[2:]])})", WRAP + 3)
        lines[node_id] = wrapped

    def height(node_id: str) -> int:
        return 2 * JUNCTION_RADIUS if node_id not in lines else len(lines[node_id]) * LINE_HEIGHT + 2 * PADDING

    columns: dict[int, list[str]] = defaultdict(list)
    for node_id in sorted(nodes):
        columns[column[node_id]].append(node_id)
    predecessors: dict[str, list[str]] = defaultdict(list)
    for source, target in edges:
        predecessors[target].append(source)
    rank: dict[str, float] = {}
    for number in sorted(columns):  # order each column by where its causes stand: fewer crossings
        order = columns[number]
        place: dict[str, float] = {}
        for index, node_id in enumerate(order):
            ranked = [rank[p] for p in predecessors[node_id] if p in rank]
            place[node_id] = sum(ranked) / len(ranked) if ranked else index
        order.sort(key=place.__getitem__)
        rank.update({node_id: index for index, node_id in enumerate(order)})
    totals = {number: sum(height(n) for n in ids) + GAP * (len(ids) - 1) for number, ids in columns.items()}
    long_edges = [(s, t) for s, t in edges if column[t] - column[s] > 1]
    lanes = ROUTE_GAP * (len(long_edges) + 1)  # room above and below the nodes for edges that skip columns
    full_height = max(totals.values(), default=0) + 2 * MARGIN + 2 * lanes
    x_left: dict[int, int] = {}
    has_boxes = {number: any(n in lines for n in ids) for number, ids in columns.items()}
    x = MARGIN
    for number in sorted(columns):
        x_left[number] = x
        x += BOX_COLUMN if has_boxes[number] else JUNCTION_COLUMN
    last = max(columns, default=0)
    width = x_left.get(last, MARGIN) + (NODE_WIDTH if has_boxes.get(last) else 2 * JUNCTION_RADIUS) + MARGIN
    box: dict[str, tuple[float, float, float, float]] = {}  # left, top, width, height
    for number, ids in columns.items():
        y = (full_height - totals[number]) / 2
        for node_id in ids:
            if node_id in lines:
                box[node_id] = (x_left[number], y, NODE_WIDTH, height(node_id))
            else:  # a junction: centred in its column
                middle = NODE_WIDTH / 2 if has_boxes[number] else JUNCTION_RADIUS
                box[node_id] = (x_left[number] + middle - JUNCTION_RADIUS, y, 2 * JUNCTION_RADIUS, height(node_id))
            y += height(node_id) + GAP

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{full_height}" '
        f'viewBox="0 0 {width} {full_height}" font-family="system-ui, sans-serif" font-size="{FONT_SIZE}">',
        '<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" '
        'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#444"/></marker></defs>',
    ]
    for source, target in edges:
        parts.append(
            _edge(
                box[source],
                box[target],
                column[target] - column[source] > 1,
                full_height,
                lanes,
                long_edges.index((source, target)) if (source, target) in long_edges else 0,
            )
        )
    for node_id, node in nodes.items():
        left, top, node_width, node_height = box[node_id]
        kind = str(node["kind"])
        if node_id not in lines:
            cx, cy = left + JUNCTION_RADIUS, top + JUNCTION_RADIUS
            parts.append(
                f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{JUNCTION_RADIUS}" fill="{COLORS["rule"]}"/>'
                f'<text x="{cx:.1f}" y="{cy + 4:.1f}" text-anchor="middle" font-size="10" fill="#fff">AND</text>'
            )
            continue
        weight = ' font-weight="bold"' if kind == "goal" else ""
        parts.append(
            f'<rect x="{left:.1f}" y="{top:.1f}" width="{node_width}" height="{node_height}" rx="8" '
            f'fill={quoteattr(COLORS[kind])} stroke="#666"/>'
        )
        for index, text in enumerate(lines[node_id]):
            y = top + PADDING + (index + 0.8) * LINE_HEIGHT
            small = ' font-size="11" fill="#444"' if text.startswith("(") and index > 0 else ""
            parts.append(
                f'<text x="{left + node_width / 2:.1f}" y="{y:.1f}" text-anchor="middle"{weight}{small}>'
                f"{escape(text)}</text>"
            )
    parts.append("</svg>")
    return "".join(parts).encode("utf-8", "replace")
