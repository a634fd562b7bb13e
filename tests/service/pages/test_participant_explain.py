"""Step 2's "Why?" and "Why not…?": the participant's draft model explained in words."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.service.fixtures import error_of
from tests.service.pages.flows import LAMP_FUNCTIONS, LAMP_RULES, new_participant, post


def _at_step2(client: TestClient) -> str:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    assert client.post(f"/p/{code}/check", json={"rules": LAMP_RULES}).status_code == 200
    return code


def test_why_a_step_and_why_not_the_shade(client: TestClient) -> None:
    code = _at_step2(client)
    why = client.post(f"/p/{code}/explain", json={"object": "desk_lamp", "why": "1"})
    assert why.status_code == 200, why.text
    assert (
        "attaches the light bulb because the light bulb carries 'turn electricity into light'" in why.json()["answer"]
    )
    why_not = client.post(f"/p/{code}/explain", json={"object": "desk_lamp", "why_not": "attach the shade"}).json()
    assert why_not["code"] == "not_needed"
    assert why_not["alternative"] == [
        "Screw the light bulb into the base with cables.",
        "Clip the shade onto the base with cables.",
    ]


def test_a_question_about_a_part_the_object_lacks_is_refused(client: TestClient) -> None:
    code = _at_step2(client)
    response = client.post(f"/p/{code}/explain", json={"object": "desk_lamp", "why_not": "attach the wick"})
    assert error_of(response, 422)["code"] == "unknown_part"
    other = client.post(f"/p/{code}/explain", json={"object": "candle", "why": "1"})
    assert error_of(other, 404)["code"] == "not_found"
