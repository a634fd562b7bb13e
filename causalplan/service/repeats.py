"""Repeated plan requests, answered before FastAPI parses them: the same body gets the same answer.

A ``POST /v1/plans`` whose inline model was planned before is answered from the result cache;
through the route that still took ~1.1 ms in the app, most of it FastAPI parsing and validating
the body and solving the dependencies, the kept documents looked up, the answer validated and
rendered, and the model's record built and converted for its INSERT. Here, for each body whose
answer came from the cache, the app keeps what the next identical body needs: the record's
INSERT parameters, converted once (``PreparedModelRow``), and the answer rendered around its
``model_id``. A request with the same bytes and content type gets a record of its own (new id,
time and client ids, stored as the route stores it) and that answer with the new id.

It is the answer the route gives: the route's answer to a request whose answer is cached depends
on the body and on what does not change while the app runs (the catalog, the settings), and on
the planner registry, which can change and so is checked on every use. Tests compare the two
byte for byte. Whatever this layer is not sure of goes to the app as usual: a body not seen, a
query string, a client id the route would refuse or one sent twice, a write lock held elsewhere,
a database other than SQLite, a failure while storing.
"""

from __future__ import annotations

import hashlib
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from starlette.responses import Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from causalplan.errors import CausalPlanError
from causalplan.service.cache import LruCache
from causalplan.service.crud import ClientIds, NoWaitWriter, PreparedModelRow
from causalplan.service.db.models import MAX_CLIENT_ID_LENGTH
from causalplan.service.responses import render_json

if TYPE_CHECKING:
    from causalplan.service.deps import Services

PLANS_PATH = "/v1/plans"
_CLIENT_HEADERS = {b"x-participant-id": "participant_id", b"x-session-id": "session_id"}


@dataclass(frozen=True)
class RepeatedPlan:
    """What answering a body again takes: its model's row, the answer around the model id, the planner checked."""

    row: PreparedModelRow
    head: bytes
    tail: bytes
    planner_requested: str
    planner: str
    """What ``planner_requested`` ran as when the answer was kept; a registry that now says otherwise misses."""


def body_key(headers: list[tuple[bytes, bytes]], body: bytes) -> str | None:
    """Return the key of a request body and its content type (which decides how FastAPI reads it).

    None when the content type is sent more than once: such a request is left to the app.
    """
    content_types = [value for name, value in headers if name == b"content-type"]
    if len(content_types) > 1:
        return None
    digest = hashlib.sha256(content_types[0] if content_types else b"-")
    digest.update(b"\n")
    digest.update(body)
    return digest.hexdigest()


def client_ids(headers: list[tuple[bytes, bytes]]) -> ClientIds | None:
    """Return the client ids as the route reads them; None when the route would refuse them or one is sent twice."""
    found: dict[str, str] = {}
    for name, value in headers:
        field = _CLIENT_HEADERS.get(name)
        if field is None:
            continue
        if field in found or len(value) > MAX_CLIENT_ID_LENGTH:
            return None
        found[field] = value.decode("latin-1")
    return ClientIds(found.get("participant_id") or None, found.get("session_id") or None)


def _marker() -> str:
    return uuid.uuid4().hex


class RepeatedPlans:
    """The kept answers of repeated bodies: a bounded LRU map (as many entries as the result cache)."""

    def __init__(self, size: int) -> None:
        self._kept: LruCache[RepeatedPlan] = LruCache(size)

    def keep(
        self,
        key: str,
        row: PreparedModelRow,
        answer: dict[str, Any],
        planner_requested: str,
        planner: str,
    ) -> None:
        """Keep ``answer`` (the route's JSON, cached) for the body ``key``, with its model's ``row``."""
        if self._kept.size <= 0:
            return
        marker = _marker()  # where the model id goes: a text no answer contains otherwise
        rendered = render_json({**answer, "model_id": marker})
        pieces = rendered.split(marker.encode())
        if len(pieces) != 2:
            return
        head, tail = pieces
        kept = RepeatedPlan(row, head, tail, planner_requested, planner)
        self._kept.put(key, kept, len(rendered) + row.weight)

    def knows(self, key: str) -> bool:
        """Return whether the body ``key`` is kept (not counted as a hit or a miss)."""
        return self._kept.peek(key) is not None

    def answer(
        self, key: str, client: ClientIds, writer: NoWaitWriter, resolve_planner: Callable[[str], str]
    ) -> bytes | None:
        """Store a new record of the kept body's model for ``client``, and return the answer with its id.

        None, with nothing stored, when the body is not kept, the planner registry now resolves
        it differently, or the record cannot be stored at once.
        """
        kept = self._kept.get(key)
        if kept is None:
            return None
        try:
            if resolve_planner(kept.planner_requested) != kept.planner:
                return None
            model_id = writer.save_prepared(kept.row, client)
        except CausalPlanError:  # an unknown planner, a failed write: the route says what went wrong
            return None
        if model_id is None:
            return None
        return kept.head + str(model_id).encode() + kept.tail

    def stats(self) -> dict[str, int]:
        """Return the size, entries, hits and misses."""
        return self._kept.stats()


class RepeatedPlanMiddleware:
    """Answer ``POST /v1/plans`` with a kept body's answer (``RepeatedPlans``); pass everything else on.

    Inside ``BodyLimitMiddleware``, which has refused bodies over the limit. It uses the app's
    services (``app.state.services``) once the app has started; ``resolve_planner`` is what the
    route resolves a requested planner with.
    """

    def __init__(self, app: ASGIApp, resolve_planner: Callable[[str], str]) -> None:
        self.app = app
        self.resolve_planner = resolve_planner

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] != "POST" or scope["path"] != PLANS_PATH or scope["query_string"]:
            await self.app(scope, receive, send)
            return
        services: Services | None = getattr(scope["app"].state, "services", None)
        writer = services.no_wait_writer if services is not None else None
        if services is None or writer is None:
            await self.app(scope, receive, send)
            return
        messages: list[Message] = []
        more = True
        while more:
            message = await receive()
            messages.append(message)
            if message["type"] != "http.request":
                break
            more = message.get("more_body", False)
        if not more and messages[-1]["type"] == "http.request":
            answer = self._answer(scope, b"".join(message.get("body", b"") for message in messages), services, writer)
            if answer is not None:
                await Response(answer, media_type="application/json")(scope, receive, send)
                return

        async def replay() -> Message:
            return messages.pop(0) if messages else await receive()

        await self.app(scope, replay, send)

    def _answer(self, scope: Scope, body: bytes, services: Services, writer: NoWaitWriter) -> bytes | None:
        headers: list[tuple[bytes, bytes]] = scope["headers"]
        key = body_key(headers, body)
        client = client_ids(headers)
        if key is None or client is None:
            return None
        return services.repeats.answer(key, client, writer, self.resolve_planner)
