"""The ``jobs`` table: create, read, cancel, and the runner's claim, lease renewal and finish.

Every change a runner makes is a conditional UPDATE (``WHERE lease_owner = me AND status =
'running'``), so two replicas never both own a job: a claim succeeds for exactly one of them,
and a runner whose lease was taken over (or whose job was cancelled) finds its writes refused
and stops. That works the same on PostgreSQL and SQLite, with no lock held between statements.

Creating a job is the one exception: the limits (the service's unfinished jobs, its owner's
jobs in flight and bytes stored) are counted and the job inserted in one transaction that holds
the jobs' write lock (``BEGIN IMMEDIATE`` on SQLite, an advisory lock on PostgreSQL), so
creators on every replica at once never take one job over a limit.

Every job has an owner (``service.owners``); reading or cancelling it as another owner finds
no job, the same answer as a job that never existed.
"""

from __future__ import annotations

import math
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from enum import StrEnum
from typing import Any, cast

from sqlalchemy import CursorResult, Engine, and_, delete, func, or_, select, update
from sqlalchemy.orm import Session, aliased

from causalplan.service.errors import (
    BodyTooLargeError,
    JobFinishedError,
    JobNotFoundError,
    JobStorageFullError,
    TooManyJobsError,
    TooManyJobsInFlightError,
)
from causalplan.service.storage.allowance import first_expiry, json_size, stored_bytes, take_write_lock
from causalplan.service.storage.crud import clean_json, storage_errors
from causalplan.service.storage.records import JobRecord, utc_now

MEGABYTE = 1_000_000
"""What a job's stored bytes are counted and told in."""
MAX_ATTEMPTS = 3
"""Runs of a job whose replica stopped before finishing it, before it is given up as failed."""


class JobKind(StrEnum):
    """The kinds of job ``POST /v1/jobs`` takes."""

    BATCH = "batch"
    """Transfer trials uploaded as JSON Lines or CSV, judged as ``causalplan batch`` does."""
    SIMULATION = "simulation"
    """A plan run in the physics simulator, with the picture of the final assembly."""
    CONSENSUS = "consensus"
    """The crowd's consensus model of participants uploaded as JSON Lines, judged."""
    VIDEO = "video"
    """The robot carrying out a plan, filmed; the film is served from the job (``service.jobs.video``)."""
    FIT_ESTIMATION = "fit_estimation"
    """Each fit's success probability by noisy robot insertions, as ``causalplan estimate-fits``."""
    TROUBLESHOOTING = "troubleshooting"
    """The robot carrying out a troubleshooting episode in physics (``service.jobs.troubleshooting``)."""


class JobStatus(StrEnum):
    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"


UNFINISHED = (JobStatus.QUEUED, JobStatus.RUNNING)

TRY_LATER_SECONDS = 30
"""``Retry-After`` when the service, or a client, has as many unfinished jobs as it may: about a short job."""


@dataclass(frozen=True)
class OwnerLimits:
    """What one client may hold: jobs queued or running, and bytes stored (requests and results until they expire).

    ``address``: a client without a key (an address, a participant's pages) posting from it: its
    job is anonymous work, stored with the address; all its address's anonymous jobs may be at
    most ``address_in_flight`` unfinished, and anonymous jobs of every address together at most
    ``anonymous_share`` of the service's cap, so keyed clients and the research token find room.
    """

    in_flight: int
    stored_bytes: int
    address: str | None = None
    address_in_flight: int = 0
    anonymous_share: float = 1.0


def _changed(result: object) -> bool:
    return cast(CursorResult[Any], result).rowcount == 1


def _megabytes(size: float) -> str:
    return f"{size / MEGABYTE:.1f} MB"


def _check_owner(session: Session, owner: str, limits: OwnerLimits, size: int, now: datetime) -> None:
    """Raise the 429 (or 413) error of the first of ``owner``'s limits another job of ``size`` bytes would pass."""
    mine = JobRecord.owner == owner
    unfinished = JobRecord.status.in_(UNFINISHED)
    in_flight = session.scalar(select(func.count()).select_from(JobRecord).where(mine, unfinished))
    if (in_flight or 0) >= limits.in_flight:
        raise TooManyJobsInFlightError(
            f"You have {in_flight} jobs queued or running, as many as you may: "
            f"try again when one has finished (or cancel one).",
            TRY_LATER_SECONDS,
        )
    if size > limits.stored_bytes:
        raise BodyTooLargeError(
            f"This job's request takes {_megabytes(size)}; your jobs may keep {_megabytes(limits.stored_bytes)} "
            "stored in all.",
            details={"limit": limits.stored_bytes, "actual": size},
        )
    stored = stored_bytes(session, owner, now)  # its models and trials too: one allowance
    if stored + size > limits.stored_bytes:
        first_to_go = first_expiry(session, owner, now)
        wait = TRY_LATER_SECONDS
        if first_to_go is not None:
            wait = max(1, math.ceil((aware(first_to_go) - now).total_seconds()))
        raise JobStorageFullError(
            f"Your jobs, models and trials keep {_megabytes(stored)} stored and this one adds {_megabytes(size)}; "
            f"you may keep {_megabytes(limits.stored_bytes)}. A finished job is deleted when its result expires: "
            f"try again in {wait} s.",
            wait,
        )


