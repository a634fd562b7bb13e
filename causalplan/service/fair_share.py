"""Each client's fair share of the interactive planner workers.

Every request that runs on the interactive pool (plans, transfers and their repairs,
explanations, pictures, the robot runs a participant waits for) takes its turn here first:

- a client may have at most ``client_requests_in_flight`` of them running or waiting; one
  more is refused at once (429 ``too_many_requests_in_flight``, ``Retry-After``);
- a client may hold at most ``client_workers`` workers at once (by default all but one), so
  with two or more workers one client alone never takes them all;
- a participant's pages count per participant and per address: the participants of one
  address share one share of the workers, and may have ``address_requests_in_flight`` requests
  running or waiting together (so demo participants made by the dozen take one share);
- when a worker frees, it goes to the waiting client that holds the fewest workers, and among
  those to the one served longest ago (round-robin; a client's own requests in arrival order),
  never to the next request of a client over its share. So another client's plan waits
  behind at most one request of a client over its share.

Who the client is comes from the request (``ClientMiddleware``): the client of a bearer token
that is the research token or an API key, a participant's pages (``/p/<code>/...``), or else
the client's address, as the throttles count it. Work started without a request (pictures drawn
at start-up) is the service's own.

``FairSharePool`` is the interactive ``PlannerPool`` with its turn taken in ``run``: the one
place every interactive request passes, so no route needs to know of it. The counts are
this process's own (each replica has its own workers).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, TypeVar

from starlette.requests import Request
from starlette.types import ASGIApp, Receive, Scope, Send

from causalplan.service.deps import ALLOWANCE_STATE, client_address
from causalplan.service.errors import QueueFullError, TooManyRequestsInFlightError
from causalplan.service.owners import PARTICIPANT_PREFIX, address_owner, owner_of_token, storage_allowance
from causalplan.service.pool.pool import PlannerPool, PoolStats
from causalplan.settings import Settings

T = TypeVar("T")

SERVICE_CLIENT = "service"
"""The client of work no request asked for (pictures drawn ahead at start-up)."""
PAGES_PREFIX = "/p/"
"""Where a participant's pages live: ``/p/<code>/...``, the code names the participant."""

current_client: ContextVar[str] = ContextVar("causalplan_client", default=SERVICE_CLIENT)
"""The client of the request this code runs for (set by ``ClientMiddleware``; copied into route threads)."""
current_address: ContextVar[str | None] = ContextVar("causalplan_address", default=None)
"""A participant's address (``address:<ip>``): its participants share one share and one cap; None for others."""


def request_client(scope: Scope, settings: Settings) -> str:
    """Return who a request's interactive work counts against (see the module's docstring).

    A bearer token that is neither the research token nor a key counts as the address: the
    route refuses it anyway (and counts it as a wrong token).
    """
    request = Request(scope)
    authorization = request.headers.get("authorization", "")
    scheme, _, token = authorization.partition(" ")
    if scheme.lower() == "bearer" and token.strip():
        owner = owner_of_token(token.strip(), settings)
        if owner is not None:
            return owner.id
    path: str = scope.get("path", "")
    if path.startswith(PAGES_PREFIX):
        code = path[len(PAGES_PREFIX) :].split("/", 1)[0]
        if code:
            return f"{PARTICIPANT_PREFIX}{code}"
    return address_owner(client_address(request, settings)).id


class ClientMiddleware:
    """Name each HTTP request's client in ``current_client`` while the app answers it, and its storage allowance."""

    def __init__(self, app: ASGIApp, settings: Settings) -> None:
        self.app = app
        self.settings = settings

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        client = request_client(scope, self.settings)
        scope.setdefault("state", {})[ALLOWANCE_STATE] = storage_allowance(client, self.settings)
        address = None
        if client.startswith(PARTICIPANT_PREFIX):
            address = address_owner(client_address(Request(scope), self.settings)).id
        token, address_token = current_client.set(client), current_address.set(address)
        try:
            await self.app(scope, receive, send)
        finally:
            current_address.reset(address_token)
            current_client.reset(token)


