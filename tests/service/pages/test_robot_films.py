"""The robot on the participant pages: 'Watch the robot' films (routes.robot_films) and the robot_verdict option."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from tests.conftest import EXAMPLES
from tests.service.fixtures import AUTH, error_of, running_client, settings_for, sqlite_url, wait_until
from tests.service.pages.flows import experiment, links, new_participant, post, through_step2

pytestmark = pytest.mark.slow  # the Panda films a participant's plan


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that knows the robot examples' catalog and films small."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    settings = settings_for(
        url, catalog_folders=[EXAMPLES / "robot" / "catalog"], robot_video_width=96, robot_video_height=72
    )
    with running_client(settings) as running:
        yield running


def test_a_film_of_the_plan_is_made_in_the_background_and_then_served(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", {"part:base_with_cables": "provide electricity", "part:light_bulb": "x"})
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": "provide electricity AND x CAUSES light"}).json()["plans"]
    started = client.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": plan["fits"]})
    assert started.status_code == 200, started.text
    film = started.json()
    assert film["state"] in ("filming", "ready") and film["status_url"] == f"/p/{code}/films/{film['key']}"

    def is_done() -> bool:
        nonlocal film
        film = client.get(film["status_url"]).json()
        return film["state"] != "filming"

    wait_until(is_done, 120)
    assert film["state"] == "ready" and film["robot"]["carried_out"] is True
    assert film["expected_frames"] is None or film["frames"] <= film["expected_frames"]
    video = client.get(film["video_url"])
    assert video.headers["content-type"] == "video/mp4" and video.content[4:8] == b"ftyp"
    again = client.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": plan["fits"]}).json()
    assert again["state"] == "ready" and again["key"] == film["key"]  # kept per object and plan


def test_a_film_of_another_object_or_fit_is_refused(client: TestClient) -> None:
    code = new_participant(client)
    assert error_of(client.post(f"/p/{code}/films", json={"object": "flashlight", "fits": ["x"]}), 404)
    refused = error_of(client.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": ["nope"]}), 422)
    assert "has no fit 'nope'" in refused["message"]
    assert client.get(f"/p/{code}/films/{'0' * 32}").status_code == 404


def test_an_experiment_that_needs_the_robot_fails_a_transfer_the_robot_cannot_carry_out(client: TestClient) -> None:
    conditions = [{"name": "bench", "training": ["walled_plate"], "tests": ["long_bench"]}]
    for robot, verdict in ((False, "transfers"), (True, "fails")):
        created = experiment(client, conditions=conditions, robot_verdict=robot)
        assert created["robot_verdict"] is robot
        (participant,) = links(client, created["id"])
        code = participant["code"]
        functions = {"part:plate": "support", "part:peg": "hold"}
        through_step2(client, code, functions, "support AND hold CAUSES holding")
        post(client, f"/p/{code}/step3/1", {"chosen:bench": "support", "chosen:peg": "hold"})
        results = client.get(f"/v1/experiments/{created['id']}/export?format=json", headers=AUTH).json()
        (trial,) = results["trials"]
        assert trial["verdict"] == verdict, trial
        codes = {reason["code"] for reason in trial["reasons"]}
        assert ("robot_cannot_execute" in codes) is robot


def test_the_research_form_offers_the_robot_option(client: TestClient) -> None:
    page = client.get("/research/experiments/new", headers=AUTH)
    assert 'name="robot_verdict"' in page.text


@pytest.mark.slow
def test_the_robots_run_for_the_3d_player_has_the_motor_commands_and_the_parts_tracks(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", {"part:base_with_cables": "provide electricity", "part:light_bulb": "x"})
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": "provide electricity AND x CAUSES light"}).json()["plans"]
    answer = client.post(f"/p/{code}/films/playback", json={"object": "desk_lamp", "fits": plan["fits"]})
    assert answer.status_code == 200, answer.text
    run = answer.json()
    assert run["format"] == "causalplan-playback/2" and run["outcome"] == {"carried_out": True, "reason": None}
    commands = run["trajectory"]
    assert commands["times"][-1] == run["seconds"] and len(commands["positions"][0]) == 7
    assert len(commands["times"]) == len(commands["positions"]) == len(commands["gripper_widths"])
    assert set(run["assembled"]) == {"light_bulb"}
    (bulb,) = [part for part in run["parts"] if part["id"] == "light_bulb"]
    assert bulb["track"]["poses"][-1] == run["assembled"]["light_bulb"]
    refused = client.post(f"/p/{code}/films/playback", json={"object": "flashlight", "fits": plan["fits"]})
    assert error_of(refused, 404)["code"] == "not_found"


def test_the_players_libraries_and_the_pandas_files_are_served_and_nothing_else(client: TestClient) -> None:
    three = client.get("/web/vendor/three/build/three.module.js")
    assert three.status_code == 200 and three.headers["content-type"].startswith("text/javascript")
    assert client.get("/web/vendor/three/LICENSE").text.startswith("The MIT License")
    assert "Apache License" in client.get("/web/vendor/urdf-loader/LICENSE").text
    urdf = client.get("/web/vendor/franka_panda/panda.urdf")
    assert urdf.status_code == 200 and 'name="panda_joint7"' in urdf.text
    assert client.get("/web/vendor/franka_panda/meshes/collision/link0.obj").status_code == 200
    for path in ("franka_panda/meshes/visual/link1.obj", "franka_panda/../plane.urdf", "three/package.json", "x/y.js"):
        assert error_of(client.get(f"/web/vendor/{path}"), 404)["code"] == "not_found", path
