"""Experiments on SQLite and on a real PostgreSQL: the API, the research pages, results and exports."""

from __future__ import annotations

import csv
import io
import json
import uuid
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import func, inspect, select
from sqlalchemy.orm import Session

from causalplan.service.api.schemas.experiments import ExperimentExportOut
from causalplan.service.storage.migrate import current_revision, head_revision, upgrade
from causalplan.service.storage.records import ParticipantTrialRecord, TrialRecord
from causalplan.service.storage.session import create_database_engine
from tests.service.fixtures import AUTH, RESEARCH_TOKEN, error_of, running_client, services_of, settings_for
from tests.service.pages.flows import complete, experiment, links

NEAR_AND_FAR: dict[str, Any] = {
    "name": "Near and far",
    "conditions": [
        {"name": "near", "training": ["desk_lamp", "flashlight"], "tests": ["candle", "kerosene_lamp"]},
        {"name": "far", "training": ["desk_lamp", "candle"], "tests": ["flashlight", "kerosene_lamp"]},
    ],
}


def test_the_migration_adds_the_experiment_tables(database_url: str) -> None:
    engine = create_database_engine(database_url)
    try:
        assert upgrade(engine) == head_revision() == "0011" == current_revision(engine)
        tables = set(inspect(engine).get_table_names())
        assert {"experiments", "participants", "participant_trials"} <= tables
        unique = inspect(engine).get_unique_constraints("participant_trials")
        assert {"uq_participant_trials_test_object", "uq_participant_trials_trial_id"} <= {u["name"] for u in unique}
    finally:
        engine.dispose()


def test_an_experiment_is_defined_and_its_links_are_counterbalanced(storage_client: TestClient) -> None:
    created = experiment(storage_client, **NEAR_AND_FAR)
    assert created["conditions"][1]["training"] == ["desk_lamp", "candle"]
    assert created["counterbalance_training"] and created["show_verdict"] and created["participants"] == 0
    made = links(storage_client, created["id"], count=4)
    assert [p["condition"] for p in made] == ["near", "far", "near", "far"]  # spread evenly
    assert [p["ordinal"] for p in made] == [0, 0, 1, 1]
    near = [p for p in made if p["condition"] == "near"]
    assert [p["training_order"] for p in near] == [["desk_lamp", "flashlight"], ["flashlight", "desk_lamp"]]
    assert {p["stage"] for p in made} == {"step1"} and {p["progress"] for p in made} == {"step 1, object 1 of 2"}
    assert len({p["code"] for p in made}) == 4
    assert made[0]["url"] == f"http://testserver/p/{made[0]['code']}"
    more = links(storage_client, created["id"], count=2, condition="far")
    assert [(p["condition"], p["ordinal"]) for p in more] == [("far", 2), ("far", 3)]
    assert [p["test_order"] for p in more] == [["kerosene_lamp", "flashlight"], ["kerosene_lamp", "flashlight"]]
    listed = storage_client.get("/v1/experiments", headers=AUTH).json()
    assert {"id": created["id"], "participants": 6}.items() <= next(
        e for e in listed if e["id"] == created["id"]
    ).items()


