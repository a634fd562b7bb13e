"""POST /v1/plans: plans like `causalplan plan --json`, the cache, planner and time-limit checks."""

from __future__ import annotations

import sys
import uuid
from collections.abc import Callable
from pathlib import Path
from types import FrameType
from typing import Any

import pytest
from fastapi.testclient import TestClient

import causalplan.service
from causalplan.planners import pipeline
from causalplan.planners.result import MIN_TIME_LIMIT
from causalplan.service.api.routes.plans import create_plan
from causalplan.service.api.schemas.plans import PlanIn
from causalplan.service.storage.crud import ClientIds
from tests.service.fixtures import (
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    services_of,
    sqlite_write_lock_for_a_moment,
    with_unique_effect,
)

PLAN_FIELDS = {
    "status",
    "planner_used",
    "object",
    "plan",
    "plan_length",
    "valid_under_model",
    "valid_under_true_mechanism",
    "unmet_requirements",
    "timing",
    "message",
    "planner_requested",
    "cached",
    "model_id",
    "warnings",
}


def test_an_inline_model_is_planned_replayed_and_stored(client: TestClient) -> None:
    response = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}, headers={"X-Session-Id": "s"})
    assert response.status_code == 200, response.text
    body = response.json()
    assert set(body) >= PLAN_FIELDS
    assert body["status"] == "solved"
    assert body["planner_requested"] == "auto"
    assert body["planner_used"] in pipeline.PLANNERS
    assert [step["text"] for step in body["plan"]] == ["Screw the light bulb into the base with cables."]
    assert body["plan"][0] == {
        "action": "screw",
        "args": ["light_bulb", "base_with_cables"],
        "fit": "bulb_into_socket",
        "text": "Screw the light bulb into the base with cables.",
    }
    assert body["valid_under_model"] and body["valid_under_true_mechanism"]
    assert body["cached"] is False
    assert "pddl" not in body or body["pddl"] is None
    assert body["timing"]["total"] > 0
    stored = client.get(f"/v1/models/{body['model_id']}").json()
    assert stored["session_id"] == "s" and stored["valid"] is True


def test_an_identical_request_is_answered_from_the_cache(client: TestClient) -> None:
    model = with_unique_effect(DESK_LAMP)
    first = client.post("/v1/plans", json={"model": model}).json()
    assert first["cached"] is False
    # The same model in another layout: parts, labels and rules reordered, spaces doubled.
    shuffled = {
        "rules": [rule.replace(" AND ", "  AND  ") for rule in reversed(model["rules"])],
        "functions": {part: list(reversed(labels)) for part, labels in reversed(model["functions"].items())},
        "object": "desk_lamp",
    }
    second = client.post("/v1/plans", json={"model": shuffled}).json()
    assert second["cached"] is True
    assert second["plan"] == first["plan"]
    assert second["model_id"] != first["model_id"]  # every submission is kept
    other_planner = client.post("/v1/plans", json={"model": model, "planner": "fd-opt"}).json()
    assert other_planner["cached"] is False


@pytest.mark.parametrize("mapping", [None, FLASHLIGHT_MAPPING], ids=["own object", "mapping"])
def test_a_repeated_request_gets_the_same_answer_and_a_record_of_its_own(
    client: TestClient, mapping: dict[str, Any] | None
) -> None:
    request = {"model": with_unique_effect(DESK_LAMP), "include_pddl": True} | ({"mapping": mapping} if mapping else {})
    first = client.post("/v1/plans", json=request, headers={"X-Participant-Id": "again"}).json()
    again = client.post("/v1/plans", json=request, headers={"X-Participant-Id": "again"}).json()
    assert first["cached"] is False and again["cached"] is True
    assert first["model_id"] != again["model_id"]  # every submission is kept
    assert {**again, "model_id": None, "cached": False} == {**first, "model_id": None}
    stored = client.get(f"/v1/models/{again['model_id']}").json()
    assert stored["participant_id"] == "again" and stored["model"] == request["model"]


