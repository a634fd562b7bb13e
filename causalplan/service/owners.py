"""Who a job belongs to, and how much each client may hold: the owner of every job.

A job's owner is stored on its row, one string per client:

- ``research``: ``Authorization: Bearer <research token>``: the operator's, it sees every job
  and is held only by the service's own cap (``max_queued_jobs``), not by a client's limits;
- ``key:<the key's SHA-256, 64 hex digits>``: an API key (``CAUSALPLAN_API_KEYS``),
  compared in constant time as the research token is (the key itself is never stored);
- ``participant:<id>``: a participant's pages (their films of the robot), capped per participant
  and, with the address they come from, per address;
- ``address:<client address>``: anyone else, by the address the throttles count
  (``deps.client_address``: an IP address, a forwarded one only as a valid IP address).

An owner longer than the column (``MAX_OWNER_LENGTH``) is stored as its kind and its full
SHA-256 (``stored_owner``), never cut: two long owners never share jobs.

Only the owner reads, cancels or downloads a job (the research token any); another client is
answered 404 ``job_not_found``, as for a job that never existed. Each owner has limits on jobs
in flight, bytes stored and jobs a minute (``job_limits``); a client without a key has the
smaller ``anonymous_*`` ones. A bearer token that is neither the research token nor a key is
refused (401) and counted with the wrong research tokens, so keys cannot be guessed faster.
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from causalplan.service.deps import Services, ServicesDep, client_address, is_research_token
from causalplan.service.errors import NotAuthenticatedError, TooManyJobStartsError
from causalplan.service.storage.allowance import Allowance
from causalplan.service.storage.jobs import MEGABYTE, OwnerLimits
from causalplan.service.storage.records import MAX_ADDRESS_LENGTH, MAX_OWNER_LENGTH
from causalplan.service.storage.throttle import PerMinute
from causalplan.settings import Settings

RESEARCH_OWNER = "research"
KEY_PREFIX = "key:"
PARTICIPANT_PREFIX = "participant:"
ADDRESS_PREFIX = "address:"
DIGEST_PREFIX = "sha256:"
"""An owner too long to store as it is is stored as its kind and this, then its full SHA-256."""


@dataclass(frozen=True)
class JobOwner:
    """The client of a request, as the owner of the jobs it posts."""

    id: str
    is_anonymous: bool = False
    address: str | None = None
    """Of a client without a key (an address, a participant's pages): the address it posts from."""

    @property
    def sees_every_job(self) -> bool:
        """Return whether this client may read and cancel every job (the research token)."""
        return self.id == RESEARCH_OWNER

    @property
    def visible_owner(self) -> str | None:
        """Return the owner whose jobs this client sees (None: every job's), as ``storage.jobs`` takes it."""
        return None if self.sees_every_job else self.id


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def stored_owner(owner: str) -> str:
    """Return ``owner`` as stored: itself, or when longer than the column its kind and full digest (never cut)."""
    if len(owner) <= MAX_OWNER_LENGTH:
        return owner
    kind = owner.split(":", 1)[0][:16]
    return f"{kind}:{DIGEST_PREFIX}{_digest(owner)}"


def key_owner(key: str) -> str:
    """Return the owner of the jobs posted with API key ``key``: the key's full SHA-256, never the key."""
    return KEY_PREFIX + _digest(key)


def participant_owner(participant_id: object, address: str | None = None) -> JobOwner:
    """Return the owner of the jobs a participant's pages start (from ``address``: counted there too)."""
    return JobOwner(stored_owner(f"{PARTICIPANT_PREFIX}{participant_id}"), address=address)


def address_owner(address: str) -> JobOwner:
    """Return the owner of the jobs of a client without a key, known by its address."""
    return JobOwner(stored_owner(f"{ADDRESS_PREFIX}{address}"), is_anonymous=True, address=address)


def owner_of_token(candidate: str, settings: Settings) -> JobOwner | None:
    """Return the owner ``candidate`` names (the research token or an API key); None when it names none.

    Every key is compared, in constant time, whichever matches: the time taken tells nothing.
    """
    owner = JobOwner(RESEARCH_OWNER) if is_research_token(candidate, settings) else None
    for key in settings.api_keys:
        secret = key.get_secret_value()
        if secrets.compare_digest(candidate.encode(), secret.encode()) and owner is None:
            owner = JobOwner(key_owner(secret))
    return owner


def job_limits(owner: JobOwner, settings: Settings) -> OwnerLimits | None:
    """Return what ``owner`` may hold: jobs in flight and bytes stored (smaller without a key; None: the operator's).

    A client without a key (an address, a participant) is capped per address too, and shares
    ``anonymous_job_share`` of the service's cap with every other such client.
    """
    if owner.sees_every_job:
        return None
    if owner.is_anonymous or owner.address is not None:
        if owner.is_anonymous:
            in_flight, megabytes = settings.anonymous_jobs_in_flight, settings.anonymous_job_megabytes
        else:  # a participant's films: few at once, but a study's worth of them kept
            in_flight, megabytes = settings.participant_jobs_in_flight, settings.job_megabytes
        return OwnerLimits(
            in_flight,
            int(megabytes * MEGABYTE),
            address=(owner.address or "")[:MAX_ADDRESS_LENGTH],
            address_in_flight=settings.address_jobs_in_flight,
            anonymous_share=settings.anonymous_job_share,
        )
    return OwnerLimits(settings.jobs_in_flight, int(settings.job_megabytes * MEGABYTE))


def storage_allowance(owner: str, settings: Settings) -> Allowance | None:
    """Return the storage allowance the models and trials ``owner``'s requests store count in.

    The research token: no limit; a key: ``job_megabytes``, kept; an address:
    ``anonymous_job_megabytes``, expiring after ``anonymous_record_hours`` (its rows belong to
    no experiment). None for a participant's pages (their rows are their study's).
    """
    if owner == RESEARCH_OWNER:
        return Allowance(owner, None, None)
    if owner.startswith(KEY_PREFIX):
        return Allowance(owner, int(settings.job_megabytes * MEGABYTE), None)
    if owner.startswith(ADDRESS_PREFIX):
        keep = settings.anonymous_record_hours * 3600
        return Allowance(owner, int(settings.anonymous_job_megabytes * MEGABYTE), keep)
    return None


class JobStarts(PerMinute):
    """Jobs each owner posts a minute, counted in the database (one count for every replica)."""

    def __init__(self, services: Services, owner: JobOwner) -> None:
        settings = services.settings
        per_minute = settings.anonymous_jobs_per_minute if owner.is_anonymous else settings.jobs_per_minute
        super().__init__(services.engine, "job", per_minute, TooManyJobStartsError)

    def message(self, count: int, retry_after: int) -> str:
        """Return what the 429 error says to a client that posted ``count`` jobs this minute."""
        return f"You have posted {count} jobs this minute, as many as you may: wait {retry_after} s."


def admit_job(services: Services, owner: JobOwner) -> None:
    """Count one job ``owner`` posts this minute; ``TooManyJobStartsError`` (429) when its minute is full.

    The research token's jobs are not counted: it is the operator's.
    """
    if not owner.sees_every_job:
        JobStarts(services, owner).admit(owner.id)


_bearer = HTTPBearer(
    auto_error=False,
    scheme_name="ClientKey",
    description="An API key (CAUSALPLAN_API_KEYS) or the research token: the jobs posted with it are its own. "
    "Without it, a client is known by its address, with smaller limits.",
)


def resolve_owner(request: Request, services: Services, credentials: HTTPAuthorizationCredentials | None) -> JobOwner:
    """Return the owner of this request's jobs: the bearer token's, else the client's address.

    A token that is neither the research token nor an API key is ``NotAuthenticatedError`` (401),
    counted against the client as a wrong research token is (``TooManyAttemptsError`` beyond).
    """
    address = client_address(request, services.settings)
    if credentials is None:
        return address_owner(address)
    found: list[JobOwner] = []

    def is_known() -> bool:
        owner = owner_of_token(credentials.credentials, services.settings)
        found.extend([owner] if owner is not None else [])
        return owner is not None

    if not services.failed_attempts.check(address, is_known):
        raise NotAuthenticatedError("The bearer token is neither an API key of this service nor the research token.")
    return found[0]


def get_job_owner(
    request: Request,
    services: ServicesDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> JobOwner:
    return resolve_owner(request, services, credentials)


JobOwnerDep = Annotated[JobOwner, Depends(get_job_owner)]
BearerDep = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]
"""The bearer token as sent, unchecked: for a route that needs an owner only sometimes (``resolve_owner``)."""
