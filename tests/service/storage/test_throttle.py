"""Failed research-token attempts: the per-address throttle, then the JSON endpoints and the sign-in form."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError
from sqlalchemy import Engine, delete, func, select
from sqlalchemy.orm import Session

from causalplan.service.errors import TooManyAttemptsError
from causalplan.service.storage.records import FailedAttemptRecord
from causalplan.service.storage.throttle import FailedAttempts
from causalplan.settings import Settings
from tests.service.fixtures import (
    AUTH,
    RESEARCH_TOKEN,
    error_of,
    migrated_engine,
    running_client,
    services_of,
    serving,
    settings_for,
    sqlite_url,
)

MAX_FAILURES = 3
WINDOW = 60.0
TOTAL = 1000
WRONG = {"Authorization": "Bearer wrong"}


@pytest.fixture
def engine(tmp_path: Path) -> Engine:
    """A migrated SQLite database for one throttle."""
    return migrated_engine(tmp_path)


class FakeClock:
    """A clock that moves only when told to."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def right() -> bool:
    return True


def wrong() -> bool:
    return False


def fail(attempts: FailedAttempts, address: str, times: int) -> None:
    """Record ``times`` failures of ``address`` (each one still allowed to be checked)."""
    for _ in range(times):
        assert attempts.check(address, wrong) is False


def retry_after(attempts: FailedAttempts, address: str) -> int:
    """Return the Retry-After of a refused wrong token of ``address``; assert a right one is still accepted."""
    with pytest.raises(TooManyAttemptsError) as refused:
        attempts.check(address, wrong)
    assert refused.value.headers == {"Retry-After": str(refused.value.retry_after)}
    assert attempts.check(address, right) is True  # wrong tokens cost only their sender, never a right token
    return refused.value.retry_after


# -- the throttle -------------------------------------------------------------------------------


def test_after_max_failures_an_address_is_refused_until_its_oldest_failure_leaves_the_window(engine: Engine) -> None:
    clock = FakeClock()
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=clock)
    fail(attempts, "a", 1)
    clock.now += 10
    fail(attempts, "a", MAX_FAILURES - 1)
    assert retry_after(attempts, "a") == 60 - 10
    clock.now += 20.5
    assert retry_after(attempts, "a") == 30  # 29.5 s, rounded up
    clock.now += 29.5  # the first failure leaves the window: one more attempt may be checked
    assert attempts.check("a", right) is True
    fail(attempts, "a", 1)
    assert retry_after(attempts, "a") == 10  # now the failures made 10 s after the first one are the oldest


def test_successes_do_not_count_and_do_not_reset(engine: Engine) -> None:
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=FakeClock())
    fail(attempts, "a", MAX_FAILURES - 1)
    for _ in range(20):
        assert attempts.check("a", right) is True
    fail(attempts, "a", 1)
    assert retry_after(attempts, "a") == 60


def test_addresses_are_counted_apart(engine: Engine) -> None:
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=FakeClock())
    fail(attempts, "a", MAX_FAILURES)
    retry_after(attempts, "a")
    assert attempts.check("b", right) is True
    fail(attempts, "b", MAX_FAILURES - 1)
    assert attempts.check("b", right) is True


def test_failures_that_left_the_window_are_deleted(engine: Engine) -> None:
    clock = FakeClock()
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=clock)
    for address in ("a", "b", "c"):
        fail(attempts, address, MAX_FAILURES)
    assert len(attempts) == 3
    clock.now += WINDOW  # every failure has left the window: the next one clears them out
    fail(attempts, "e", 1)
    assert len(attempts) == 1
    with Session(engine) as session:
        assert session.scalar(select(func.count()).select_from(FailedAttemptRecord)) == 1


def test_two_throttles_on_one_database_hold_one_count(engine: Engine) -> None:
    clock = FakeClock()
    first = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=clock)
    second = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=clock)  # as another replica's
    fail(first, "a", MAX_FAILURES - 1)
    fail(second, "a", 1)
    assert retry_after(first, "a") == retry_after(second, "a") == 60


