"""Replay: every plan is checked step by step against the catalog, the model and the mechanism."""

from __future__ import annotations

from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.planners.replay import replay, unmet_requirements
from tests.conftest import example_mapping, example_model

BULB = ("screw", ("light_bulb", "base_with_cables", "bulb_into_socket"))
SHADE = ("clip", ("shade", "base_with_cables", "shade_onto_ring"))


def test_a_correct_plan_holds_under_model_and_mechanism(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    result = replay(task, (BULB,))
    assert result.executable and result.valid_under_model and result.valid_under_true_mechanism


def test_an_empty_plan_does_not_produce_light(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    result = replay(task, ())
    assert result.executable and not result.valid_under_model and not result.valid_under_true_mechanism
    assert result.unmet_requirements == ("the light bulb is screwed into the socket of the base",)


def test_an_order_that_a_blocking_part_forbids_fails_at_that_step(catalog: Catalog) -> None:
    task = build_task(example_model("paper/failed_desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    result = replay(task, (SHADE, BULB))
    assert not result.executable
    assert result.failure is not None and result.failure.startswith("step 2")
    assert "taken or covered" in result.failure
    assert replay(task, (BULB, SHADE)).valid_under_model


def test_a_step_that_is_not_a_fit_of_the_object_is_rejected(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    wrong_primitive = ("insert", ("light_bulb", "base_with_cables", "bulb_into_socket"))
    assert "not an assembly step" in (replay(task, (wrong_primitive,)).failure or "")
    assert "not an assembly step" in (replay(task, (("screw", ("light_bulb",)),)).failure or "")


def test_a_part_cannot_be_attached_twice_or_to_a_missing_part(catalog: Catalog) -> None:
    task = build_task(example_model("near/candle.yaml", catalog), catalog.get("candle"))
    light_first = ("ignite", ("match", "wick", "match_lights_wick"))
    assert "not in the assembly yet" in (replay(task, (light_first,)).failure or "")
    wick = ("insert", ("wick", "wax", "wick_into_wax"))
    assert "already in the assembly" in (replay(task, (wick, wick)).failure or "")


def test_model_and_mechanism_are_judged_separately(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    mapping = example_mapping("far/candle_mapping_for_paper_desk_lamp.yaml", catalog)
    task = build_task(model, catalog.get("candle"), mapping)
    result = replay(task, (("insert", ("wick", "wax", "wick_into_wax")),))
    assert result.valid_under_model and not result.valid_under_true_mechanism
    assert result.unmet_requirements == ("the wick has been lit",)


def test_unmet_requirements_accept_any_alternative(user_catalog: Catalog) -> None:
    lamp = user_catalog.get("bedside_lamp")
    assert unmet_requirements(lamp, ["cool_bulb_into_socket"]) == ()
    assert unmet_requirements(lamp, []) == ("a bulb is screwed into the socket",)
