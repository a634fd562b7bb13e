"""Reading the pages' forms: text the API refuses is refused here too, with the field it is in."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.service.fixtures import error_of
from tests.service.pages.flows import LAMP_FUNCTIONS, new_participant, post, sent_back

DESK_LAMP = {
    "object": "desk_lamp",
    "functions": {"base_with_cables": ["provide electricity"], "light_bulb": ["turn electricity into light"]},
    "rules": ["provide electricity AND turn electricity into light CAUSES light"],
}


def test_a_nul_is_refused_by_the_form_as_by_the_api(client: TestClient) -> None:
    code = new_participant(client)
    refused = client.post(
        f"/p/{code}/step1/1", data={**LAMP_FUNCTIONS, "part:shade": "diffuse\x00light"}, follow_redirects=False
    )
    assert refused.status_code == 422
    assert "part:shade" in refused.text and "control characters" in refused.text
    assert "\ufffd" not in client.get(f"/p/{code}/step1/1").text  # nothing was changed and kept
    api = client.post("/v1/models", json={**DESK_LAMP, "functions": {"light_bulb": ["diffuse\x00light"]}})
    assert "invalid_character" in [d["code"] for d in error_of(api, 422)["details"]["model"]["errors"]]


def test_ordinary_line_breaks_and_tabs_are_text(client: TestClient) -> None:
    code = new_participant(client)
    functions = {**LAMP_FUNCTIONS, "part:light_bulb": "turn electricity into light\r\n\tclose the circuit"}
    assert post(client, f"/p/{code}/step1/1", functions).headers["location"] == f"/p/{code}/step2"


def test_a_label_holding_a_keyword_is_noted_once_before_step_one_goes_on(client: TestClient) -> None:
    code = new_participant(client)
    functions = {**LAMP_FUNCTIONS, "part:shade": "rock and roll"}
    noted = sent_back(client, f"/p/{code}/step1/1", functions)
    assert "keyword_in_label" in noted.text and "rock and roll" in noted.text
    fingerprint = noted.text.split('name="noted" value="')[1].split('"')[0]
    changed = sent_back(
        client, f"/p/{code}/step1/1", {**functions, "part:shade": "heat causes glow", "noted": fingerprint}
    )
    assert "keyword_in_label" in changed.text  # other labels with a keyword: noted again
    again = changed.text.split('name="noted" value="')[1].split('"')[0]
    kept = post(client, f"/p/{code}/step1/1", {**functions, "part:shade": "heat causes glow", "noted": again})
    assert kept.headers["location"] == f"/p/{code}/step2"


def test_step_two_keeps_saying_which_label_no_rule_can_name(client: TestClient) -> None:
    code = new_participant(client)
    noted = sent_back(client, f"/p/{code}/step1/1", {**LAMP_FUNCTIONS, "part:shade": "rock and roll"})
    fingerprint = noted.text.split('name="noted" value="')[1].split('"')[0]
    post(client, f"/p/{code}/step1/1", {**LAMP_FUNCTIONS, "part:shade": "rock and roll", "noted": fingerprint})
    check = client.post(f"/p/{code}/check", json={"rules": "rock and roll CAUSES light"}).json()
    assert "keyword_in_label" in [warning["code"] for warning in check["warnings"]]
    assert "keyword_in_label" in client.get(f"/p/{code}/step2").text
