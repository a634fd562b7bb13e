"""The strategies' priors: a model's routes to the goal, and who it suspects."""

from __future__ import annotations

import pytest

from causalplan.causal.diagnostics import Location
from causalplan.causal.model import Labelling
from causalplan.causal.rules import Rule, parse_rule
from causalplan.objects.catalog import Catalog
from causalplan.troubleshoot.errors import MappingMismatchError
from causalplan.troubleshoot.priors import goal_routes, model_suspicion, oracle_suspicion, uniform_suspicion
from tests.conftest import example_mapping, example_model


def _rules(*texts: str) -> list[Rule]:
    rules = []
    for index, text in enumerate(texts, start=1):
        rule, problems = parse_rule(text, index, Location())
        assert rule is not None, problems
        rules.append(rule)
    return rules


def test_routes_are_the_minimal_sets_of_functions_that_make_the_goal() -> None:
    rules = _rules("a AND b CAUSES flow", "flow AND c CAUSES light", "d CAUSES flow")
    routes = goal_routes(rules, "light", {"a", "b", "c", "d"})
    assert routes == [frozenset({"c", "d"}), frozenset({"a", "b", "c"})]


def test_a_route_through_a_circle_is_no_route() -> None:
    rules = _rules("x CAUSES y", "y CAUSES x", "x AND f CAUSES light", "g CAUSES x")
    assert goal_routes(rules, "light", {"f", "g"}) == [frozenset({"f", "g"})]
    assert goal_routes(rules, "light", {"f"}) == []


def test_the_good_desk_lamp_model_suspects_the_base_and_the_bulb_not_the_shade(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    lamp = catalog.get("desk_lamp")
    believed = model_suspicion(model.rules, model.goal_key, model.labelling, lamp)
    assert believed.suspicion.as_dict(lamp.part_ids) == {"base_with_cables": 0.5, "light_bulb": 0.5, "shade": 0.0}
    assert len(believed.routes) == 1


def test_the_failed_model_puts_the_shade_in_the_chain(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    lamp = catalog.get("desk_lamp")
    believed = model_suspicion(model.rules, model.goal_key, model.labelling, lamp)
    assert believed.suspicion.weights == (1.0, 1.0, 1.0)


def test_on_a_new_object_the_mapping_carries_the_suspicion(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    mapping = example_mapping("far/candle_mapping_for_paper_desk_lamp.yaml", catalog)
    candle = catalog.get("candle")
    believed = model_suspicion(model.rules, model.goal_key, mapping, candle)
    assert believed.suspicion.as_dict(candle.part_ids) == {"wax": 0.5, "wick": 0.5, "match": 0.0}


def test_a_mapping_of_another_object_or_with_no_route_does_not_fit(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    with pytest.raises(MappingMismatchError, match="not for the flashlight"):
        model_suspicion(model.rules, model.goal_key, model.labelling, catalog.get("flashlight"))
    failed = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    with pytest.raises(MappingMismatchError, match="no route") as raised:
        model_suspicion(model.rules, model.goal_key, failed, catalog.get("flashlight"))
    assert raised.value.code == "mapping_does_not_fit"
    empty = Labelling("flashlight", {})
    with pytest.raises(MappingMismatchError):
        model_suspicion(model.rules, model.goal_key, empty, catalog.get("flashlight"))


def test_uniform_suspects_every_part_and_the_oracle_only_the_catalog_faults(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    assert uniform_suspicion(lamp).weights == (1.0, 1.0, 1.0)
    assert oracle_suspicion(lamp).as_dict(lamp.part_ids) == {"base_with_cables": 0.3, "light_bulb": 0.7, "shade": 0.0}
