"""Helpers of the web tests: define an experiment, make links, and take a participant through the pages."""

from __future__ import annotations

from typing import Any

import httpx
from fastapi.testclient import TestClient

from tests.service.fixtures import AUTH

TUTORIAL_ANSWERS = {"answer:sticker": "no", "answer:diffuse": "no", "answer:and": "and"}
TUTORIAL_RULES = (
    "store energy AND turn the axle CAUSES the axle spins\nthe axle spins AND roll on the ground CAUSES motion"
)
LAMP_FUNCTIONS = {
    "part:base_with_cables": "provide electricity",
    "part:light_bulb": "turn electricity into light\nclose the circuit",
}
LAMP_RULES = (
    "provide electricity AND close the circuit CAUSES electricity flows\n"
    "electricity flows AND turn electricity into light CAUSES light"
)
FLASHLIGHT_CHOICES: dict[str, Any] = {
    "chosen:batteries": "provide electricity",
    "chosen:head": ["turn electricity into light", "close the circuit"],
}


def experiment(client: httpx.Client, tutorial: bool = False, **fields: Any) -> dict[str, Any]:
    """Define an experiment through the API (desk lamp, then flashlight, unless ``fields`` say otherwise).

    ``client``: the tests' ``TestClient``, or an ``httpx.Client`` of a live server.
    """
    body = {
        "name": "desk lamp to flashlight",
        "tutorial": tutorial,
        "conditions": [{"name": "near", "training": ["desk_lamp"], "tests": ["flashlight"]}],
        **fields,
    }
    response = client.post("/v1/experiments", json=body, headers=AUTH)
    assert response.status_code == 201, response.text
    created: dict[str, Any] = response.json()
    return created


def links(
    client: httpx.Client, experiment_id: str, count: int = 1, condition: str | None = None
) -> list[dict[str, Any]]:
    """Make participant links through the API; return the participants."""
    response = client.post(
        f"/v1/experiments/{experiment_id}/participants", json={"count": count, "condition": condition}, headers=AUTH
    )
    assert response.status_code == 201, response.text
    made: list[dict[str, Any]] = response.json()["data"]
    return made


def new_participant(client: TestClient, tutorial: bool = False) -> str:
    """Return the code of a new participant of a new desk-lamp-to-flashlight experiment."""
    (participant,) = links(client, experiment(client, tutorial=tutorial)["id"])
    code: str = participant["code"]
    return code


def post(client: TestClient, path: str, data: dict[str, Any], status: int = 303) -> Any:
    """Post a page's form; assert the status (303: accepted, and sent on)."""
    response = client.post(path, data=data, follow_redirects=False)
    assert response.status_code == status, response.text
    return response


def through_step2(
    client: TestClient, code: str, functions: dict[str, str] | None = None, rules: str = LAMP_RULES
) -> None:
    """Do step 1 of the desk lamp and submit the rules of step 2."""
    post(client, f"/p/{code}/step1/1", functions or LAMP_FUNCTIONS)
    post(client, f"/p/{code}/step2", {"rules": rules})


def complete(client: TestClient, code: str, choices: dict[str, Any] | None = None) -> str:
    """Take a participant (after the tutorial) through steps 1-3 and finish; return the verdict page's text."""
    through_step2(client, code)
    post(client, f"/p/{code}/step3/1", choices or FLASHLIGHT_CHOICES)
    verdict = client.get(f"/p/{code}/step3/1")
    assert verdict.status_code == 200
    post(client, f"/p/{code}/step3/1/next", {})
    return str(verdict.text)


def sent_back(client: TestClient, path: str, data: dict[str, Any]) -> Any:
    """Post a form that needs another look; assert it is sent back (post/redirect/get); return the page got."""
    response = post(client, path, data)
    location = response.headers["location"]
    assert location.startswith(path + "?"), location
    page = client.get(location)
    assert page.status_code == 200, page.text
    return page
