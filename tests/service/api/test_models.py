"""POST /v1/models, GET /v1/models/{id} and its graph; validation with the CLI's codes; limits."""

from __future__ import annotations

import json
import uuid
from collections.abc import Iterator
from datetime import timedelta
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import update
from sqlalchemy.orm import Session

from causalplan.service.pages.upkeep import purge
from causalplan.service.storage.records import ModelRecord, utc_now
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FAILED_DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
)

MODELS_PER_MINUTE = 3
INVALID = {**DESK_LAMP, "rules": ["light CAUSES"]}


@pytest.fixture(scope="module")
def limited(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that stores ``MODELS_PER_MINUTE`` models a minute per client."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with running_client(settings_for(url, models_per_minute=MODELS_PER_MINUTE, planning_workers=1)) as running:
        yield running


def test_a_valid_model_is_stored_with_its_report_and_links(client: TestClient) -> None:
    response = client.post("/v1/models", json=DESK_LAMP, headers={"X-Participant-Id": "p-7", "X-Session-Id": "s-1"})
    assert response.status_code == 201, response.text
    body = response.json()
    assert body["valid"] is True
    assert body["report"] == {"valid": True, "errors": [], "warnings": []}
    assert body["object"] == "desk_lamp"
    assert body["participant_id"] == "p-7" and body["session_id"] == "s-1"
    assert body["model"] == DESK_LAMP
    assert response.headers["Location"] == body["links"]["self"] == f"/v1/models/{body['id']}"
    assert body["created_at"].endswith("Z")
    fetched = client.get(body["links"]["self"])
    assert fetched.status_code == 200
    assert fetched.json() == body


def test_warnings_do_not_make_a_model_invalid(client: TestClient) -> None:
    response = client.post("/v1/models", json=FAILED_DESK_LAMP)
    assert response.status_code == 201
    assert response.json()["valid"] is True
    assert response.json()["report"]["warnings"] == []
    with_unused = {**DESK_LAMP, "functions": {**DESK_LAMP["functions"], "shade": ["hold things together"]}}
    warnings = client.post("/v1/models", json=with_unused).json()["report"]["warnings"]
    assert [w["code"] for w in warnings] == ["unused_function"]


def test_an_invalid_model_is_422_with_the_cli_codes_and_still_kept(client: TestClient) -> None:
    model = {**DESK_LAMP, "rules": ["provide electricity AND close the circut CAUSES light", "light CAUSES"]}
    error = error_of(client.post("/v1/models", json=model), 422)
    assert error["code"] == "invalid_model"
    codes = [d["code"] for d in error["details"]["model"]["errors"]]
    assert codes == ["rule_without_effect", "unknown_cause"]
    assert error["details"]["model"]["errors"][1]["hint"] == "Did you mean 'close the circuit'?"
    assert error["details"]["model"]["errors"][1]["location"] == {"rule": 1}
    kept = client.get(f"/v1/models/{error['details']['model_id']}").json()
    assert kept["valid"] is False
    assert [d["code"] for d in kept["report"]["errors"]] == codes


def test_document_problems_get_the_cli_codes(client: TestClient) -> None:
    cases: list[tuple[dict[str, Any], str]] = [
        ({**DESK_LAMP, "colour": "red"}, "unknown_field"),
        ({"object": "desk_lamp", "functions": {}}, "missing_field"),
        ({**DESK_LAMP, "object": "desk_lmap"}, "unknown_object"),
        ({**DESK_LAMP, "functions": {"bulb": ["x"]}}, "unknown_part"),
        ({**DESK_LAMP, "rules": 5}, "invalid_type"),
        ({**DESK_LAMP, "rules": ["a CAUSES b CAUSES light"]}, "multiple_causes_keywords"),
        ({**DESK_LAMP, "rules": ["provide electricity light"]}, "missing_causes_keyword"),
        ({**DESK_LAMP, "functions": {"light_bulb": [""]}}, "empty_label"),
        ({**DESK_LAMP, "functions": {"light_bulb": ["a\u0007b"]}}, "invalid_character"),
    ]
    for model, code in cases:
        error = error_of(client.post("/v1/models", json=model), 422)
        assert error["code"] == "invalid_model"
        assert code in [d["code"] for d in error["details"]["model"]["errors"]], (code, error)


def test_a_cycle_is_named(client: TestClient) -> None:
    model = {
        **DESK_LAMP,
        "rules": [*DESK_LAMP["rules"], "light CAUSES heat", "heat CAUSES electricity flows"],
    }
    error = error_of(client.post("/v1/models", json=model), 422)
    cycle = [d for d in error["details"]["model"]["errors"] if d["code"] == "cycle"]
    assert len(cycle) == 1
    assert cycle[0]["message"].startswith("The rules go round in a circle: ")
    assert set(cycle[0]["message"].split(": ")[1].rstrip(".").split(" → ")) == {"electricity flows", "light", "heat"}


def test_a_body_that_is_not_a_model_is_422(client: TestClient) -> None:
    error = error_of(client.post("/v1/models", json=["object", "desk_lamp"]), 422)
    assert error["code"] == "invalid_request"
    error = error_of(client.post("/v1/models", content=b"{not json", headers={"Content-Type": "application/json"}), 422)
    assert error["code"] == "invalid_json"
    error = error_of(
        client.post("/v1/models", content=b'{"object": NaN}', headers={"Content-Type": "application/json"}), 422
    )
    assert error["code"] == "invalid_json" and "NaN" in error["message"]  # read as JSON by the body's reader
    deep: Any = "x"
    for _ in range(40):
        deep = {"a": deep}
    error = error_of(client.post("/v1/models", json={**DESK_LAMP, "goal": deep}), 422)
    assert error["code"] == "invalid_json" and "nested" in error["message"]


def test_limits_each_have_a_clear_error(client: TestClient) -> None:
    long_label = "x" * 201
    cases: list[tuple[dict[str, Any], str, str]] = [
        ({**DESK_LAMP, "functions": {f"part_{i}": ["x"] for i in range(65)}}, "too_many_parts", "65 parts"),
        ({**DESK_LAMP, "functions": {"light_bulb": [f"f{i}" for i in range(17)]}}, "too_many_labels", "17"),
        ({**DESK_LAMP, "functions": {"light_bulb": [long_label]}}, "label_too_long", "201 characters"),
        ({**DESK_LAMP, "goal": long_label}, "label_too_long", "goal"),
        ({**DESK_LAMP, "rules": ["a CAUSES light"] * 201}, "too_many_rules", "201 rules"),
        ({**DESK_LAMP, "rules": ["a " * 401 + "CAUSES light"]}, "label_too_long", "Rule 1"),
    ]
    for model, code, words in cases:
        error = error_of(client.post("/v1/models", json=model), 422)
        assert error["code"] == code
        assert words in error["message"]
        assert error["details"]["limit"] < error["details"]["actual"]


def test_a_body_over_the_size_limit_is_413(client: TestClient) -> None:
    big = {**DESK_LAMP, "goal": "x" * 300_000}
    error = error_of(client.post("/v1/models", json=big), 413)
    assert error["code"] == "body_too_large"
    assert error["details"]["limit"] == 262_144

    def chunks() -> Any:  # no Content-Length: the limit holds while the body streams in
        for _ in range(40):
            yield b" " * 10_000

    error = error_of(client.post("/v1/models", content=chunks(), headers={"Content-Type": "application/json"}), 413)
    assert error["code"] == "body_too_large"


def test_client_ids_over_128_characters_are_refused(client: TestClient) -> None:
    error = error_of(client.post("/v1/models", json=DESK_LAMP, headers={"X-Participant-Id": "p" * 129}), 422)
    assert error["code"] == "invalid_request"
    assert "x-participant-id" in error["message"]


def test_unknown_and_malformed_model_ids(client: TestClient) -> None:
    missing = uuid.uuid4()
    error = error_of(client.get(f"/v1/models/{missing}"), 404)
    assert error["code"] == "model_not_found" and str(missing) in error["message"]
    error = error_of(client.get(f"/v1/models/{missing}/graph"), 404)
    assert error["code"] == "model_not_found"
    error = error_of(client.get("/v1/models/not-a-uuid"), 422)
    assert error["code"] == "invalid_request"


def test_the_graph_as_svg_dot_and_json(client: TestClient) -> None:
    model_id = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    svg = client.get(f"/v1/models/{model_id}/graph")
    assert svg.status_code == 200
    assert svg.headers["content-type"] == "image/svg+xml"
    assert svg.headers["content-security-policy"].startswith("default-src 'none'")
    assert svg.text.lstrip().startswith("<?xml") and "<svg" in svg.text
    for text in (
        ">turn electricity",
        ">into light",
        ">electricity flows",
        ">close the circuit",
        ">(light bulb)",
        ">AND",
    ):
        assert text in svg.text  # labels are text (wrapped), not paths
    dot = client.get(f"/v1/models/{model_id}/graph", params={"format": "dot"})
    assert dot.headers["content-type"].startswith("text/vnd.graphviz")
    assert "rankdir=LR" in dot.text and '"n:electricity flows" -> "r:2"' in dot.text
    graph = client.get(f"/v1/models/{model_id}/graph", params={"format": "json"}).json()
    columns = {node["id"]: node["column"] for node in graph["nodes"]}
    assert columns["n:provide electricity"] == 0 < columns["n:electricity flows"] < columns["n:light"]
    assert {"source": "r:2", "target": "n:light"} in graph["edges"]
    error = error_of(client.get(f"/v1/models/{model_id}/graph", params={"format": "png"}), 422)
    assert error["code"] == "invalid_request"


def test_an_invalid_model_is_drawn_too(client: TestClient) -> None:
    model = {**DESK_LAMP, "rules": ["provide electricity AND magic CAUSES light"]}
    model_id = client.post("/v1/models", json=model).json()["error"]["details"]["model_id"]
    graph = client.get(f"/v1/models/{model_id}/graph", params={"format": "json"}).json()
    assert {"id": "n:magic", "label": "magic", "kind": "unknown", "column": 0} in graph["nodes"]
    assert client.get(f"/v1/models/{model_id}/graph").status_code == 200


def test_text_that_utf8_cannot_hold_is_stored_and_echoed_safely(client: TestClient) -> None:
    body = json.dumps({**DESK_LAMP, "functions": {"light_bulb": ["bad SURROGATE label", "nul NUL label"]}})
    body = body.replace("SURROGATE", "\\ud800").replace("NUL", "\\u0000")  # JSON escapes, as a client sends them
    response = client.post("/v1/models", content=body.encode(), headers={"Content-Type": "application/json"})
    error = error_of(response, 422)
    assert [d["code"] for d in error["details"]["model"]["errors"]][:2] == ["invalid_character", "invalid_character"]
    kept = client.get(f"/v1/models/{error['details']['model_id']}").json()
    assert kept["model"]["functions"]["light_bulb"] == ["bad \ufffd label", "nul \ufffd label"]


def test_one_client_storing_models_too_often_is_told_to_wait(limited: TestClient) -> None:
    for _ in range(MODELS_PER_MINUTE):
        assert limited.post("/v1/models", json=INVALID).status_code == 422
    refused = limited.post("/v1/models", json=INVALID)
    error = error_of(refused, 429)
    assert error["code"] == "too_many_models" and int(refused.headers["retry-after"]) >= 1


def test_invalid_models_expire_unless_a_trial_uses_them(client: TestClient) -> None:
    alone = error_of(client.post("/v1/models", json=INVALID), 422)["details"]["model_id"]
    valid = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    tried = error_of(client.post("/v1/transfers", json={"model": INVALID, "mapping": FLASHLIGHT_MAPPING}), 422)
    trials = client.get("/v1/export", headers=AUTH).json()["trials"]
    (used,) = [trial["model_id"] for trial in trials if trial["id"] == tried["details"]["trial_id"]]
    services = services_of(client)
    with Session(services.engine) as session:
        old = utc_now() - timedelta(hours=services.settings.invalid_model_hours, minutes=1)
        session.execute(update(ModelRecord).values(created_at=old))
        session.commit()
    purge(services)
    assert client.get(f"/v1/models/{alone}").status_code == 404
    assert client.get(f"/v1/models/{valid}").status_code == 200
    assert client.get(f"/v1/models/{used}").status_code == 200  # its trial is a study's data