def test_a_repeated_request_waits_for_a_locked_database_and_is_stored(client: TestClient) -> None:
    model = with_unique_effect(DESK_LAMP)
    assert client.post("/v1/plans", json={"model": model}).json()["cached"] is False
    with sqlite_write_lock_for_a_moment(str(services_of(client).engine.url)):
        response = client.post("/v1/plans", json={"model": model})
    assert response.status_code == 200 and response.json()["cached"] is True
    assert client.get(f"/v1/models/{response.json()['model_id']}").status_code == 200


def test_a_stored_model_by_id_and_a_mapping_to_another_object(client: TestClient) -> None:
    model_id = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    body = client.post("/v1/plans", json={"model_id": model_id, "mapping": FLASHLIGHT_MAPPING}).json()
    assert body["object"] == "flashlight"
    assert [step["text"] for step in body["plan"]] == [
        "Insert the batteries into the case.",
        "Screw the head onto the case.",
    ]
    assert body["model_id"] == model_id


def test_the_pddl_on_request(client: TestClient) -> None:
    body = client.post("/v1/plans", json={"model": DESK_LAMP, "include_pddl": True}).json()
    assert "(define (domain causalplan-desk_lamp)" in body["pddl"]["domain"]
    assert "(:derived" in body["pddl"]["domain"]
    assert "(define (problem" in body["pddl"]["problem"]


def test_a_model_no_part_can_satisfy_is_unsolvable_not_an_error(client: TestClient) -> None:
    model = {
        **DESK_LAMP,
        "functions": {"base_with_cables": ["provide electricity"]},
        "rules": ["provide electricity AND spark CAUSES light", "magic CAUSES spark"],
    }
    error = error_of(client.post("/v1/plans", json={"model": model}), 422)
    assert "uncaused_effect" in [d["code"] for d in error["details"]["model"]["errors"]]
    mapping = {"object": "flashlight", "functions": {"batteries": ["provide electricity"]}}
    body = client.post("/v1/plans", json={"model": DESK_LAMP, "mapping": mapping}).json()
    assert body["status"] == "unsolvable" and body["plan"] is None
    assert "no part carries" in body["message"]


def test_warnings_come_with_the_plan(client: TestClient) -> None:
    model = {**DESK_LAMP, "functions": {**DESK_LAMP["functions"], "shade": ["hold things together"]}}
    body = client.post("/v1/plans", json={"model": model}).json()
    assert body["status"] == "solved"
    assert [w["code"] for w in body["warnings"]] == ["unused_function"]


def test_invalid_models_and_mappings_are_422_with_the_cli_codes(client: TestClient) -> None:
    error = error_of(client.post("/v1/plans", json={"model": {**DESK_LAMP, "object": "desk_lam"}}), 422)
    assert error["code"] == "invalid_model"
    assert [d["code"] for d in error["details"]["model"]["errors"]] == ["unknown_object"]
    assert error["details"]["model"]["errors"][0]["hint"] == "Did you mean 'desk_lamp'?"
    mapping = {"object": "flashlight", "functions": {"bateries": ["provide electricity"]}, "rules": []}
    error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, "mapping": mapping}), 422)
    assert error["code"] == "invalid_mapping"
    codes = [d["code"] for d in error["details"]["mapping"]["errors"]]
    assert codes == ["unknown_field", "unknown_part"]
    assert error["details"]["mapping"]["errors"][1]["hint"] == "Did you mean 'batteries'?"


def test_the_request_must_name_exactly_one_model(client: TestClient) -> None:
    model_id = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    for body in ({}, {"model": DESK_LAMP, "model_id": model_id}):
        error = error_of(client.post("/v1/plans", json=body), 422)
        assert error["code"] == "invalid_request"
        assert "exactly one of 'model'" in error["message"]
    error = error_of(client.post("/v1/plans", json={"model_id": str(uuid.uuid4())}), 404)
    assert error["code"] == "model_not_found"
    error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, "colour": "red"}), 422)
    assert error["code"] == "invalid_request" and "colour" in error["message"]


