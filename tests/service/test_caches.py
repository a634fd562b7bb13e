"""The app's caches: held by its ``Services``, empty in a new app, each hit when a request repeats."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from causalplan.service.caches import ServiceCaches
from tests.service.fixtures import DESK_LAMP, services_of, settings_for, sqlite_url, with_unique_effect
from tests.service.pages.flows import LAMP_FUNCTIONS, LAMP_RULES, new_participant, post, through_step2


def test_new_caches_are_empty_and_the_answers_sized_by_the_settings(tmp_path: Path) -> None:
    caches = ServiceCaches.of(settings_for(sqlite_url(tmp_path), cache_size=7))
    stats = caches.stats()
    assert set(stats) == {each.name for each in fields(ServiceCaches)}
    assert stats["answers"]["size"] == 7
    assert all(each["entries"] == each["hits"] == each["misses"] == 0 for each in stats.values())


def test_clear_forgets_everything_the_app_kept(client: TestClient) -> None:
    caches = services_of(client).caches
    client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
    assert caches.stats()["answers"]["entries"] >= 1
    caches.clear()
    assert all(each["entries"] == 0 for each in caches.stats().values())


def _twice(request: Callable[[], None]) -> None:
    for _ in range(2):
        request()


def _plan(client: TestClient) -> None:
    body = {"model": with_unique_effect(DESK_LAMP)}
    _twice(lambda: client.post("/v1/plans", json=body).raise_for_status())


def _model_graph(client: TestClient) -> None:
    model_id = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    _twice(lambda: client.get(f"/v1/models/{model_id}/graph").raise_for_status())


def _page_graph(client: TestClient) -> None:
    code = new_participant(client)
    through_step2(client, code)
    _twice(lambda: client.get(f"/p/{code}/graph.svg").raise_for_status())


def _part_picture(client: TestClient) -> None:
    for _ in range(2):
        assert client.get("/web/pictures/flashlight/head.png").headers["content-type"] == "image/png"


def _plan_picture(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": LAMP_RULES}).json()["plans"]
    services_of(client).caches.plan_pictures.clear()  # it may have been drawn ahead
    for _ in range(2):
        assert client.get(plan["picture_url"]).headers["content-type"] == "image/png"


def _robot_run(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": LAMP_RULES}).json()["plans"]  # computed ahead from here
    for _ in range(2):
        played = client.post(f"/p/{code}/films/playback", json={"object": "desk_lamp", "fits": plan["fits"]})
        assert played.status_code == 200 and played.json()["outcome"]["carried_out"], played.text


REPEATS: dict[str, Callable[[TestClient], None]] = {
    "answers": _plan,
    "model_graphs": _model_graph,
    "page_graphs": _page_graph,
    "part_pictures": _part_picture,
    "plan_pictures": _plan_picture,
    "robot_runs": _robot_run,
}
SLOW = {"part_pictures", "plan_pictures", "robot_runs"}  # the simulator draws them, in a worker


def test_every_cache_of_the_app_has_a_repeat_here() -> None:
    assert set(REPEATS) == {each.name for each in fields(ServiceCaches)}


@pytest.mark.parametrize(
    "name", [pytest.param(name, marks=[pytest.mark.slow] if name in SLOW else []) for name in REPEATS]
)
def test_each_cache_is_hit_when_a_request_repeats(name: str, client: TestClient) -> None:
    caches = services_of(client).caches
    before = caches.stats()[name]
    REPEATS[name](client)
    after = caches.stats()[name]
    assert after["hits"] > before["hits"] and after["entries"] > 0, (before, after)
