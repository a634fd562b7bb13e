"""GET /v1/trials and GET /v1/export, on SQLite and on a real PostgreSQL: token, paging, formats."""

from __future__ import annotations

import csv
import io
import uuid

from fastapi.testclient import TestClient

from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FAILED_DESK_LAMP,
    FAILED_FLASHLIGHT_MAPPING,
    FLASHLIGHT_MAPPING,
    error_of,
    running_client,
    settings_for,
)


def run_trials(client: TestClient, participant: str) -> list[str]:
    """Store three trials of ``participant`` (two sessions); return their ids, oldest first."""
    ids = []
    for session, model, mapping in (
        ("a", DESK_LAMP, FLASHLIGHT_MAPPING),
        ("a", FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING),
        ("b", DESK_LAMP, FLASHLIGHT_MAPPING),
    ):
        headers = {"X-Participant-Id": participant, "X-Session-Id": f"{participant}-{session}"}
        response = client.post("/v1/transfers", json={"model": model, "mapping": mapping}, headers=headers)
        assert response.status_code == 200, response.text
        ids.append(response.json()["trial_id"])
    return ids


def test_research_endpoints_need_the_token(storage_client: TestClient) -> None:
    for path in ("/v1/trials", "/v1/export"):
        error = error_of(storage_client.get(path), 401)
        assert error["code"] == "not_authenticated"
        assert storage_client.get(path).headers["www-authenticate"] == "Bearer"
        error = error_of(storage_client.get(path, headers={"Authorization": "Bearer wrong"}), 401)
        assert error["code"] == "not_authenticated"
        assert storage_client.get(path, headers=AUTH).status_code == 200


def test_trials_newest_first_with_filters_and_pages(storage_client: TestClient) -> None:
    participant = f"p-{uuid.uuid4().hex[:8]}"
    ids = run_trials(storage_client, participant)
    page = storage_client.get("/v1/trials", params={"participant_id": participant}, headers=AUTH).json()
    assert page["count"] == 3
    assert [trial["id"] for trial in page["data"]] == list(reversed(ids))
    assert [trial["verdict"] for trial in page["data"]] == ["transfers", "fails", "transfers"]
    one = storage_client.get(
        "/v1/trials", params={"participant_id": participant, "limit": 1, "offset": 1}, headers=AUTH
    ).json()
    assert one["count"] == 3 and [trial["id"] for trial in one["data"]] == [ids[1]]
    session = storage_client.get("/v1/trials", params={"session_id": f"{participant}-b"}, headers=AUTH).json()
    assert [trial["id"] for trial in session["data"]] == [ids[2]]
    for bad in ({"limit": 0}, {"limit": 1001}, {"offset": -1}):
        assert error_of(storage_client.get("/v1/trials", params=bad, headers=AUTH), 422)["code"] == "invalid_request"


def test_export_as_json_has_every_model_and_trial(storage_client: TestClient) -> None:
    participant = f"p-{uuid.uuid4().hex[:8]}"
    ids = run_trials(storage_client, participant)
    response = storage_client.get("/v1/export", headers=AUTH)
    assert response.headers["content-disposition"].startswith('attachment; filename="causalplan-')
    export = response.json()
    trials = {trial["id"]: trial for trial in export["trials"]}
    assert set(ids) <= set(trials)
    model_ids = {model["id"] for model in export["models"]}
    assert {trials[trial_id]["model_id"] for trial_id in ids} <= model_ids
    mine = [model for model in export["models"] if model["participant_id"] == participant]
    assert len(mine) == 3 and all(model["document"]["object"] == "desk_lamp" for model in mine)
    assert export["exported_at"]


def test_export_as_csv_one_table_at_a_time_and_safe_for_spreadsheets(storage_client: TestClient) -> None:
    participant = f"=p-{uuid.uuid4().hex[:8]}"  # a cell starting with '=' would be a formula
    run_trials(storage_client, participant)
    response = storage_client.get("/v1/export", params={"format": "csv"}, headers=AUTH)
    assert response.headers["content-type"] == "text/csv; charset=utf-8"
    rows = list(csv.DictReader(io.StringIO(response.text)))
    mine = [row for row in rows if row["participant_id"] == "'" + participant]
    assert len(mine) == 3
    assert mine[0]["verdict"] in ("transfers", "fails")
    assert mine[0]["mapping"].startswith("{")
    models = storage_client.get("/v1/export", params={"format": "csv", "table": "models"}, headers=AUTH).text
    header = next(csv.reader(io.StringIO(models)))
    assert header[:4] == ["id", "created_at", "participant_id", "session_id"] and "document" in header
    error = error_of(storage_client.get("/v1/export", params={"format": "xml"}, headers=AUTH), 422)
    assert error["code"] == "invalid_request"


def test_without_a_token_configured_research_is_disabled(tmp_path: object) -> None:
    assert settings_for("sqlite://", research_token="  ").research_token is None  # an empty variable
    settings = settings_for(f"sqlite:///{tmp_path}/db.sqlite3", research_token=None, planning_workers=1)
    with running_client(settings) as client:
        for headers in (AUTH, {"Authorization": "Bearer "}, {}):
            error = error_of(client.get("/v1/trials", headers=headers), 403)
            assert error["code"] == "research_disabled"
            assert "CAUSALPLAN_RESEARCH_TOKEN" in error["message"]
