"""Dependencies of the routes, as ``Annotated`` aliases (``SessionDep``, ``SettingsDep``, ...)."""

from __future__ import annotations

import secrets
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Annotated

from fastapi import Depends, Header, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from causalplan.objects.catalog import Catalog
from causalplan.service.attempts import FailedAttempts
from causalplan.service.cache import LruCache, ResultCache
from causalplan.service.crud import ClientIds, NoWaitWriter
from causalplan.service.db.checkpoints import WalCheckpointer
from causalplan.service.db.models import MAX_CLIENT_ID_LENGTH
from causalplan.service.errors import NotAuthenticatedError, ResearchDisabledError
from causalplan.service.planning import PlannerPool
from causalplan.service.repeats import RepeatedPlans
from causalplan.service.settings import Settings


@dataclass
class Services:
    """What the app holds while it runs: set up on start-up, closed on shutdown."""

    settings: Settings
    catalog: Catalog
    engine: Engine
    pool: PlannerPool
    cache: ResultCache
    revision: str
    reads: LruCache[object]
    """What reading model and mapping documents gave, by the document's exact JSON."""
    catalog_key: str
    """The catalog's fingerprint, part of every answer's cache key."""
    failed_attempts: FailedAttempts
    """Wrong research tokens by client address, to refuse guessing at full speed."""
    checkpointer: WalCheckpointer | None = None
    """SQLite's log checkpoints, off the requests (None for other databases)."""
    no_wait_writer: NoWaitWriter | None = None
    """The event loop's own SQLite connection, which stores only what needs no waiting (None for other databases)."""
    repeats: RepeatedPlans = field(default_factory=lambda: RepeatedPlans(0))
    """Answers of plan requests kept by their exact body (``RepeatedPlanMiddleware``)."""
    probe: dict[str, object] | None = None
    probe_done: threading.Event = field(default_factory=threading.Event)


# Dependencies that do not block are `async def`: FastAPI runs a plain `def` dependency in a
# worker thread, and each hop there and back costs ~0.1-0.2 ms on every request.


async def get_services(request: Request) -> Services:
    services: Services = request.app.state.services
    return services


ServicesDep = Annotated[Services, Depends(get_services)]


async def get_settings(services: ServicesDep) -> Settings:
    return services.settings


async def get_catalog(services: ServicesDep) -> Catalog:
    return services.catalog


def open_session(services: Services) -> Session:
    """Return a new session on the app's database (objects stay readable after a commit)."""
    return Session(services.engine, expire_on_commit=False)


def get_session(services: ServicesDep) -> Iterator[Session]:
    with open_session(services) as session:
        yield session


SettingsDep = Annotated[Settings, Depends(get_settings)]
CatalogDep = Annotated[Catalog, Depends(get_catalog)]
SessionDep = Annotated[Session, Depends(get_session)]


async def get_client_ids(
    x_participant_id: Annotated[
        str | None,
        Header(max_length=MAX_CLIENT_ID_LENGTH, description="Who submits (a study participant); stored as given."),
    ] = None,
    x_session_id: Annotated[
        str | None, Header(max_length=MAX_CLIENT_ID_LENGTH, description="The client's session; stored as given.")
    ] = None,
) -> ClientIds:
    return ClientIds(x_participant_id or None, x_session_id or None)


ClientIdsDep = Annotated[ClientIds, Depends(get_client_ids)]

_bearer = HTTPBearer(auto_error=False, description="The research token (CAUSALPLAN_RESEARCH_TOKEN).")


def is_research_token(candidate: str, settings: Settings) -> bool:
    """Return whether ``candidate`` is the research token (compared in constant time)."""
    token = settings.research_token
    return token is not None and secrets.compare_digest(candidate.encode(), token.get_secret_value().encode())


def client_address(request: Request) -> str:
    """Return the client's address as the server saw it (empty when unknown, e.g. a Unix socket)."""
    return request.client.host if request.client is not None else ""


def check_research_token(candidate: str, request: Request, services: Services) -> bool:
    """Return whether ``candidate`` is the research token, counting a wrong one against the client's address.

    Raises ``TooManyAttemptsError`` without comparing while that address has too many recent failures.
    """
    return services.failed_attempts.check(
        client_address(request), lambda: is_research_token(candidate, services.settings)
    )


def require_research_token(
    request: Request,
    services: ServicesDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """Let the request through only with ``Authorization: Bearer <research token>``."""
    if services.settings.research_token is None:
        raise ResearchDisabledError(
            "The research endpoints are disabled: start the service with CAUSALPLAN_RESEARCH_TOKEN set."
        )
    if credentials is None:
        raise NotAuthenticatedError("This endpoint needs 'Authorization: Bearer <research token>'.")
    if not check_research_token(credentials.credentials, request, services):
        raise NotAuthenticatedError("The bearer token is not the research token.")


ResearchAccessDep = Annotated[None, Depends(require_research_token)]
