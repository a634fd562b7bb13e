"""Storage on SQLite and on a real PostgreSQL: migrations, one transaction per request, odd text, outages."""

from __future__ import annotations

import json
import time
import uuid
from pathlib import Path
from typing import Any

import pytest
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from fastapi.testclient import TestClient
from sqlalchemy import func, insert, inspect, select
from sqlalchemy.orm import Session

from causalplan.service import crud
from causalplan.service.db.migrate import current_revision, head_revision, upgrade
from causalplan.service.db.models import Base, ModelRecord, TrialRecord
from causalplan.service.db.session import create_database_engine
from causalplan.service.errors import StorageError
from tests.service_fixtures import (
    AUTH,
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    error_of,
    postgres_database,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    sqlite_write_lock,
    sqlite_write_lock_for_a_moment,
)


def test_migrations_build_exactly_the_models_schema(database_url: str) -> None:
    engine = create_database_engine(database_url)
    try:
        assert current_revision(engine) is None
        assert upgrade(engine) == head_revision() == "0003"
        assert upgrade(engine) == "0003"  # a second start changes nothing
        assert set(inspect(engine).get_table_names()) == {
            "alembic_version",
            "models",
            "trials",
            "experiments",
            "participants",
            "participant_trials",
            "revoked_research_sessions",
        }
        with engine.connect() as connection:
            differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)
        assert differences == []
    finally:
        engine.dispose()


def test_a_sqlite_file_and_its_folder_are_created_on_first_start(tmp_path: Any) -> None:
    path = tmp_path / "new" / "folder" / "causalplan.sqlite3"
    with running_client(settings_for(f"sqlite:///{path}", planning_workers=1)) as client:
        assert client.get("/health").json()["database"]["revision"] == "0003"
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


_DIFFERING = {"id", "participant_id", "model_id"}
"""The columns in which the records of ``_records("fast")`` and ``_records("core")`` differ."""


def _stored(engine: Any, record: ModelRecord | TrialRecord) -> dict[str, Any]:
    """The record's row as the driver returns it (no SQLAlchemy type processing), but for ``_DIFFERING``.

    The database is the test's own, so the participant finds the row.
    """
    with engine.connect() as connection:
        rows = connection.exec_driver_sql(f"SELECT * FROM {record.__table__.name}").mappings().all()
    [row] = [row for row in rows if row["participant_id"] == record.participant_id]
    return {key: value for key, value in row.items() if key not in _DIFFERING}


def test_saved_records_are_stored_exactly_as_core_stores_them(database_url: str) -> None:
    """save() runs its INSERTs on the driver's connection, with the columns' own bind processors."""
    engine = create_database_engine(database_url)
    upgrade(engine)
    fast_model, fast_trial = _records("fast")
    crud.save(engine, [fast_model, fast_trial])
    core_model, core_trial = _records("core")
    core_model.created_at, core_trial.created_at = fast_model.created_at, fast_trial.created_at
    with engine.begin() as connection:
        connection.execute(insert(ModelRecord), [crud._row(core_model)])
        connection.execute(insert(TrialRecord), [crud._row(core_trial)])
    assert _stored(engine, fast_model) == _stored(engine, core_model)
    assert _stored(engine, fast_trial) == _stored(engine, core_trial)
    with Session(engine) as session:  # and read back through the ORM, the same values too
        for fast, core in ((fast_model, core_model), (fast_trial, core_trial)):
            fast_stored, core_stored = session.get(type(fast), fast.id), session.get(type(core), core.id)
            assert fast_stored is not None and core_stored is not None
            for column in fast.__table__.columns:
                if column.key not in _DIFFERING:
                    assert getattr(fast_stored, column.key) == getattr(core_stored, column.key), column.key
    engine.dispose()


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


def test_saving_without_waiting_stores_on_sqlite_and_only_there(database_url: str) -> None:
    engine = create_database_engine(database_url, background_checkpoints=True)
    upgrade(engine)
    writer = crud.NoWaitWriter.open(engine)
    assert (writer is not None) is (engine.dialect.name == "sqlite")  # a server's round trips are never made at once
    if writer is not None:
        model, trial = _records("at-once")
        assert writer.save([model, trial]) is True
        assert _count(engine, "at-once") == (1, 1)
        writer.close()
    engine.dispose()


