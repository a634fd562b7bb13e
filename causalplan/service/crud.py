"""Reading and writing the stored records; database failures become ``StorageError``.

Every write is one transaction: a trial and the inline model it was run with are stored
together or not at all.
"""

from __future__ import annotations

import sqlite3
import threading
import uuid
import weakref
from collections.abc import Callable, Iterator, Sequence
from contextlib import closing, contextmanager
from dataclasses import dataclass
from typing import Any

from sqlalchemy import Dialect, Engine, Table, func, insert, select
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import Session

from causalplan.service.db.models import MAX_CLIENT_ID_LENGTH, ModelRecord, TrialRecord, utc_now
from causalplan.service.errors import ModelNotFoundError, StorageError
from causalplan.service.limits import clean_json, clean_text

_SHORT_TEXT = 200


@dataclass(frozen=True)
class ClientIds:
    """Who sent a request, as the client says (``X-Participant-Id``, ``X-Session-Id``)."""

    participant_id: str | None = None
    session_id: str | None = None


@contextmanager
def storage_errors(session: Session | None = None, driver_errors: tuple[type[Exception], ...] = ()) -> Iterator[None]:
    """Turn database failures into StorageError, rolling back whatever ``session`` had begun.

    ``driver_errors``: the database driver's own errors too, for work done on its connection.
    """
    caught: tuple[type[Exception], ...] = (SQLAlchemyError, *driver_errors)
    try:
        yield
    except caught as exc:
        if session is not None:
            session.rollback()
        reason = str(getattr(exc, "orig", None) or exc).strip().splitlines()[0]
        raise StorageError(
            f"The database could not be used ({exc.__class__.__name__}: {reason}); nothing was stored.",
            details={"operation": "storage"},
        ) from None


def _short(text: str | None, length: int = _SHORT_TEXT) -> str | None:
    return None if text is None else clean_text(text)[:length]


def _new_record_fields(client: ClientIds) -> dict[str, Any]:
    """Return what every new record gets: a new id, the time now, and ``client``'s ids, cleaned and cut."""
    return {
        "id": uuid.uuid4(),
        "created_at": utc_now(),
        "participant_id": _short(client.participant_id, MAX_CLIENT_ID_LENGTH),
        "session_id": _short(client.session_id, MAX_CLIENT_ID_LENGTH),
    }


def new_model_record(
    document: dict[str, Any],
    object_id: str,
    is_valid: bool,
    report: dict[str, Any],
    canonical_hash: str | None,
    client: ClientIds,
    cleaned: bool = False,
) -> ModelRecord:
    """Return an unsaved record of a submitted model.

    ``cleaned``: ``document`` and ``report`` are ``clean_json``'s copies already (a request's
    document is cleaned as it is checked, and a report once per document read): not cleaned again.
    """
    return ModelRecord(
        **_new_record_fields(client),
        object_id=_short(object_id) or "",
        is_valid=is_valid,
        canonical_hash=canonical_hash,
        document=document if cleaned else clean_json(document),
        report=report if cleaned else clean_json(report),
    )


def new_trial_record(
    model_id: uuid.UUID,
    mapping: dict[str, Any],
    planner: str,
    verdict: dict[str, Any],
    cached: bool,
    seconds: float,
    client: ClientIds,
) -> TrialRecord:
    """Return an unsaved record of a transfer trial (``verdict`` is ``TransferVerdict.as_dict()``)."""
    return TrialRecord(
        **_new_record_fields(client),
        model_id=model_id,
        mapping=clean_json(mapping),
        training_object=_short(verdict.get("training_object")),
        test_object=_short(verdict.get("test_object")),
        planner=_short(planner, 64) or "",
        verdict=str(verdict["verdict"]),
        generalization=verdict.get("generalization"),
        decided_by=str(verdict["decided_by"]),
        cached=cached,
        seconds=seconds,
        result=clean_json(verdict),
    )


def _row(record: ModelRecord | TrialRecord) -> dict[str, Any]:
    return {column.key: getattr(record, column.key) for column in record.__table__.columns}


