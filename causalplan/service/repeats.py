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
from starlette.types import ASGIApp, Receive, Scope, Send

from causalplan.errors import CausalPlanError
from causalplan.service.cache import LruCache
from causalplan.service.crud import ClientIds, NoWaitWriter, PreparedModelRow
from causalplan.service.db.models import MAX_CLIENT_ID_LENGTH
from causalplan.service.replay import replaying
from causalplan.service.responses import render_json

if TYPE_CHECKING:
    from causalplan.service.deps import Services

PLANS_PATH = "/v1/plans"
REPEAT_KEY = "causalplan.repeat_key"
"""The scope entry where the middleware leaves a body's key for the route, which keeps a cached answer under it."""
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

    @property
    def size(self) -> int:
        """Return how many bodies may be kept (0: none)."""
        return self._kept.size

    def keep(
        self,
        key: str,
        row: PreparedModelRow,
        answer: dict[str, Any],
        planner_requested: str,
        planner: str,
    ) -> None:
        """Keep ``answer`` (the route's JSON, cached) for the body ``key``, with its model's ``row``."""
        marker = _marker()  # where the model id goes: a text no answer contains otherwise
        rendered = render_json({**answer, "model_id": marker})
        pieces = rendered.split(marker.encode())
        if len(pieces) != 2:
            return
        head, tail = pieces
        kept = RepeatedPlan(row, head, tail, planner_requested, planner)
        self._kept.put(key, kept, len(rendered) + row.weight)

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

    Inside ``BodyLimitMiddleware``, which has refused bodies over the limit and passes the body on
    in one message. It uses the app's services (``app.state.services``) once the app has started;
    ``resolve_planner`` is what the route resolves a requested planner with. A body it does not
    answer goes on with its key in the scope (``REPEAT_KEY``).
    """

    def __init__(self, app: ASGIApp, resolve_planner: Callable[[str], str]) -> None:
        self.app = app
        self.resolve_planner = resolve_planner

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        found = _services_to_answer(scope)
        if found is None:
            await self.app(scope, receive, send)
            return
        message = await receive()
        if message["type"] == "http.request" and not message.get("more_body", False):
            answer = self._answer(scope, message.get("body", b""), *found)
            if answer is not None:
                await Response(answer, media_type="application/json")(scope, receive, send)
                return
        await self.app(scope, replaying(message, receive), send)

    def _answer(self, scope: Scope, body: bytes, services: Services, writer: NoWaitWriter) -> bytes | None:
        headers: list[tuple[bytes, bytes]] = scope["headers"]
        key = body_key(headers, body)
        if key is None:
            return None
        scope[REPEAT_KEY] = key
        client = client_ids(headers)
        if client is None:
            return None
        return services.repeats.answer(key, client, writer, self.resolve_planner)


def _services_to_answer(scope: Scope) -> tuple[Services, NoWaitWriter] | None:
    """Return the app's services and event-loop writer for a request this layer may answer, else None.

    It may answer ``POST /v1/plans`` without a query string, once the app has started, on SQLite,
    with room for kept bodies.
    """
    if scope["type"] != "http" or scope["method"] != "POST" or scope["path"] != PLANS_PATH or scope["query_string"]:
        return None
    services: Services | None = getattr(scope["app"].state, "services", None)
    if services is None or services.no_wait_writer is None or services.repeats.size <= 0:
        return None
    return services, services.no_wait_writer