def test_a_prepared_row_is_stored_as_core_stores_the_same_record(tmp_path: Path) -> None:
    """A repeated request's record: the document and report converted once, id, time and client ids new."""
    engine = create_database_engine(sqlite_url(tmp_path), background_checkpoints=True)
    upgrade(engine)
    writer = crud.NoWaitWriter.open(engine)
    assert writer is not None
    first, _ = _records("first")
    row = crud.PreparedModelRow(engine, first)
    ids = [writer.save_prepared(row, crud.ClientIds("fast", "séance ☃")) for _ in range(2)]
    assert ids[0] is not None and ids[1] is not None and ids[0] != ids[1]  # a record per request
    with Session(engine) as session:
        stored = session.get(ModelRecord, ids[0])
        assert stored is not None and stored.participant_id == "fast" and stored.session_id == "séance ☃"
        assert stored.created_at > first.created_at.replace(tzinfo=None)  # its own time (SQLite's are naive)
        created_at = stored.created_at
    core, _ = _records("core")
    core.created_at = created_at
    with engine.begin() as connection:
        connection.execute(insert(ModelRecord), [crud._row(core)])
    [fast_row] = [row for row in _rows(engine, "models") if row["id"] == ids[0].hex]
    [core_row] = [row for row in _rows(engine, "models") if row["participant_id"] == "core"]
    assert {**fast_row, "id": None, "participant_id": None} == {**core_row, "id": None, "participant_id": None}
    # A client id is stored cleaned and cut to length, as new_model_record stores it.
    nul_id = writer.save_prepared(row, crud.ClientIds("a\x00b" + "x" * 300, None))
    with Session(engine) as session:
        stored = session.get(ModelRecord, nul_id)
        assert stored is not None and stored.participant_id == ("a\ufffdb" + "x" * 300)[:128]
        assert stored.session_id is None
    writer.close()
    engine.dispose()


def _rows(engine: Any, table: str) -> list[dict[str, Any]]:
    with engine.connect() as connection:
        return [dict(row) for row in connection.exec_driver_sql(f"SELECT * FROM {table}").mappings().all()]


def test_saving_without_waiting_gives_way_to_a_held_write_lock(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    engine = create_database_engine(url, background_checkpoints=True)
    upgrade(engine)
    writer = crud.NoWaitWriter.open(engine)
    assert writer is not None
    model, _ = _records("locked")
    with sqlite_write_lock(url):
        assert writer.save([model]) is False  # at once, not after the 10 s busy timeout
        assert writer.save_prepared(crud.PreparedModelRow(engine, model), crud.ClientIds("locked")) is None
    assert _count(engine, "locked") == (0, 0)
    assert writer.save([model]) is True  # the lock is free again: the same connection stores
    assert _count(engine, "locked") == (1, 0)
    # A failed write (NOT NULL) stores nothing, raises StorageError, and leaves the connection usable.
    failed, failed_trial = _records("refused")
    failed_trial.verdict = None  # type: ignore[assignment]
    with pytest.raises(StorageError, match="nothing was stored"):
        writer.save([failed, failed_trial])
    assert _count(engine, "refused") == (0, 0)
    after, _ = _records("after")
    assert writer.save([after]) is True
    # The pooled connections wait for a lock (their busy timeout is the engine's): a save made
    # while another connection holds the lock for a moment succeeds once the lock is free.
    model, _ = _records("waited")
    with sqlite_write_lock_for_a_moment(url):
        crud.save(engine, [model])
    assert _count(engine, "waited") == (1, 0)
    writer.close()
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA busy_timeout").scalar() == 10_000
    engine.dispose()


def test_the_service_checkpoints_sqlite_off_the_requests(tmp_path: Path) -> None:
    """Its commits never checkpoint the log (autocheckpoint 0); its checkpointer does, in the background."""
    url = sqlite_url(tmp_path)
    with running_client(settings_for(url)) as client:
        services = services_of(client)
        with services.engine.connect() as connection:
            assert connection.exec_driver_sql("PRAGMA wal_autocheckpoint").scalar() == 0
        assert client.post("/v1/plans", json={"model": DESK_LAMP}).status_code == 200
        checkpointer = services.checkpointer
        assert checkpointer is not None
        busy, frames, done = checkpointer.checkpoint()
        assert busy == 0 and frames > 0 and done == frames  # the model's record was in the log, now in the file
        ran = checkpointer.checkpoints
        deadline = time.monotonic() + 10
        while checkpointer.checkpoints == ran and time.monotonic() < deadline:  # its thread, once a second
            time.sleep(0.05)
        assert checkpointer.checkpoints > ran
    plain = create_database_engine(url)  # other users of the database keep SQLite's own checkpoints
    with plain.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA wal_autocheckpoint").scalar() == 1000
    plain.dispose()


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
        health = client.get("/health").json()
        assert health["status"] == "degraded"
        assert health["database"]["reachable"] is False and health["database"]["problem"]
        assert client.post("/v1/plans", json={"model_id": str(uuid.uuid4())}).status_code == 503


def test_a_database_that_cannot_be_reached_at_start_is_a_clear_error() -> None:
    engine = create_database_engine("postgresql+psycopg://nobody@127.0.0.1:1/none")
    with pytest.raises(StorageError, match="Cannot prepare the database"):
        upgrade(engine)
    with pytest.raises(StorageError, match="not valid"):
        create_database_engine("not a url")
