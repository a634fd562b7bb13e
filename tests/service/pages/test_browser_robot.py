"""The robot's 3D player in a real browser: it rests while paused, and plays on the research page too."""

from __future__ import annotations

import json
from collections.abc import Iterator

import httpx
import pytest
from playwright.sync_api import Page, expect

from tests.conftest import builtin_catalog
from tests.service.fixtures import AUTH, serving, settings_for, sqlite_url
from tests.service.pages.browsing import PLAYER, lamp_plan_shown, shoot, signed_in
from tests.service.pages.flows import FLASHLIGHT_CHOICES, complete, experiment, links

pytestmark = pytest.mark.slow  # a real Chromium plays the robot's run


@pytest.fixture(scope="module")
def robot_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with serving(settings_for(url)) as base:
        yield base


def test_the_paused_player_draws_a_frame_only_when_something_changes(robot_server: str, page: Page) -> None:
    lamp_plan_shown(page, robot_server)
    page.get_by_role("button", name="Watch the robot").click()
    expect(page.locator(".robot-player canvas")).to_have_count(1, timeout=60_000)
    page.wait_for_function(f"() => {PLAYER}.state().frames > 2")
    page.get_by_role("button", name="Pause").click()
    page.wait_for_timeout(200)  # the frame under way when the button was pressed
    paused = page.evaluate(f"{PLAYER}.state()")
    page.wait_for_timeout(1000)  # some 60 frames' time
    assert page.evaluate(f"{PLAYER}.state().frames") == paused["frames"]
    page.evaluate(f"{PLAYER}.seek(1.0)")  # a new time is drawn once
    page.wait_for_function(f"() => {PLAYER}.state().frames === {paused['frames'] + 1}")
    page.wait_for_timeout(300)
    assert page.evaluate(f"{PLAYER}.state()")["frames"] == paused["frames"] + 1
    page.get_by_role("button", name="Play").click()  # and playing draws again
    page.wait_for_function(f"() => {PLAYER}.state().time > 1.2 && {PLAYER}.state().frames > {paused['frames'] + 3}")


def finished_participant(base: str) -> str:
    """Return the experiment id of a desk-lamp-to-flashlight study whose one participant's model transfers."""
    with httpx.Client(base_url=base, timeout=120) as client:
        study = experiment(client)
        (participant,) = links(client, study["id"])
        complete(client, participant["code"], FLASHLIGHT_CHOICES)  # type: ignore[arg-type]  # posts as a TestClient does
        trials = client.get(f"/v1/experiments/{study['id']}/export?format=json", headers=AUTH).json()["trials"]
        assert [trial["verdict"] for trial in trials] == ["transfers"], trials
        experiment_id: str = study["id"]
        return experiment_id


def test_the_researcher_watches_the_robot_carry_out_a_trials_plan(robot_server: str, page: Page) -> None:
    experiment_id = finished_participant(robot_server)
    signed_in(page, robot_server)
    page.goto(f"{robot_server}/research/experiments/{experiment_id}#trials")
    trial = page.locator("#trials details.trial")
    trial.locator("summary").click()
    trial.get_by_role("button", name="Watch the robot").click()
    canvas = trial.locator(".robot-player canvas")
    expect(canvas).to_have_count(1, timeout=60_000)
    player = "document.querySelector('#trials .robot-player').player"
    page.wait_for_function(f"() => {player}.state().frames > 2")
    first = page.evaluate(f"{player}.state().time")
    before = canvas.screenshot()
    page.wait_for_function(f"() => {player}.state().time > {first} + 1", timeout=30_000)
    assert canvas.screenshot() != before  # the arm has moved on the canvas

    fits = trial.locator(".robot-film").get_attribute("data-fits")
    assert fits is not None
    run = page.request.post(f"{robot_server}/research/playback", data={"object": "flashlight", "fits": fits_of(fits)})
    assert run.ok, run.text()
    assembled = run.json()["assembled"]
    page.evaluate(f"{player}.seek({player}.state().seconds - 0.5); {player}.play()")
    page.wait_for_function(f"() => !{player}.state().playing", timeout=30_000)
    state = page.evaluate(f"{player}.state()")
    assert state["time"] == state["seconds"] == run.json()["seconds"]
    assert set(assembled) == {"head", "batteries"}  # the model needs both, fitted into the case
    for part, pose in assembled.items():
        assert max(abs(a - b) for a, b in zip(state["parts"][part], pose, strict=True)) < 1e-4, part
    shoot(page, "research-2-watch-the-robot")


def fits_of(attribute: str) -> list[str]:
    """Return the fits a trial's player holds (its ``data-fits``: a JSON list)."""
    fits = json.loads(attribute)
    assert isinstance(fits, list) and all(isinstance(fit, str) for fit in fits), attribute
    return fits


def test_the_research_playback_needs_the_research_token_and_the_objects_fits(robot_server: str) -> None:
    body = {"object": "flashlight", "fits": [builtin_catalog().get("flashlight").fits[0].id]}
    with httpx.Client(base_url=robot_server, timeout=60) as client:
        refused = client.post("/research/playback", json=body)
        assert refused.status_code == 401, refused.text
        unknown = client.post("/research/playback", json={**body, "object": "no_such"}, headers=AUTH)
        assert unknown.status_code == 404, unknown.text
        wrong = client.post("/research/playback", json={**body, "fits": ["nope"]}, headers=AUTH)
        assert wrong.status_code == 422 and "has no fit 'nope'" in wrong.json()["error"]["message"]
