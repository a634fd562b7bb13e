"""Connecting to the database: one engine per app, SQLite tuned for a web server's threads."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url

from causalplan.service.errors import StorageError

WAL_SIZE_LIMIT_BYTES = 8 * 1024 * 1024
"""What SQLite truncates its write-ahead log to after a checkpoint (``PRAGMA journal_size_limit``)."""
WAL_CHECKPOINT_PAGES = 1000
"""SQLite checkpoints the log when a commit brings it over this many pages (its default, said out loud)."""
CONNECT_TIMEOUT_SECONDS = 10
"""How long a new PostgreSQL connection may take (libpq's ``connect_timeout``; a URL's own wins).
Without it, a server that takes the TCP connection but never answers holds the caller for as
long as the kernel keeps trying."""


def sqlite_path(url: str) -> Path | None:
    """Return the file of a SQLite URL (None for other databases and in-memory SQLite)."""
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite" or not parsed.database or parsed.database == ":memory:":
        return None
    return Path(parsed.database)


def _tune_sqlite(dbapi_connection: Any, _record: object) -> None:
    cursor = dbapi_connection.cursor()
    # WAL lets readers work while one thread writes; the busy timeout makes writers queue up
    # instead of failing with "database is locked"; foreign keys are off by default in SQLite.
    # synchronous=NORMAL (with WAL): a commit is synced at checkpoints, not by itself. A
    # committed record survives the service crashing; an OS crash or power cut may lose the last
    # commits (never corrupt the file). Use PostgreSQL where every commit must survive a power cut.
    # SQLite checkpoints by itself; journal_size_limit keeps the log file from staying as large
    # as its largest burst of writes.
    # Incremental vacuum: a purge gives freed pages back to the file system (storage.allowance).
    # It takes effect only in a file without tables yet; an older file is converted on its first purge.
    cursor.execute("PRAGMA auto_vacuum=INCREMENTAL")
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute("PRAGMA busy_timeout=10000")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute(f"PRAGMA wal_autocheckpoint={WAL_CHECKPOINT_PAGES}")
    cursor.execute(f"PRAGMA journal_size_limit={WAL_SIZE_LIMIT_BYTES}")
    cursor.close()


KEPT_CONNECTIONS = 5
"""Connections an engine keeps open between requests; more are opened (up to ``connections``) under load."""
DEFAULT_CONNECTIONS = 30
"""Connections at once of an engine not told the concurrency it serves (tools, tests)."""


def create_database_engine(url: str, connections: int = DEFAULT_CONNECTIONS) -> Engine:
    """Return an engine for ``url``; a SQLite file's folder is created if it is missing.

    ``connections``: how many threads may use the database at once (the server's request
    threads, job runners and background threads: ``Settings.database_connections``); the pool
    opens that many before a thread must wait, so a burst of requests never finds it exhausted.
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
            engine = create_engine(
                url, connect_args={"check_same_thread": False, "timeout": 10}, **_pool_sizes(connections)
            )
            event.listen(engine, "connect", _tune_sqlite)
        else:
            timeout = {} if "connect_timeout" in parsed.query else {"connect_timeout": CONNECT_TIMEOUT_SECONDS}
            engine = create_engine(url, pool_pre_ping=True, connect_args=timeout, **_pool_sizes(connections))
    except Exception as exc:  # noqa: BLE001 - a missing driver or a bad option, reported as such
        raise StorageError(f"Cannot use the database {parsed.render_as_string()}: {exc}") from None
    return engine


def _pool_sizes(connections: int) -> dict[str, int]:
    kept = min(KEPT_CONNECTIONS, connections)
    return {"pool_size": kept, "max_overflow": connections - kept}
