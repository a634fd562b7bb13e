"""The participant pages and their JSON endpoints, through FastAPI's TestClient (SQLite)."""

from __future__ import annotations

import re

import pytest
from fastapi.testclient import TestClient

from tests.service.fixtures import error_of
from tests.service.pages.flows import (
    FLASHLIGHT_CHOICES,
    LAMP_FUNCTIONS,
    LAMP_RULES,
    TUTORIAL_ANSWERS,
    TUTORIAL_RULES,
    complete,
    new_participant,
    post,
    sent_back,
    through_step2,
)

XSS = "<script>alert(1)</script>"


def test_the_start_page_makes_a_demo_participant_who_begins_with_the_tutorial(client: TestClient) -> None:
    start = client.get("/")
    assert start.status_code == 200 and start.headers["content-type"].startswith("text/html")
    assert 'action="/try"' in start.text
    made = client.post("/try", follow_redirects=False)
    assert made.status_code == 303
    code = made.headers["location"].removeprefix("/p/")
    assert re.fullmatch(r"[A-Za-z0-9]{22}", code)
    assert client.get(f"/p/{code}", follow_redirects=False).headers["location"] == f"/p/{code}/tutorial"
    page = client.get(f"/p/{code}/tutorial")
    assert "wind-up toy car" in page.text and "hold things together" in page.text
    # A participant's page: strict content policy, never cached, its address (a secret) never sent on.
    assert page.headers["referrer-policy"] == "no-referrer"
    assert page.headers["cache-control"] == "no-store"
    assert "script-src 'self'" in page.headers["content-security-policy"]
    assert "<script>" not in page.text.replace('<script src="/web/static/participant.js" defer></script>', "")


def test_an_unknown_link_is_a_page_for_people_and_json_for_scripts(client: TestClient) -> None:
    for code in ("A" * 22, "not a code", "x"):
        page = client.get(f"/p/{code}/step2")
        assert page.status_code == 404 and page.headers["content-type"].startswith("text/html")
        assert "This participant link is not valid" in page.text
    error = error_of(client.post(f"/p/{'A' * 22}/check", json={"rules": ""}), 404)
    assert error["code"] == "participant_not_found"


def test_the_tutorial_explains_wrong_answers_and_needs_valid_practice_rules(client: TestClient) -> None:
    code = new_participant(client, tutorial=True)
    wrong = sent_back(client, f"/p/{code}/tutorial", {**TUTORIAL_ANSWERS, "answer:diffuse": "yes", "rules": ""})
    assert "Not quite. Diffusing light changes light that is already there" in wrong.text
    assert "Write rules for the toy car that produce motion" in wrong.text
    check = client.post(f"/p/{code}/check", json={"rules": TUTORIAL_RULES, "practice": True}).json()
    assert check["valid"] and [w["code"] for w in check["warnings"]] == ["unused_function", "unused_function"]
    assert check["graph_url"].startswith(f"/p/{code}/graph.svg?practice=1&v=")
    graph = client.get(check["graph_url"])
    assert graph.headers["content-type"] == "image/svg+xml" and ">motion</text>" in graph.text
    moved = post(client, f"/p/{code}/tutorial", {**TUTORIAL_ANSWERS, "rules": TUTORIAL_RULES})
    assert moved.headers["location"] == f"/p/{code}/step1/1"
    # The tutorial is behind them now: its page sends them on, its endpoints refuse.
    assert client.get(f"/p/{code}/tutorial", follow_redirects=False).headers["location"] == f"/p/{code}/step1/1"
    assert error_of(client.post(f"/p/{code}/check", json={"rules": "", "practice": True}), 409)["code"] == "step_locked"