def test_planner_names_come_from_the_registry(client: TestClient) -> None:
    error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, "planner": "lama"}), 422)
    assert error["code"] == "unknown_planner"
    assert "auto" in error["details"]["planners"] and "fd" in error["details"]["planners"]
    body = client.post("/v1/plans", json={"model": DESK_LAMP, "planner": "fd-opt"}).json()
    assert body["planner_used"] == "fd-opt" and body["planner_requested"] == "fd-opt"


def test_auto_means_fd_until_the_registry_has_it(client: TestClient, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(pipeline, "PLANNERS", tuple(name for name in pipeline.PLANNERS if name != "auto"))
    body = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}).json()
    assert body["planner_requested"] == "auto" and body["planner_used"] == "fd"
    assert client.get("/health").json()["default_planner"] == "fd"


def test_time_limits(client: TestClient) -> None:
    error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, "time_limit": 61}), 422)
    assert error["code"] == "time_limit_too_long"
    assert error["details"] == {"limit": 60.0, "actual": 61.0, "field": "time_limit"}
    for bad in (0, -1, "soon"):
        error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, "time_limit": bad}), 422)
        assert error["code"] == "invalid_request"
    body = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP), "time_limit": 5}).json()
    assert body["status"] == "solved"


def test_a_planner_timeout_is_an_answer_and_is_not_cached(client: TestClient) -> None:
    # A problem no other test solves: the workers keep Fast Downward's definite answers, and a
    # known answer is given at once, whatever the time limit.
    model = {
        "object": "toy_car",
        "goal": "motion",
        "functions": {"wind_up_motor": ["store energy"], "wheels": ["roll"], "sticker": ["look nice"]},
        "rules": ["store energy AND roll AND look nice CAUSES motion"],
    }
    timed_out = {"model": model, "time_limit": 0.001, "planner": "fd"}
    body = client.post("/v1/plans", json=timed_out).json()
    assert body["status"] == "timeout"
    assert "did not finish" in body["message"]
    # The very same request (same key): a kept timeout would come back cached.
    assert client.post("/v1/plans", json=timed_out).json()["cached"] is False
    again = client.post("/v1/plans", json={"model": model, "planner": "fd"}).json()
    assert again["status"] == "solved" and again["cached"] is False
    assert services_of(client).caches.answers.stats()["entries"] >= 1


def test_the_exact_mdp_at_the_smallest_time_limit_is_an_answer(client: TestClient) -> None:
    # It was a 500 once: a status the exact MDP gives was not among PlanOut's statuses.
    body = {"model": with_unique_effect(DESK_LAMP), "planner": "mdp-exact", "time_limit": MIN_TIME_LIMIT}
    response = client.post("/v1/plans", json=body)
    assert response.status_code == 200, response.text
    assert response.json()["status"] in ("solved", "timeout") and response.json()["planner_used"] == "mdp-exact"


def test_a_time_limit_below_the_minimum_is_refused_and_the_mdp_out_of_time_is_a_timeout(client: TestClient) -> None:
    for tiny in (1e-6, 5e-324):
        body = {"model": with_unique_effect(DESK_LAMP), "planner": "mdp", "time_limit": tiny}
        error = error_of(client.post("/v1/plans", json=body), 422)
        assert error["details"]["errors"][0]["location"] == "time_limit"
        assert str(MIN_TIME_LIMIT) in error["details"]["errors"][0]["message"]
    body = {"model": with_unique_effect(DESK_LAMP), "planner": "mdp", "time_limit": MIN_TIME_LIMIT}
    response = client.post("/v1/plans", json=body)
    assert response.status_code == 200, response.text
    assert response.json()["status"] in ("solved", "timeout")  # a millisecond: never 'too_large'


@pytest.mark.parametrize(
    ("field", "value"),
    [("time_limit", True), ("time_limit", "5"), ("validate", "true"), ("validate", 1), ("include_pddl", "yes")],
)
def test_numbers_and_booleans_are_not_coerced_from_other_types(client: TestClient, field: str, value: object) -> None:
    error = error_of(client.post("/v1/plans", json={"model": DESK_LAMP, field: value}), 422)
    assert error["code"] == "invalid_request" and error["details"]["errors"][0]["location"] == field


