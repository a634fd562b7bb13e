"""Bringing a database to the newest schema with the Alembic migrations shipped in the package.

``causalplan serve`` calls ``upgrade`` on start, so a fresh machine needs no manual step.
To add a revision after changing ``models.py`` (from a checkout)::

    python -m causalplan.service.storage.migrate revision "what changed"
"""

from __future__ import annotations

import fcntl
import logging
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import Connection, Engine, text
from sqlalchemy.exc import OperationalError, SQLAlchemyError

from causalplan.service.errors import StorageError
from causalplan.service.storage.session import sqlite_path

SCRIPT_LOCATION = "causalplan.service.storage:migrations"
_MIGRATION_LOCK_ID = 0x63617573  # any constant: PostgreSQL advisory lock held while migrating
_LONGEST_PAUSE_SECONDS = 5.0

logger = logging.getLogger(__name__)


def alembic_config(connection: Connection | None = None, url: str | None = None) -> Config:
    """Return an Alembic config for the shipped migrations, on ``connection`` or ``url``."""
    config = Config()
    config.set_main_option("script_location", SCRIPT_LOCATION)
    if url is not None:
        config.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    if connection is not None:
        config.attributes["connection"] = connection
    return config


def head_revision() -> str:
    """Return the newest revision the package ships."""
    head = ScriptDirectory.from_config(alembic_config()).get_current_head()
    assert head is not None, "the package ships no migration"
    return head


def current_revision(engine: Engine) -> str | None:
    """Return the database's revision (None before the first migration)."""
    with engine.connect() as connection:
        return MigrationContext.configure(connection).get_current_revision()


@contextmanager
def _sqlite_file_lock(engine: Engine) -> Iterator[None]:
    """Hold an exclusive lock on a file beside a SQLite database while it migrates (no-op for others).

    Two servers started at once on one SQLite file then migrate one after the other: SQLite's
    own busy wait would let both read the old revision before either wrote the new one.
    """
    path = sqlite_path(engine.url.render_as_string(hide_password=False))
    if path is None:
        yield
        return
    with open(path.with_name(path.name + ".migrate-lock"), "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def wait_until_up(engine: Engine, seconds: float) -> None:
    """Wait up to ``seconds`` for a database server to take a connection; StorageError if it does not.

    A replica or container often starts before its database does (or while it restarts). Any
    failure to connect (refused, not yet accepting, a name not yet resolvable) is tried again,
    after pauses that double up to five seconds; the error at the end names the last one.
    SQLite needs no server, so it is not waited for.
    """
    if engine.dialect.name == "sqlite":
        return
    deadline, pause = time.monotonic() + seconds, 0.25
    while True:
        try:
            with engine.connect():
                return
        except OperationalError as exc:
            cause, left = str(exc.orig).strip(), deadline - time.monotonic()
            if left <= 0:
                database = engine.url.render_as_string()
                raise StorageError(
                    f"The database {database} did not take a connection within {seconds:g} s "
                    f"(CAUSALPLAN_DATABASE_WAIT_SECONDS): {cause}",
                    details={"database": database},
                ) from None
            pause = min(pause * 2, _LONGEST_PAUSE_SECONDS, left)
            logger.warning("database not up yet (%s); trying again in %.1f s", cause, pause)
            time.sleep(pause)


def upgrade(engine: Engine, wait_seconds: float = 0.0) -> str:
    """Migrate the database to the newest schema; return its revision. StorageError says why not.

    A database server that does not take connections yet is waited for up to ``wait_seconds``
    (``wait_until_up``). Servers started together migrate once: a PostgreSQL advisory lock, or
    a file lock beside a SQLite database, makes the others wait and then find the schema up to
    date.
    """
    wait_until_up(engine, wait_seconds)
    try:
        with _sqlite_file_lock(engine), engine.begin() as connection:
            if connection.dialect.name == "postgresql":
                # Two servers starting at once on one database must not both create the tables.
                connection.execute(text("SELECT pg_advisory_xact_lock(:id)"), {"id": _MIGRATION_LOCK_ID})
            command.upgrade(alembic_config(connection), "head")
    except SQLAlchemyError as exc:
        raise StorageError(
            f"Cannot prepare the database {engine.url.render_as_string()}: {exc.__class__.__name__}: "
            f"{str(exc.orig if hasattr(exc, 'orig') else exc).strip()}",
            details={"database": engine.url.render_as_string()},
        ) from None
    except Exception as exc:  # noqa: BLE001 - e.g. a database stamped by a newer causalplan
        raise StorageError(
            f"Cannot migrate the database {engine.url.render_as_string()}: {exc}",
            details={"database": engine.url.render_as_string()},
        ) from None
    return head_revision()


def make_revision(message: str) -> None:
    """Write a new revision that takes the newest schema to ``models.py`` (autogenerated)."""
    from sqlalchemy import create_engine

    with tempfile.TemporaryDirectory() as folder:
        url = f"sqlite:///{Path(folder) / 'scratch.sqlite3'}"
        engine = create_engine(url)
        upgrade(engine)
        engine.dispose()
        command.revision(alembic_config(url=url), message=message, autogenerate=True)


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "revision":
        sys.exit('usage: python -m causalplan.service.storage.migrate revision "what changed"')
    make_revision(sys.argv[2])
