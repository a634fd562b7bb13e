"""Storage is an allowance: models and trials count with jobs; anonymous rows expire and give their space back."""

from __future__ import annotations

import sqlite3
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import Engine, func, select
from sqlalchemy.orm import Session

from causalplan.service.errors import StorageFullError
from causalplan.service.owners import key_owner, storage_allowance
from causalplan.service.storage import crud
from causalplan.service.storage.allowance import AUTO_VACUUM_INCREMENTAL, Allowance, stored_bytes
from causalplan.service.storage.records import ModelRecord, TrialRecord, utc_now
from causalplan.settings import Settings
from tests.service.fixtures import (
    API_KEY,
    DESK_LAMP,
    KEY_AUTH,
    TEST_CLIENT_OWNER,
    error_of,
    first_trials,
    migrated_engine,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    with_unique_effect,
)

ANONYMOUS = Allowance("address:198.51.100.4", 200_000, 3600.0)


def _model(client: crud.ClientIds, padding: int = 0) -> ModelRecord:
    document = {**DESK_LAMP, "padding": "x" * padding}
    return crud.new_model_record(document, "desk_lamp", True, {}, None, client)


def _pages(path: Path) -> tuple[int, int]:
    with sqlite3.connect(path) as connection:
        return connection.execute("PRAGMA page_count").fetchone()[0], connection.execute(
            "PRAGMA freelist_count"
        ).fetchone()[0]


def test_each_client_has_its_allowance_by_kind() -> None:
    settings = Settings(anonymous_job_megabytes=2, job_megabytes=50, anonymous_record_hours=5)
    assert storage_allowance("address:1.2.3.4", settings) == Allowance("address:1.2.3.4", 2_000_000, 5 * 3600)
    assert storage_allowance(key_owner(API_KEY), settings) == Allowance(key_owner(API_KEY), 50_000_000, None)
    assert storage_allowance("research", settings) == Allowance("research", None, None)
    assert storage_allowance("participant:abc", settings) is None  # the pages' rows are their study's


def test_rows_past_the_allowance_are_refused_and_nothing_is_stored(tmp_path: Path) -> None:
    engine = migrated_engine(tmp_path)
    client = crud.ClientIds(allowance=ANONYMOUS)
    crud.save(engine, [_model(client, 150_000)], client)
    with pytest.raises(StorageFullError) as refused:
        crud.save(engine, [_model(client, 60_000)], client)
    assert 1 <= refused.value.retry_after <= 3600
    with Session(engine) as session:
        assert session.scalar(select(func.count()).select_from(ModelRecord)) == 1
        assert 150_000 < stored_bytes(session, ANONYMOUS.owner, utc_now()) <= ANONYMOUS.limit_bytes
    other = crud.ClientIds(allowance=Allowance("address:203.0.113.1", 200_000, 3600.0))
    crud.save(engine, [_model(other, 60_000)], other)  # another client's allowance is its own
    engine.dispose()


def test_expired_anonymous_rows_are_purged_and_the_file_shrinks(tmp_path: Path) -> None:
    engine = migrated_engine(tmp_path)
    path = tmp_path / "causalplan.sqlite3"
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA auto_vacuum").scalar() == AUTO_VACUUM_INCREMENTAL
    anonymous = crud.ClientIds(allowance=Allowance("address:198.51.100.4", None, 60.0))
    keyed = crud.ClientIds(allowance=Allowance(key_owner(API_KEY), None, None))
    kept_model = _model(anonymous)
    verdict: dict[str, Any] = {"verdict": "transfers", "decided_by": "planner", "note": "y" * 50_000}
    for _ in range(40):
        model = _model(anonymous, 50_000)
        crud.save(engine, [model, crud.new_trial_record(model.id, {}, "fd", verdict, False, 0.1, anonymous)])
    crud.save(engine, [kept_model, crud.new_trial_record(kept_model.id, {}, "fd", verdict, False, 0.1, keyed)])
    full_pages, _ = _pages(path)
    assert crud.purge_expired_records(engine, utc_now()) == 0  # not yet
    later = utc_now() + timedelta(seconds=61)
    assert crud.purge_expired_records(engine, later) == 80  # 40 trials, 40 models; one model a key's trial uses
    with Session(engine) as session:
        assert session.scalar(select(func.count()).select_from(TrialRecord)) == 1
        assert session.get(ModelRecord, kept_model.id) is not None
    pages, free = _pages(path)
    assert free == 0 and pages < full_pages / 4  # the space went back to the file system
    engine.dispose()


def test_an_older_file_is_converted_on_its_first_purge(tmp_path: Path) -> None:
    path = tmp_path / "causalplan.sqlite3"
    with sqlite3.connect(path) as connection:  # made before incremental vacuuming: auto_vacuum off
        connection.execute("CREATE TABLE filler (x TEXT)")
    engine = migrated_engine(tmp_path)
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA auto_vacuum").scalar() == 0
    anonymous = crud.ClientIds(allowance=Allowance("address:198.51.100.4", None, 1.0))
    crud.save(engine, [_model(anonymous, 100_000)])
    assert crud.purge_expired_records(engine, utc_now() + timedelta(seconds=2)) == 1
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA auto_vacuum").scalar() == AUTO_VACUUM_INCREMENTAL
    assert _pages(path)[1] == 0
    engine.dispose()


def test_plans_fill_an_anonymous_clients_allowance_then_jobs_and_plans_get_429(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), job_runners=0, anonymous_job_megabytes=0.005)
    with running_client(settings) as client:
        refused = None
        for _ in range(40):
            answer = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
            if answer.status_code == 429:
                refused = answer
                break
            assert answer.status_code == 200, answer.text
        assert refused is not None, "the allowance never filled"
        assert error_of(refused, 429)["code"] == "storage_full"
        assert int(refused.headers["Retry-After"]) <= settings.anonymous_record_hours * 3600
        engine: Engine = services_of(client).engine
        with Session(engine) as session:
            assert stored_bytes(session, TEST_CLIENT_OWNER, utc_now()) <= 5_000
            rows = session.scalars(select(ModelRecord.expires_at).where(ModelRecord.owner == TEST_CLIENT_OWNER)).all()
            assert rows and all(expires is not None for expires in rows)
        job = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(1), "simulate": False})
        assert error_of(job, 429)["code"] == "job_storage_full"  # one allowance for jobs, models and trials
        keyed = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}, headers=KEY_AUTH)
        assert keyed.status_code == 200, keyed.text