def test_failures_from_many_clients_together_are_limited_too(engine: Engine) -> None:
    clock = FakeClock()
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, 5, clock=clock)
    for client in range(5):
        fail(attempts, f"client-{client}", 1)
    assert retry_after(attempts, "a new client") == 60  # a wrong token, from anyone; the right one passes
    clock.now += WINDOW
    assert attempts.check("a new client", right) is True


def test_concurrent_wrong_guesses_cannot_overshoot_the_limit(engine: Engine) -> None:
    attempts = FailedAttempts(engine, MAX_FAILURES, WINDOW, TOTAL, clock=FakeClock())
    start = threading.Barrier(16)
    compared: list[int] = []
    refused: list[int] = []

    def guess(number: int) -> None:
        def is_correct() -> bool:
            compared.append(number)
            time.sleep(0)  # let the other threads run mid-comparison (no waiting: the lock must hold the counts)
            return False

        start.wait()
        try:
            attempts.check("a", is_correct)
        except TooManyAttemptsError:
            refused.append(number)

    threads = [threading.Thread(target=guess, args=(number,)) for number in range(16)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(compared) == 16 and len(refused) == 16 - MAX_FAILURES
    with Session(engine) as session:
        assert session.scalar(select(func.count()).select_from(FailedAttemptRecord)) == MAX_FAILURES


def test_limits_must_be_positive(engine: Engine) -> None:
    with pytest.raises(ValueError, match="must be positive"):
        FailedAttempts(engine, 0, WINDOW, TOTAL)
    with pytest.raises(ValueError, match="must be positive"):
        FailedAttempts(engine, MAX_FAILURES, 0.0, TOTAL)
    with pytest.raises(ValueError, match="must be positive"):
        FailedAttempts(engine, MAX_FAILURES, WINDOW, 0)
    for setting in (
        {"research_max_failures": 0},
        {"research_max_failures": -1},
        {"research_failure_window_seconds": 0},
        {"research_failure_window_seconds": -5},
        {"research_failure_window_seconds": float("inf")},
    ):
        with pytest.raises(ValidationError):
            Settings(database_url="sqlite://", **setting)


def test_the_limits_are_read_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CAUSALPLAN_RESEARCH_MAX_FAILURES", raising=False)
    monkeypatch.delenv("CAUSALPLAN_RESEARCH_FAILURE_WINDOW_SECONDS", raising=False)
    assert (Settings().research_max_failures, Settings().research_failure_window_seconds) == (10, 60.0)
    monkeypatch.setenv("CAUSALPLAN_RESEARCH_MAX_FAILURES", "5")
    monkeypatch.setenv("CAUSALPLAN_RESEARCH_FAILURE_WINDOW_SECONDS", "300")
    assert (Settings().research_max_failures, Settings().research_failure_window_seconds) == (5, 300.0)


# -- through the app ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def app_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """A running app that allows MAX_FAILURES wrong tokens per WINDOW."""
    settings = settings_for(
        sqlite_url(tmp_path_factory.mktemp("db")),
        planning_workers=1,
        research_max_failures=MAX_FAILURES,
        research_failure_window_seconds=WINDOW,
    )
    with running_client(settings) as client:
        yield client


@pytest.fixture
def clock(app_client: TestClient) -> Iterator[FakeClock]:
    """Give the app a fresh record of failures on a fake clock for one test; put its own back afterwards."""
    services = services_of(app_client)
    own = services.failed_attempts
    with Session(services.engine) as session:  # the failures of earlier tests are on another clock
        session.execute(delete(FailedAttemptRecord))
        session.commit()
    clock = FakeClock()
    services.failed_attempts = FailedAttempts(services.engine, MAX_FAILURES, WINDOW, TOTAL, clock=clock)
    yield clock
    services.failed_attempts = own


def client_at(app_client: TestClient, address: str = "203.0.113.1") -> TestClient:
    """Return a client of the running app whose requests come from ``address`` (and with no cookies)."""
    return TestClient(app_client.app, client=(address, 50000))


def sign_in(client: TestClient, token: str) -> httpx.Response:
    """Post ``token`` to the sign-in form; return the answer (not following its redirect)."""
    return client.post("/research/login", data={"token": token, "next": "/research"}, follow_redirects=False)


def test_the_app_counts_failures_with_its_settings(app_client: TestClient) -> None:
    attempts = services_of(app_client).failed_attempts
    assert (attempts.max_failures, attempts.window_seconds) == (MAX_FAILURES, WINDOW)
    client = client_at(app_client, "192.0.2.99")
    for _ in range(MAX_FAILURES):
        assert error_of(client.get("/v1/trials", headers=WRONG), 401)["code"] == "not_authenticated"
    refused = client.get("/v1/trials", headers=WRONG)
    assert error_of(refused, 429)["code"] == "too_many_attempts"
    assert 1 <= int(refused.headers["retry-after"]) <= WINDOW


def test_after_max_wrong_tokens_wrong_ones_get_429_and_the_right_one_works(
    app_client: TestClient, clock: FakeClock
) -> None:
    client = client_at(app_client)
    for path in ("/v1/trials", "/v1/experiments", "/v1/export"):  # one count across the research endpoints
        assert error_of(client.get(path, headers=WRONG), 401)["code"] == "not_authenticated"
    clock.now += 15
    for path in ("/v1/trials", "/v1/export", "/v1/experiments", "/research"):
        refused = client.get(path, headers=WRONG)
        assert refused.status_code == 429 and refused.headers["retry-after"] == "45", path
        assert client.get(path, headers=AUTH).status_code == 200, path  # wrong tokens cost only their sender
    error = error_of(client.get("/v1/trials", headers=WRONG), 429)
    assert error == {
        "code": "too_many_attempts",
        "message": "Too many wrong tokens from this address: try again in 45 s.",
        "details": {"retry_after": 45},
    }
    clock.now += 45
    assert error_of(client.get("/v1/trials", headers=WRONG), 401)["code"] == "not_authenticated"


def test_right_tokens_keep_working_whatever_the_wrong_ones(app_client: TestClient, clock: FakeClock) -> None:
    client = client_at(app_client)
    for _ in range(MAX_FAILURES - 1):
        assert client.get("/v1/trials", headers=WRONG).status_code == 401
        assert client.get("/v1/trials", headers=AUTH).status_code == 200
    for _ in range(10):
        assert client.get("/v1/experiments", headers=AUTH).status_code == 200
        assert client.get("/v1/trials").status_code == 401  # no token at all is no guess
    assert client.get("/v1/trials", headers=WRONG).status_code == 401
    assert client.get("/v1/trials", headers=WRONG).status_code == 429
    assert client.get("/v1/trials", headers=AUTH).status_code == 200


def test_the_sign_in_form_says_when_to_try_again(app_client: TestClient, clock: FakeClock) -> None:
    client = client_at(app_client)
    for _ in range(MAX_FAILURES):
        refused = sign_in(client, "guess")
        assert refused.status_code == 401 and "That is not the research token." in refused.text
    clock.now += 0.5
    locked = sign_in(client, "another guess")
    assert locked.status_code == 429 and locked.headers["retry-after"] == "60"
    assert "Too many wrong tokens from your address" in locked.text and "try again in 60 s." in locked.text
    assert "That is not the research token." not in locked.text
    assert "set-cookie" not in locked.headers and "<form" in locked.text
    signed_in = sign_in(client, RESEARCH_TOKEN)  # the right token, from this address, during the lockout
    assert signed_in.status_code == 303 and "set-cookie" in signed_in.headers


def test_a_lockout_refuses_wrong_bearer_tokens_on_pages_and_keeps_researchers_in(
    app_client: TestClient, clock: FakeClock
) -> None:
    client = client_at(app_client)
    assert "set-cookie" in sign_in(client, RESEARCH_TOKEN).headers
    for _ in range(MAX_FAILURES):
        assert client.get("/v1/trials", headers=WRONG).status_code == 401
    assert client.get("/research").status_code == 200  # the cookie is no token guess
    assert client.get("/research", headers=AUTH).status_code == 200
    page = client.get("/research", headers=WRONG)
    assert page.status_code == 429 and page.headers["retry-after"] == "60"
    assert "Please try again shortly" in page.text and "try again in 60 s." in page.text


def test_another_address_is_not_affected(app_client: TestClient, clock: FakeClock) -> None:
    locked_out = client_at(app_client, "203.0.113.1")
    for _ in range(MAX_FAILURES):
        locked_out.get("/v1/trials", headers=WRONG)
    assert locked_out.get("/v1/trials", headers=WRONG).status_code == 429
    other = client_at(app_client, "198.51.100.2")
    assert other.get("/v1/trials", headers=AUTH).status_code == 200
    assert other.get("/v1/trials", headers=WRONG).status_code == 401
    assert sign_in(other, "guess").status_code == 401
    assert sign_in(other, RESEARCH_TOKEN).status_code == 303


def test_without_a_token_configured_nothing_is_counted(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), research_token=None, planning_workers=1, research_max_failures=1)
    with running_client(settings) as client:
        for _ in range(3):
            assert sign_in(client, "guess").status_code == 401
            assert error_of(client.get("/v1/trials", headers=WRONG), 403)["code"] == "research_disabled"
        assert len(services_of(client).failed_attempts) == 0


