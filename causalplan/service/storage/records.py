"""The stored records: every submitted model and transfer trial, and the experiments run in the browser.

The schema is managed by the Alembic migrations in ``migrations/``; change a table here, then
add a revision there (see ``migrate.py``).
"""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    JSON,
    Boolean,
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    MetaData,
    String,
    UniqueConstraint,
    Uuid,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

from causalplan.studies.recruitment import MAX_PLATFORM_ID_LENGTH

MAX_CLIENT_ID_LENGTH = 128
"""Longest participant or session id a client may send."""
MAX_CLIENT_ADDRESS_LENGTH = 64
"""Longest client address stored with an arrival (an IPv6 address in full is 45 characters)."""
MAX_OWNER_LENGTH = 160
"""Longest owner of a job: a kind of client and its id (``address:<address>``, ``participant:<uuid>``, ...)."""
MAX_ADDRESS_LENGTH = 64
"""Longest address stored with a job (an IPv6 address takes at most 45 characters)."""

NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}


def utc_now() -> datetime:
    """Return the current time, timezone-aware in UTC."""
    return datetime.now(UTC)


class Base(DeclarativeBase):
    """The declarative base; constraint names follow one convention so migrations can name them."""

    metadata = MetaData(naming_convention=NAMING_CONVENTION)


class ModelRecord(Base):
    """One submitted causal model, valid or not, exactly as the client sent it."""

    __tablename__ = "models"

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now, index=True)
    participant_id: Mapped[str | None] = mapped_column(String(MAX_CLIENT_ID_LENGTH), index=True)
    session_id: Mapped[str | None] = mapped_column(String(MAX_CLIENT_ID_LENGTH), index=True)
    object_id: Mapped[str] = mapped_column(String(200))
    is_valid: Mapped[bool] = mapped_column(Boolean)
    canonical_hash: Mapped[str | None] = mapped_column(String(64), index=True)
    document: Mapped[dict[str, Any]] = mapped_column(JSON)
    report: Mapped[dict[str, Any]] = mapped_column(JSON)
    owner: Mapped[str | None] = mapped_column(String(MAX_OWNER_LENGTH), index=True)
    """The client whose storage allowance it counts in (``service.owners``); None: the pages' own, or older."""
    stored_bytes: Mapped[int] = mapped_column(Integer, server_default="0")
    expires_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), index=True)
    """When it is purged (a client without a key, no experiment); None: kept."""

    trials: Mapped[list[TrialRecord]] = relationship(back_populates="model")


class TrialRecord(Base):
    """One transfer trial: a model tried on an object through a step-3 mapping, and the verdict."""

    __tablename__ = "trials"
    __table_args__ = (Index("ix_trials_participant_created", "participant_id", "created_at"),)

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now, index=True)
    participant_id: Mapped[str | None] = mapped_column(String(MAX_CLIENT_ID_LENGTH))
    session_id: Mapped[str | None] = mapped_column(String(MAX_CLIENT_ID_LENGTH), index=True)
    model_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("models.id", ondelete="RESTRICT"), index=True)
    mapping: Mapped[dict[str, Any]] = mapped_column(JSON)
    training_object: Mapped[str | None] = mapped_column(String(200))
    test_object: Mapped[str | None] = mapped_column(String(200))
    planner: Mapped[str] = mapped_column(String(64))
    verdict: Mapped[str] = mapped_column(String(32), index=True)
    generalization: Mapped[str | None] = mapped_column(String(32))
    decided_by: Mapped[str] = mapped_column(String(32))
    cached: Mapped[bool] = mapped_column(Boolean, default=False)
    seconds: Mapped[float] = mapped_column(Float)
    result: Mapped[dict[str, Any]] = mapped_column(JSON)
    owner: Mapped[str | None] = mapped_column(String(MAX_OWNER_LENGTH), index=True)
    """As a model's: whose allowance it counts in; None: the pages' own, or older."""
    stored_bytes: Mapped[int] = mapped_column(Integer, server_default="0")
    expires_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), index=True)

    model: Mapped[ModelRecord] = relationship(back_populates="trials")


MAX_CODE_LENGTH = 64
"""Longest participant link code (the codes made are 22 characters)."""