def test_definitions_and_link_requests_are_checked(storage_client: TestClient) -> None:
    bad = storage_client.post(
        "/v1/experiments",
        headers=AUTH,
        json={"name": "x", "conditions": [{"name": "near", "training": ["desk_lamp"], "tests": ["torch"]}]},
    )
    error = error_of(bad, 422)
    assert error["code"] == "invalid_experiment"
    assert error["details"]["errors"] == [
        "Condition 'near': there is no object 'torch' in the catalog. Known objects: candle, desk_lamp, "
        "flashlight, gas_lantern, headlamp, kerosene_lamp, oil_lamp, solar_lantern, toy_car."
    ]
    shape = storage_client.post("/v1/experiments", headers=AUTH, json={"name": "x", "conditions": []})
    assert error_of(shape, 422)["details"]["errors"] == [
        "The experiment has no condition; add at least one (e.g. 'near')."
    ]
    unknown = storage_client.post("/v1/experiments", headers=AUTH, json={"name": "x", "template": "near_only"})
    assert error_of(unknown, 422)["code"] == "invalid_request"
    assert error_of(storage_client.post("/v1/experiments", json=NEAR_AND_FAR), 401)["code"] == "not_authenticated"
    created = experiment(storage_client)
    wrong = storage_client.post(
        f"/v1/experiments/{created['id']}/participants", headers=AUTH, json={"count": 1, "condition": "far"}
    )
    assert error_of(wrong, 422)["message"] == "The experiment has no condition 'far'; its conditions are: near."
    too_many = storage_client.post(f"/v1/experiments/{created['id']}/participants", headers=AUTH, json={"count": 501})
    assert error_of(too_many, 422)["code"] == "invalid_request"
    missing = storage_client.get(f"/v1/experiments/{uuid.uuid4()}/results", headers=AUTH)
    assert error_of(missing, 404)["code"] == "experiment_not_found"
    # Strict JSON types: no 0 for a boolean, no "5" for a number.
    for loose in ({**NEAR_AND_FAR, "tutorial": 0}, {**NEAR_AND_FAR, "show_verdict": "true"}):
        assert error_of(storage_client.post("/v1/experiments", headers=AUTH, json=loose), 422)["code"] == (
            "invalid_request"
        )
    links_url = f"/v1/experiments/{created['id']}/participants"
    assert error_of(storage_client.post(links_url, headers=AUTH, json={"count": "5"}), 422)["code"] == "invalid_request"
    recruitment_url = f"/v1/experiments/{created['id']}/recruitment"
    for loose_recruitment in ({"too_fast_seconds": "5"}, {"require_platform_id": 1}, {"quotas": {"near": "3"}}):
        refused = storage_client.put(recruitment_url, headers=AUTH, json=loose_recruitment)
        assert error_of(refused, 422)["code"] == "invalid_request", loose_recruitment
    assert storage_client.post(links_url, headers=AUTH, json={"count": 1}).status_code == 201


def test_results_and_exports_hold_every_trial_with_its_model_mapping_and_reasons(storage_client: TestClient) -> None:
    created = experiment(storage_client)
    first, second, _ = links(storage_client, created["id"], count=3)
    assert "Your model works for the flashlight." in complete(storage_client, first["code"])
    failing = {"chosen:batteries": "provide electricity", "added:case": "=hold things together"}
    assert "Your model does not work for the flashlight." in complete(storage_client, second["code"], failing)

    results = storage_client.get(f"/v1/experiments/{created['id']}/results", headers=AUTH).json()
    assert results["rates"] == [
        {
            "condition": "near",
            "training_span": "one category",
            "test_object": "flashlight",
            "generalization": "near",
            "trials": 2,
            "transfers": 1,
            "fails": 1,
            "undecided": 0,
            "excluded": 0,
            "rate": 0.5,
            "interval": pytest.approx([0.0945, 0.9055], abs=1e-4),
        }
    ]
    assert results["rates_problem"] is None
    assert [p["progress"] for p in results["participants"]] == ["finished", "finished", "step 1, object 1 of 1"]
    works, fails = results["trials"]
    assert works["verdict"] == "transfers" and works["plan"] == [
        "Insert the batteries into the case.",
        "Screw the head onto the case.",
    ]
    assert fails["mapping"] == {
        "object": "flashlight",
        "functions": {"case": ["=hold things together"], "batteries": ["provide electricity"]},
    }
    assert [r["code"] for r in fails["reasons"]] == ["missing_function", "missing_function", "unmodelled_function"]
    assert fails["model"]["rules"][1] == "electricity flows AND turn electricity into light CAUSES light"
    page = storage_client.get(f"/research/experiments/{created['id']}", headers=AUTH).text
    # "Watch the robot" for the trial with a plan only: its test object and fits, for research.js's player.
    assert page.count('class="watch-robot"') == 1 and '<script type="module" src="/web/static/research.js">' in page
    assert """data-object="flashlight" data-fits='["batteries_into_bay", "head_onto_case"]'""" in page

    exported = storage_client.get(f"/v1/experiments/{created['id']}/export", headers=AUTH)
    assert exported.headers["content-disposition"].startswith('attachment; filename="causalplan-experiment-')
    data = exported.json()
    assert data["experiment"]["design"]["conditions"][0]["tests"] == ["flashlight"]
    assert [t["trial_id"] for t in data["trials"]] == [works["trial_id"], fails["trial_id"]]
    assert data["trials"][1]["result"]["decided_by"] == "precheck"
    assert data["participants"][0]["work"]["rules"].startswith("provide electricity AND close the circuit")
    assert data["rates"] == results["rates"]
    ExperimentExportOut.model_validate(data)
    empty = experiment(storage_client)
    nothing = storage_client.get(f"/v1/experiments/{empty['id']}/export", headers=AUTH).json()
    assert (nothing["trials"], nothing["rates"]) == ([], [])
    ExperimentExportOut.model_validate(nothing)  # every required field, rates too
    table = storage_client.get(f"/v1/experiments/{created['id']}/export?format=csv", headers=AUTH)
    rows = list(csv.DictReader(io.StringIO(table.text)))
    assert [row["verdict"] for row in rows] == ["transfers", "fails"]
    assert json.loads(rows[1]["mapping"]) == fails["mapping"]
    people = storage_client.get(
        f"/v1/experiments/{created['id']}/export?format=csv&table=participants", headers=AUTH
    ).text
    assert [row["progress"] for row in csv.DictReader(io.StringIO(people))][2] == "step 1, object 1 of 1"

    # The service's own tables have them too: the trials under the participant's id.
    trials = storage_client.get(f"/v1/trials?participant_id={first['id']}", headers=AUTH).json()
    assert trials["count"] == 1 and trials["data"][0]["session_id"] == f"experiment:{created['id']}"
    engine = services_of(storage_client).engine
    with Session(engine) as session:
        linked = session.scalar(
            select(func.count())
            .select_from(ParticipantTrialRecord)
            .join(TrialRecord, ParticipantTrialRecord.trial_id == TrialRecord.id)
            .where(TrialRecord.id.in_([uuid.UUID(works["trial_id"]), uuid.UUID(fails["trial_id"])]))
        )
    assert linked == 2