@dataclass(eq=False)
class _Ticket:
    """One request waiting for, or holding, a worker; ``sharer``: whose share it takes (its address's, or its own)."""

    client: str
    sharer: str
    address: str | None
    order: int
    granted: bool = False
    started: float = 0.0


class FairShare:
    """Turns on ``workers`` workers, shared fairly between clients (see the module's docstring).

    ``queue_size``: requests of all clients together that may wait (then 429 ``queue_full``);
    ``wait_seconds``: the longest wait for a turn (then 429 ``queue_full``). A request with an
    address (a participant's) takes its address's share of the workers, and the address may
    have at most ``address_requests_in_flight`` of them running or waiting.
    """

    def __init__(
        self,
        workers: int,
        requests_in_flight: int,
        workers_per_client: int,
        queue_size: int,
        wait_seconds: float,
        address_requests_in_flight: int | None = None,
    ) -> None:
        if min(workers, requests_in_flight, workers_per_client) < 1:
            raise ValueError("workers, requests_in_flight and workers_per_client must be positive")
        self.workers = workers
        self.requests_in_flight = requests_in_flight
        self.workers_per_client = min(workers_per_client, workers)
        self.queue_size = queue_size
        self.wait_seconds = wait_seconds
        self.address_requests_in_flight = address_requests_in_flight or requests_in_flight
        self._lock = threading.Condition()
        self._waiting: list[_Ticket] = []
        self._running: Counter[str] = Counter()
        self._in_flight: Counter[str] = Counter()  # by client, and by address for participants' requests
        self._orders = itertools.count()
        self._grants = itertools.count()
        self._last_grant: dict[str, int] = {}  # client -> the number of its latest turn (round-robin)
        self._seconds_per_turn = 1.0  # moving average, for Retry-After

    def stats(self) -> dict[str, int]:
        """Return the workers held, the requests waiting and the clients with work in flight."""
        with self._lock:
            return {
                "running": sum(self._running.values()),
                "waiting": len(self._waiting),
                "clients": len(self._in_flight),
            }

    def in_flight(self, client: str) -> int:
        """Return how many requests ``client`` has running or waiting."""
        with self._lock:
            return self._in_flight[client]

    def _retry_after(self, client: str) -> int:
        turns = max(1, self._in_flight[client]) / self.workers_per_client
        return max(1, math.ceil(self._seconds_per_turn * turns))

    @contextmanager
    def turn(self, client: str, address: str | None = None) -> Iterator[None]:
        """Wait for ``client``'s fair turn on a worker, hold it in the block, then pass it on.

        ``address``: a participant's, whose participants share one share of the workers.
        Raises ``TooManyRequestsInFlightError`` when ``client`` has ``requests_in_flight``
        requests already (its address ``address_requests_in_flight``), and ``QueueFullError``
        when the queue is full or no turn came within ``wait_seconds``.
        """
        ticket = self._enter(client, address)
        try:
            self._wait_for(ticket)
            yield
        finally:
            self._leave(ticket)

    def _enter(self, client: str, address: str | None) -> _Ticket:
        with self._lock:
            count = self._in_flight[client]
            if count >= self.requests_in_flight:
                retry = self._retry_after(client)
                raise TooManyRequestsInFlightError(
                    f"You have {count} planner requests running or waiting, as many as you may at once: "
                    f"try again in {retry} s, or when one has been answered.",
                    retry,
                )
            if address is not None and self._in_flight[address] >= self.address_requests_in_flight:
                retry = self._retry_after(address)
                raise TooManyRequestsInFlightError(
                    f"Your address has {self._in_flight[address]} planner requests of participants running or "
                    f"waiting, as many as it may at once: try again in {retry} s.",
                    retry,
                )
            if len(self._waiting) >= self.queue_size and sum(self._running.values()) >= self.workers:
                retry = max(1, math.ceil(self._seconds_per_turn * len(self._waiting) / self.workers))
                raise QueueFullError(
                    f"All {self.workers} planner worker(s) are busy and {len(self._waiting)} request(s) are already "
                    f"waiting. Try again in {retry} s.",
                    retry,
                )
            ticket = _Ticket(client, address or client, address, next(self._orders))
            self._in_flight[client] += 1
            if address is not None:
                self._in_flight[address] += 1
            self._waiting.append(ticket)
            self._dispatch()
            return ticket

    def _wait_for(self, ticket: _Ticket) -> None:
        deadline = time.monotonic() + self.wait_seconds
        with self._lock:
            while not ticket.granted:
                left = deadline - time.monotonic()
                if left <= 0:
                    retry = self._retry_after(ticket.client)
                    raise QueueFullError(
                        f"No planner worker became free for you within {self.wait_seconds:g} s. "
                        f"Try again in {retry} s.",
                        retry,
                    )
                self._lock.wait(left)

    def _leave(self, ticket: _Ticket) -> None:
        with self._lock:
            for counted in {ticket.client, ticket.sharer}:
                self._in_flight[counted] -= 1
                if not self._in_flight[counted]:
                    del self._in_flight[counted]
                    self._last_grant.pop(counted, None)
            if ticket.granted:
                self._running[ticket.sharer] -= 1
                if not self._running[ticket.sharer]:
                    del self._running[ticket.sharer]
                held = time.monotonic() - ticket.started
                self._seconds_per_turn = 0.8 * self._seconds_per_turn + 0.2 * held
            else:
                self._waiting.remove(ticket)
            self._dispatch()

    def _dispatch(self) -> None:
        """Grant free workers to waiting requests: fewest held first, then the client served longest ago (lock held)."""
        granted = False
        while sum(self._running.values()) < self.workers:
            eligible = [t for t in self._waiting if self._running[t.sharer] < self.workers_per_client]
            if not eligible:
                break
            ticket = min(eligible, key=lambda t: (self._running[t.sharer], self._last_grant.get(t.sharer, -1), t.order))
            self._last_grant[ticket.sharer] = next(self._grants)
            self._waiting.remove(ticket)
            ticket.granted = True
            ticket.started = time.monotonic()
            self._running[ticket.sharer] += 1
            granted = True
        if granted:
            self._lock.notify_all()


