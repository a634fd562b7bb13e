"""Plans drawn ahead: the part sets of an object, the model needing each, and their pictures kept before anyone asks."""

from __future__ import annotations

import threading

import pytest
from fastapi.testclient import TestClient

from causalplan.causal.graph import goal_holds
from causalplan.service.pages import ahead
from causalplan.service.pages.drawings import is_plan_picture_kept
from tests.conftest import builtin_catalog
from tests.service.fixtures import services_of
from tests.service.pages.flows import LAMP_FUNCTIONS, LAMP_RULES, new_participant, post


def test_part_sets_are_largest_first_and_bounded() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    sets = list(ahead.part_sets(lamp))
    assert [len(parts) for parts in sets] == [3, 2, 2, 2]
    assert sets[0] == lamp.part_ids
    kerosene = builtin_catalog().get("kerosene_lamp")
    assert len(list(ahead.part_sets(kerosene))) == min(
        ahead.MAX_PART_SETS, 2 ** len(kerosene.part_ids) - 1 - len(kerosene.part_ids)
    )


def test_the_model_of_a_part_set_needs_exactly_those_parts() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    model = ahead.needing(lamp, ("light_bulb", "base_with_cables"))
    assert model.goal == lamp.goal and len(model.rules) == 1
    carried = model.labelling.carriers()
    assert sorted(part for parts in carried.values() for part in parts) == ["base_with_cables", "light_bulb"]
    functions = set(carried)
    assert goal_holds(functions, model.rules, model.goal_key)
    assert not any(goal_holds(functions - {key}, model.rules, model.goal_key) for key in functions)


@pytest.mark.slow
def test_drawn_ahead_the_participants_plan_picture_is_kept_before_they_ask(client: TestClient) -> None:
    services = services_of(client)
    lamp = services.catalog.get("desk_lamp")
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": LAMP_RULES}).json()["plans"]
    fits = tuple(str(plan["picture_url"]).split("fits=")[1].split(","))
    services.caches.plan_pictures.clear()
    assert not is_plan_picture_kept(services, lamp, fits)
    assert ahead.draw_ahead(services, [lamp], threading.Event()) >= 1
    assert is_plan_picture_kept(services, lamp, fits)
    assert client.get(plan["picture_url"]).headers["content-type"] == "image/png"


def test_a_stopped_drawing_draws_nothing(client: TestClient) -> None:
    stop = threading.Event()
    stop.set()
    assert ahead.draw_ahead(services_of(client), [builtin_catalog().get("candle")], stop) == 0
