"""GET /v1/jobs/{id}/playback: the 3D player's document of a troubleshooting job's robot run."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from causalplan.service.api.schemas.playback import EpisodePlaybackOut
from causalplan.service.main import create_app
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    KEY_AUTH,
    error_of,
    first_trials,
    running_client,
    settings_for,
    sqlite_url,
)
from tests.service.jobs.test_runner import finished

REPAIR = {"model": DESK_LAMP, "fault": "light_bulb", "strategy": "oracle", "robot": True}
"""The desk lamp's burnt-out bulb, repaired by the oracle's policy: 7 actions (docs/troubleshooting.md)."""


def queued(client: TestClient, **body: Any) -> dict[str, Any]:
    response = client.post("/v1/troubleshooting", json=body)
    assert response.status_code == 202, response.text
    job: dict[str, Any] = response.json()
    return job


@pytest.mark.slow
def test_a_finished_repair_serves_the_player_s_document_with_each_action(client: TestClient) -> None:
    job = finished(client, queued(client, **REPAIR)["url"], 300.0)
    assert job["status"] == "succeeded", job
    result = job["result"]
    described = result["playback"]
    assert described["url"] == f"/v1/jobs/{job['id']}/playback"
    assert described["content_type"] == "application/json"

    response = client.get(described["url"])
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/json"
    assert response.headers["x-content-type-options"] == "nosniff"
    assert len(response.content) == described["bytes"]
    document = EpisodePlaybackOut.model_validate(response.json())
    assert document.format == "causalplan-playback/2" and document.object == "desk_lamp"
    assert {part.id for part in document.parts} == {"base_with_cables", "light_bulb", "shade", "light_bulb:spare"}
    # Each action of the episode, in order, with what it observed: the inspection the episode's,
    # the test what physics showed.
    steps = [(step["action"], step["part"], step["observed"]) for step in result["episode"]["steps"]]
    assert [(a.action, a.part, a.observed) for a in document.actions] == steps
    assert steps[1] == ("inspect", "light_bulb", "broken") and steps[-1] == ("test", None, "goal")
    assert all(action.passed for action in document.actions)
    # When each plays: in order, within the run; a motionless action takes no time.
    starts = [action.start for action in document.actions]
    assert starts == sorted(starts) and starts[0] == 0.0
    assert document.actions[-1].end == pytest.approx(document.seconds)
    for action, robot in zip(document.actions[:-1], result["robot"]["actions"][:-1], strict=True):
        assert (action.end > action.start) == bool(robot["robot"]), action  # looking, taking a spare: no motion
    assert document.actions[-1].end > document.actions[-1].start  # the arm's way back to rest, after the test


def test_the_playback_is_typed_in_the_openapi_document() -> None:
    document = create_app(settings_for("sqlite://")).openapi()
    operation = document["paths"]["/v1/jobs/{job_id}/playback"]["get"]
    assert operation["operationId"] == "read_job_playback"
    answer = operation["responses"]["200"]["content"]["application/json"]["schema"]
    assert answer == {"$ref": "#/components/schemas/EpisodePlaybackOut"}
    assert {"404", "409"} <= set(operation["responses"])
    schemas = document["components"]["schemas"]
    assert {"PlaybackActionOut", "PlaybackFileOut", "PlaybackCommandsOut"} <= set(schemas)
    assert "playback" in schemas["TroubleshootingRobotOut"]["properties"]


@pytest.fixture(scope="module")
def answering(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """A replica that answers for jobs but runs none: a job it queues stays queued."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with running_client(settings_for(url, planning_workers=1, job_runners=0)) as running:
        yield running


def test_a_queued_repair_is_409_until_it_has_finished_then_a_cancelled_one_is_404(answering: TestClient) -> None:
    job = queued(answering, **REPAIR)
    playback = f"{job['url']}/playback"
    error = error_of(answering.get(playback), 409)
    assert error["code"] == "job_not_finished" and error["details"]["status"] == "queued"
    assert answering.delete(job["url"]).status_code == 200
    error = error_of(answering.get(playback), 404)
    assert error["code"] == "playback_not_found" and error["details"]["status"] == "cancelled"
    # A troubleshooting job's file is no film either.
    assert error_of(answering.get(f"{job['url']}/video"), 404)["code"] == "video_not_found"


@pytest.mark.parametrize(
    ("path", "status", "code"),
    [
        ("/v1/jobs/00000000-0000-0000-0000-000000000000/playback", 404, "job_not_found"),
        ("/v1/jobs/not-a-job/playback", 422, "invalid_request"),
        ("/v1/jobs/1'%20OR%201=1%20--/playback", 422, "invalid_request"),
        ("/v1/jobs/%00%2F..%2F/playback", 404, "not_found"),  # the slashes make it no route at all
    ],
)
def test_an_unknown_or_hostile_job_id_is_refused(answering: TestClient, path: str, status: int, code: str) -> None:
    assert error_of(answering.get(path), status)["code"] == code


def test_another_kind_of_job_has_no_playback(answering: TestClient) -> None:
    response = answering.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(1), "simulate": False})
    assert response.status_code == 202, response.text
    error = error_of(answering.get(f"{response.json()['url']}/playback"), 404)
    assert error["code"] == "playback_not_found" and error["details"]["kind"] == "batch"


def test_another_client_s_repair_is_not_found(answering: TestClient) -> None:
    job = queued(answering, **REPAIR)
    playback = f"{job['url']}/playback"
    assert error_of(answering.get(playback, headers=KEY_AUTH), 404)["code"] == "job_not_found"
    assert error_of(answering.get(playback, headers=AUTH), 409)["code"] == "job_not_finished"  # the operator's view
    assert answering.delete(job["url"]).status_code == 200