def fair_share_of(settings: Settings) -> FairShare:
    """Return the fair share of the interactive workers the settings describe."""
    workers = settings.planning_workers
    per_client = settings.client_workers or max(1, workers - 1)
    return FairShare(
        workers,
        settings.client_requests_in_flight,
        per_client,
        settings.queue_size,
        settings.queue_wait_seconds,
        settings.address_requests_in_flight,
    )


class FairSharePool(PlannerPool):
    """The interactive ``PlannerPool``: every ``run`` first takes its client's fair turn (``current_client``)."""

    def __init__(self, settings: Settings) -> None:
        super().__init__(
            settings.planning_workers, settings.queue_size, settings.worker_memory_mb, settings.queue_wait_seconds
        )
        self.fair_share = fair_share_of(settings)

    def stats(self) -> PoolStats:
        """Return the pool's numbers; ``waiting`` counts the requests waiting for their turn here.

        A request enters the pool only with a turn, so the pool's own waiting line stays empty.
        """
        stats = super().stats()
        return dataclasses.replace(stats, waiting=stats.waiting + self.fair_share.stats()["waiting"])

    def run(
        self,
        function: Callable[..., T],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
        stop: threading.Event | None = None,
    ) -> T:
        """Run ``function(*args)`` as ``PlannerPool.run`` does, once the request's client has its turn."""
        with self.fair_share.turn(current_client.get(), current_address.get()):
            return super().run(function, args, timeout, meanwhile, stop)
