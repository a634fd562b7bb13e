"""The stored records: every submitted model and every transfer trial, with who sent it and when.

The schema is managed by the Alembic migrations in ``migrations/``; change a table here, then
add a revision there (see ``migrate.py``).
"""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import JSON, Boolean, DateTime, Float, ForeignKey, Index, MetaData, String, Uuid
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

MAX_CLIENT_ID_LENGTH = 128
"""Longest participant or session id a client may send."""

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

    model: Mapped[ModelRecord] = relationship(back_populates="trials")