class _CompiledInsert:
    """A table's INSERT compiled once for a dialect, with each column's own bind processor.

    ``connection.execute(insert(table), rows)`` builds an execution context and runs its events
    on every call: ~0.15 ms of the ~0.3 ms that storing a request's record took in SQLite, on
    the path that answers a repeated plan in ~1.5 ms. The values go through the processors Core
    uses, so they are stored exactly as Core stores them (tests compare the stored rows with Core's).
    """

    def __init__(self, table: Table, dialect: Dialect) -> None:
        compiled = insert(table).compile(dialect=dialect)
        self.statement = str(compiled)
        self.positional = compiled.positional
        self.names = list(compiled.positiontup or ()) if compiled.positional else list(compiled.params)
        self._positions = {name: position for position, name in enumerate(self.names)}
        self.processors: list[Callable[[Any], Any] | None] = [
            table.columns[name].type.dialect_impl(dialect).bind_processor(dialect) for name in self.names
        ]

    def parameters(self, rows: list[dict[str, Any]]) -> list[list[Any]] | list[dict[str, Any]]:
        """Return the driver's parameters for ``rows``: value lists or dicts, as its paramstyle wants."""
        values = [
            [
                row[name] if processor is None else processor(row[name])
                for name, processor in zip(self.names, self.processors, strict=True)
            ]
            for row in rows
        ]
        return values if self.positional else [dict(zip(self.names, row, strict=True)) for row in values]

    def replaced(self, parameters: list[Any] | dict[str, Any], changes: dict[str, Any]) -> list[Any] | dict[str, Any]:
        """Return a copy of one row's ``parameters`` with the columns in ``changes`` set to new values (converted)."""
        converted = {name: self._convert(name, value) for name, value in changes.items()}
        if isinstance(parameters, dict):
            return parameters | converted
        copy = list(parameters)
        for name, value in converted.items():
            copy[self._positions[name]] = value
        return copy

    def _convert(self, name: str, value: Any) -> Any:
        processor = self.processors[self._positions[name]]
        return value if processor is None else processor(value)


_inserts: weakref.WeakKeyDictionary[Engine, dict[str, _CompiledInsert]] = weakref.WeakKeyDictionary()
_inserts_lock = threading.Lock()


def _compiled_insert(engine: Engine, kind: type[ModelRecord | TrialRecord]) -> _CompiledInsert:
    """Return the compiled INSERT of ``kind``'s table for ``engine`` (compiled once; forgotten with the engine)."""
    table = kind.__table__
    assert isinstance(table, Table)
    with _inserts_lock:
        by_table = _inserts.setdefault(engine, {})
        compiled = by_table.get(table.name)
        if compiled is None:
            compiled = by_table[table.name] = _CompiledInsert(table, engine.dialect)
        return compiled


def _insert(cursor: Any, engine: Engine, records: Sequence[ModelRecord | TrialRecord]) -> None:
    for kind in (ModelRecord, TrialRecord):  # models first: trials refer to them
        rows = [_row(record) for record in records if isinstance(record, kind)]
        if not rows:
            continue
        compiled = _compiled_insert(engine, kind)
        parameters = compiled.parameters(rows)
        if len(parameters) == 1:
            cursor.execute(compiled.statement, parameters[0])
        else:
            cursor.executemany(compiled.statement, parameters)


def save(engine: Engine, records: Sequence[ModelRecord | TrialRecord]) -> None:
    """Store new ``records`` (as ``new_model_record`` and ``new_trial_record`` make them) in one transaction.

    Plain INSERTs on a pooled driver connection, compiled once (see ``_CompiledInsert``), rather
    than a session's unit of work. The records stay as they were built (not attached to any session).
    """
    with storage_errors(driver_errors=(engine.dialect.loaded_dbapi.Error,)):
        connection = engine.raw_connection()
        try:
            cursor = connection.cursor()
            _insert(cursor, engine, records)
            cursor.close()
            connection.commit()
        finally:
            connection.close()  # back to the pool, which rolls back what was not committed


def _is_busy(error: sqlite3.OperationalError) -> bool:
    code = getattr(error, "sqlite_errorcode", None)
    return code is not None and code & 0xFF in (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED)