def _check_address(session: Session, limits: OwnerLimits, max_unfinished: int) -> None:
    """Raise the 429 error when anonymous work (all of it, or its address's) is at its cap."""
    unfinished = JobRecord.status.in_(UNFINISHED)
    anonymous_cap = max(1, math.floor(max_unfinished * limits.anonymous_share))
    anonymous = session.scalar(select(func.count()).where(unfinished, JobRecord.address.is_not(None)))
    if (anonymous or 0) >= anonymous_cap:
        raise TooManyJobsError(
            f"Clients without a key have {anonymous} unfinished jobs, as many as they may together "
            f"(the rest of the service's {max_unfinished} is kept for API keys); try again when some have finished.",
            TRY_LATER_SECONDS,
        )
    if limits.address_in_flight:
        from_here = session.scalar(select(func.count()).where(unfinished, JobRecord.address == limits.address))
        if (from_here or 0) >= limits.address_in_flight:
            raise TooManyJobsInFlightError(
                f"Your address has {from_here} jobs queued or running (its films and its own jobs), as many as "
                "it may: try again when one has finished.",
                TRY_LATER_SECONDS,
            )


def create_job(
    engine: Engine,
    kind: str,
    request: dict[str, Any],
    total: int,
    max_unfinished: int,
    *,
    owner: str,
    limits: OwnerLimits | None = None,
) -> JobRecord:
    """Store a new queued job of ``owner``.

    Refused (429, ``TryLaterError``) when the service has ``max_unfinished`` jobs queued or
    running, or when ``owner`` would pass one of its ``limits`` (None: only the service's),
    its address's or the anonymous share of the service's cap (``OwnerLimits``).
    """
    stored = clean_json(request, "the job's request")
    size = json_size(stored)
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        take_write_lock(session)
        now = utc_now()
        unfinished = session.scalar(select(func.count()).select_from(JobRecord).where(JobRecord.status.in_(UNFINISHED)))
        if (unfinished or 0) >= max_unfinished:
            raise TooManyJobsError(
                f"This service has {unfinished} unfinished jobs, its limit; try again when some have finished.",
                TRY_LATER_SECONDS,
            )
        if limits is not None:
            if limits.address is not None:
                _check_address(session, limits, max_unfinished)
            _check_owner(session, owner, limits, size, now)
        record = JobRecord(
            id=uuid.uuid4(),
            owner=owner,
            address=limits.address if limits is not None else None,
            kind=kind,
            status=JobStatus.QUEUED,
            request=stored,
            request_bytes=size,
            result_bytes=0,
            created_at=now,
            attempts=0,
            done=0,
            total=total,
        )
        session.add(record)
        session.commit()
    return record


def get_job(engine: Engine, job_id: uuid.UUID, now: datetime | None = None, *, owner: str | None = None) -> JobRecord:
    """Return the job; JobNotFoundError when there is none, its result has expired, or it is not ``owner``'s.

    ``owner``: the client asking (None: whoever may see every job, the research token). Another
    client's job is answered exactly as one that never existed.
    """
    now = now or utc_now()
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        _check_visible(session, job_id, owner, now)
        record = session.get(JobRecord, job_id)
    if record is None:  # deleted since it was looked at
        raise _not_found(job_id)
    return record


def _not_found(job_id: uuid.UUID) -> JobNotFoundError:
    return JobNotFoundError(
        f"There is no job {job_id}: it never existed, or it finished and its result has expired.",
        details={"job_id": str(job_id)},
    )


def _check_visible(session: Session, job_id: uuid.UUID, owner: str | None, now: datetime) -> None:
    """Raise JobNotFoundError unless the job exists, has not expired and is ``owner``'s (None: anyone's).

    One small query of the job's owner and expiry, the same for a missing job and another
    owner's: the request and result (megabytes, for a batch) are read only for the owner, so
    a foreign job's 404 costs what a missing one's does and tells nothing of its size.
    """
    found = session.execute(select(JobRecord.owner, JobRecord.expires_at).where(JobRecord.id == job_id)).one_or_none()
    if (
        found is None
        or (found.expires_at is not None and aware(found.expires_at) <= now)
        or (owner is not None and found.owner != owner)
    ):
        raise _not_found(job_id)


