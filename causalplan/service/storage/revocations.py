"""Signed-out research sessions: kept until the session would have lapsed, then forgotten."""

from __future__ import annotations

from datetime import UTC, datetime

from sqlalchemy import delete
from sqlalchemy.orm import Session

from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.records import RevokedResearchSessionRecord


def is_revoked(session: Session, session_id: str) -> bool:
    """Return whether the research session ``session_id`` was signed out."""
    with storage_errors(session):
        return session.get(RevokedResearchSessionRecord, session_id) is not None


def revoke(session: Session, session_id: str, expires: int) -> None:
    """Store the research session ``session_id`` as signed out until it would have lapsed."""
    with storage_errors(session):
        if session.get(RevokedResearchSessionRecord, session_id) is None:
            session.add(RevokedResearchSessionRecord(id=session_id, expires_at=datetime.fromtimestamp(expires, UTC)))
            session.commit()


def forget_lapsed_revocations(session: Session, now: datetime) -> int:
    """Delete the revocations of sessions that have lapsed anyway; return how many."""
    with storage_errors(session):
        result = session.execute(
            delete(RevokedResearchSessionRecord).where(RevokedResearchSessionRecord.expires_at < now)
        )
        session.commit()
    return int(getattr(result, "rowcount", 0) or 0)