@pytest.mark.slow
def test_the_research_pages_need_the_token_as_a_cookie_or_a_bearer(storage_client: TestClient) -> None:
    storage_client.cookies.clear()
    away = storage_client.get("/research/experiments/new", follow_redirects=False)
    assert away.status_code == 303 and away.headers["location"] == "/research/login?next=/research/experiments/new"
    assert storage_client.get("/research", headers=AUTH).status_code == 200
    refused = storage_client.post("/research/login", data={"token": "guess", "next": "/research"})
    assert refused.status_code == 401 and "That is not the research token." in refused.text
    signed_in = storage_client.post(
        "/research/login", data={"token": RESEARCH_TOKEN, "next": "//evil.example/research"}, follow_redirects=False
    )
    assert signed_in.headers["location"] == "/research"  # never to another site
    cookie = signed_in.headers["set-cookie"]
    assert "HttpOnly" in cookie and "SameSite=strict" in cookie and "Path=/research" in cookie
    assert RESEARCH_TOKEN not in cookie

    form = {
        "name": "Form <i>study</i>",
        "condition:0:name": "near",
        "condition:0:training:0": "candle",
        "condition:0:training:1": "",
        "condition:0:tests": "kerosene_lamp",
        "counterbalance_tests": "1",
        "show_verdict": "1",
    }
    cross_site = storage_client.post(
        "/research/experiments", data=form, headers={"Origin": "https://evil.example"}, follow_redirects=False
    )
    assert cross_site.status_code == 403 and "sent from another site" in cross_site.text
    made = storage_client.post(
        "/research/experiments", data=form, headers={"Origin": "http://testserver"}, follow_redirects=False
    )
    assert made.status_code == 303
    page = storage_client.get(made.headers["location"])
    assert "Form &lt;i&gt;study&lt;/i&gt;" in page.text and "<i>study</i>" not in page.text
    assert "Tutorial: no." in page.text and "No participant links yet." in page.text
    linked = storage_client.post(f"{made.headers['location']}/participants", data={"count": "2", "condition": ""})
    assert linked.status_code == 200 and linked.text.count('class="link-box"') == 2
    chart = storage_client.get(f"{made.headers['location']}/rates.svg")
    assert chart.headers["content-type"] == "image/svg+xml" and b"kerosene lamp" in chart.content
    incomplete = storage_client.post("/research/experiments", data={"name": "", "condition:0:name": "near"})
    assert incomplete.status_code == 422
    assert "Give the experiment a name." in incomplete.text and "has no training object" in incomplete.text
    storage_client.post("/research/logout")
    assert storage_client.get("/research", follow_redirects=False).status_code == 303


@pytest.mark.slow
def test_without_a_token_the_research_pages_and_api_are_off(tmp_path: Path) -> None:
    settings = settings_for(f"sqlite:///{tmp_path / 'off.sqlite3'}", research_token=None, planning_workers=1)
    with running_client(settings) as client:
        page = client.get("/research")
        assert page.status_code == 403 and "CAUSALPLAN_RESEARCH_TOKEN" in page.text
        assert "disabled" in client.get("/research/login").text
        assert error_of(client.get("/v1/experiments", headers=AUTH), 403)["code"] == "research_disabled"
