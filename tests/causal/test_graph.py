"""The causal graph and the paper's eq. 1: AND within a rule, OR across rules with the same effect."""

from __future__ import annotations

from causalplan.causal.diagnostics import Location
from causalplan.causal.documents import SourceMap
from causalplan.causal.graph import active_nodes, causal_graph, goal_holds
from causalplan.causal.model import CausalModel, read_model
from causalplan.causal.rules import Rule, parse_rule


def rules(*texts: str) -> list[Rule]:
    parsed = []
    for index, text in enumerate(texts, start=1):
        rule, problems = parse_rule(text, index, Location(rule=index))
        assert rule is not None and not problems, problems
        parsed.append(rule)
    return parsed


PAPER = rules(
    "provide electricity AND close the circuit CAUSES electricity flows",
    "electricity flows AND turn electricity into light CAUSES light",
)
PAPER_FUNCTIONS = {"provide electricity", "close the circuit", "turn electricity into light"}


def model(data: dict[str, object]) -> CausalModel:
    built, problems = read_model(data, SourceMap())
    assert built is not None and not problems, problems
    return built


# --- eq. 1 -------------------------------------------------------------------------------------


def test_paper_model_holds_with_all_functions() -> None:
    assert goal_holds(PAPER_FUNCTIONS, PAPER, "light")
    assert active_nodes(PAPER_FUNCTIONS, PAPER) == PAPER_FUNCTIONS | {"electricity flows", "light"}


def test_paper_model_needs_every_function() -> None:
    for missing in PAPER_FUNCTIONS:
        assert not goal_holds(PAPER_FUNCTIONS - {missing}, PAPER, "light"), missing


def test_intermediate_effect_holds_without_the_goal() -> None:
    active = active_nodes({"provide electricity", "close the circuit"}, PAPER)
    assert active == {"provide electricity", "close the circuit", "electricity flows"}
    assert "light" not in active


def test_no_functions_produce_nothing() -> None:
    assert active_nodes(set(), PAPER) == set()
    assert not goal_holds([], PAPER, "light")


def test_and_within_one_rule() -> None:
    both = rules("a AND b CAUSES light")
    assert goal_holds({"a", "b"}, both, "light")
    assert not goal_holds({"a"}, both, "light")
    assert not goal_holds({"b"}, both, "light")


def test_or_across_rules_with_the_same_effect() -> None:
    either = rules("a CAUSES light", "b CAUSES light")
    assert goal_holds({"a"}, either, "light")
    assert goal_holds({"b"}, either, "light")
    assert goal_holds({"a", "b"}, either, "light")
    assert not goal_holds({"c"}, either, "light")


def test_or_of_ands() -> None:
    alternatives = rules("a AND b CAUSES light", "c AND d CAUSES light")
    assert goal_holds({"a", "b"}, alternatives, "light")
    assert goal_holds({"c", "d"}, alternatives, "light")
    assert not goal_holds({"a", "c"}, alternatives, "light")
    assert not goal_holds({"b", "d"}, alternatives, "light")


def test_chain_of_effects() -> None:
    chain = rules(
        "fuel at the tip AND start a flame CAUSES burning",
        "burning CAUSES light",
        "provide fuel AND draw up the fuel CAUSES fuel at the tip",
    )
    functions = {"provide fuel", "draw up the fuel", "start a flame"}
    assert active_nodes(functions, chain) == functions | {"fuel at the tip", "burning", "light"}
    assert not goal_holds(functions - {"draw up the fuel"}, chain, "light")


def test_rule_order_does_not_matter() -> None:
    forward = rules("a CAUSES b", "b CAUSES c", "c CAUSES light")
    backward = list(reversed(forward))
    assert active_nodes({"a"}, forward) == active_nodes({"a"}, backward) == {"a", "b", "c", "light"}


def test_alternative_intermediate_effects() -> None:
    both = rules("batteries CAUSES power", "cables CAUSES power", "power AND bulb CAUSES light")
    assert goal_holds({"batteries", "bulb"}, both, "light")
    assert goal_holds({"cables", "bulb"}, both, "light")
    assert not goal_holds({"batteries", "cables"}, both, "light")


def test_a_cycle_does_not_produce_itself() -> None:
    circular = rules("a CAUSES b", "b CAUSES a", "b CAUSES light")
    assert not goal_holds(set(), circular, "light")
    assert goal_holds({"a"}, circular, "light")


