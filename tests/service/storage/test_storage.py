"""Storage on SQLite and on a real PostgreSQL: migrations, one transaction per request, odd text, outages."""

from __future__ import annotations

import contextlib
import json
import logging
import socket
import threading
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from fastapi.testclient import TestClient
from sqlalchemy import func, inspect, select
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session

from causalplan.service.errors import StorageError
from causalplan.service.storage import crud
from causalplan.service.storage.migrate import current_revision, head_revision, upgrade
from causalplan.service.storage.records import Base, ModelRecord, TrialRecord
from causalplan.service.storage.session import WAL_SIZE_LIMIT_BYTES, create_database_engine
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    free_port,
    postgres_database,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
)


def test_migrations_build_exactly_the_models_schema(database_url: str) -> None:
    engine = create_database_engine(database_url)
    try:
        assert current_revision(engine) is None
        assert upgrade(engine) == head_revision() == "0011"
        assert upgrade(engine) == "0011"  # a second start changes nothing
        assert set(inspect(engine).get_table_names()) == {
            "alembic_version",
            "models",
            "trials",
            "experiments",
            "participants",
            "participant_trials",
            "revoked_research_sessions",
            "study_places",
            "study_arrivals",
            "participant_exclusions",
            "failed_attempts",
            "window_counts",
            "jobs",
        }
        with engine.connect() as connection:
            differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)
        assert differences == []
    finally:
        engine.dispose()


@pytest.mark.slow
def test_a_sqlite_file_and_its_folder_are_created_on_first_start(tmp_path: Any) -> None:
    path = tmp_path / "new" / "folder" / "causalplan.sqlite3"
    with running_client(settings_for(f"sqlite:///{path}", planning_workers=1)) as client:
        assert client.get("/health").json()["database"]["revision"] == "0011"
    assert path.exists()


def test_the_database_url_accepts_plain_postgresql_urls() -> None:
    url = settings_for("postgresql://user:secret@db.example/causalplan").database_url
    assert url == "postgresql+psycopg://user:secret@db.example/causalplan"


def _records(participant: str) -> tuple[ModelRecord, TrialRecord]:
    client = crud.ClientIds(participant, "séance ☃")
    document = {"name": "lamp 💡", "rules": ["a causes b"], "nested": {"n": [1, 2.5, None, True]}}
    model = crud.new_model_record(document, "desk_lamp", True, {"errors": [], "score": 0.5}, "ab" * 32, client)
    verdict = {"verdict": "works", "decided_by": "planner", "training_object": "desk_lamp", "test_object": "candle"}
    trial = crud.new_trial_record(model.id, {"parts": {"wick": "emitter"}}, "fd", verdict, True, 0.0125, client)
    return model, trial


def test_several_records_of_a_kind_are_stored_in_one_save(database_url: str) -> None:
    engine = create_database_engine(database_url)
    upgrade(engine)
    first, first_trial = _records("many")
    second, second_trial = _records("many")
    crud.save(engine, [first_trial, first, second_trial, second])  # trials listed first: models still go in first
    with Session(engine) as session:
        models = session.scalars(select(ModelRecord.id).where(ModelRecord.participant_id == "many")).all()
        trials = session.scalars(select(TrialRecord.model_id).where(TrialRecord.participant_id == "many")).all()
    assert set(models) == {first.id, second.id}
    assert sorted(trials) == sorted([first.id, second.id])
    engine.dispose()


def test_a_failed_save_stores_nothing_and_keeps_the_connection_usable(database_url: str) -> None:
    engine = create_database_engine(database_url)
    upgrade(engine)
    model, trial = _records("failed")
    trial.verdict = None  # type: ignore[assignment]  # NOT NULL: the driver refuses the second INSERT
    with pytest.raises(StorageError, match="nothing was stored"):
        crud.save(engine, [model, trial])
    with Session(engine) as session:
        assert session.get(ModelRecord, model.id) is None
    model, trial = _records("after")
    crud.save(engine, [model, trial])
    with Session(engine) as session:
        assert session.get(TrialRecord, trial.id) is not None
    engine.dispose()


