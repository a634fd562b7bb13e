"""POST /v1/troubleshooting: the strategies' table and an episode, typed in OpenAPI, errors with codes."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from causalplan.service.api.schemas.troubleshooting import TroubleshootingRobotOut
from causalplan.service.main import create_app
from tests.service.fixtures import (
    DESK_LAMP,
    FAILED_DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    services_of,
    settings_for,
)
from tests.service.jobs.test_runner import finished


def post(client: TestClient, **body: Any) -> Any:
    return client.post("/v1/troubleshooting", json=body)


def test_the_table_is_the_cli_s_and_the_model_is_stored(client: TestClient) -> None:
    response = post(client, model=DESK_LAMP)
    assert response.status_code == 200, response.text
    data = response.json()
    assert data["status"] == "solved" and data["object"] == "desk_lamp" and data["episode"] is None
    strategies = data["strategies"]
    assert strategies["model"]["expected_actions"] < strategies["uniform"]["expected_actions"]
    assert strategies["oracle"]["expected_actions"] <= strategies["model"]["expected_actions"]
    assert set(strategies["model"]["faults"]) == {"light_bulb", "base_with_cables"}
    stored = client.get(f"/v1/models/{data['model_id']}")
    assert stored.status_code == 200


def test_a_fault_adds_the_episode_and_a_mapping_moves_to_its_object(client: TestClient) -> None:
    data = post(client, model=DESK_LAMP, mapping=FLASHLIGHT_MAPPING, fault="batteries", strategy="uniform").json()
    assert data["object"] == "flashlight"
    episode = data["episode"]
    assert episode["strategy"] == "uniform" and episode["fault"] == "batteries"
    assert episode["steps"][-1] == {"action": "test", "part": None, "observed": "goal"}
    assert episode["actions"] == len(episode["steps"]) == episode["strategies"]["uniform"]["actions"]


def test_the_failed_model_needs_more_actions_than_the_good_one(client: TestClient) -> None:
    good = post(client, model=DESK_LAMP).json()["strategies"]["model"]["expected_actions"]
    failed = post(client, model=FAILED_DESK_LAMP).json()["strategies"]["model"]["expected_actions"]
    assert failed > good


@pytest.mark.parametrize(
    ("extra", "status", "code"),
    [
        ({"fault": "lid"}, 422, "unknown_fault_part"),
        ({"fault": "shade"}, 422, "fault_not_needed"),
        ({"object": "flashlight"}, 422, "mapping_does_not_fit"),
        ({"object": "no_such_object"}, 404, "unknown_object"),
        ({"strategy": "guess"}, 422, "invalid_request"),
        ({"fault": "light_bulb", "motors": True}, 422, "invalid_request"),  # the motors drive the robot's run
    ],
)
def test_bad_input_is_an_error_with_a_code(client: TestClient, extra: dict[str, Any], status: int, code: str) -> None:
    assert error_of(post(client, model=DESK_LAMP, **extra), status)["code"] == code


def test_the_route_is_typed_in_the_openapi_document() -> None:
    document = create_app(settings_for("sqlite://")).openapi()
    operation = document["paths"]["/v1/troubleshooting"]["post"]
    assert operation["operationId"] == "create_troubleshooting"
    answer = operation["responses"]["200"]["content"]["application/json"]["schema"]
    assert answer == {"$ref": "#/components/schemas/TroubleshootingOut"}
    schemas = document["components"]["schemas"]
    assert {"TroubleshootingIn", "StrategyOut", "EpisodeOut", "FaultResultOut"} <= set(schemas)
    assert set(schemas["StrategyOut"]["required"]) >= {"expected_actions", "worst_actions", "reward_share"}
    assert "422" in operation["responses"]


def test_the_table_is_solved_by_a_worker_and_a_repeat_comes_from_the_kept_answers(client: TestClient) -> None:
    cache = services_of(client).work.cache
    body = {"model": DESK_LAMP, "fault": "light_bulb", "strategy": "oracle"}
    first = post(client, **body)
    hits = cache.stats()["hits"]
    again = post(client, **body)
    assert first.status_code == again.status_code == 200
    assert cache.stats()["hits"] == hits + 1
    assert {k: v for k, v in again.json().items() if k != "model_id"} == {
        k: v for k, v in first.json().items() if k != "model_id"
    }


@pytest.mark.parametrize(
    ("extra", "status", "code"),
    [
        ({}, 422, "invalid_request"),  # the robot carries out one episode: a fault is needed
        ({"fault": "lid"}, 422, "unknown_fault_part"),
        ({"fault": "shade"}, 422, "fault_not_needed"),
        ({"fault": "light_bulb", "object": "no_such_object"}, 404, "unknown_object"),
    ],
)
def test_a_robot_run_of_bad_input_is_refused_at_once_and_nothing_is_queued(
    client: TestClient, extra: dict[str, Any], status: int, code: str
) -> None:
    before = client.get("/v1/jobs").json()
    assert error_of(post(client, model=DESK_LAMP, robot=True, **extra), status)["code"] == code
    assert client.get("/v1/jobs").json() == before


def test_the_robot_s_run_is_typed_in_the_openapi_document() -> None:
    document = create_app(settings_for("sqlite://")).openapi()
    operation = document["paths"]["/v1/troubleshooting"]["post"]
    queued = operation["responses"]["202"]["content"]["application/json"]["schema"]
    assert queued == {"$ref": "#/components/schemas/JobOut"}
    schemas = document["components"]["schemas"]
    assert {"TroubleshootingRobotOut", "RobotEpisodeOut", "RobotActionOut", "TroubleshootingJobIn"} <= set(schemas)
    assert {"robot", "motors"} <= set(schemas["TroubleshootingIn"]["properties"])
    motors = schemas["RobotEpisodeOut"]["properties"]["motors"]
    assert {"$ref": "#/components/schemas/MotorRunOut"} in motors["anyOf"]


@pytest.mark.slow
def test_the_robot_carries_out_the_episode_as_a_job(client: TestClient) -> None:
    response = post(client, model=DESK_LAMP, fault="light_bulb", strategy="oracle", robot=True)
    assert response.status_code == 202, response.text
    job = response.json()
    assert job["kind"] == "troubleshooting" and response.headers["location"] == job["url"]
    done = finished(client, job["url"], 300.0)
    assert done["status"] == "succeeded", done
    result = done["result"]
    assert result["status"] == "repaired" and result["robot"]["produces_goal"]
    assert [a["action"] for a in result["robot"]["actions"]] == [s["action"] for s in result["episode"]["steps"]]
    TroubleshootingRobotOut.model_validate(result)


@pytest.mark.slow
def test_driven_by_its_motors_the_robot_carries_out_the_episode_as_a_job(client: TestClient) -> None:
    response = post(client, model=DESK_LAMP, fault="light_bulb", strategy="oracle", robot=True, motors=True)
    assert response.status_code == 202, response.text
    done = finished(client, response.json()["url"], 300.0)
    assert done["status"] == "succeeded", done
    result = done["result"]
    motors = result["robot"]["motors"]
    assert result["status"] == "repaired" and motors["produces_goal"] and motors["failure"] is None
    assert TroubleshootingRobotOut.model_validate(result).model_dump(mode="json")["robot"]["motors"] == motors
