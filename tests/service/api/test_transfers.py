"""POST /v1/transfers: verdicts like `causalplan transfer --json`, each trial stored."""

from __future__ import annotations

from fastapi.testclient import TestClient

from causalplan.service.api.schemas.common import ReportOut
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FAILED_DESK_LAMP,
    FAILED_FLASHLIGHT_MAPPING,
    FLASHLIGHT_MAPPING,
    error_of,
    with_unique_effect,
)
from tests.service.pages.flows import experiment, links

VERDICT_FIELDS = {
    "verdict",
    "training_object",
    "test_object",
    "generalization",
    "decided_by",
    "reasons",
    "plan",
    "planning",
    "diagnostics",
    "planner_requested",
    "cached",
    "trial_id",
    "model_id",
}


def trials_of(client: TestClient, participant: str) -> list[dict[str, object]]:
    data: list[dict[str, object]] = client.get(
        "/v1/trials", params={"participant_id": participant}, headers=AUTH
    ).json()["data"]
    return data


def test_the_paper_model_transfers_to_the_flashlight(client: TestClient) -> None:
    response = client.post(
        "/v1/transfers",
        json={"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING},
        headers={"X-Participant-Id": "transfer-1"},
    )
    assert response.status_code == 200, response.text
    body = response.json()
    assert set(body) >= VERDICT_FIELDS
    assert (body["verdict"], body["generalization"], body["decided_by"]) == ("transfers", "near", "planner")
    assert [step["text"] for step in body["plan"]] == [
        "Insert the batteries into the case.",
        "Screw the head onto the case.",
    ]
    assert body["planning"]["status"] == "solved"
    [trial] = trials_of(client, "transfer-1")
    assert trial["id"] == body["trial_id"] and trial["model_id"] == body["model_id"]
    assert trial["verdict"] == "transfers" and trial["test_object"] == "flashlight"
    assert trial["mapping"] == FLASHLIGHT_MAPPING
    assert trial["result"]["plan"] == body["plan"]  # type: ignore[index]


def test_the_failed_model_fails_for_the_papers_two_reasons(client: TestClient) -> None:
    body = client.post("/v1/transfers", json={"model": FAILED_DESK_LAMP, "mapping": FAILED_FLASHLIGHT_MAPPING}).json()
    assert (body["verdict"], body["decided_by"]) == ("fails", "precheck")
    reasons = {(reason["code"], reason["severity"]) for reason in body["reasons"]}
    assert reasons == {("missing_function", "error"), ("unmodelled_function", "warning")}
    assert body["diagnostics"] == {}  # valid inputs: their reports come with an invalid trial's 422


def test_a_repeated_trial_is_cached_and_stored_again(client: TestClient) -> None:
    model = with_unique_effect(DESK_LAMP)
    headers = {"X-Participant-Id": "transfer-cache"}
    first = client.post("/v1/transfers", json={"model": model, "mapping": FLASHLIGHT_MAPPING}, headers=headers).json()
    second = client.post("/v1/transfers", json={"model": model, "mapping": FLASHLIGHT_MAPPING}, headers=headers).json()
    assert (first["cached"], second["cached"]) == (False, True)
    assert second["plan"] == first["plan"] and second["trial_id"] != first["trial_id"]
    cached_flags = sorted(trial["cached"] for trial in trials_of(client, "transfer-cache"))  # type: ignore[type-var]
    assert cached_flags == [False, True]


def test_a_repeated_trial_gets_the_same_verdict_and_records_of_its_own(client: TestClient) -> None:
    request = {"model": with_unique_effect(DESK_LAMP), "mapping": FLASHLIGHT_MAPPING}
    headers = {"X-Participant-Id": "transfer-again"}
    first = client.post("/v1/transfers", json=request, headers=headers).json()
    again = client.post("/v1/transfers", json=request, headers=headers).json()
    assert first["cached"] is False and again["cached"] is True
    ids = {"model_id": None, "trial_id": None}
    assert {**again, **ids, "cached": False} == {**first, **ids}
    trials = trials_of(client, "transfer-again")
    assert len(trials) == 2 and len({trial["model_id"] for trial in trials}) == 2  # each with its own model record
    stored = next(trial for trial in trials if trial["id"] == again["trial_id"])
    assert stored["cached"] is True and stored["model_id"] == again["model_id"]
    assert stored["mapping"] == FLASHLIGHT_MAPPING and stored["verdict"] == again["verdict"]
    assert client.get(f"/v1/models/{again['model_id']}").json()["model"] == request["model"]


def test_a_stored_model_by_id(client: TestClient) -> None:
    model_id = client.post("/v1/models", json=DESK_LAMP).json()["id"]
    body = client.post("/v1/transfers", json={"model_id": model_id, "mapping": FLASHLIGHT_MAPPING}).json()
    assert body["verdict"] == "transfers" and body["model_id"] == model_id


def test_an_invalid_trial_is_422_and_is_stored_as_invalid(client: TestClient) -> None:
    mapping = {"object": "flashlight", "functions": {"head": ["turn electricity into light"], "lens": ["focus"]}}
    headers = {"X-Participant-Id": "transfer-invalid"}
    response = client.post("/v1/transfers", json={"model": DESK_LAMP, "mapping": mapping}, headers=headers)
    error = error_of(response, 422)
    assert error["code"] == "invalid_mapping"
    assert error["details"]["verdict"]["verdict"] == "invalid"
    assert [reason["code"] for reason in error["details"]["verdict"]["reasons"]] == ["invalid_mapping"]
    assert [d["code"] for d in error["details"]["mapping"]["errors"]] == ["unknown_part"]
    for report in error["details"]["verdict"]["diagnostics"].values():  # what TransferOut.diagnostics declares
        assert ReportOut.model_validate(report).model_dump(mode="json", exclude_unset=True) == report
    [trial] = trials_of(client, "transfer-invalid")
    assert trial["id"] == error["details"]["trial_id"] and trial["verdict"] == "invalid"

    bad_model = {**DESK_LAMP, "rules": ["provide electricity CAUSES"]}
    error = error_of(client.post("/v1/transfers", json={"model": bad_model, "mapping": FLASHLIGHT_MAPPING}), 422)
    assert error["code"] == "invalid_model"
    assert error["details"]["verdict"]["decided_by"] == "validation"


def test_a_mapping_is_required(client: TestClient) -> None:
    error = error_of(client.post("/v1/transfers", json={"model": DESK_LAMP}), 422)
    assert error["code"] == "invalid_request" and "mapping" in error["message"]


def test_unknown_planner_and_too_long_time_limit(client: TestClient) -> None:
    body = {"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING}
    assert error_of(client.post("/v1/transfers", json={**body, "planner": "x"}), 422)["code"] == "unknown_planner"
    error = error_of(client.post("/v1/transfers", json={**body, "time_limit": 1000}), 422)
    assert error["code"] == "time_limit_too_long"


def test_a_study_participants_id_cannot_be_claimed_by_an_anonymous_client(client: TestClient) -> None:
    (participant,) = links(client, experiment(client)["id"])
    body = {"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING}
    forged = client.post("/v1/transfers", json=body, headers={"X-Participant-Id": participant["id"]})
    assert error_of(forged, 403)["code"] == "participant_id_reserved"
    page_session = f"experiment:{participant['id']}"
    assert error_of(client.post("/v1/transfers", json=body, headers={"X-Session-Id": page_session}), 403)
    assert error_of(client.post("/v1/models", json=DESK_LAMP, headers={"X-Participant-Id": participant["id"]}), 403)
    assert trials_of(client, participant["id"]) == []
    exported = client.get("/v1/export", headers=AUTH).json()
    assert participant["id"] not in {trial["participant_id"] for trial in exported["trials"]}
