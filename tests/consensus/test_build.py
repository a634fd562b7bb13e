"""The consensus model: known crowds with known answers."""

from __future__ import annotations

import networkx as nx
from hypothesis import given, settings
from hypothesis import strategies as st

from causalplan.causal.graph import causal_graph
from causalplan.consensus.build import RuleSupport, _select, build_consensus
from causalplan.consensus.participants import Participant
from causalplan.objects.catalog import Catalog

FLASHLIGHT = "flashlight"


def desk_lamp(
    power: str, close: str, convert: str, flows: str = "electricity flows", diffuse: str | None = None
) -> dict[str, object]:
    """Return the paper's desk-lamp model in these words, optionally with 'diffuse light' made necessary."""
    functions: dict[str, list[str]] = {"base_with_cables": [power], "light_bulb": [convert, close]}
    last = f"{flows} AND {convert}"
    if diffuse:
        functions["shade"] = [diffuse]
        last += f" AND {diffuse}"
    return {
        "object": "desk_lamp",
        "functions": functions,
        "rules": [f"{power} AND {close} CAUSES {flows}", f"{last} CAUSES light"],
    }


def person(name: str, model: dict[str, object], power: str = "provide electricity") -> Participant:
    functions = model["functions"]
    assert isinstance(functions, dict)
    bulb = functions["light_bulb"]
    mapping = {"object": FLASHLIGHT, "functions": {"batteries": [functions["base_with_cables"][0]], "head": list(bulb)}}
    return Participant(name, model, {FLASHLIGHT: mapping}, where=name)


PARAPHRASES = [
    person("ann", desk_lamp("provide electricity", "close the circuit", "turn electricity into light")),
    person("bob", desk_lamp("supply power", "complete the circuit", "make light from power", "current runs")),
    person("cy", desk_lamp("gives electricity", "connect the circuit", "convert electricity into light")),
]


def test_three_paraphrases_of_one_model_give_that_model(catalog: Catalog) -> None:
    consensus = build_consensus(PARAPHRASES, catalog)
    assert consensus.loaded.is_valid and consensus.loaded.model is not None
    paper = build_consensus([PARAPHRASES[0]], catalog).loaded.model
    assert paper is not None
    assert nx.is_isomorphic(causal_graph(consensus.loaded.model), causal_graph(paper))
    assert [rule.share for rule in consensus.rules] == [1.0, 1.0]
    # Each node is named by its most common writing; on a tie, the shortest.
    assert consensus.mappings[FLASHLIGHT].data["functions"] == {
        "batteries": ["supply power"],
        "head": ["close the circuit", "make light from power"],
    }


def test_a_minority_error_does_not_enter(catalog: Catalog) -> None:
    crowd = [
        *PARAPHRASES,
        person("dee", desk_lamp("provide electricity", "close the circuit", "glow", diffuse="diffuse light")),
    ]
    consensus = build_consensus(crowd, catalog)
    assert "diffuse light" not in str(consensus.model_data)
    left_out = [rule for rule in consensus.rules if not rule.entered]
    assert [(rule.holders, rule.share) for rule in left_out] == [(("dee",), 0.25)]


def test_a_majority_error_enters_and_the_report_names_who_held_it(catalog: Catalog) -> None:
    crowd = [
        person("ann", desk_lamp("provide electricity", "close the circuit", "glow", diffuse="diffuse light")),
        person("bob", desk_lamp("provide electricity", "close the circuit", "glow", diffuse="spread the light")),
        person("cy", desk_lamp("provide electricity", "close the circuit", "glow", diffuse="diffuse light")),
        person("dee", desk_lamp("provide electricity", "close the circuit", "glow")),
    ]
    consensus = build_consensus(crowd, catalog)
    entered = [rule for rule in consensus.rules if rule.entered]
    with_diffuse = [rule for rule in entered if "diffuse light" in consensus.rule_text(rule)]
    assert [(rule.holders, rule.share) for rule in with_diffuse] == [(("ann", "bob", "cy"), 0.75)]
    assert consensus.model_data["functions"] == {
        "light_bulb": ["close the circuit", "glow"],
        "base_with_cables": ["provide electricity"],
        "shade": ["diffuse light"],
    }


