"""Repeated plan bodies answered before the route (RepeatedPlanMiddleware): the route's answer, byte for byte."""

from __future__ import annotations

import json
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import Engine

from causalplan.planners import pipeline
from causalplan.service import repeats, submissions
from causalplan.service.crud import ClientIds, NoWaitWriter, PreparedModelRow, new_model_record
from causalplan.service.db.models import MAX_CLIENT_ID_LENGTH
from causalplan.service.repeats import RepeatedPlans
from tests.service_fixtures import (
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    postgres_database,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    sqlite_write_lock_for_a_moment,
    with_unique_effect,
)

JSON = {"content-type": "application/json"}


class RouteCalls:
    """Counts the requests that reached the plan route (the others were answered before it)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.count = 0
        real = submissions.kept_answer

        def counted(*args: Any) -> Any:
            self.count += 1
            return real(*args)

        monkeypatch.setattr(submissions, "kept_answer", counted)  # the route's first call


@pytest.fixture
def routes(monkeypatch: pytest.MonkeyPatch) -> RouteCalls:
    return RouteCalls(monkeypatch)


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    with running_client(settings_for(sqlite_url(tmp_path_factory.mktemp("db")))) as running:
        yield running


def _body(mapping: dict[str, Any] | None = None, **fields: Any) -> bytes:
    request = {"model": with_unique_effect(DESK_LAMP), **fields} | ({"mapping": mapping} if mapping else {})
    return json.dumps(request).encode()


def _post(client: TestClient, body: bytes, headers: dict[str, str | bytes] | None = None) -> Any:
    return client.post("/v1/plans", content=body, headers=JSON | (headers or {}))


def _stored_row(engine: Engine, model_id: str) -> dict[str, Any]:
    with engine.connect() as connection:
        rows = connection.exec_driver_sql("SELECT * FROM models WHERE id = ?", (uuid.UUID(model_id).hex,))
        [row] = rows.mappings().all()
    return dict(row)


@pytest.mark.parametrize(
    ("mapping", "fields"),
    [(None, {}), (FLASHLIGHT_MAPPING, {}), (None, {"include_pddl": True, "planner": "fd"})],
    ids=["own object", "mapping", "pddl and a planner"],
)
def test_a_repeated_body_gets_the_routes_answer_and_its_own_record(
    client: TestClient, routes: RouteCalls, monkeypatch: pytest.MonkeyPatch, mapping: Any, fields: dict[str, Any]
) -> None:
    body = _body(mapping, **fields)
    headers = {"X-Participant-Id": "p ☃".encode(), "X-Session-Id": "s1"}  # read as Latin-1, as FastAPI reads it
    first = _post(client, body, headers)
    assert first.json()["cached"] is False  # solved
    second = _post(client, body, headers)
    assert second.json()["cached"] is True and routes.count == 2  # from the cache, through the route: kept
    third = _post(client, body, {"X-Session-Id": "s2"})
    assert third.status_code == 200 and routes.count == 2  # answered before the route
    services = services_of(client)
    with monkeypatch.context() as without:
        without.setattr(services, "repeats", RepeatedPlans(0))
        routed = _post(client, body, {"X-Session-Id": "s2"})
    assert routes.count == 3
    # Byte for byte the route's answer, but for the model id (a record per request).
    third_id, routed_id = third.json()["model_id"], routed.json()["model_id"]
    assert third_id != routed_id and third_id != second.json()["model_id"]
    assert third.content.replace(third_id.encode(), b"ID") == routed.content.replace(routed_id.encode(), b"ID")
    assert third.headers == routed.headers
    # Its record is the route's record, with its own id, time and client ids.
    third_row, routed_row = _stored_row(services.engine, third_id), _stored_row(services.engine, routed_id)
    assert third_row["session_id"] == "s2" and third_row["participant_id"] is None
    assert third_row["created_at"] > _stored_row(services.engine, second.json()["model_id"])["created_at"]
    assert {**third_row, "id": 0, "created_at": 0} == {**routed_row, "id": 0, "created_at": 0}
    assert client.get(f"/v1/models/{third_id}").json()["model"] == json.loads(body)["model"]


def test_what_the_route_would_refuse_or_read_otherwise_goes_to_the_route(
    client: TestClient, routes: RouteCalls
) -> None:
    body = _body()
    assert [_post(client, body).json()["cached"] for _ in range(3)] == [False, True, True]
    assert routes.count == 2
    too_long = error_of(_post(client, body, {"X-Participant-Id": "x" * (MAX_CLIENT_ID_LENGTH + 1)}), 422)
    assert "x-participant-id" in json.dumps(too_long).lower()
    assert routes.count == 2  # refused by FastAPI, before the route: nothing stored
    sent_twice = [*JSON.items(), ("X-Session-Id", "a"), ("X-Session-Id", "b")]
    twice = client.post("/v1/plans", content=body, headers=sent_twice)
    assert twice.status_code == 200 and routes.count == 3
    assert client.post("/v1/plans?x=1", content=body, headers=JSON).status_code == 200 and routes.count == 4
    # Other bytes for the same document (another layout) are read by the route, then kept as well.
    spaced = json.dumps(json.loads(body), indent=2).encode()
    assert [_post(client, spaced).json()["cached"] for _ in range(3)] == [True, True, True]
    assert routes.count == 5
    # A content type is part of the key: FastAPI decides by it how to read a body.
    plain = client.post("/v1/plans", content=body, headers={"content-type": "text/plain"})
    assert plain.status_code == 422 and routes.count == 5  # refused before the route
    assert _post(client, body, {"content-type": "application/json; charset=utf-8"}).json()["cached"] is True
    assert routes.count == 6


def test_a_held_write_lock_sends_the_repeat_to_the_route(client: TestClient, routes: RouteCalls) -> None:
    body = _body()
    assert [_post(client, body).json()["cached"] for _ in range(2)] == [False, True]
    with sqlite_write_lock_for_a_moment(str(services_of(client).engine.url)):
        response = _post(client, body)
    assert response.status_code == 200 and response.json()["cached"] is True
    assert routes.count == 3  # the route stored it in a thread, once the lock was free
    assert client.get(f"/v1/models/{response.json()['model_id']}").status_code == 200


def test_a_planner_registry_that_changed_sends_the_repeat_to_the_route(
    client: TestClient, routes: RouteCalls, monkeypatch: pytest.MonkeyPatch
) -> None:
    body = _body(planner="auto")
    assert [_post(client, body).json()["cached"] for _ in range(3)] == [False, True, True]
    assert routes.count == 2
    # A registry without 'auto' (planners are registered at run time): 'auto' runs as 'fd' now,
    # so what was kept is another planner's answer.
    monkeypatch.setattr(pipeline, "PLANNERS", tuple(name for name in pipeline.PLANNERS if name != "auto"))
    now = _post(client, body).json()
    assert routes.count == 3 and now["cached"] is False and now["planner_used"] == "fd"
    # A planner the registry no longer has: the route says so (and which there are).
    monkeypatch.setattr(pipeline, "PLANNERS", ("fd",))
    kept = _body(planner="fd-opt")
    monkeypatch.undo()
    assert [_post(client, kept).json()["cached"] for _ in range(3)] == [False, True, True]
    monkeypatch.setattr(pipeline, "PLANNERS", ("fd",))
    assert error_of(_post(client, kept), 422)["code"] == "unknown_planner"


def test_an_answer_that_contains_the_marker_is_not_kept(
    client: TestClient, routes: RouteCalls, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The model id's place is found by a random marker; an answer quoting it is left to the route."""
    marker = uuid.uuid4()
    model = {**DESK_LAMP, "rules": [rule.replace("electricity flows", marker.hex) for rule in DESK_LAMP["rules"]]}
    body = json.dumps({"model": model, "include_pddl": True}).encode()  # the PDDL names the effect
    monkeypatch.setattr(repeats, "_marker", lambda: marker.hex)
    answers = [_post(client, body).json() for _ in range(3)]
    assert marker.hex in answers[0]["pddl"]["domain"]
    assert [answer["cached"] for answer in answers] == [False, True, True]
    assert routes.count == 3