def test_work_is_saved_as_typed_and_shown_again(client: TestClient) -> None:
    code = new_participant(client)
    saved = client.post(
        f"/p/{code}/draft",
        json={"step": "step1", "object": "desk_lamp", "functions": {"shade": f"diffuse light\n{XSS}"}},
    )
    assert saved.status_code == 200 and saved.json()["saved"]
    page = client.get(f"/p/{code}/step1/1")
    assert "diffuse light\n&lt;script&gt;alert(1)&lt;/script&gt;</textarea>" in page.text
    assert XSS not in page.text
    unknown = client.post(f"/p/{code}/draft", json={"step": "step1", "object": "desk_lamp", "functions": {"wick": "x"}})
    assert error_of(unknown, 422)["message"] == "The desk lamp has no part 'wick'."
    other = client.post(f"/p/{code}/draft", json={"step": "step1", "object": "candle", "functions": {}})
    assert error_of(other, 409)["code"] == "step_locked"
    early = client.post(f"/p/{code}/draft", json={"step": "step3", "object": "flashlight", "mapping": {}})
    assert error_of(early, 409)["code"] == "step_locked"
    assert error_of(client.post(f"/p/{code}/draft", json={"step": "step9"}), 422)["code"] == "invalid_request"
    # Pages ahead of the participant send them back to where they are.
    assert client.get(f"/p/{code}/step2", follow_redirects=False).headers["location"] == f"/p/{code}/step1/1"


def test_step_one_needs_a_function(client: TestClient) -> None:
    code = new_participant(client)
    empty = sent_back(client, f"/p/{code}/step1/1", {"part:shade": "  "})
    assert "No part of the desk lamp has a function yet." in empty.text
    assert post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS).headers["location"] == f"/p/{code}/step2"


def test_labels_are_shown_as_text_on_every_page(client: TestClient) -> None:
    code = new_participant(client)
    functions = {**LAMP_FUNCTIONS, "part:shade": XSS}
    post(client, f"/p/{code}/step1/1", functions)
    step2 = client.get(f"/p/{code}/step2")
    refused = sent_back(client, f"/p/{code}/step2", {"rules": f"{XSS} AND <b>nothing</b> CAUSES light"})
    for page in (step2, refused):
        assert XSS not in page.text
        assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page.text
    assert "&#39;&lt;b&gt;nothing&lt;/b&gt;&#39;" in refused.text  # in the problem's message
    post(client, f"/p/{code}/step2", {"rules": f"{LAMP_RULES}\n{XSS} CAUSES light"})
    step3 = client.get(f"/p/{code}/step3/1")
    assert XSS not in step3.text
    assert 'value="&lt;script&gt;alert(1)&lt;/script&gt;"' in step3.text  # a checkbox of the model's functions
    graph = client.get(f"/p/{code}/graph.svg")
    assert "<script" not in graph.text and "&lt;script&gt;" in graph.text
    assert graph.headers["content-security-policy"].startswith("default-src 'none'")


