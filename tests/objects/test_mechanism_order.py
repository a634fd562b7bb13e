"""Each catalog object's true mechanism, checked for the order a real object imposes.

For every object, every order of its working plan's steps is replayed: an order that breaks
one of the mechanism's ``after`` (a wick lit before its fuel is there) must fail the true
mechanism, and every other order the object allows must work. Objects whose light does not
depend on order (a circuit closes whichever part goes in last) list no such pair.
"""

from __future__ import annotations

from itertools import permutations

import pytest

from causalplan.causal.documents import SourceMap
from causalplan.inputs import model_from_data
from causalplan.objects.catalog import Catalog, load_catalog
from causalplan.objects.model import AssemblyObject
from causalplan.objects.reference import reference_model
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.replay import replay

ORDERS = {
    # (earlier fit, later fit): what a real object needs
    "candle": [("wick_into_wax", "match_lights_wick")],
    "desk_lamp": [],  # the powered socket lights the bulb whenever it goes in
    "flashlight": [],  # the circuit closes with the head; the batteries must be in first anyway (blocks)
    "gas_lantern": [
        ("burner_onto_cartridge", "igniter_lights_mantle"),
        ("knob_onto_valve", "igniter_lights_mantle"),
        ("mantle_onto_nozzle", "igniter_lights_mantle"),
    ],
    "headlamp": [],  # the circuit closes with whichever of battery, switch, LED goes in last
    "kerosene_lamp": [("burner_onto_tank", "lighter_lights_wick"), ("wick_into_burner", "lighter_lights_wick")],
    "oil_lamp": [("bottle_into_filling_hole", "match_lights_wick"), ("wick_into_spout", "match_lights_wick")],
    "solar_lantern": [],  # the battery charges and the LED lights in any order
    "toy_car": [],  # the spring turns the wheels once both are in
}


@pytest.fixture(scope="module")
def builtin() -> Catalog:
    return load_catalog()


def test_every_catalog_object_has_its_order_reviewed(builtin: Catalog) -> None:
    assert sorted(builtin.objects) == sorted(ORDERS)


def reference_task(obj: AssemblyObject, catalog: Catalog) -> PlanningTask:
    loaded = model_from_data(reference_model(obj), SourceMap(), catalog)
    assert loaded.model is not None and loaded.is_valid
    return build_task(loaded.model, obj)


@pytest.mark.parametrize("object_id", sorted(ORDERS))
def test_a_plan_in_the_wrong_order_fails_the_true_mechanism_and_the_right_order_works(
    object_id: str, builtin: Catalog
) -> None:
    obj = builtin.get(object_id)
    task = reference_task(obj, builtin)
    planned = plan_task(task, "fd", val=False)
    assert planned.valid_under_true_mechanism, planned.message  # the robot's own plan works
    steps = [(step.action, (*step.args, step.fit)) for step in planned.steps]
    wrong_but_doable = 0
    for order in permutations(steps):
        made = [args[2] for _, args in order]
        in_order = all(made.index(earlier) < made.index(later) for earlier, later in ORDERS[object_id])
        checked = replay(task, tuple(order))
        if not in_order:
            assert not checked.valid_under_true_mechanism, made
            wrong_but_doable += checked.executable
        elif checked.executable:
            assert checked.valid_under_true_mechanism, (made, checked.unmet_requirements)
    # Where the parts let a robot do it in the wrong order, only the mechanism's order stops it working;
    # elsewhere the fits already forbid it (a wick is lit only once it is in the candle or the burner).
    assert (wrong_but_doable > 0) == (object_id in ("oil_lamp", "gas_lantern"))


def test_the_oil_lamp_lit_before_its_oil_says_the_order_it_needs(builtin: Catalog) -> None:
    obj = builtin.get("oil_lamp")
    lit_first = (
        ("insert", ("wick", "lamp_bowl", "wick_into_spout")),
        ("ignite", ("match", "wick", "match_lights_wick")),
        ("insert", ("oil_bottle", "lamp_bowl", "bottle_into_filling_hole")),
    )
    checked = replay(reference_task(obj, builtin), lit_first)
    assert checked.executable and checked.valid_under_model and not checked.valid_under_true_mechanism
    assert checked.unmet_requirements == (
        "the wick has been lit after the oil bottle stands in the filling hole and the wick lies in the spout",
    )


def test_the_planner_lights_the_oil_lamp_last_even_when_its_search_would_not(builtin: Catalog) -> None:
    obj = builtin.get("oil_lamp")
    planned = plan_task(reference_task(obj, builtin), "fd", val=True)
    assert [step.fit for step in planned.steps][-1] == "match_lights_wick"
    assert planned.validated_by == {"replay": "valid", "val": "valid"} and planned.valid_under_true_mechanism


def test_a_model_without_the_fuel_gets_no_fuel_from_the_order(builtin: Catalog) -> None:
    obj = builtin.get("oil_lamp")
    document = reference_model(obj)
    functions = dict(document["functions"])  # type: ignore[call-overload]
    rules = [rule.replace("provide fuel AND ", "") for rule in document["rules"]]  # type: ignore[attr-defined]
    functions.pop("oil_bottle")
    loaded = model_from_data({**document, "functions": functions, "rules": rules}, SourceMap(), builtin)
    assert loaded.model is not None and loaded.is_valid, loaded.report.as_dict()
    planned = plan_task(build_task(loaded.model, obj), "fd", val=False)
    assert "bottle_into_filling_hole" not in [step.fit for step in planned.steps]
    assert not planned.valid_under_true_mechanism