def test_the_kept_bodies_are_bounded(tmp_path: Path, routes: RouteCalls) -> None:
    with running_client(settings_for(sqlite_url(tmp_path), cache_size=2)) as client:
        kept = services_of(client).repeats
        bodies = [_body() for _ in range(3)]
        for body in bodies:
            assert [_post(client, body).json()["cached"] for _ in range(2)] == [False, True]
        assert kept.stats() | {"misses": 0} == {"size": 2, "entries": 2, "hits": 0, "misses": 0}
        # The least recent body is forgotten here as in the result cache: solved, kept, answered.
        assert [_post(client, bodies[0]).json()["cached"] for _ in range(3)] == [False, True, True]
        assert kept.stats()["hits"] == 1 and kept.stats()["entries"] == 2 and routes.count == 8
        assert client.get("/health").json()["repeats"] == kept.stats()


def test_no_cache_keeps_no_bodies(tmp_path: Path, routes: RouteCalls) -> None:
    with running_client(settings_for(sqlite_url(tmp_path), cache_size=0)) as client:
        body = _body()
        assert [_post(client, body).json()["cached"] for _ in range(3)] == [False, False, False]
        assert routes.count == 3 and services_of(client).repeats.stats()["entries"] == 0


def test_postgresql_repeats_go_to_the_route(postgres_admin_url: str, routes: RouteCalls) -> None:
    """A database server's writes are round trips: the event loop never makes them."""
    with postgres_database(postgres_admin_url) as url, running_client(settings_for(url)) as client:
        assert services_of(client).no_wait_writer is None
        body = _body()
        assert [_post(client, body).json()["cached"] for _ in range(3)] == [False, True, True]
        assert routes.count == 3


def test_a_prepared_row_weighs_its_text(tmp_path: Path) -> None:
    from causalplan.service.db.session import create_database_engine

    engine = create_database_engine(sqlite_url(tmp_path))
    record = new_model_record({"rules": ["x" * 1000]}, "desk_lamp", True, {"errors": []}, None, ClientIds())
    assert PreparedModelRow(engine, record).weight > 1000
    writer = NoWaitWriter.open(engine)
    assert writer is not None  # SQLite
    writer.close()
    engine.dispose()


def test_a_failed_write_sends_the_repeat_to_the_route(
    client: TestClient, routes: RouteCalls, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The route stores the record its own way, and says what went wrong if that fails too."""
    from causalplan.service.errors import StorageError

    body = _body()
    assert [_post(client, body).json()["cached"] for _ in range(2)] == [False, True]

    def failing(*_: Any) -> None:
        raise StorageError("The database could not be used (test); nothing was stored.")

    monkeypatch.setattr(NoWaitWriter, "save_prepared", failing)
    response = _post(client, body)
    assert response.status_code == 200 and response.json()["cached"] is True
    assert routes.count == 3
    assert client.get(f"/v1/models/{response.json()['model_id']}").status_code == 200
