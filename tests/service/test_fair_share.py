"""Each client's fair share of the interactive workers: limits, turns, who the client is, the 429."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from causalplan.service.errors import QueueFullError, TooManyRequestsInFlightError
from causalplan.service.fair_share import FairShare, fair_share_of, request_client
from causalplan.service.owners import key_owner
from causalplan.settings import Settings
from tests.service.fixtures import (
    API_KEY,
    DESK_LAMP,
    KEY_AUTH,
    TEST_CLIENT_OWNER,
    error_of,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    with_unique_effect,
)


class Holder:
    """A thread that takes ``client``'s turn and holds it until released; ``granted`` is set once it has it."""

    def __init__(self, share: FairShare, client: str, log: list[str] | None = None, address: str | None = None) -> None:
        self.granted = threading.Event()
        self.release = threading.Event()
        self.error: Exception | None = None
        self._share, self._client, self._log, self._address = share, client, log, address
        self._thread = threading.Thread(target=self._run)
        self._thread.start()

    def _run(self) -> None:
        try:
            with self._share.turn(self._client, self._address):
                if self._log is not None:
                    self._log.append(self._client)
                self.granted.set()
                self.release.wait(30)
        except Exception as exc:  # noqa: BLE001 - the test reads it
            self.error = exc
            self.granted.set()

    def done(self) -> None:
        self.release.set()
        self._thread.join(30)


def finish(*holders: Holder) -> None:
    """Release every holder, then wait for each (one waiting for its turn gets it as the others leave)."""
    for holder in holders:
        holder.release.set()
    for holder in holders:
        holder.done()


def waiting_for(share: FairShare, count: int) -> None:
    """Wait until ``count`` requests wait for a turn (a signal, not a sleep)."""
    with share._lock:
        assert share._lock.wait_for(lambda: len(share._waiting) == count, 30)


def test_one_client_never_takes_every_worker() -> None:
    share = FairShare(workers=2, requests_in_flight=4, workers_per_client=1, queue_size=16, wait_seconds=30)
    first = Holder(share, "address:flood")
    assert first.granted.wait(30)
    second = Holder(share, "address:flood")  # a worker is free, but not for this client
    waiting_for(share, 1)
    other = Holder(share, "address:other")
    assert other.granted.wait(30), "another client found the worker the flooding client may not take"
    assert not second.granted.is_set()
    first.done()
    assert second.granted.wait(30)
    for holder in (second, other):
        holder.done()
    assert share.stats() == {"running": 0, "waiting": 0, "clients": 0}


def test_a_free_worker_goes_to_the_client_holding_fewest() -> None:
    share = FairShare(workers=1, requests_in_flight=4, workers_per_client=1, queue_size=16, wait_seconds=30)
    log: list[str] = []
    first = Holder(share, "A", log)
    assert first.granted.wait(30)
    queued = [Holder(share, "A", log) for _ in range(3)]
    waiting_for(share, 3)
    late = Holder(share, "B", log)  # came after three of A's
    waiting_for(share, 4)
    first.done()
    assert late.granted.wait(30)
    assert log == ["A", "B"], "B waited behind only the one request A was running"
    late.done()
    for holder in queued:
        holder.done()
    assert log == ["A", "B", "A", "A", "A"]


def test_past_its_limit_a_client_is_refused_with_retry_after() -> None:
    share = FairShare(workers=1, requests_in_flight=2, workers_per_client=1, queue_size=16, wait_seconds=30)
    holders = [Holder(share, "A")]
    assert holders[0].granted.wait(30)
    holders.append(Holder(share, "A"))
    waiting_for(share, 1)
    with pytest.raises(TooManyRequestsInFlightError) as refused, share.turn("A"):
        pass
    assert refused.value.retry_after >= 1
    assert refused.value.headers == {"Retry-After": str(refused.value.retry_after)}
    other = Holder(share, "B")  # another client is not refused
    waiting_for(share, 2)
    finish(*holders, other)
    assert other.error is None