class ExperimentRecord(Base):
    """A study: its conditions (training and test objects), counterbalancing and options."""

    __tablename__ = "experiments"

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now, index=True)
    name: Mapped[str] = mapped_column(String(200))
    description: Mapped[str] = mapped_column(String(2000), default="")
    design: Mapped[dict[str, Any]] = mapped_column(JSON)
    is_demo: Mapped[bool] = mapped_column(Boolean, default=False)
    recruitment: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    """Consent text, completion codes, the comprehension rule, ... (``web.recruitment``); None: the defaults."""

    participants: Mapped[list[ParticipantRecord]] = relationship(back_populates="experiment")


class ParticipantRecord(Base):
    """One participant link: condition, counterbalanced object order, progress and saved work.

    ``code`` is the opaque secret in the participant's link; ``work`` holds everything typed
    so far (drafts included), so a reload or a lost connection loses nothing.
    """

    __tablename__ = "participants"

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    code: Mapped[str] = mapped_column(String(MAX_CODE_LENGTH), unique=True)
    experiment_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("experiments.id", ondelete="RESTRICT"), index=True)
    condition: Mapped[str] = mapped_column(String(200))
    ordinal: Mapped[int] = mapped_column(Integer)
    training_order: Mapped[list[str]] = mapped_column(JSON)
    test_order: Mapped[list[str]] = mapped_column(JSON)
    stage: Mapped[str] = mapped_column(String(16))
    position: Mapped[int] = mapped_column(Integer, default=0)
    work: Mapped[dict[str, Any]] = mapped_column(JSON)
    model_id: Mapped[uuid.UUID | None] = mapped_column(ForeignKey("models.id", ondelete="RESTRICT"))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    updated_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))

    experiment: Mapped[ExperimentRecord] = relationship(back_populates="participants")
    trials: Mapped[list[ParticipantTrialRecord]] = relationship(
        back_populates="participant", order_by="ParticipantTrialRecord.position"
    )
    arrival: Mapped[ArrivalRecord | None] = relationship(back_populates="participant", uselist=False)
    exclusions: Mapped[list[ExclusionRecord]] = relationship(order_by="ExclusionRecord.created_at")


class ParticipantTrialRecord(Base):
    """A participant's step-3 trial on one test object (at most one per object)."""

    __tablename__ = "participant_trials"
    __table_args__ = (UniqueConstraint("participant_id", "test_object", name="uq_participant_trials_test_object"),)

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    participant_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("participants.id", ondelete="RESTRICT"), index=True)
    trial_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("trials.id", ondelete="RESTRICT"), unique=True)
    test_object: Mapped[str] = mapped_column(String(200))
    position: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)

    participant: Mapped[ParticipantRecord] = relationship(back_populates="trials")
    trial: Mapped[TrialRecord] = relationship()


class StudyPlaceRecord(Base):
    """The places of one condition on an experiment's public link: how many are taken, and the quota.

    Arrivals take a place with a compare-and-set update of ``taken``, so two arrivals on two
    service replicas cannot both take the last place (see ``web.arrivals.claim_place``).
    """

    __tablename__ = "study_places"

    experiment_id: Mapped[uuid.UUID] = mapped_column(
        ForeignKey("experiments.id", ondelete="RESTRICT"), primary_key=True
    )
    condition: Mapped[str] = mapped_column(String(200), primary_key=True)
    taken: Mapped[int] = mapped_column(Integer, default=0)
    quota: Mapped[int | None] = mapped_column(Integer)


class ArrivalRecord(Base):
    """One arrival on an experiment's public link, with the platform's ids and the consent decision.

    Before consent, this row is all that is stored about a person. ``code`` is the opaque secret
    the consent form sends back; one platform session (the platform id with Prolific's
    ``SESSION_ID`` or MTurk's ``assignmentId``) arrives once per experiment, and coming back with
    both finds it: the platform id alone, which anyone may copy, finds nothing.
    """

    __tablename__ = "study_arrivals"
    __table_args__ = (
        UniqueConstraint(
            "experiment_id", "platform", "platform_id", "platform_session", name="uq_study_arrivals_platform_session"
        ),
        Index("ix_study_arrivals_client", "experiment_id", "client_address"),
    )

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    code: Mapped[str] = mapped_column(String(MAX_CODE_LENGTH), unique=True)
    experiment_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("experiments.id", ondelete="RESTRICT"), index=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    platform: Mapped[str] = mapped_column(String(16))
    platform_id: Mapped[str | None] = mapped_column(String(MAX_PLATFORM_ID_LENGTH))
    platform_study: Mapped[str | None] = mapped_column(String(MAX_PLATFORM_ID_LENGTH))
    platform_session: Mapped[str | None] = mapped_column(String(MAX_PLATFORM_ID_LENGTH))
    submit_to: Mapped[str | None] = mapped_column(String(64))
    client_address: Mapped[str | None] = mapped_column(String(MAX_CLIENT_ADDRESS_LENGTH))
    """The address the arrival came from (``deps.client_address``): one may hold ``places_per_client`` places."""
    consented: Mapped[bool | None] = mapped_column(Boolean)
    decided_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    participant_id: Mapped[uuid.UUID | None] = mapped_column(
        ForeignKey("participants.id", ondelete="RESTRICT"), unique=True
    )

    participant: Mapped[ParticipantRecord | None] = relationship(back_populates="arrival")


