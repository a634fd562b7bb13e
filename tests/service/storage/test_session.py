"""The database engine's pool: sized to the concurrency the server allows."""

from __future__ import annotations

import threading
from pathlib import Path

from sqlalchemy import text
from sqlalchemy.pool import QueuePool

from causalplan.service.storage.session import create_database_engine
from causalplan.settings import Settings
from tests.service.fixtures import sqlite_url


def test_every_thread_the_server_allows_gets_a_connection_at_once(tmp_path: Path) -> None:
    settings = Settings(database_url=sqlite_url(tmp_path), planning_workers=2, queue_size=16, job_runners=1)
    threads = settings.database_connections
    assert threads >= settings.request_threads + settings.job_runners
    engine = create_database_engine(settings.database_url, threads)
    assert isinstance(engine.pool, QueuePool)
    assert engine.pool.size() + engine.pool._max_overflow == threads
    together = threading.Barrier(threads)
    failures: list[BaseException] = []

    def hold() -> None:
        try:
            with engine.connect() as connection:
                connection.execute(text("SELECT 1"))
                together.wait(30)  # every thread holds its connection at this moment
        except BaseException as exc:  # noqa: BLE001 - the test reads it
            failures.append(exc)

    workers = [threading.Thread(target=hold) for _ in range(threads)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    engine.dispose()
    assert failures == []


def test_more_waiting_solves_mean_more_threads_and_connections() -> None:
    small, large = Settings(queue_size=16), Settings(queue_size=200)
    assert small.request_threads == 40 and large.request_threads == 2 + 200 + 20
    assert large.database_connections > small.database_connections
