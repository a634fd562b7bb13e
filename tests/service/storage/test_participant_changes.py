"""A participant's work changed by two requests at once: each change lands on the record as stored then."""

from __future__ import annotations

from fastapi.testclient import TestClient
from sqlalchemy.orm import Session

from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.service.storage.records import utc_now
from tests.service.fixtures import services_of, storage_client  # noqa: F401 - the fixture
from tests.service.pages.flows import FLASHLIGHT_CHOICES, LAMP_FUNCTIONS, complete, new_participant, post

OLD_RULES = "provide electricity AND turn electricity into light CAUSES light"
NEW_RULES = "provide electricity AND close the circuit AND turn electricity into light CAUSES light"


def journey_in(session: Session, client: TestClient, code: str) -> ParticipantJourney:
    return ParticipantJourney.of(store.participant_by_code(session, code), services_of(client).catalog)


def test_a_slow_requests_change_keeps_what_another_stored_meanwhile(storage_client: TestClient) -> None:  # noqa: F811
    code = new_participant(storage_client)
    post(storage_client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    engine = services_of(storage_client).engine
    with Session(engine, expire_on_commit=False) as slow, Session(engine, expire_on_commit=False) as quick:
        planning = journey_in(slow, storage_client, code)  # a plan request reads the record, saves, plans...
        store.change_participant(slow, planning.participant, lambda: planning.save_rules(OLD_RULES))
        checking = journey_in(quick, storage_client, code)  # ...while a check saves newer rules
        store.change_participant(quick, checking.participant, lambda: checking.save_rules(NEW_RULES))
        # The plan request's own copy still holds the old rules: its log must not bring them back.
        store.change_participant(slow, planning.participant, lambda: planning.log_plan_request(utc_now()))
    with Session(engine) as fresh:
        stored = journey_in(fresh, storage_client, code)
        assert stored.rules_text() == NEW_RULES
        assert len(stored.participant.work["plan_requests"]) == 1


def test_a_save_older_than_the_one_stored_changes_nothing(storage_client: TestClient) -> None:  # noqa: F811
    code = new_participant(storage_client)
    functions = {"step": "step1", "object": "desk_lamp"}
    newer = storage_client.post(
        f"/p/{code}/draft", json={**functions, "functions": {"shade": "diffuse light"}, "revision": 2000}
    ).json()
    assert newer["applied"] and newer["revision"] == 2000
    late = storage_client.post(f"/p/{code}/draft", json={**functions, "functions": {"shade": ""}, "revision": 1000})
    assert late.json()["applied"] is False and late.json()["revision"] == 2000
    assert "diffuse light</textarea>" in storage_client.get(f"/p/{code}/step1/1").text
    # An old form posted again (a reload of a page that a failed submit answered) changes nothing either.
    post(storage_client, f"/p/{code}/step1/1", {"part:shade": "", "revision": "1500"})
    page = storage_client.get(f"/p/{code}/step1/1")
    assert "diffuse light</textarea>" in page.text and 'data-revision="2000"' in page.text
    # A form posted without the page's script (no revision) is the participant's latest word.
    post(storage_client, f"/p/{code}/step1/1", {"part:shade": "hold the bulb", "revision": ""})
    assert "hold the bulb</textarea>" in storage_client.get(f"/p/{code}/step1/1").text
    refused = post(storage_client, f"/p/{code}/step1/1", {"revision": "soon"}, 422)
    assert "revision&#39; must be a whole number" in refused.text


def test_rules_checked_late_are_not_stored_over_newer_ones(storage_client: TestClient) -> None:  # noqa: F811
    code = new_participant(storage_client)
    post(storage_client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    assert storage_client.post(f"/p/{code}/check", json={"rules": NEW_RULES, "revision": 20}).json()["applied"]
    late = storage_client.post(f"/p/{code}/check", json={"rules": OLD_RULES, "revision": 10}).json()
    assert late["applied"] is False and late["valid"]  # checked as typed all the same
    assert f"{NEW_RULES}</textarea>" in storage_client.get(f"/p/{code}/step2").text
    # A failed submission sends the browser back to the page: a reload then shows what is stored.
    refused = post(storage_client, f"/p/{code}/step2", {"rules": "nothing CAUSES light", "revision": "30"})
    assert refused.headers["location"] == f"/p/{code}/step2?check=1"
    assert "nothing CAUSES light</textarea>" in storage_client.get(refused.headers["location"]).text


def test_the_end_page_leaves_for_the_platform_once_the_server_confirms(storage_client: TestClient) -> None:  # noqa: F811
    code = new_participant(storage_client)
    before = storage_client.get(f"/p/{code}/progress")
    assert before.json()["stage"] == "step1" and before.json()["finished"] is False
    complete(storage_client, code, FLASHLIGHT_CHOICES)
    after = storage_client.get(f"/p/{code}/progress").json()
    assert after["stage"] == "done" and after["finished"] is True