def _count(engine: Any, participant: str) -> tuple[int, int]:
    with Session(engine) as session:
        models = session.scalar(select(func.count()).where(ModelRecord.participant_id == participant))
        trials = session.scalar(select(func.count()).where(TrialRecord.participant_id == participant))
    return models or 0, trials or 0


@pytest.mark.slow
def test_the_sqlite_log_stays_bounded_after_many_writes(tmp_path: Path) -> None:
    """SQLite checkpoints by itself, and journal_size_limit truncates the log after a burst of writes."""
    url = sqlite_url(tmp_path)
    with running_client(settings_for(url, planning_workers=1)) as client:
        engine = services_of(client).engine
        text = "x" * 20_000
        for batch in range(100):  # 2,000 records of ~20 KB: about 40 MB written
            records = []
            for index in range(20):
                model, _ = _records(f"bulk-{batch}-{index}")
                model.document = {**model.document, "padding": text}
                records.append(model)
            crud.save(engine, records)
        wal = Path(f"{make_url(url).database}-wal")
        assert wal.stat().st_size <= WAL_SIZE_LIMIT_BYTES + 4 * 1024 * 1024  # the limit, and one checkpoint's worth
        with engine.connect() as connection:
            assert connection.exec_driver_sql("PRAGMA wal_autocheckpoint").scalar() > 0


@pytest.mark.slow
def test_health_says_degraded_when_free_space_is_below_the_minimum(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, min_free_disk_mb=10**12)  # more than any disk
    with running_client(settings) as client:
        health = client.get("/health").json()
        assert health["status"] == "degraded"
        assert health["storage"]["free_mb"] >= 0 and "MB free" in health["storage"]["problem"]
    with running_client(settings_for(sqlite_url(tmp_path), planning_workers=1, min_free_disk_mb=0)) as client:
        assert client.get("/health").json()["storage"]["problem"] is None