def test_the_goal_can_be_a_function() -> None:
    assert goal_holds({"light"}, [], "light")


def test_functions_are_normalised_keys() -> None:
    mixed = rules(
        "Provide  Electricity AND CLOSE the circuit CAUSES Electricity flows",
        "electricity FLOWS and turn electricity into light causes LIGHT",
    )
    assert goal_holds(PAPER_FUNCTIONS, mixed, "light")


def test_the_paper_failed_model_needs_diffuse_light() -> None:
    failed = rules("provide electricity AND turn electricity into light AND diffuse light CAUSES light")
    assert not goal_holds({"provide electricity", "turn electricity into light"}, failed, "light")
    assert goal_holds({"provide electricity", "turn electricity into light", "diffuse light"}, failed, "light")


# --- the graph ---------------------------------------------------------------------------------


DESK_LAMP_FUNCTIONS = {
    "base_with_cables": ["provide electricity"],
    "light_bulb": ["Turn electricity into light", "close the circuit"],
}
DESK_LAMP = {
    "object": "desk_lamp",
    "goal": "light",
    "functions": DESK_LAMP_FUNCTIONS,
    "rules": [
        "provide electricity AND close the circuit CAUSES electricity flows",
        "electricity flows AND turn electricity into light CAUSES light",
    ],
}


def test_nodes_have_kinds_and_labels() -> None:
    graph = causal_graph(model(DESK_LAMP))
    assert dict(graph.nodes(data="kind")) == {
        "provide electricity": "function",
        "turn electricity into light": "function",
        "close the circuit": "function",
        "electricity flows": "effect",
        "light": "goal",
    }
    assert graph.nodes["turn electricity into light"]["label"] == "Turn electricity into light"


def test_edges_go_from_cause_to_effect_with_their_rules() -> None:
    graph = causal_graph(model(DESK_LAMP))
    assert {(a, b, tuple(rules)) for a, b, rules in graph.edges(data="rules")} == {
        ("provide electricity", "electricity flows", (1,)),
        ("close the circuit", "electricity flows", (1,)),
        ("electricity flows", "light", (2,)),
        ("turn electricity into light", "light", (2,)),
    }


def test_an_edge_shared_by_two_rules_remembers_both() -> None:
    from causalplan.causal.documents import SourceMap
    from causalplan.causal.model import read_model

    shared, _ = read_model(
        {
            "object": "desk_lamp",
            "functions": {"light_bulb": ["glow", "heat"]},
            "rules": ["glow CAUSES light", "glow AND heat CAUSES light"],
        },
        SourceMap(),
    )
    assert shared is not None
    assert causal_graph(shared).edges["glow", "light"]["rules"] == [1, 2]


def test_unused_function_is_an_isolated_function_node() -> None:
    data = {**DESK_LAMP, "functions": {**DESK_LAMP_FUNCTIONS, "shade": ["diffuse light"]}}
    graph = causal_graph(model(data))
    assert graph.nodes["diffuse light"]["kind"] == "function"
    assert graph.degree("diffuse light") == 0


def test_cause_without_origin_is_an_unknown_node() -> None:
    data = {**DESK_LAMP, "rules": ["current AND turn electricity into light CAUSES light"]}
    graph = causal_graph(model(data))
    assert graph.nodes["current"]["kind"] == "unknown"
    assert graph.has_edge("current", "light")


def test_goal_node_is_present_even_when_no_rule_produces_it() -> None:
    data = {**DESK_LAMP, "rules": ["provide electricity CAUSES electricity flows"]}
    graph = causal_graph(model(data))
    assert graph.nodes["light"]["kind"] == "goal"
    assert graph.in_degree("light") == 0


def test_rules_with_the_same_effect_share_one_effect_node() -> None:
    data = {
        "object": "flashlight",
        "functions": {"batteries": ["store charge"], "head": ["glow"]},
        "rules": ["store charge CAUSES power", "glow CAUSES power", "power CAUSES light"],
    }
    graph = causal_graph(model(data))
    assert sorted(graph.predecessors("power")) == ["glow", "store charge"]
    assert graph.number_of_nodes() == 4


def test_cycle_appears_in_the_graph() -> None:
    import networkx as nx

    data = {**DESK_LAMP, "rules": ["provide electricity AND heat CAUSES glow", "glow CAUSES heat", "glow CAUSES light"]}
    graph = causal_graph(model(data))
    assert sorted(map(sorted, nx.simple_cycles(graph))) == [["glow", "heat"]]