def find_job(engine: Engine, kind: str, field: str, value: str) -> JobRecord | None:
    """Return the newest job of ``kind`` whose request has ``field`` == ``value`` and that is unfinished or
    succeeded and not expired; None when there is none (a failed or cancelled one is not reused)."""
    now = utc_now()
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        return session.scalars(
            select(JobRecord)
            .where(
                JobRecord.kind == kind,
                JobRecord.request[field].as_string() == value,
                JobRecord.status.in_((*UNFINISHED, JobStatus.SUCCEEDED)),
                or_(JobRecord.expires_at.is_(None), JobRecord.expires_at > now),
            )
            .order_by(JobRecord.created_at.desc())
            .limit(1)
        ).first()


def get_job_file(engine: Engine, job_id: uuid.UUID, *, owner: str | None = None) -> tuple[bytes, str] | None:
    """Return the file the job made (bytes, media type); None when it made none (yet).

    JobNotFoundError when there is no such job, it has expired, or it is not ``owner``'s (``get_job``).
    """
    with Session(engine) as session, storage_errors(session):
        _check_visible(session, job_id, owner, utc_now())
        row = session.execute(
            select(JobRecord.file_data, JobRecord.file_type).where(JobRecord.id == job_id)
        ).one_or_none()
    if row is None or row.file_data is None or row.file_type is None:
        return None
    return bytes(row.file_data), str(row.file_type)


def count_unfinished(engine: Engine) -> dict[str, int]:
    """Return how many jobs are queued and how many running, across all replicas."""
    with Session(engine) as session, storage_errors(session):
        rows = session.execute(
            select(JobRecord.status, func.count()).where(JobRecord.status.in_(UNFINISHED)).group_by(JobRecord.status)
        ).all()
    counts = {str(status): int(count) for status, count in rows}
    return {status.value: counts.get(status.value, 0) for status in UNFINISHED}


def cancel_job(engine: Engine, job_id: uuid.UUID, keep_seconds: float, *, owner: str | None = None) -> JobRecord:
    """Cancel a queued or running job (its runner stops at its next progress report); return it.

    JobFinishedError when the job has finished already (its result stays until it expires);
    JobNotFoundError as ``get_job`` (another ``owner``'s job is not touched).
    """
    now = utc_now()
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        _check_visible(session, job_id, owner, now)
        changed = session.execute(
            update(JobRecord)
            .where(JobRecord.id == job_id, JobRecord.status.in_(UNFINISHED))
            .values(
                status=JobStatus.CANCELLED,
                finished_at=now,
                expires_at=now + timedelta(seconds=keep_seconds),
                lease_owner=None,
                lease_expires_at=None,
            )
        )
        session.commit()
    record = get_job(engine, job_id)
    if not _changed(changed):
        raise JobFinishedError(
            f"Job {job_id} has finished ({record.status}); there is nothing to cancel.",
            details={"job_id": str(job_id), "status": record.status},
        )
    return record


def aware(value: datetime) -> datetime:
    """Return a stored timestamp with its zone (SQLite hands them back without; they were written in UTC)."""
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value


def claim_job(
    engine: Engine, owner: str, lease_seconds: float, kinds: Sequence[str], keep_seconds: float = 86_400.0
) -> JobRecord | None:
    """Take a queued job of ``kinds``, or a running one whose lease has lapsed; None when there is none.

    Round-robin across posters (an anonymous job's address, else its owner), whatever the kind:
    the job of the poster with the fewest jobs running, then of the poster whose latest job
    started longest ago (never: first), then the oldest. So one address's many films (of many
    participants) never hold back a keyed client's batch by more than one job.

    Only ``kinds`` (what this replica can do): during an upgrade, an older replica leaves a new
    kind to the newer ones. A job taken over for the ``MAX_ATTEMPTS``-th time is marked failed
    instead of run again (and kept ``keep_seconds``, as a finished job).
    """
    now = utc_now()
    claimable = and_(
        JobRecord.kind.in_(list(kinds)),
        or_(
            JobRecord.status == JobStatus.QUEUED,
            and_(JobRecord.status == JobStatus.RUNNING, JobRecord.lease_expires_at < now),
        ),
    )
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        for job_id, attempts in session.execute(
            select(JobRecord.id, JobRecord.attempts)
            .where(claimable)
            .order_by(*_round_robin(now), JobRecord.created_at)
            .limit(10)
        ).all():
            if attempts >= MAX_ATTEMPTS:
                session.execute(
                    update(JobRecord)
                    .where(JobRecord.id == job_id, claimable)
                    .values(
                        status=JobStatus.FAILED,
                        lease_owner=None,
                        finished_at=now,
                        expires_at=now + timedelta(seconds=keep_seconds),
                        error={
                            "code": "job_abandoned",
                            "message": f"The job was started {attempts} times and its server stopped each time.",
                            "details": {"attempts": attempts},
                        },
                    )
                )
                session.commit()
                continue
            taken = session.execute(
                update(JobRecord)
                .where(JobRecord.id == job_id, claimable)
                .values(
                    status=JobStatus.RUNNING,
                    lease_owner=owner,
                    lease_expires_at=now + timedelta(seconds=lease_seconds),
                    attempts=JobRecord.attempts + 1,
                    started_at=now,
                )
            )
            session.commit()
            if _changed(taken):  # else another replica took it between the two statements
                return session.get(JobRecord, job_id)
    return None


