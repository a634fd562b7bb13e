"""Jobs have owners and quotas: only a job's client (or the research token) sees it; each client is limited.

A client is an API key, the research token, a participant's pages, or (without a key) its
address. Another client asking for a job gets the answer of a job that never existed; each
limit (jobs in flight, bytes stored, jobs a minute) is a 429 with `Retry-After`; the service's
own cap holds however many creators race for its last places.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import Engine, func, select
from sqlalchemy.orm import Session

from causalplan.service.errors import TooManyJobsError, TryLaterError
from causalplan.service.owners import JobOwner, job_limits, key_owner, owner_of_token
from causalplan.service.storage import jobs as store
from causalplan.service.storage.jobs import OwnerLimits
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.records import JobRecord
from causalplan.service.storage.session import create_database_engine
from tests.service.fixtures import (
    API_KEY,
    AUTH,
    DESK_LAMP,
    KEY_AUTH,
    error_of,
    first_trials,
    migrated_engine,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
)
from tests.service.pages.flows import new_participant, post

OTHER_KEY = "another-api-key-for-tests-987654"
OTHER_AUTH = {"Authorization": f"Bearer {OTHER_KEY}"}
BATCH = {"kind": "batch", "trials": first_trials(1), "simulate": False}


def queue(client: TestClient, headers: dict[str, str] | None = None, body: dict[str, Any] = BATCH) -> dict[str, Any]:
    response = client.post("/v1/jobs", json=body, headers=headers)
    assert response.status_code == 202, response.text
    job: dict[str, Any] = response.json()
    return job


@pytest.fixture(scope="module")
def idle_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that runs no job (they stay queued) and knows two API keys."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    settings = settings_for(url, planning_workers=1, job_runners=0, api_keys=[API_KEY, OTHER_KEY])
    with running_client(settings) as client:
        yield client


# -- who sees a job --------------------------------------------------------------------------------


def test_another_client_cannot_read_cancel_or_download_a_job(idle_client: TestClient) -> None:
    film = queue(idle_client, KEY_AUTH, {"kind": "video", "model": DESK_LAMP})
    url = film["url"]
    never = f"/v1/jobs/{uuid.uuid4()}"
    for stranger in (OTHER_AUTH, {}):  # another key, and a client without one
        for method, path in (("GET", url), ("DELETE", url), ("GET", f"{url}/video")):
            refused = error_of(idle_client.request(method, path, headers=stranger), 404)
            missing = error_of(idle_client.request(method, path.replace(url, never), headers=stranger), 404)
            assert refused["code"] == missing["code"] == "job_not_found"  # the same answer as no job at all
            assert refused["message"].replace(film["id"], "X") == missing["message"].replace(never[9:], "X")
    mine = idle_client.get(url, headers=KEY_AUTH)
    assert mine.status_code == 200 and mine.json()["status"] == "queued"  # nobody else cancelled it
    assert error_of(idle_client.get(f"{url}/video", headers=KEY_AUTH), 404)["code"] == "video_not_found"  # not yet
    assert idle_client.delete(url, headers=KEY_AUTH).json()["status"] == "cancelled"


def test_the_research_token_reads_and_cancels_every_job(idle_client: TestClient) -> None:
    url = queue(idle_client, KEY_AUTH)["url"]
    read = idle_client.get(url, headers=AUTH)
    assert read.status_code == 200 and read.json()["status"] == "queued"
    assert idle_client.delete(url, headers=AUTH).json()["status"] == "cancelled"
    its_own = queue(idle_client, AUTH)["url"]
    assert error_of(idle_client.get(its_own, headers=KEY_AUTH), 404)["code"] == "job_not_found"
    assert idle_client.delete(its_own, headers=AUTH).json()["status"] == "cancelled"


def test_a_bearer_token_that_is_no_key_is_refused(idle_client: TestClient) -> None:
    wrong = {"Authorization": "Bearer not-a-key-of-this-service"}
    error = error_of(idle_client.post("/v1/jobs", json=BATCH, headers=wrong), 401)
    assert error["code"] == "not_authenticated"
    assert error_of(idle_client.get(f"/v1/jobs/{uuid.uuid4()}", headers=wrong), 401)["code"] == "not_authenticated"


def test_wrong_tokens_cost_only_their_senders(tmp_path: Path) -> None:
    settings = settings_for(
        sqlite_url(tmp_path), planning_workers=1, job_runners=0, research_max_failures=2, research_max_failures_total=5
    )
    wrong = {"Authorization": "Bearer not-a-key-of-this-service"}
    with running_client(settings) as app:
        url = queue(app, KEY_AUTH)["url"]
        flooders = [TestClient(app.app, client=(f"203.0.113.{number}", 40000)) for number in range(6)]
        for flooder in flooders:  # more wrong tokens than every address together may send
            for _ in range(3):
                flooder.get(url, headers=wrong)
        assert error_of(flooders[0].get(url, headers=wrong), 429)["code"] == "too_many_attempts"
        assert error_of(app.get(url, headers=wrong), 429)["code"] == "too_many_attempts"  # a newcomer's guess too
        for client in (app, flooders[0]):  # a right token from anywhere, the flooding address too
            assert client.get(url, headers=KEY_AUTH).status_code == 200
            assert client.get(url, headers=AUTH).status_code == 200
            assert client.get("/v1/trials", headers=AUTH).status_code == 200


def test_a_key_is_stored_only_as_its_hash(idle_client: TestClient) -> None:
    job_id = uuid.UUID(queue(idle_client, KEY_AUTH)["id"])
    with Session(services_of(idle_client).engine) as session:
        owner = session.scalar(select(JobRecord.owner).where(JobRecord.id == job_id))
    assert owner == key_owner(API_KEY) and API_KEY not in str(owner) and owner != key_owner(OTHER_KEY)
    settings = services_of(idle_client).settings
    assert owner_of_token(API_KEY, settings) == JobOwner(key_owner(API_KEY))
    assert owner_of_token(API_KEY[:-1], settings) is None


# -- each client's limits --------------------------------------------------------------------------


def test_jobs_in_flight_are_limited_per_client(tmp_path: Path) -> None:
    settings = settings_for(
        sqlite_url(tmp_path), planning_workers=1, job_runners=0, anonymous_jobs_in_flight=2, jobs_in_flight=3
    )
    with running_client(settings) as client:
        first, _ = queue(client), queue(client)
        refused = client.post("/v1/jobs", json=BATCH)
        assert error_of(refused, 429)["code"] == "too_many_jobs_in_flight"
        assert int(refused.headers["retry-after"]) > 0
        for _ in range(3):
            queue(client, KEY_AUTH)  # another client is not held up, and a key has more room
        assert error_of(client.post("/v1/jobs", json=BATCH, headers=KEY_AUTH), 429)["code"] == "too_many_jobs_in_flight"
        for _ in range(4):
            queue(client, AUTH)  # the operator's research token: only the service's own cap holds it
        assert client.delete(first["url"]).status_code == 200
        queue(client)  # one finished (cancelled): room for one more


def test_bytes_stored_are_limited_per_client_until_the_jobs_expire(tmp_path: Path) -> None:
    upload = first_trials(4)
    body = {"kind": "batch", "trials": upload}
    room = 2.5 * len(upload) / 1e6  # two such jobs fit, not three
    settings = settings_for(
        sqlite_url(tmp_path), planning_workers=1, job_runners=0, anonymous_job_megabytes=room, job_result_seconds=600
    )
    with running_client(settings) as client:
        first, _ = queue(client, body=body), queue(client, body=body)
        assert client.delete(first["url"]).status_code == 200  # cancelled, but kept (and counted) until it expires
        refused = client.post("/v1/jobs", json=body)
        assert error_of(refused, 429)["code"] == "job_storage_full"
        assert 500 < int(refused.headers["retry-after"]) <= 600  # when the cancelled job expires
        queue(client, KEY_AUTH, body)  # another client's room is its own
        too_big = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(12)})
        assert error_of(too_big, 413)["code"] == "body_too_large"  # more than all the room there is


def test_a_jobs_result_counts_against_its_owner(tmp_path: Path) -> None:
    engine = migrated_engine(tmp_path)
    limits = OwnerLimits(in_flight=10, stored_bytes=3_000)
    job_id = store.create_job(engine, "batch", {"trials": "x"}, 1, 10, owner="address:a", limits=limits).id
    assert store.claim_job(engine, "replica", 30, ["batch"]) is not None
    assert store.finish_job(engine, job_id, "replica", 60, result={"rows": "r" * 1_000}, file=(b"f" * 1_500, "x/y"))
    assert 2_500 < store.get_job(engine, job_id).result_bytes < 2_600
    with pytest.raises(TryLaterError) as refused:  # the owner's room is taken by the result
        store.create_job(engine, "batch", {"trials": "y" * 500}, 1, 10, owner="address:a", limits=limits)
    assert refused.value.code == "job_storage_full"
    store.create_job(engine, "batch", {"trials": "y" * 500}, 1, 10, owner="address:b", limits=limits)


def test_jobs_a_minute_are_limited_per_client(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0, anonymous_jobs_per_minute=3)
    with running_client(settings) as client:
        for _ in range(3):
            assert client.delete(queue(client)["url"]).status_code == 200  # none stays in flight
        refused = client.post("/v1/jobs", json=BATCH)
        assert error_of(refused, 429)["code"] == "too_many_job_starts"
        assert 0 < int(refused.headers["retry-after"]) <= 60
        queue(client, KEY_AUTH)


def test_a_client_with_a_key_has_the_larger_limits(idle_client: TestClient) -> None:
    settings = services_of(idle_client).settings
    anonymous, keyed = (
        job_limits(JobOwner("address:x", is_anonymous=True), settings),
        job_limits(JobOwner("k"), settings),
    )
    assert anonymous is not None and keyed is not None
    assert anonymous.in_flight < keyed.in_flight and anonymous.stored_bytes < keyed.stored_bytes
    assert job_limits(JobOwner("research"), settings) is None
    assert settings.anonymous_jobs_per_minute < settings.jobs_per_minute


# -- the service's cap ---------------------------------------------------------------------------


def _unfinished(engine: Engine) -> int:
    with Session(engine) as session:
        return session.scalar(select(func.count()).select_from(JobRecord).where(JobRecord.status == "queued")) or 0


def _race(engine: Engine, cap: int, creators: int, tries: int) -> list[str]:
    """Let ``creators`` threads each create ``tries`` jobs at the same moment; return the codes of the refusals."""
    start = threading.Barrier(creators)
    refused: list[str] = []

    def create() -> None:
        start.wait()
        for _ in range(tries):
            try:
                store.create_job(engine, "batch", {"trials": "x"}, 1, cap, owner="address:racer")
            except TooManyJobsError as exc:
                refused.append(exc.code)

    threads = [threading.Thread(target=create) for _ in range(creators)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return refused


def test_the_services_cap_holds_against_creators_racing_for_its_last_places(database_url: str) -> None:
    engine = create_database_engine(database_url)
    upgrade(engine)
    cap, creators, tries = 10, 16, 2
    try:
        for _ in range(3):
            refused = _race(engine, cap, creators, tries)
            assert _unfinished(engine) == cap and len(refused) == creators * tries - cap
            with Session(engine) as session:
                session.query(JobRecord).delete()
                session.commit()
    finally:
        engine.dispose()


# -- a participant's film ------------------------------------------------------------------------


def test_a_participants_film_is_theirs_and_served_from_every_participants_pages(idle_client: TestClient) -> None:
    code, other = new_participant(idle_client), new_participant(idle_client)
    for person in (code, other):
        post(
            idle_client,
            f"/p/{person}/step1/1",
            {"part:base_with_cables": "provide electricity", "part:light_bulb": "x"},
        )
    (plan,) = idle_client.post(f"/p/{code}/plan", json={"rules": "provide electricity AND x CAUSES light"}).json()[
        "plans"
    ]
    asked = idle_client.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": plan["fits"]})
    assert asked.status_code == 200, asked.text
    film = asked.json()
    assert film["state"] == "filming" and film["video_url"] is None
    assert error_of(idle_client.get(f"{film['status_url']}/video"), 404)["code"] == "video_not_found"  # not yet
    job_id = uuid.UUID(hex=film["key"])
    assert error_of(idle_client.get(f"/v1/jobs/{job_id}"), 404)["code"] == "job_not_found"  # the API's is not theirs
    engine = services_of(idle_client).engine
    record = store.get_job(engine, job_id)
    assert record.owner.startswith("participant:")
    # A replica's runner films it (as the runner stores a film).
    assert store.claim_job(engine, "replica", 30, ["video"]) is not None
    made = b"\x00\x00\x00\x18ftypmp42" + bytes(64)
    result = {"robot": {"carried_out": True, "reason": None}, "video": {"content_type": "video/mp4", "bytes": 76}}
    assert store.finish_job(engine, job_id, "replica", 600, result=result, file=(made, "video/mp4"))
    for person in (code, other):  # one film per plan, for everyone who asks
        again = idle_client.post(f"/p/{person}/films", json={"object": "desk_lamp", "fits": plan["fits"]}).json()
        assert again["state"] == "ready" and again["key"] == film["key"]
        served = idle_client.get(again["video_url"])
        assert served.status_code == 200 and served.content == made and served.headers["content-type"] == "video/mp4"
    assert error_of(idle_client.get(f"/v1/jobs/{job_id}/video"), 404)["code"] == "job_not_found"
    assert idle_client.get(f"/v1/jobs/{job_id}/video", headers=AUTH).content == made


def test_a_job_the_api_made_is_no_participants_film(idle_client: TestClient) -> None:
    code = new_participant(idle_client)
    key = uuid.UUID(queue(idle_client, body={"kind": "video", "model": DESK_LAMP})["id"]).hex
    assert error_of(idle_client.get(f"/p/{code}/films/{key}/video"), 404)["code"] == "video_not_found"


# -- the API's description -----------------------------------------------------------------------


def test_openapi_lists_each_job_routes_404_and_429(idle_client: TestClient) -> None:
    paths = idle_client.get("/openapi.json").json()["paths"]
    posted = paths["/v1/jobs"]["post"]["responses"]
    for code in ("too_many_jobs", "too_many_jobs_in_flight", "job_storage_full", "too_many_job_starts"):
        assert code in posted["429"]["description"]
    assert "401" in posted
    for method, path in (
        ("get", "/v1/jobs/{job_id}"),
        ("delete", "/v1/jobs/{job_id}"),
        ("get", "/v1/jobs/{job_id}/video"),
    ):
        responses = paths[path][method]["responses"]
        assert "another client's" in responses["404"]["description"] and {"401", "429"} <= set(responses)
    assert "too_many_jobs_in_flight" in paths["/v1/simulations"]["post"]["responses"]["429"]["description"]
