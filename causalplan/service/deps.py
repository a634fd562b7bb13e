"""Dependencies of the routes, as ``Annotated`` aliases (``SessionDep``, ``SettingsDep``, ...)."""

from __future__ import annotations

import ipaddress
import secrets
import threading
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Annotated, Protocol

from fastapi import Depends, Header, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from causalplan.objects.catalog import Catalog
from causalplan.service.caches import ServiceCaches
from causalplan.service.errors import NotAuthenticatedError, ParticipantIdReservedError, ResearchDisabledError
from causalplan.service.pool.pool import PlannerPool
from causalplan.service.readiness import Readiness
from causalplan.service.storage.crud import PAGE_SESSION_PREFIX, ClientIds
from causalplan.service.storage.experiments import is_participant
from causalplan.service.storage.records import MAX_CLIENT_ID_LENGTH
from causalplan.service.storage.throttle import FailedAttempts
from causalplan.service.work.calls import Workers
from causalplan.settings import Settings


class Runner(Protocol):
    """This replica's job runner as the app drives it (``service.jobs.runner.JobRunner``, which needs ``Services``)."""

    def start(self) -> None: ...

    def stop(self, seconds: float = 2.0) -> None: ...

    def join(self, seconds: float) -> None: ...

    def stats(self) -> dict[str, int]: ...

    def cancel(self, job_id: uuid.UUID, seconds: float) -> bool: ...


@dataclass
class Services:
    """What the app holds while it runs: set up on start-up, closed on shutdown."""

    settings: Settings
    catalog: Catalog
    engine: Engine
    pool: PlannerPool
    """The interactive requests' workers (their numbers for /health): work runs through ``work``."""
    caches: ServiceCaches
    """The app's caches (answers, drawings): a new app's are empty."""
    revision: str
    catalog_key: str
    """The catalog's fingerprint, part of every answer's cache key."""
    failed_attempts: FailedAttempts
    """Wrong research tokens by client and in total, to refuse guessing at full speed."""
    job_pool: PlannerPool
    """The workers of long work (jobs: batches, robot runs, films), one per job runner: ``pool``
    is for interactive requests (and the robot runs a participant waits for), so no job can take
    its workers."""
    work: Workers
    """The one way to run work in a worker (on ``pool`` or ``job_pool``), through the answer cache or not."""
    runner: Runner | None = None
    """This replica's job runner (started after the pool)."""
    probe: dict[str, object] | None = None
    probe_done: threading.Event = field(default_factory=threading.Event)
    readiness: Readiness = field(default_factory=Readiness)
    """Whether the pool has answered its first plan (``GET /health/ready``)."""


# Dependencies that do not block are `async def`: FastAPI runs a plain `def` dependency in a
# worker thread, a hop there and back on every request.


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


ALLOWANCE_STATE = "causalplan_allowance"
"""Where the request's scope state holds its client's storage allowance (``fair_share.ClientMiddleware`` puts it)."""


def get_client_ids(
    request: Request,
    services: ServicesDep,
    x_participant_id: Annotated[
        str | None,
        Header(
            max_length=MAX_CLIENT_ID_LENGTH,
            description="Who submits, in the client's own words; stored as given. "
            "The id of a participant of a study on this service is refused (403): their pages store their work.",
        ),
    ] = None,
    x_session_id: Annotated[
        str | None,
        Header(
            max_length=MAX_CLIENT_ID_LENGTH,
            description=f"The client's session; stored as given ('{PAGE_SESSION_PREFIX}...' is the pages' own).",
        ),
    ] = None,
) -> ClientIds:
    """Return who the client says it is; a study participant's id, or their pages' session, is not the client's to say.

    With the storage allowance its stored models and trials count in (``owners.storage_allowance``).

    A participant's trials are attributed only by their own pages (``pages.participation``),
    so an anonymous request can never store a trial, or a model, under a participant.
    """
    if x_session_id and x_session_id.startswith(PAGE_SESSION_PREFIX):
        raise ParticipantIdReservedError(
            f"X-Session-Id may not begin with '{PAGE_SESSION_PREFIX}': those sessions are the participant pages' own.",
            details={"header": "X-Session-Id"},
        )
    if x_participant_id:
        with open_session(services) as session:
            if is_participant(session, x_participant_id):
                raise ParticipantIdReservedError(
                    "X-Participant-Id names a participant of a study here: "
                    "their work is stored only from their own participant pages.",
                    details={"header": "X-Participant-Id"},
                )
    allowance = request.scope.get("state", {}).get(ALLOWANCE_STATE)
    return ClientIds(x_participant_id or None, x_session_id or None, allowance)


ClientIdsDep = Annotated[ClientIds, Depends(get_client_ids)]

_bearer = HTTPBearer(auto_error=False, description="The research token (CAUSALPLAN_RESEARCH_TOKEN).")


def is_research_token(candidate: str, settings: Settings) -> bool:
    """Return whether ``candidate`` is the research token (compared in constant time)."""
    token = settings.research_token
    return token is not None and secrets.compare_digest(candidate.encode(), token.get_secret_value().encode())


def client_address(request: Request, settings: Settings) -> str:
    """Return the client's address: the peer's, or what X-Forwarded-For says when the peer is a trusted proxy.

    Of the forwarded chain, the last address that is not itself a trusted proxy is the client
    (the ones before it are whatever the client chose to send). Each hop is read as an IP
    address, written in its canonical form; a hop that is not one (a name, text, a port) is
    ignored, so a made-up value can never name a client. Empty when unknown (a Unix socket).
    """
    peer = request.client.host if request.client is not None else ""
    if not settings.is_trusted_proxy(peer):
        return peer
    chain = [hop for value in request.headers.getlist("x-forwarded-for") for hop in value.split(",")]
    for hop in reversed(chain):
        address = ip_address_or_none(hop)
        if address is not None and not settings.is_trusted_proxy(address):
            return address
    return peer


def ip_address_or_none(text: str) -> str | None:
    """Return ``text`` as an IP address in canonical form, or None when it is not one."""
    try:
        return str(ipaddress.ip_address(text.strip()))
    except ValueError:
        return None


def check_research_token(candidate: str, request: Request, services: Services) -> bool:
    """Return whether ``candidate`` is the research token, counting a wrong one against the client.

    Raises ``TooManyAttemptsError`` without comparing while the client, or all clients together,
    have too many recent failures.
    """
    settings = services.settings
    return services.failed_attempts.check(
        client_address(request, settings), lambda: is_research_token(candidate, settings)
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
