"""POST /v1/simulations with ``robot``: the robot's report, its film, and what it cannot do."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from fastapi.testclient import TestClient

from causalplan.service.films import FilmStore
from tests.conftest import EXAMPLES
from tests.service_fixtures import DESK_LAMP, error_of, running_client, settings_for, sqlite_url

pytestmark = pytest.mark.slow  # the Panda films its plans through the service

SMALL = {"robot_video_width": 96, "robot_video_height": 72}
"""A small film keeps the tests quick; the robot's run is the same at any size."""


@pytest.fixture(scope="module")
def robot_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that also knows the robot examples' catalog (the walled plate the robot cannot build)."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    settings = settings_for(url, catalog_folders=[EXAMPLES / "robot" / "catalog"], **SMALL)
    with running_client(settings) as running:
        yield running


def _walled_plate() -> dict[str, object]:
    document: dict[str, object] = yaml.safe_load(Path(EXAMPLES / "robot" / "walled_plate.yaml").read_text())
    return document


def test_the_robot_builds_the_desk_lamp_and_its_mp4_can_be_fetched(robot_client: TestClient) -> None:
    body = {"model": DESK_LAMP, "robot": True, "video": "mp4"}
    response = robot_client.post("/v1/simulations", json=body)
    assert response.status_code == 200, response.text
    answer = response.json()
    assert answer["robot"] == {"carried_out": True, "reason": None}
    assert answer["simulation"]["produces_goal"] is True
    assert all("grasp" in step["robot"] for step in answer["simulation"]["steps"])
    video = answer["video"]
    assert video["content_type"] == "video/mp4" and video["url"] == f"/v1/simulations/videos/{video['key']}"
    film = robot_client.get(video["url"])
    assert film.status_code == 200 and film.headers["content-type"] == "video/mp4"
    assert film.content[4:8] == b"ftyp" and len(film.content) == video["bytes"]
    again = robot_client.post("/v1/simulations", json=body).json()
    assert again["cached"] is True and again["video"]["key"] == video["key"]


def test_a_gif_is_served_as_a_gif(robot_client: TestClient) -> None:
    answer = robot_client.post("/v1/simulations", json={"model": DESK_LAMP, "robot": True, "video": "gif"}).json()
    film = robot_client.get(answer["video"]["url"])
    assert film.headers["content-type"] == "image/gif" and film.content[:6] == b"GIF89a"


def test_a_plan_the_robot_cannot_carry_out_names_the_step_and_the_code(robot_client: TestClient) -> None:
    answer = robot_client.post("/v1/simulations", json={"model": _walled_plate(), "robot": True}).json()
    reason = answer["robot"]["reason"]
    assert answer["robot"]["carried_out"] is False and answer["video"] is None
    assert reason["code"] == "robot_cannot_execute"
    assert reason["step"] == 1 and reason["failure"] == "no_collision_free_path"


def test_a_video_without_the_robot_is_refused(robot_client: TestClient) -> None:
    response = robot_client.post("/v1/simulations", json={"model": DESK_LAMP, "video": "mp4"})
    assert "needs 'robot'" in str(error_of(response, 422))


def test_an_unknown_or_malformed_video_key_is_a_404_or_422(robot_client: TestClient) -> None:
    assert error_of(robot_client.get("/v1/simulations/videos/" + "0" * 32), 404)["code"] == "video_not_found"
    assert robot_client.get("/v1/simulations/videos/../../etc").status_code in (404, 422)


def test_the_store_lets_the_least_used_films_go_when_full() -> None:
    store = FilmStore(max_bytes=8000)  # two films of 2000 bytes and their records
    store.put("a", "mp4", b"x" * 2000)
    store.put("b", "mp4", b"x" * 2000)
    store.get("a")  # used: b is now the least used
    store.put("c", "mp4", b"x" * 2000)
    assert store.has("a") and store.has("c") and not store.has("b")
    assert store.put("huge", "gif", b"x" * 7000).state == "failed"


def test_openapi_documents_the_robot_and_the_video_route(robot_client: TestClient) -> None:
    schema = robot_client.get("/openapi.json").json()
    assert "/v1/simulations/videos/{key}" in schema["paths"]
    fields = schema["components"]["schemas"]["SimulationIn"]["properties"]
    assert {"robot", "video"} <= set(fields)