def test_a_trial_and_its_inline_model_are_stored_together_or_not_at_all(
    storage_client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    participant = f"atomic-{uuid.uuid4().hex[:8]}"
    real = crud.new_trial_record

    def broken_trial(*args: Any, **kwargs: Any) -> TrialRecord:
        trial = real(*args, **kwargs)
        trial.verdict = None  # type: ignore[assignment]  # NOT NULL: the insert fails inside the transaction
        return trial

    monkeypatch.setattr(crud, "new_trial_record", broken_trial)
    response = storage_client.post(
        "/v1/transfers",
        json={"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING},
        headers={"X-Participant-Id": participant},
    )
    error = error_of(response, 503)
    assert error["code"] == "storage_unavailable" and "nothing was stored" in error["message"]
    engine = services_of(storage_client).engine
    with Session(engine) as session:
        models = session.scalar(select(func.count()).where(ModelRecord.participant_id == participant))
        trials = session.scalar(select(func.count()).where(TrialRecord.participant_id == participant))
    assert (models, trials) == (0, 0)
    monkeypatch.setattr(crud, "new_trial_record", real)
    response = storage_client.post(
        "/v1/transfers",
        json={"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING},
        headers={"X-Participant-Id": participant},
    )
    assert response.status_code == 200
    with Session(engine) as session:
        models = session.scalar(select(func.count()).where(ModelRecord.participant_id == participant))
        trials = session.scalar(select(func.count()).where(TrialRecord.participant_id == participant))
    assert (models, trials) == (1, 1)


def test_text_no_database_column_takes_is_stored_cleaned(storage_client: TestClient) -> None:
    participant = f"odd-{uuid.uuid4().hex[:8]}"
    mapping = {"object": "flash\\u0000light" + "x" * 300, "functions": {"he\\ud800ad": ["nul \\u0000 label"]}}
    body = json.dumps({"model": DESK_LAMP, "mapping": "MAPPING"}).replace('"MAPPING"', json.dumps(mapping))
    body = body.replace("\\\\u0000", "\\u0000").replace("\\\\ud800", "\\ud800")  # real escapes in the JSON text
    response = storage_client.post(
        "/v1/transfers",
        content=body.encode(),
        headers={"Content-Type": "application/json", "X-Participant-Id": participant},
    )
    error = error_of(response, 422)
    assert error["code"] == "invalid_mapping"
    trials = storage_client.get("/v1/trials", params={"participant_id": participant}, headers=AUTH).json()["data"]
    [trial] = trials
    assert trial["verdict"] == "invalid"
    assert trial["test_object"] == ("flash\ufffdlight" + "x" * 300)[:200]
    assert trial["mapping"]["functions"] == {"he\ufffdad": ["nul \ufffd label"]}


def test_a_models_document_and_report_are_stored_cleaned_when_read_and_when_repeated(
    storage_client: TestClient,
) -> None:
    """The second request reuses the document's read (its report cleaned once): both records are cleaned."""
    model = {**DESK_LAMP, "functions": {**DESK_LAMP["functions"], "shade": [f"nul \\u0000 label {uuid.uuid4().hex}"]}}
    body = json.dumps({"model": model}).replace("\\\\u0000", "\\u0000")  # a real escape in the JSON text
    ids = []
    for _ in range(2):
        response = storage_client.post("/v1/plans", content=body.encode(), headers={"Content-Type": "application/json"})
        error = error_of(response, 422)
        assert error["code"] == "invalid_model"
        ids.append(error["details"]["model_id"])
    assert ids[0] != ids[1]
    for model_id in ids:
        stored = storage_client.get(f"/v1/models/{model_id}").json()
        [label] = stored["model"]["functions"]["shade"]
        assert label.startswith("nul \ufffd label")
        assert [problem["code"] for problem in stored["report"]["errors"]] == ["invalid_character"]
        assert "\\u0000" not in json.dumps(stored)  # no NUL in the document or the report


@pytest.mark.slow
def test_an_unreachable_database_is_503_and_health_says_so(postgres_admin_url: str) -> None:
    import psycopg
    from sqlalchemy.engine import make_url

    with postgres_database(postgres_admin_url) as url, running_client(settings_for(url, planning_workers=1)) as client:
        assert client.post("/v1/models", json=DESK_LAMP).status_code == 201
        admin = make_url(postgres_admin_url).set(drivername="postgresql").render_as_string(hide_password=False)
        with psycopg.connect(admin, autocommit=True) as connection:
            connection.execute(f'DROP DATABASE "{make_url(url).database}" WITH (FORCE)')
        error = error_of(client.post("/v1/models", json=DESK_LAMP), 503)
        assert error["code"] == "storage_unavailable"
        server = make_url(url)
        health = client.get("/health").json()
        assert health["status"] == "degraded"
        assert health["database"]["reachable"] is False and health["database"]["problem"]
        for said in (json.dumps(error), json.dumps(health["database"])):  # the driver's words stay in the log
            assert str(server.host) not in said and str(server.port) not in said and "psycopg" not in said
        assert client.post("/v1/plans", json={"model_id": str(uuid.uuid4())}).status_code == 503


def test_a_database_that_cannot_be_reached_at_start_is_a_clear_error(caplog: pytest.LogCaptureFixture) -> None:
    engine = create_database_engine("postgresql+psycopg://nobody@127.0.0.1:1/none")
    with pytest.raises(StorageError, match=r"did not take a connection within 0 s .*refused"):
        upgrade(engine)  # no wait: one try
    started = time.monotonic()
    waited = pytest.raises(StorageError, match=r"within 1.2 s \(CAUSALPLAN_DATABASE_WAIT_SECONDS\)")
    with caplog.at_level(logging.WARNING, logger="causalplan.service.storage.migrate"), waited:
        upgrade(engine, wait_seconds=1.2)
    assert time.monotonic() - started >= 1.2
    assert any("database not up yet" in record.getMessage() for record in caplog.records)
    with pytest.raises(StorageError, match="not valid"):
        create_database_engine("not a url")


@pytest.mark.slow
def test_a_server_that_takes_the_connection_but_never_answers_is_given_up_on(monkeypatch: pytest.MonkeyPatch) -> None:
    from causalplan.service.storage import session

    monkeypatch.setattr(session, "CONNECT_TIMEOUT_SECONDS", 1)
    with socket.create_server(("127.0.0.1", 0)) as silent:  # the kernel takes connections; nobody answers
        engine = create_database_engine(f"postgresql+psycopg://nobody@127.0.0.1:{silent.getsockname()[1]}/none")
        started = time.monotonic()
        with pytest.raises(StorageError, match=r"did not take a connection within 0 s .*timeout"):
            upgrade(engine)
        assert time.monotonic() - started < 5  # without the timeout it waits for as long as TCP keeps trying


@contextmanager
def forwarded_later(target: tuple[str, int] | str, after: float) -> Iterator[int]:
    """Yield a free port that, from ``after`` seconds on, forwards every connection to ``target``.

    ``target``: a (host, port), or the path of a Unix socket (the wheel's server listens on one only).

    A database server that comes up while a replica is already starting.
    """
    port, done = free_port(), threading.Event()

    def pipe(source: socket.socket, sink: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := source.recv(65536):
                sink.sendall(data)
        for end in (source, sink):
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)

    def serve() -> None:
        if done.wait(after):
            return
        with socket.create_server(("127.0.0.1", port)) as listener:
            listener.settimeout(0.1)
            while not done.is_set():
                try:
                    accepted, _ = listener.accept()
                except TimeoutError:
                    continue
                if isinstance(target, str):
                    upstream = socket.socket(socket.AF_UNIX)
                    upstream.connect(target)
                else:
                    upstream = socket.create_connection(target)
                for ends in ((accepted, upstream), (upstream, accepted)):
                    threading.Thread(target=pipe, args=ends, daemon=True).start()

    server = threading.Thread(target=serve, daemon=True)
    server.start()
    try:
        yield port
    finally:
        done.set()
        server.join()


@pytest.mark.slow
def test_a_replica_that_starts_before_its_database_waits_for_it(
    postgres_admin_url: str, caplog: pytest.LogCaptureFixture
) -> None:
    with postgres_database(postgres_admin_url) as url:
        server = make_url(url)
        socket_folder = server.query.get("host")  # a server on a Unix socket only: ?host=FOLDER
        target: tuple[str, int] | str = (str(server.host), int(server.port or 5432))
        if isinstance(socket_folder, str):
            target = f"{socket_folder}/.s.PGSQL.{server.port or 5432}"
        with forwarded_later(target, after=1.0) as port:
            forwarded = server.set(host="127.0.0.1", port=port).difference_update_query(["host"])
            engine = create_database_engine(forwarded.render_as_string(False))
            try:
                with caplog.at_level(logging.WARNING, logger="causalplan.service.storage.migrate"):
                    assert upgrade(engine, wait_seconds=30) == head_revision()
                assert current_revision(engine) == head_revision()
            finally:
                engine.dispose()
    assert any("database not up yet" in record.getMessage() for record in caplog.records)


@pytest.mark.slow
def test_health_says_degraded_when_the_database_takes_no_writes(postgres_admin_url: str) -> None:
    import psycopg

    with postgres_database(postgres_admin_url) as url, running_client(settings_for(url, planning_workers=1)) as client:
        assert client.get("/health").json()["database"]["problem"] is None
        admin = make_url(postgres_admin_url).set(drivername="postgresql").render_as_string(hide_password=False)
        with psycopg.connect(admin, autocommit=True) as connection:
            connection.execute(f'ALTER DATABASE "{make_url(url).database}" SET default_transaction_read_only = on')
        services_of(client).engine.dispose()  # new connections get the new default
        health = client.get("/health").json()
        assert health["status"] == "degraded" and health["database"]["problem"] == "the database server is read-only"