def _round_robin(now: datetime) -> tuple[Any, ...]:
    """Return the claim's order before age: fewest running jobs of the job's poster, then its longest wait.

    The poster is the job's address for anonymous work (so the films of many participants from
    one address take one turn between them), else its owner (a key, the research token).
    """
    same = aliased(JobRecord)
    poster = func.coalesce(JobRecord.address, JobRecord.owner)
    same_poster = func.coalesce(same.address, same.owner) == poster
    running = (
        select(func.count())
        .where(same_poster, same.status == JobStatus.RUNNING, same.lease_expires_at >= now)
        .scalar_subquery()
    )
    latest_start = select(func.max(same.started_at)).where(same_poster).scalar_subquery()
    return running, latest_start.asc().nulls_first()


def _mine(job_id: uuid.UUID, owner: str) -> Any:
    return and_(JobRecord.id == job_id, JobRecord.lease_owner == owner, JobRecord.status == JobStatus.RUNNING)


def is_held(engine: Engine, job_id: uuid.UUID, owner: str) -> bool:
    """Return whether the job still runs under ``owner``'s lease (False once it was cancelled or taken)."""
    with Session(engine) as session, storage_errors(session):
        return session.scalar(select(JobRecord.id).where(_mine(job_id, owner))) is not None


def renew_lease(
    engine: Engine, job_id: uuid.UUID, owner: str, lease_seconds: float, progress: tuple[int, int] | None = None
) -> bool:
    """Extend ``owner``'s lease (and store the progress); False when the job is no longer ``owner``'s."""
    values: dict[str, Any] = {"lease_expires_at": utc_now() + timedelta(seconds=lease_seconds)}
    if progress is not None:
        values["done"], values["total"] = progress
    with Session(engine) as session, storage_errors(session):
        changed = session.execute(update(JobRecord).where(_mine(job_id, owner)).values(**values))
        session.commit()
    return _changed(changed)


def finish_job(
    engine: Engine,
    job_id: uuid.UUID,
    owner: str,
    keep_seconds: float,
    result: dict[str, Any] | None = None,
    error: dict[str, Any] | None = None,
    file: tuple[bytes, str] | None = None,
) -> bool:
    """Store ``owner``'s result (or error) and end the job; False when the job was no longer ``owner``'s.

    ``file``: (bytes, media type) of a file the job made, kept with the job and expiring with it.
    """
    now = utc_now()
    values: dict[str, Any] = {
        "status": JobStatus.FAILED if error is not None else JobStatus.SUCCEEDED,
        "finished_at": now,
        "expires_at": now + timedelta(seconds=keep_seconds),
        "lease_owner": None,
        "lease_expires_at": None,
        "result": clean_json(result, "the job's result") if result is not None else None,
        "error": error,
    }
    size = sum(json_size(values[field]) for field in ("result", "error") if values[field] is not None)
    if error is None:
        values["done"] = JobRecord.total
    if file is not None and error is None:
        values["file_data"], values["file_type"] = file
        size += len(file[0])
    values["result_bytes"] = size
    with Session(engine) as session, storage_errors(session):
        changed = session.execute(update(JobRecord).where(_mine(job_id, owner)).values(**values))
        session.commit()
    return _changed(changed)


def release_job(engine: Engine, job_id: uuid.UUID, owner: str) -> None:
    """Put ``owner``'s running job back in the queue (its server is stopping), not counting the attempt."""
    with Session(engine) as session, storage_errors(session):
        session.execute(
            update(JobRecord)
            .where(_mine(job_id, owner))
            .values(
                status=JobStatus.QUEUED,
                lease_owner=None,
                lease_expires_at=None,
                attempts=JobRecord.attempts - 1,
                done=0,
            )
        )
        session.commit()


def delete_expired(engine: Engine) -> int:
    """Delete the jobs whose results have expired; return how many."""
    with Session(engine) as session, storage_errors(session):
        gone = session.execute(delete(JobRecord).where(JobRecord.expires_at <= utc_now()))
        session.commit()
    return cast(CursorResult[Any], gone).rowcount
