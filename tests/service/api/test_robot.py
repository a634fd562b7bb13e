"""POST /v1/simulations with ``robot``: a job (202) whose result is the robot's report and film.

A robot run is long work: it runs in the jobs' workers, so a plan request is answered by an
interactive worker while every job worker is busy filming.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from fastapi.testclient import TestClient

from causalplan.service.api.schemas.simulations import MotorRunOut
from tests.conftest import EXAMPLES
from tests.service.fixtures import (
    DESK_LAMP,
    error_of,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    wait_until,
    with_unique_effect,
)
from tests.service.jobs.test_runner import finished

pytestmark = pytest.mark.slow  # the Panda films its plans through the service

SMALL = {"robot_video_width": 96, "robot_video_height": 72}
"""A small film keeps the tests quick; the robot's run is the same at any size."""


@pytest.fixture(scope="module")
def robot_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that also knows the robot examples' catalog (the walled plate the robot cannot build)."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    settings = settings_for(url, catalog_folders=[EXAMPLES / "robot" / "catalog"], job_poll_seconds=0.05, **SMALL)
    with running_client(settings) as running:
        yield running


def _walled_plate() -> dict[str, object]:
    document: dict[str, object] = yaml.safe_load(Path(EXAMPLES / "robot" / "walled_plate.yaml").read_text())
    return document


def _queued(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    """Post a robot simulation; return the job it was answered with (202, its URL in Location)."""
    response = client.post("/v1/simulations", json=body)
    assert response.status_code == 202, response.text
    job: dict[str, Any] = response.json()
    assert response.headers["location"] == job["url"] == f"/v1/jobs/{job['id']}"
    assert job["status"] == "queued" and job["result"] is None
    return job


@pytest.mark.slow
def test_the_robot_builds_the_desk_lamp_as_a_job_and_its_mp4_can_be_fetched(robot_client: TestClient) -> None:
    job = _queued(robot_client, {"model": DESK_LAMP, "robot": True, "video": "mp4"})
    assert job["kind"] == "video"
    done = finished(robot_client, job["url"], 300.0)
    assert done["status"] == "succeeded", done
    answer = done["result"]
    assert answer["robot"] == {"carried_out": True, "reason": None}
    assert answer["simulation"]["produces_goal"] is True
    assert all("grasp" in step["robot"] for step in answer["simulation"]["steps"])
    video = answer["video"]
    assert video["content_type"] == "video/mp4" and video["url"] == f"{job['url']}/video"
    film = robot_client.get(video["url"])
    assert film.status_code == 200 and film.headers["content-type"] == "video/mp4"
    assert film.content[4:8] == b"ftyp" and len(film.content) == video["bytes"]


@pytest.mark.slow
def test_a_robot_job_is_driven_by_the_motors_unless_asked_not_to(robot_client: TestClient) -> None:
    driven = finished(robot_client, _queued(robot_client, {"model": DESK_LAMP, "robot": True})["url"], 300.0)
    answer = driven["result"]
    assert answer["robot"] == {"carried_out": True, "reason": None}
    motors = answer["simulation"]["robot"]["motors"]  # as `causalplan simulate --robot` reports them
    assert motors["failure"] is None and motors["grasp_slipped"] is False
    assert motors["tracking"]["max_joint_error_rad"] <= motors["tracking"]["tolerance_rad"]
    assert MotorRunOut.model_validate(motors).model_dump(mode="json") == motors  # the schema declares every key
    body = {"model": DESK_LAMP, "robot": True, "motors": False}
    kinematic = finished(robot_client, _queued(robot_client, body)["url"], 300.0)["result"]
    assert kinematic["robot"]["carried_out"] is True and "motors" not in kinematic["simulation"]["robot"]


@pytest.mark.slow
def test_a_plan_the_robot_cannot_carry_out_names_the_step_and_the_code(robot_client: TestClient) -> None:
    job = _queued(robot_client, {"model": _walled_plate(), "robot": True})
    assert job["kind"] == "simulation"
    answer = finished(robot_client, job["url"], 300.0)["result"]
    reason = answer["robot"]["reason"]
    assert answer["robot"]["carried_out"] is False
    assert reason["code"] == "robot_cannot_execute"
    assert reason["step"] == 1 and reason["failure"] == "no_collision_free_path"


def test_a_video_without_the_robot_is_refused(robot_client: TestClient) -> None:
    response = robot_client.post("/v1/simulations", json={"model": DESK_LAMP, "video": "mp4"})
    assert "needs 'robot'" in str(error_of(response, 422))


def test_a_robot_run_of_a_model_that_cannot_be_read_is_refused_and_nothing_is_queued(
    robot_client: TestClient,
) -> None:
    before = robot_client.get("/health").json()["jobs"]
    broken = {**DESK_LAMP, "rules": ["provide electricity light"]}
    for video in ("gif", None):
        response = robot_client.post("/v1/simulations", json={"model": broken, "robot": True, "video": video})
        assert "missing_causes_keyword" in str(error_of(response, 422))
    assert robot_client.get("/health").json()["jobs"] == before


def test_openapi_documents_the_robot_run_as_a_job(robot_client: TestClient) -> None:
    schema = robot_client.get("/openapi.json").json()
    assert "/v1/simulations/videos/{key}" not in schema["paths"]
    answers = schema["paths"]["/v1/simulations"]["post"]["responses"]
    assert answers["202"]["content"]["application/json"]["schema"] == {"$ref": "#/components/schemas/JobOut"}
    fields = schema["components"]["schemas"]["SimulationIn"]["properties"]
    assert {"robot", "video"} <= set(fields)


@pytest.mark.slow
def test_a_plan_is_answered_by_an_interactive_worker_while_films_hold_every_job_worker(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=1, job_poll_seconds=0.05)
    with running_client(settings) as client:
        services = services_of(client)
        films = [_queued(client, {"model": DESK_LAMP, "robot": True, "video": "mp4"}) for _ in range(3)]
        filming = films[0]["url"]
        # The film is being drawn in the one job worker (frames expected are known), the others wait.
        wait_until(lambda: client.get(filming).json()["progress"]["total"] > 1, 240.0)
        assert services.job_pool.stats().busy == 1 == services.job_pool.size
        answered_before = services.pool.stats().completed
        plan = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
        assert plan.status_code == 200, plan.text
        assert plan.json()["status"] == "solved" and plan.json()["cached"] is False
        # Answered while the long work still runs, by the interactive pool, not the job's worker.
        assert client.get(filming).json()["status"] == "running"
        assert [client.get(film["url"]).json()["status"] for film in films[1:]] == ["queued", "queued"]
        assert services.pool.stats().completed == answered_before + 1
        assert services.job_pool.stats().busy == 1
        for film in films:
            assert client.delete(film["url"]).json()["status"] == "cancelled"