def test_an_invalid_model_is_checked_as_typed_and_cannot_be_submitted(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    typed = "provide electricity AND close the circuit CAUSES electricity flows\n\nelectricity flow CAUSES light"
    check = client.post(f"/p/{code}/check", json={"rules": typed}).json()
    assert not check["valid"]
    (problem,) = check["errors"]
    assert problem["code"] == "unknown_cause" and problem["line"] == 3
    assert problem["message"] == (
        "Rule 2 uses 'electricity flow', which is neither a function of a part nor the effect of another rule."
    )
    assert problem["hint"] == "Did you mean 'electricity flows'?"
    plan = client.post(f"/p/{code}/plan", json={"rules": typed})
    assert error_of(plan, 422)["code"] == "invalid_model"
    blocked = sent_back(client, f"/p/{code}/step2", {"rules": typed})
    assert "Problem (line 3):" in blocked.text and "disabled" in blocked.text
    assert client.get(f"/p/{code}", follow_redirects=False).headers["location"] == f"/p/{code}/step2"
    assert "electricity flow CAUSES light</textarea>" in client.get(f"/p/{code}/step2").text  # kept for fixing


@pytest.mark.slow
def test_the_robot_plan_is_shown_with_the_simulator_picture(client: TestClient) -> None:
    code = new_participant(client)
    post(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    (plan,) = client.post(f"/p/{code}/plan", json={"rules": LAMP_RULES}).json()["plans"]
    assert plan["steps"] == ["Screw the light bulb into the base with cables."] and plan["works"]
    picture = client.get(plan["picture_url"])
    assert picture.status_code == 200 and picture.content.startswith(b"\x89PNG")
    assert error_of(client.get(f"/p/{code}/pictures/desk_lamp.png?fits=nothing"), 422)["code"] == "invalid_request"
    assert error_of(client.get(f"/p/{code}/pictures/candle.png?fits=wick_into_wax"), 404)["code"] == "not_found"


def test_step_three_cannot_change_the_model_and_records_one_trial(client: TestClient) -> None:
    code = new_participant(client)
    through_step2(client, code)
    assert client.get(f"/p/{code}/step1/1", follow_redirects=False).headers["location"] == f"/p/{code}/step3/1"
    for locked in (
        client.post(f"/p/{code}/check", json={"rules": "x CAUSES light"}),
        client.post(f"/p/{code}/draft", json={"step": "step1", "object": "desk_lamp", "functions": {}}),
    ):
        assert error_of(locked, 409)["code"] == "step_locked"
    page = post(client, f"/p/{code}/step2", {"rules": "x CAUSES light"}, 409)
    assert page.headers["content-type"].startswith("text/html") and "cannot change once step 3" in page.text
    assert 'textarea id="rules"' not in client.get(f"/p/{code}/step3/1").text

    foreign = post(client, f"/p/{code}/step3/1", {"chosen:head": "shine brightly"}, 422)
    assert "is not a function of your model" in foreign.text
    assert "No part has a function yet." in sent_back(client, f"/p/{code}/step3/1", {}).text
    saved = client.post(
        f"/p/{code}/draft",
        json={"step": "step3", "object": "flashlight", "mapping": {"head": {"chosen": ["close the circuit"]}}},
    )
    assert saved.status_code == 200
    assert 'value="close the circuit" checked' in client.get(f"/p/{code}/step3/1").text

    post(client, f"/p/{code}/step3/1", FLASHLIGHT_CHOICES)
    result = client.get(f"/p/{code}/step3/1").text
    assert "Your model works for the flashlight." in result and "Insert the batteries into the case." in result
    again = post(client, f"/p/{code}/step3/1", {"chosen:head": "close the circuit"})  # a second click
    assert again.headers["location"] == f"/p/{code}/step3/1"
    late = client.post(f"/p/{code}/draft", json={"step": "step3", "object": "flashlight", "mapping": {}})
    assert error_of(late, 409)["code"] == "step_locked"
    done = post(client, f"/p/{code}/step3/1/next", {})
    assert done.headers["location"] == f"/p/{code}/done"
    assert "The flashlight: your model works." in client.get(f"/p/{code}/done").text


def test_a_hidden_verdict_is_recorded_but_not_shown(client: TestClient) -> None:
    from tests.service.pages.flows import experiment, links

    (participant,) = links(client, experiment(client, show_verdict=False)["id"])
    text = complete(client, participant["code"])
    assert "your answer for the flashlight is recorded" in text and "works for the flashlight" not in text


def test_the_pages_scripts_styles_and_pictures_are_served(client: TestClient) -> None:
    css = client.get("/web/static/app.css")
    assert css.status_code == 200 and css.headers["content-type"].startswith("text/css")
    script = client.get("/web/static/participant.js")
    assert script.headers["content-type"].startswith("text/javascript") and "textContent" in script.text
    for name in ("nothing.js", "..%2Fstudy.py", "app.css.map"):
        assert client.get(f"/web/static/{name}").status_code == 404
    part = client.get("/web/pictures/flashlight/head.png")
    assert part.status_code == 200 and part.headers["content-type"] in ("image/png", "image/svg+xml")
    assert error_of(client.get("/web/pictures/flashlight/bulb.png"), 404)["message"].startswith("The flashlight has no")
    assert error_of(client.get("/web/pictures/lantern/head.png"), 404)["code"] == "unknown_object"


def test_the_web_pages_stay_out_of_the_api_document(client: TestClient) -> None:
    paths = client.get("/openapi.json").json()["paths"]
    assert not [path for path in paths if path.startswith(("/p/", "/research", "/web"))]
    assert "/v1/experiments/{experiment_id}/export" in paths