def _post_raw(client: TestClient, body: bytes) -> Any:
    return client.post("/v1/plans", content=body, headers={"Content-Type": "application/json"})


def test_a_key_twice_in_a_body_is_refused_with_the_key_and_its_line(client: TestClient) -> None:
    body = b'{"model": {\n  "object": "desk_lamp",\n  "object": "candle",\n  "functions": {}, "rules": []}}'
    error = error_of(_post_raw(client, body), 422)
    assert error["code"] == "invalid_json"
    assert '"object"' in error["message"] and "twice" in error["message"]
    assert error["details"]["line"] == 3 and error["details"]["column"] == 3


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (b"[" * 100_000, "nested more than 16 levels"),
        (b'{"time_limit": ' + b"9" * 5000 + b"}", "5000 digits"),
        (b'{"time_limit": NaN}', "NaN is not a JSON value"),
        (b'{"model": "\xff"}', "not UTF-8"),
        (b'{"model" 1}', "expecting ':'"),
    ],
    ids=["deep", "long integer", "NaN", "not UTF-8", "malformed"],
)
def test_a_body_that_is_not_readable_json_says_what_is_wrong(client: TestClient, body: bytes, words: str) -> None:
    error = error_of(_post_raw(client, body), 422)
    assert error["code"] == "invalid_json"
    assert words in error["message"], error["message"]
    assert "UTF-8" not in error["message"] or words == "not UTF-8"


def test_a_wrong_method_names_every_method_of_the_path(client: TestClient) -> None:
    response = client.put("/v1/experiments")
    assert error_of(response, 405)["code"] == "method_not_allowed"
    assert response.headers["Allow"] == "GET, POST"


def test_a_trailing_slash_on_an_api_path_is_a_404_that_names_the_path(client: TestClient) -> None:
    response = client.get("/v1/objects/", follow_redirects=False)
    error = error_of(response, 404)
    assert "/v1/objects" in error["message"]
    assert client.get("/v1/objects").status_code == 200


def test_val_checks_the_plan_by_default_as_in_the_cli_and_validate_false_skips_it(client: TestClient) -> None:
    checked = client.post("/v1/plans", json={"model": DESK_LAMP})
    plain = client.post("/v1/plans", json={"model": DESK_LAMP, "validate": False})
    assert plain.status_code == checked.status_code == 200, checked.text
    assert checked.json()["validated_by"] == {"replay": "valid", "val": "valid"}  # `causalplan plan --json`'s
    assert plain.json()["validated_by"] == {"replay": "valid"}  # `causalplan plan --no-val --json`'s


SERVICE = Path(causalplan.service.__file__).parent
WORK_LAYER = SERVICE / "work"


def service_files_before_the_work_layer(call: Callable[[], object]) -> tuple[list[str], bool]:
    """Return the service files whose functions ``call`` runs before it first enters the work layer, in order,
    and whether it entered it (a trace of this thread with ``sys.setprofile``)."""
    entered: list[str] = []
    reached = False

    def profile(frame: FrameType, event: str, _: object) -> None:
        nonlocal reached
        path = Path(frame.f_code.co_filename)
        if event != "call" or reached or not path.is_relative_to(SERVICE):
            return
        if path.is_relative_to(WORK_LAYER):
            reached = True
        elif (name := path.relative_to(SERVICE).as_posix()) not in entered:
            entered.append(name)

    sys.setprofile(profile)
    try:
        call()
    finally:
        sys.setprofile(None)
    return entered, reached


def test_a_plan_request_reaches_the_work_layer_through_two_service_files(client: TestClient) -> None:
    # The route and the reading of its documents, then the work layer: three service files before planning.
    services = services_of(client)
    body = PlanIn.model_validate({"model": with_unique_effect(DESK_LAMP)})
    files, reached = service_files_before_the_work_layer(lambda: create_plan(body, services, ClientIds()))
    assert reached and files == ["api/routes/plans.py", "documents.py"]
