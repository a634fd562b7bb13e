"""The anonymous demo ('Try it yourself', ``POST /try``): how often a client may start it, and how long it is kept.

Demo participants are anyone who pressed a button, so their work is not a study's data:
it is purged once it has been left alone for ``demo_retention_hours``.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from datetime import datetime

from sqlalchemy import Engine, delete, func, select
from sqlalchemy.orm import Session

from causalplan.service.errors import TooManyDemoStartsError
from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.records import (
    ExperimentRecord,
    ModelRecord,
    ParticipantRecord,
    ParticipantTrialRecord,
    TrialRecord,
)
from causalplan.service.storage.throttle import MINUTE_SECONDS, PerMinute

WINDOW_SECONDS = MINUTE_SECONDS
"""The demo's start limit counts the starts of each client in fixed windows this long."""
PURGE_BATCH = 500
"""Participants deleted per statement (keeps each IN list short)."""


class DemoStarts(PerMinute):
    """Counts demo starts per client in fixed windows, in the database (one count for every replica)."""

    def __init__(self, engine: Engine, per_window: int, clock: Callable[[], float] = time.time) -> None:
        super().__init__(engine, "demo_start", per_window, TooManyDemoStartsError, clock)

    def message(self, count: int, retry_after: int) -> str:
        """Return what the demo's 429 page says to a client that started it ``count`` times this minute."""
        return (
            f"This computer has started the demo {count} times in the last minute; "
            f"please wait {retry_after} s, or go on with the demo you already started."
        )


def _chunks(ids: list[uuid.UUID]) -> Iterator[list[uuid.UUID]]:
    for start in range(0, len(ids), PURGE_BATCH):
        yield ids[start : start + PURGE_BATCH]


def _delete_participants(session: Session, ids: Iterable[uuid.UUID]) -> None:
    """Delete participants with their trials and models (links first: the foreign keys point that way)."""
    for chunk in _chunks(list(ids)):
        texts = [str(participant_id) for participant_id in chunk]  # how models and trials name who sent them
        session.execute(delete(ParticipantTrialRecord).where(ParticipantTrialRecord.participant_id.in_(chunk)))
        session.execute(delete(ParticipantRecord).where(ParticipantRecord.id.in_(chunk)))
        session.execute(delete(TrialRecord).where(TrialRecord.participant_id.in_(texts)))
        still_tried = select(TrialRecord.model_id).where(TrialRecord.model_id == ModelRecord.id).exists()
        session.execute(delete(ModelRecord).where(ModelRecord.participant_id.in_(texts), ~still_tried))


def purge_demo_participants(session: Session, untouched_since: datetime) -> int:
    """Delete the demo participants untouched since ``untouched_since``, with all they stored; return how many.

    Only participants of the demo experiment go; a study's participants are never touched.
    """
    last_change = func.coalesce(ParticipantRecord.updated_at, ParticipantRecord.created_at)
    with storage_errors(session):
        ids = list(
            session.scalars(
                select(ParticipantRecord.id)
                .join(ExperimentRecord, ParticipantRecord.experiment_id == ExperimentRecord.id)
                .where(ExperimentRecord.is_demo, last_change < untouched_since)
            )
        )
        if ids:
            _delete_participants(session, ids)
            session.commit()
    return len(ids)