class ExclusionRecord(Base):
    """A participant screened out or flagged, with the reason: recorded once, never deleted."""

    __tablename__ = "participant_exclusions"

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    participant_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("participants.id", ondelete="RESTRICT"), index=True)
    reason: Mapped[str] = mapped_column(String(32))
    detail: Mapped[str] = mapped_column(String(500))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class RevokedResearchSessionRecord(Base):
    """A research sign-in cookie signed out before it lapsed: refused by every server process until then."""

    __tablename__ = "revoked_research_sessions"

    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    expires_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), index=True)


class FailedAttemptRecord(Base):
    """One wrong research token: who sent it and when (the throttle every replica shares)."""

    __tablename__ = "failed_attempts"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    client: Mapped[str] = mapped_column(String(MAX_CLIENT_ID_LENGTH), index=True)
    at: Mapped[float] = mapped_column(Float, index=True)
    """Seconds since the epoch: every replica's clock reads the same time."""


class WindowCountRecord(Base):
    """How often a client did something (``scope``) in one fixed window: the demo's start limit."""

    __tablename__ = "window_counts"

    scope: Mapped[str] = mapped_column(String(32), primary_key=True)
    client: Mapped[str] = mapped_column(String(MAX_CLIENT_ID_LENGTH), primary_key=True)
    window: Mapped[int] = mapped_column(Integer, primary_key=True)
    count: Mapped[int] = mapped_column(Integer)
    ends_at: Mapped[float] = mapped_column(Float, index=True)


class JobRecord(Base):
    """A long piece of work asked over HTTP: its request, progress, lease, and result.

    Any replica answers for any job; the replica running it holds a lease (``lease_owner``
    until ``lease_expires_at``) and renews it while it works, so a job whose replica died is
    taken up again by another once the lease has lapsed.
    """

    __tablename__ = "jobs"
    __table_args__ = (
        Index("ix_jobs_status_created", "status", "created_at"),
        Index("ix_jobs_owner_status", "owner", "status"),
        Index("ix_jobs_address_status", "address", "status"),
    )

    id: Mapped[uuid.UUID] = mapped_column(Uuid, primary_key=True, default=uuid.uuid4)
    owner: Mapped[str] = mapped_column(String(MAX_OWNER_LENGTH), server_default="")
    """The client the job belongs to (``service.owners``): only it, and the research token, may see it.
    Empty for jobs stored before jobs had owners: the research token's alone."""
    address: Mapped[str | None] = mapped_column(String(MAX_ADDRESS_LENGTH))
    """The address that posted an anonymous job (an address's own, a participant's film); None for a key's or the
    research token's. Anonymous jobs share part of the service's cap, and each address has a cap."""
    kind: Mapped[str] = mapped_column(String(32))
    status: Mapped[str] = mapped_column(String(16))
    request: Mapped[dict[str, Any]] = mapped_column(JSON)
    request_bytes: Mapped[int] = mapped_column(Integer, server_default="0")
    """The stored request's size (its JSON): what it counts against its owner's storage."""
    result_bytes: Mapped[int] = mapped_column(Integer, server_default="0")
    """The stored result's, error's and file's size, once the job has finished."""
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    expires_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), index=True)
    lease_owner: Mapped[str | None] = mapped_column(String(128))
    lease_expires_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    done: Mapped[int] = mapped_column(Integer, default=0)
    total: Mapped[int] = mapped_column(Integer, default=0)
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    error: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    file_type: Mapped[str | None] = mapped_column(String(64))
    """The media type of the file the job made (the robot's film), when it made one."""
    file_data: Mapped[bytes | None] = mapped_column(LargeBinary, deferred=True)
    """The file's bytes: read only when the file is asked for, never with the job."""