def test_a_full_queue_and_a_long_wait_are_queue_full() -> None:
    share = FairShare(workers=1, requests_in_flight=4, workers_per_client=1, queue_size=1, wait_seconds=30)
    first, second = Holder(share, "A"), Holder(share, "B")
    assert first.granted.wait(30)
    waiting_for(share, 1)
    with pytest.raises(QueueFullError), share.turn("C"):
        pass
    impatient = FairShare(workers=1, requests_in_flight=4, workers_per_client=1, queue_size=4, wait_seconds=0.01)
    holder = Holder(impatient, "A")
    assert holder.granted.wait(30)
    with pytest.raises(QueueFullError), impatient.turn("B"):
        pass
    assert impatient.stats() == {"running": 1, "waiting": 0, "clients": 1}
    for each in (first, second, holder):
        each.done()


def test_the_participants_of_one_address_share_one_share_and_one_cap() -> None:
    share = FairShare(
        workers=2,
        requests_in_flight=4,
        workers_per_client=1,
        queue_size=16,
        wait_seconds=30,
        address_requests_in_flight=2,
    )
    flood = "address:203.0.113.5"
    first = Holder(share, "participant:a", address=flood)
    assert first.granted.wait(30)
    second = Holder(share, "participant:b", address=flood)  # another participant, the same address
    waiting_for(share, 1)
    with pytest.raises(TooManyRequestsInFlightError, match="Your address"), share.turn("participant:c", flood):
        pass
    other = Holder(share, "address:198.51.100.8")
    assert other.granted.wait(30), "the free worker went to another client, not to the address's second participant"
    assert not second.granted.is_set()
    first.done()
    assert second.granted.wait(30)
    for holder in (second, other):
        holder.done()
    assert share.stats() == {"running": 0, "waiting": 0, "clients": 0}


def test_the_settings_give_each_client_all_workers_but_one() -> None:
    assert fair_share_of(Settings(planning_workers=4)).workers_per_client == 3
    assert fair_share_of(Settings(planning_workers=1)).workers_per_client == 1
    assert fair_share_of(Settings(planning_workers=4, client_workers=2)).workers_per_client == 2
    with pytest.raises(ValueError, match="positive"):
        FairShare(workers=1, requests_in_flight=0, workers_per_client=1, queue_size=1, wait_seconds=1)


def _scope(path: str, headers: dict[str, str], peer: str = "198.51.100.7") -> dict[str, object]:
    raw = [(name.lower().encode(), value.encode()) for name, value in headers.items()]
    return {"type": "http", "path": path, "headers": raw, "client": (peer, 5000), "method": "POST"}


def test_the_client_is_the_key_the_participant_or_the_address() -> None:
    settings = Settings(api_keys=[API_KEY], research_token="a-research-token")
    assert request_client(_scope("/v1/plans", KEY_AUTH), settings) == key_owner(API_KEY)
    assert request_client(_scope("/v1/plans", {"Authorization": "Bearer a-research-token"}), settings) == "research"
    assert request_client(_scope("/p/abc123/films/playback", {}), settings) == "participant:abc123"
    wrong = {"Authorization": "Bearer not-a-key-of-this-service"}
    assert request_client(_scope("/v1/plans", wrong), settings) == "address:198.51.100.7"
    assert request_client(_scope("/v1/plans", {}, peer="203.0.113.9"), settings) == "address:203.0.113.9"


@contextmanager
def turns_held(share: FairShare, client: str, count: int) -> Iterator[None]:
    """Hold ``count`` of ``client``'s turns (running or waiting) during the block."""
    holders = [Holder(share, client) for _ in range(count)]
    try:
        with share._lock:
            assert share._lock.wait_for(lambda: share._in_flight[client] == count, 30)
        yield
    finally:
        finish(*holders)


def test_a_client_at_its_limit_gets_429_and_others_are_answered(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), client_requests_in_flight=2)
    with running_client(settings) as client:
        share = services_of(client).pool.fair_share  # type: ignore[attr-defined]
        with turns_held(share, TEST_CLIENT_OWNER, 2):
            refused = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
            error = error_of(refused, 429)
            assert error["code"] == "too_many_requests_in_flight"
            assert int(refused.headers["Retry-After"]) >= 1
            answered = client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}, headers=KEY_AUTH)
            assert answered.status_code == 200, answered.text
