"""`causalplan serve`: a real uvicorn server on a free port, talked to over HTTP with httpx."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient

from causalplan.service.main import create_app
from tests.service.fixtures import (
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    free_port,
    is_running,
    settings_for,
    sqlite_url,
    wait_until,
)

START_SECONDS = 180.0
"""A bound on start-up to ready; the test waits for the signal, not this long."""


def children_of(pid: int) -> set[int]:
    """Return the ids of the processes whose parent is ``pid``."""
    children = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            children.add(int(stat.parent.name))
    return children


def serve(tmp_path: Path, *options: str) -> tuple[subprocess.Popen[str], str]:
    """Start ``causalplan serve`` on a free port; return the process and its base URL once it is ready.

    Ready (``/health/ready``): its planner pool has answered a plan, so the test's first plan
    does not wait for the workers to warm, however busy the machine is.
    """
    port = free_port()
    environment = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")}
    process = subprocess.Popen(
        [sys.executable, "-m", "causalplan.cli", "serve", "--port", str(port), *options],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=environment,
    )
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + START_SECONDS
    while time.monotonic() < deadline:
        if process.poll() is not None:
            pytest.fail(f"the server stopped: {process.communicate()[0]}")
        try:
            if httpx.get(f"{base}/health/ready", timeout=5).status_code == 200:
                return process, base
        except httpx.TransportError:
            pass
        time.sleep(0.1)  # a 503 (not ready yet) waits too: no stream of requests at the warming server
    process.kill()
    pytest.fail(f"the server was not ready within {START_SECONDS} s: {process.communicate()[0]}")


@pytest.mark.slow
def test_the_real_server_plans_stores_and_stops_cleanly(tmp_path: Path) -> None:
    process, base = serve(tmp_path, "--workers", "2")
    try:
        with httpx.Client(base_url=base, timeout=30) as client:
            health = client.get("/health").json()
            assert health["status"] == "ok" and health["pool"]["workers"] == 2
            assert health["database"]["backend"] == "sqlite"
            plan = client.post("/v1/plans", json={"model": DESK_LAMP}, headers={"X-Participant-Id": "real"})
            assert plan.status_code == 200
            assert plan.json()["plan"][0]["text"] == "Screw the light bulb into the base with cables."
            verdict = client.post("/v1/transfers", json={"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING}).json()
            assert verdict["verdict"] == "transfers"
            model = client.get(f"/v1/models/{plan.json()['model_id']}").json()
            assert model["participant_id"] == "real"
            assert client.get("/v1/nothing").json()["error"]["code"] == "not_found"
            assert client.get("/docs").status_code == 200
        helpers = children_of(process.pid)  # the fork server (and multiprocessing's resource tracker)
        workers = {worker for helper in helpers for worker in children_of(helper)}
        assert len(workers) >= 2  # forked by the fork server, never by the server itself
    finally:
        process.send_signal(signal.SIGINT)
        output = process.communicate(timeout=30)[0]
    assert process.returncode == 0, output
    assert "Application shutdown complete" in output
    assert "Traceback" not in output
    assert '"POST /v1/plans HTTP/1.1" 200' in output  # the access log is on by default
    assert not [pid for pid in workers if is_running(pid)]  # stopped before the server ended
    wait_until(lambda: not [pid for pid in helpers if is_running(pid)], 10.0)  # they see it gone and end
    # The default database: a SQLite file in the data folder, created on first start.
    assert (tmp_path / "data" / "causalplan" / "causalplan.sqlite3").exists()


@pytest.mark.slow
def test_the_access_log_can_be_turned_off(tmp_path: Path) -> None:
    process, base = serve(tmp_path, "--workers", "1", "--no-access-log")
    try:
        assert httpx.post(f"{base}/v1/plans", json={"model": DESK_LAMP}, timeout=30).status_code == 200
        assert httpx.get(f"{base}/v1/nothing", timeout=30).status_code == 404
    finally:
        process.send_signal(signal.SIGINT)
        output = process.communicate(timeout=30)[0]
    assert process.returncode == 0, output
    assert "Application startup complete" in output  # the rest of the log still comes
    assert "POST /v1/plans" not in output and "/v1/nothing" not in output


@pytest.mark.slow
def test_bad_settings_are_a_clear_error_not_a_traceback(tmp_path: Path) -> None:
    command = [sys.executable, "-m", "causalplan.cli", "serve", "--database-url", "mysql://nobody@127.0.0.1:1/x"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "error[storage_unavailable]" in result.stderr and "Traceback" not in result.stderr
    environment = {**os.environ, "CAUSALPLAN_MAX_TIME_LIMIT": "5", "CAUSALPLAN_DEFAULT_TIME_LIMIT": "30"}
    result = subprocess.run(
        [sys.executable, "-m", "causalplan.cli", "serve"], capture_output=True, text=True, timeout=60, env=environment
    )
    assert result.returncode == 2
    assert "error[invalid_settings]" in result.stderr and "max_time_limit" in result.stderr


def _exchange(connection: socket.socket, request: bytes) -> bytes:
    """Send one HTTP/1.1 request on a kept-alive ``connection``; return the whole response it answers."""
    connection.sendall(request)
    received = b""
    while b"\r\n\r\n" not in received:
        chunk = connection.recv(65536)
        assert chunk, "the server closed the connection"
        received += chunk
    head, _, body = received.partition(b"\r\n\r\n")
    length = int(next(line for line in head.split(b"\r\n") if line.lower().startswith(b"content-length:")).split()[1])
    while len(body) < length:
        chunk = connection.recv(65536)
        assert chunk, "the server closed the connection"
        body += chunk
    return head + b"\r\n\r\n" + body


@pytest.mark.slow
def test_a_bug_is_a_500_and_the_kept_alive_connection_still_serves(tmp_path: Path) -> None:
    import uvicorn

    app = create_app(settings_for(sqlite_url(tmp_path), planning_workers=1))

    def broken() -> None:
        raise RuntimeError("a bug in a route")

    app.add_api_route("/broken", broken)
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=free_port(), log_level="critical"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    wait_until(lambda: server.started or not thread.is_alive(), seconds=60)
    try:
        with socket.create_connection(("127.0.0.1", server.config.port), timeout=30) as connection:
            request = b"GET %s HTTP/1.1\r\nHost: test\r\n\r\n"
            first = _exchange(connection, request % b"/broken")
            assert first.startswith(b"HTTP/1.1 500") and b'"internal_error"' in first and b"a bug" not in first
            second = _exchange(connection, request % b"/v1/objects")  # the same connection
            assert second.startswith(b"HTTP/1.1 200") and b"desk_lamp" in second
    finally:
        server.should_exit = True
        thread.join(30)


@pytest.mark.parametrize("page", ["/docs", "/redoc"])
def test_the_api_docs_load_nothing_from_outside(client: TestClient, page: str) -> None:
    html = client.get(page)
    assert html.status_code == 200
    assert not re.findall(r"""(?:src|href)=["']?(?:https?:)?//""", html.text), html.text
    assets = re.findall(r"""(?:src|href)=["']?(/[^"'\s>]+)""", html.text)
    assert any(asset.endswith(".js") for asset in assets)
    for asset in assets:
        assert client.get(asset).status_code == 200, asset
