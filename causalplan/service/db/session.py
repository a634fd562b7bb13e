"""Connecting to the database: one engine per app, SQLite tuned for a web server's threads."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url

from causalplan.service.errors import StorageError


def sqlite_path(url: str) -> Path | None:
    """Return the file of a SQLite URL (None for other databases and in-memory SQLite)."""
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite" or not parsed.database or parsed.database == ":memory:":
        return None
    return Path(parsed.database)


def _tune_sqlite(dbapi_connection: Any, _record: object, background_checkpoints: bool = False) -> None:
    cursor = dbapi_connection.cursor()
    # WAL lets readers work while one thread writes; the busy timeout makes writers queue up
    # instead of failing with "database is locked"; foreign keys are off by default in SQLite.
    # synchronous=NORMAL (with WAL): a commit is not synced to disk by itself, only at WAL
    # checkpoints, so storing a request costs ~0.1 ms rather than an fsync. A committed record
    # survives the service crashing; an OS crash or power cut may lose the last commits (never
    # corrupt the file). Use PostgreSQL where every commit must survive a power cut.
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute("PRAGMA busy_timeout=10000")
    cursor.execute("PRAGMA foreign_keys=ON")
    if background_checkpoints:  # a WalCheckpointer checkpoints instead of the commits (see its module)
        cursor.execute("PRAGMA wal_autocheckpoint=0")
    cursor.close()


def create_database_engine(url: str, background_checkpoints: bool = False) -> Engine:
    """Return an engine for ``url``; a SQLite file's folder is created if it is missing.

    ``background_checkpoints``: SQLite's commits never checkpoint its log; the caller runs a
    ``WalCheckpointer`` (as the service does). Ignored for other databases.
    """
    try:
        parsed = make_url(url)
    except Exception as exc:  # noqa: BLE001 - SQLAlchemy raises several types for a bad URL
        raise StorageError(f"The database URL is not valid: {exc}", details={"setting": "database_url"}) from None
    path = sqlite_path(url)
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StorageError(
                f"Cannot create the folder of the SQLite database {path}: {exc.strerror}.", details={"path": str(path)}
            ) from None
    try:
        if parsed.get_backend_name() == "sqlite":
            engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": 10})

            def tune(dbapi_connection: Any, record: object) -> None:
                _tune_sqlite(dbapi_connection, record, background_checkpoints)

            event.listen(engine, "connect", tune)
        else:
            engine = create_engine(url, pool_pre_ping=True, pool_size=10, max_overflow=20)
    except Exception as exc:  # noqa: BLE001 - a missing driver or a bad option, reported as such
        raise StorageError(f"Cannot use the database {parsed.render_as_string()}: {exc}") from None
    return engine
