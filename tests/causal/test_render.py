"""Pictures of causal models: DOT with safe quoting, columns from functions to the goal, files."""

from __future__ import annotations

from pathlib import Path

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.causal.render import draw, drawing_graph, layers, to_dot, to_json
from causalplan.objects.catalog import Catalog
from tests.conftest import example_model


def _model(functions: dict[str, list[str]], rules: list[str]) -> CausalModel:
    model, _ = read_model({"object": "desk_lamp", "functions": functions, "rules": rules}, SourceMap())
    assert model is not None
    return model


def test_rules_with_several_causes_get_an_and_junction(catalog: Catalog) -> None:
    graph = drawing_graph(example_model("paper/desk_lamp.yaml", catalog))
    assert graph.nodes["r:1"]["kind"] == "rule"
    assert set(graph.predecessors("r:1")) == {"n:provide electricity", "n:close the circuit"}
    assert list(graph.successors("r:1")) == ["n:electricity flows"]


def test_columns_run_from_functions_to_the_goal(catalog: Catalog) -> None:
    column = layers(drawing_graph(example_model("near/candle.yaml", catalog)))
    assert column["n:provide fuel"] == 0
    assert column["n:light"] == max(column.values())
    assert column["n:fuel at the tip"] < column["n:burning"] < column["n:light"]


def test_a_cycle_still_gets_columns() -> None:
    model = _model({"light_bulb": ["glow"]}, ["glow AND heat CAUSES light", "light CAUSES heat"])
    column = layers(drawing_graph(model))
    assert column["n:light"] == column["n:heat"]  # one strongly connected component


def test_dot_quotes_hostile_labels() -> None:
    model = _model({"light_bulb": ['say "hi" \\ }']}, ['say "hi" \\ } CAUSES light'])
    dot = to_dot(model)
    assert '"n:say \\"hi\\" \\\\ }"' in dot
    assert dot.count("{") == 1 and dot.rstrip().endswith("}")


def test_json_lists_nodes_with_kinds(catalog: Catalog) -> None:
    data = to_json(example_model("paper/desk_lamp.yaml", catalog))
    kinds = {node["label"]: node["kind"] for node in data["nodes"]}  # type: ignore[attr-defined]
    assert kinds["light"] == "goal"
    assert kinds["electricity flows"] == "effect"
    assert kinds["provide electricity"] == "function"


def test_draw_writes_png_and_svg(catalog: Catalog, tmp_path: Path) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    draw(model, tmp_path / "graph.png")
    draw(model, tmp_path / "graph.svg")
    assert (tmp_path / "graph.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<svg" in (tmp_path / "graph.svg").read_text()