@pytest.mark.slow
def test_a_new_forwarded_address_per_request_does_not_reset_the_count(tmp_path: Path) -> None:
    # Through uvicorn, as `causalplan serve` runs it, from 127.0.0.1: which uvicorn itself trusted
    # by default, so each request was counted against the address its header made up.
    settings = settings_for(
        sqlite_url(tmp_path), planning_workers=1, research_max_failures=MAX_FAILURES, research_failure_window_seconds=60
    )
    with serving(settings) as base, httpx.Client(base_url=base) as client:
        for attempt in range(MAX_FAILURES):
            forwarded = {**WRONG, "X-Forwarded-For": f"10.0.0.{attempt}"}
            assert client.get("/v1/trials", headers=forwarded).status_code == 401
        refused = client.get("/v1/trials", headers={**WRONG, "X-Forwarded-For": "10.0.0.99"})
        assert error_of(refused, 429)["code"] == "too_many_attempts"


@pytest.fixture(scope="module")
def behind_proxy(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """A running app whose operator named 192.0.2.10 as its reverse proxy."""
    settings = settings_for(
        sqlite_url(tmp_path_factory.mktemp("db")),
        planning_workers=1,
        research_max_failures=MAX_FAILURES,
        research_failure_window_seconds=WINDOW,
        trusted_proxies=["192.0.2.10"],
    )
    with running_client(settings) as client:
        yield client


def test_behind_a_trusted_proxy_the_forwarded_client_is_counted(behind_proxy: TestClient) -> None:
    proxy = client_at(behind_proxy, "192.0.2.10")
    for attempt in range(MAX_FAILURES):
        # What the client sent comes first; the proxy appends the address it saw.
        chain = f"10.9.9.{attempt}, 198.51.100.7"
        assert proxy.get("/v1/trials", headers={**WRONG, "X-Forwarded-For": chain}).status_code == 401
    refused = proxy.get("/v1/trials", headers={**WRONG, "X-Forwarded-For": "10.9.9.200, 198.51.100.7"})
    assert error_of(refused, 429)["code"] == "too_many_attempts"
    other = proxy.get("/v1/trials", headers={**WRONG, "X-Forwarded-For": "198.51.100.8"})
    assert other.status_code == 401  # another client behind the same proxy is not locked out


def test_trusted_proxies_must_be_addresses_or_networks() -> None:
    assert Settings(database_url="sqlite://", trusted_proxies=["10.0.0.0/8", "::1"]).is_trusted_proxy("10.1.2.3")
    assert not Settings(database_url="sqlite://", trusted_proxies=["10.0.0.0/8"]).is_trusted_proxy("testclient")
    for wrong in (["10.0.0.1/8"], ["not an address"]):
        with pytest.raises(ValidationError):
            Settings(database_url="sqlite://", trusted_proxies=wrong)
