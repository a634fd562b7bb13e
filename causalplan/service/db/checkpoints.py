"""SQLite's WAL checkpoints, moved off the requests onto a thread of their own.

By default SQLite checkpoints inside whichever commit brings its write-ahead log over 1000
pages: with ``synchronous=NORMAL`` that commit also syncs the database file, which took ~25 ms
here, once in ~330 commits of a 3 KB row (a standalone sqlite3 loop). The service turns that off on its connections
(``create_database_engine(..., background_checkpoints=True)``) and runs this thread instead: a
PASSIVE checkpoint (it never waits for readers or writers, and writers never wait for it) once
a second. With nothing new in the log one costs ~0.01 ms. The log is then reused from its
start, so it stays about one second of writes long.
"""

from __future__ import annotations

import logging
import threading

from sqlalchemy import Engine

logger = logging.getLogger(__name__)

INTERVAL_SECONDS = 1.0


class WalCheckpointer:
    """A daemon thread that checkpoints a SQLite engine's log every ``interval`` seconds, until ``stop``."""

    def __init__(self, engine: Engine, interval: float = INTERVAL_SECONDS) -> None:
        self.engine = engine
        self.interval = interval
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="causalplan-wal-checkpoints", daemon=True)
        self.checkpoints = 0
        """Checkpoints run so far."""

    def start(self) -> None:
        self._thread.start()

    def checkpoint(self) -> tuple[int, int, int]:
        """Run one PASSIVE checkpoint; return SQLite's (busy, log frames, frames checkpointed)."""
        connection = self.engine.raw_connection()
        try:
            cursor = connection.cursor()
            busy, frames, done = cursor.execute("PRAGMA wal_checkpoint(PASSIVE)").fetchone()
            cursor.close()
        finally:
            connection.close()
        self.checkpoints += 1
        return int(busy), int(frames), int(done)

    def _run(self) -> None:
        while not self._stopping.wait(self.interval):
            try:
                self.checkpoint()
            except Exception:
                logger.warning("the SQLite checkpoint failed; retrying in %g s", self.interval, exc_info=True)

    def stop(self) -> None:
        """Stop the thread (the last connection to close checkpoints what is left)."""
        self._stopping.set()
        if self._thread.is_alive():
            self._thread.join()