def test_a_majority_with_an_uncaused_intermediate_gives_an_invalid_model_that_says_why(catalog: Catalog) -> None:
    uncaused = {
        "object": "desk_lamp",
        "functions": {"base_with_cables": ["provide electricity"], "light_bulb": ["glow"]},
        "rules": ["electricity flows AND glow CAUSES light"],
    }
    crowd = [person(name, uncaused) for name in ("ann", "bob")] + [PARAPHRASES[0]]
    consensus = build_consensus(crowd, catalog)
    assert not consensus.loaded.is_valid
    assert [d.code for d in consensus.loaded.report.errors] == ["unknown_cause"]


def test_a_rule_that_closes_a_cycle_is_left_out_the_weakest_first() -> None:
    rules = [
        RuleSupport(frozenset({"f1"}), "e1", ("a", "b"), 0.67, False),
        RuleSupport(frozenset({"e1"}), "e2", ("a", "b"), 0.67, False),
        RuleSupport(frozenset({"e2"}), "e1", ("c",), 0.33, False),
        RuleSupport(frozenset({"e2"}), "goal", ("a", "b", "c"), 1.0, False),
    ]
    chosen = _select(rules, 0.3)
    assert [rule.entered for rule in chosen] == [True, True, False, True]
    assert chosen[2].why_left_out == "it would close a cycle with better supported rules"


def test_participants_trained_on_another_object_are_left_out(catalog: Catalog) -> None:
    candle = {
        "object": "candle",
        "functions": {"wax": ["provide fuel"], "wick": ["burn"], "match": ["start a flame"]},
        "rules": ["provide fuel AND burn AND start a flame CAUSES light"],
    }
    crowd = [
        *PARAPHRASES,
        Participant("eve", candle, where="eve"),
        Participant("fay", None, where="fay", problems=["x"]),
    ]
    consensus = build_consensus(crowd, catalog)
    assert consensus.members == ("ann", "bob", "cy")
    assert consensus.left_out == {"eve": "trained on candle, the crowd on desk_lamp", "fay": "x"}


def test_a_label_both_carried_and_produced_is_aligned_as_an_effect(catalog: Catalog) -> None:
    odd = {
        "object": "desk_lamp",
        "functions": {"base_with_cables": ["provide electricity", "electricity flows"], "light_bulb": ["glow"]},
        "rules": ["provide electricity CAUSES electricity flows", "electricity flows AND glow CAUSES light"],
    }
    consensus = build_consensus([person("ann", odd)], catalog)
    assert [node.kind for node in consensus.nodes.values()] == ["function", "function", "effect", "goal"]
    assert [d.code for d in consensus.loaded.report.errors] == []


LABELS = ["provide electricity", "glow", "close the circuit", "electricity flows", "light"]
PARTS = ["base_with_cables", "light_bulb", "shade"]


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.dictionaries(st.sampled_from(PARTS), st.lists(st.sampled_from(LABELS), max_size=3), max_size=3),
            st.lists(
                st.tuples(st.lists(st.sampled_from(LABELS), min_size=1, max_size=3), st.sampled_from(LABELS)),
                max_size=4,
            ),
        ),
        min_size=1,
        max_size=5,
    )
)
def test_any_crowd_of_small_models_gives_a_consensus_or_says_why(
    crowd: list[tuple[dict[str, list[str]], list[tuple[list[str], str]]]],
) -> None:
    from tests.conftest import builtin_catalog

    people = [
        Participant(
            f"p{number}",
            {
                "object": "desk_lamp",
                "functions": functions,
                "rules": [" AND ".join(causes) + f" CAUSES {effect}" for causes, effect in rules],
            },
            where=f"p{number}",
        )
        for number, (functions, rules) in enumerate(crowd)
    ]
    consensus = build_consensus(people, builtin_catalog())
    assert consensus.loaded.model is not None
    assert consensus.loaded.is_valid or consensus.loaded.report.errors
    if consensus.loaded.is_valid:
        assert nx.is_directed_acyclic_graph(causal_graph(consensus.loaded.model))