class NoWaitWriter:
    """A SQLite connection of the event loop's own, which stores records only when that needs no waiting.

    For the event loop, which must never wait for a database. Only SQLite qualifies (``open``
    gives None for others: their writes are round trips to a server). Its writes are local
    (~0.2 ms for a request's record, as the service runs it: WAL, no sync per commit,
    checkpoints in the background), and this connection's busy timeout is 0 for good, so a write
    lock held by another connection answers False at once instead of after up to 10 s. False
    means that nothing was stored; ``save`` (in a thread) is the way then.

    The connection is taken out of the engine's pool once: a pooled one had its busy timeout
    read, set and set back, and was checked out and returned, for every record (~0.1 ms of the
    ~1.1 ms that answering a repeated request took in the app). One caller at a time: a second
    caller meanwhile (there is none on one event loop) is answered False rather than made to wait.
    """

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        pooled = engine.raw_connection()
        pooled.detach()  # closed by ``close``, never returned to the pool
        self._pooled = pooled
        self._connection: sqlite3.Connection = pooled.dbapi_connection  # type: ignore[assignment]
        self._connection.execute("PRAGMA busy_timeout=0")
        self._lock = threading.Lock()

    @classmethod
    def open(cls, engine: Engine) -> NoWaitWriter | None:
        """Return a writer for a SQLite ``engine``; None for other databases."""
        if engine.dialect.name != "sqlite":
            return None
        with storage_errors(driver_errors=(sqlite3.Error,)):
            return cls(engine)

    def save(self, records: Sequence[ModelRecord | TrialRecord]) -> bool:
        """Store ``records`` as ``save`` does, if that needs no waiting; return whether they were stored."""
        return self._write(lambda cursor: _insert(cursor, self.engine, records))

    def save_prepared(self, row: PreparedModelRow, client: ClientIds) -> uuid.UUID | None:
        """Store ``row`` as a new model record of ``client``'s, if that needs no waiting; return its id, or None."""
        model_id, parameters = row.new(client)
        stored = self._write(lambda cursor: cursor.execute(row.statement, parameters))
        return model_id if stored else None

    def _write(self, insert: Callable[[sqlite3.Cursor], object]) -> bool:
        if not self._lock.acquire(blocking=False):
            return False
        try:
            with storage_errors(driver_errors=(sqlite3.Error,)), closing(self._connection.cursor()) as cursor:
                try:
                    insert(cursor)
                    self._connection.commit()
                except BaseException as exc:
                    self._connection.rollback()
                    if isinstance(exc, sqlite3.OperationalError) and _is_busy(exc):
                        return False
                    raise
                return True
        finally:
            self._lock.release()

    def close(self) -> None:
        """Close the connection (the app is stopping)."""
        with self._lock:
            self._pooled.close()


class PreparedModelRow:
    """A model record's INSERT parameters, converted once, for storing the same submission again and again.

    A repeated request (``repeats``) stores its model anew each time: ``new`` gives a new id and
    time and the client's ids; the rest (the document and the report as JSON) is kept as it was
    converted for the first record, which is what ``save`` would convert it to again.
    """

    def __init__(self, engine: Engine, record: ModelRecord) -> None:
        self._insert = _compiled_insert(engine, ModelRecord)
        self.statement = self._insert.statement
        self._parameters = self._insert.parameters([_row(record)])[0]
        values = self._parameters.values() if isinstance(self._parameters, dict) else self._parameters
        self.weight = sum(len(value) for value in values if isinstance(value, str))
        """The size of its text, for a cache's bound."""

    def new(self, client: ClientIds) -> tuple[uuid.UUID, list[Any] | dict[str, Any]]:
        """Return a new record's id and its parameters: this row, sent now by ``client``."""
        changes = _new_record_fields(client)
        return changes["id"], self._insert.replaced(self._parameters, changes)


def get_model(session: Session, model_id: uuid.UUID) -> ModelRecord:
    """Return the stored model with this id; ModelNotFoundError when there is none."""
    with storage_errors(session):
        record = session.get(ModelRecord, model_id)
    if record is None:
        raise ModelNotFoundError(f"There is no stored model with id {model_id}.", details={"model_id": str(model_id)})
    return record


def list_trials(
    session: Session,
    offset: int,
    limit: int,
    participant_id: str | None = None,
    session_id: str | None = None,
) -> tuple[list[TrialRecord], int]:
    """Return a page of trials (newest first) and how many match the filters in all."""
    query = select(TrialRecord)
    if participant_id is not None:
        query = query.where(TrialRecord.participant_id == participant_id)
    if session_id is not None:
        query = query.where(TrialRecord.session_id == session_id)
    with storage_errors(session):
        count = session.scalar(select(func.count()).select_from(query.subquery())) or 0
        page = session.scalars(
            query.order_by(TrialRecord.created_at.desc(), TrialRecord.id).offset(offset).limit(limit)
        ).all()
    return list(page), count


def all_records(session: Session) -> tuple[list[ModelRecord], list[TrialRecord]]:
    """Return every stored model and trial, oldest first."""
    with storage_errors(session):
        models = session.scalars(select(ModelRecord).order_by(ModelRecord.created_at, ModelRecord.id)).all()
        trials = session.scalars(select(TrialRecord).order_by(TrialRecord.created_at, TrialRecord.id)).all()
    return list(models), list(trials)
