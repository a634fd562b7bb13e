"""One client's storage allowance: the bytes its jobs, models and trials keep stored until they expire.

A job's request and result, and every model and trial a client's plans, transfers and
explanations store, count against one allowance per owner (``service.owners``): a client
cannot fill the disk through the routes that are not jobs. Rows of clients without a key that
belong to no experiment expire (``anonymous_record_hours``); ``crud.purge_expired_records``
deletes them and ``give_space_back`` returns the space (SQLite: ``PRAGMA incremental_vacuum``;
PostgreSQL's autovacuum does it by itself).
"""

from __future__ import annotations

import json
import logging
import sqlite3
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import Engine, func, or_, select, text
from sqlalchemy.orm import InstrumentedAttribute, Session
from sqlalchemy.sql.elements import ColumnElement

from causalplan.service.storage.records import JobRecord, ModelRecord, TrialRecord

logger = logging.getLogger(__name__)

_WRITE_LOCK_ID = 0x6A6F6273
"""PostgreSQL advisory lock held while an owner's rows are counted and one is added (jobs, models, trials)."""
AUTO_VACUUM_INCREMENTAL = 2
"""SQLite's ``PRAGMA auto_vacuum`` value for INCREMENTAL: freed pages are kept on a list a vacuum returns."""


@dataclass(frozen=True)
class Allowance:
    """Whose allowance a request's stored rows count in, how many bytes it holds, how long they are kept.

    ``limit_bytes`` None: no limit (the research token's); ``keep_seconds`` None: kept for good.
    """

    owner: str
    limit_bytes: int | None
    keep_seconds: float | None


def json_size(value: object) -> int:
    """Return the bytes ``value`` takes stored as JSON (as the JSON columns write it)."""
    return len(json.dumps(value).encode("utf-8", "surrogatepass"))


def _live(expires_at: InstrumentedAttribute[datetime | None], now: datetime) -> ColumnElement[bool]:
    return or_(expires_at.is_(None), expires_at > now)


def stored_bytes(session: Session, owner: str, now: datetime) -> int:
    """Return the bytes ``owner``'s jobs, models and trials keep stored and have not expired."""
    jobs = select(func.sum(JobRecord.request_bytes + JobRecord.result_bytes)).where(
        JobRecord.owner == owner, _live(JobRecord.expires_at, now)
    )
    models = select(func.sum(ModelRecord.stored_bytes)).where(
        ModelRecord.owner == owner, _live(ModelRecord.expires_at, now)
    )
    trials = select(func.sum(TrialRecord.stored_bytes)).where(
        TrialRecord.owner == owner, _live(TrialRecord.expires_at, now)
    )
    return sum(int(session.scalar(query) or 0) for query in (jobs, models, trials))


def first_expiry(session: Session, owner: str, now: datetime) -> datetime | None:
    """Return when the first of ``owner``'s stored rows expires (None: none ever does)."""
    times = [
        session.scalar(select(func.min(table.expires_at)).where(table.owner == owner, table.expires_at > now))
        for table in (JobRecord, ModelRecord, TrialRecord)
    ]
    found = [time for time in times if time is not None]
    return min(found, default=None)


def take_write_lock(session: Session) -> None:
    """Hold the write lock of stored rows in ``session``'s transaction until it ends (commit or rollback).

    Counting an owner's rows and adding one happen under it, so creators on every replica at
    once never take an owner (or the service) over a limit. SQLite: ``BEGIN IMMEDIATE`` takes
    the database's write lock before the first count (other writers wait, up to the busy
    timeout). PostgreSQL: a transaction-scoped advisory lock; each statement then sees every
    row committed by the creators before (READ COMMITTED).
    """
    dialect = session.get_bind().dialect.name
    if dialect == "postgresql":
        session.execute(text("SELECT pg_advisory_xact_lock(:id)"), {"id": _WRITE_LOCK_ID})
    elif dialect == "sqlite":
        session.execute(text("BEGIN IMMEDIATE"))


def give_space_back(engine: Engine) -> None:
    """Return the pages deleted rows freed to the file system (SQLite; PostgreSQL's autovacuum does it itself).

    A SQLite file made before incremental vacuuming was on is converted once (a full ``VACUUM``).
    """
    if engine.dialect.name != "sqlite":
        return
    with engine.connect() as connection:
        mode = connection.exec_driver_sql("PRAGMA auto_vacuum").scalar()
        if mode != AUTO_VACUUM_INCREMENTAL:
            logger.info("turning on SQLite's incremental vacuum (a full VACUUM, once)")
            connection.exec_driver_sql(f"PRAGMA auto_vacuum={AUTO_VACUUM_INCREMENTAL}")
            connection.exec_driver_sql("VACUUM")
        connection.commit()
        # The pragma frees one page per step; only the driver's executescript steps it to the end.
        driver = connection.connection.driver_connection
        assert isinstance(driver, sqlite3.Connection)
        driver.executescript("PRAGMA incremental_vacuum;")
