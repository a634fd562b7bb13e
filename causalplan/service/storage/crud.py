"""Reading and writing the stored records; database failures become ``StorageError``.

Every write is one transaction: a trial and the inline model it was run with are stored
together or not at all. What is stored is cleaned first (``clean_json``), so any database
takes it: no NUL, no unpaired surrogate, no NaN.
"""

from __future__ import annotations

import json
import logging
import math
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import Engine, delete, func, select
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import Session

from causalplan.inputs import clean_text
from causalplan.service.errors import InvalidRequestError, ModelNotFoundError, StorageError
from causalplan.service.storage.records import (
    MAX_CLIENT_ID_LENGTH,
    ModelRecord,
    ParticipantRecord,
    TrialRecord,
    utc_now,
)

logger = logging.getLogger(__name__)

MAX_NESTING = 16
"""A model needs three levels (document, functions, labels); anything deeper is refused."""
_SHORT_TEXT = 200


PAGE_SESSION_PREFIX = "experiment:"
"""The participant pages store a participant's records under the session ``experiment:<id>``."""


@dataclass(frozen=True)
class ClientIds:
    """Who sent a request: as the client says (``X-Participant-Id``, ``X-Session-Id``), or a participant's pages."""

    participant_id: str | None = None
    session_id: str | None = None


@contextmanager
def storage_errors(session: Session | None = None) -> Iterator[None]:
    """Turn database failures into StorageError, rolling back whatever ``session`` had begun.

    The driver's own words (which may name the host and port) go to the log, not to the client.
    """
    try:
        yield
    except SQLAlchemyError as exc:
        if session is not None:
            session.rollback()
        logger.warning("the database failed: %s", exc)
        raise StorageError(
            "The database could not be used, so nothing was stored; the server log says why.",
            details={"operation": "storage"},
        ) from None


def clean_json(value: object, what: str = "the document") -> Any:
    """Return a copy of parsed JSON with every string cleaned; refuse NaN, infinities and deep nesting."""

    def clean(item: object, depth: int) -> Any:
        if depth > MAX_NESTING:
            raise InvalidRequestError(
                f"{what.capitalize()} is nested more than {MAX_NESTING} levels deep.", details={"limit": MAX_NESTING}
            )
        if isinstance(item, str):
            return clean_text(item)
        if isinstance(item, float) and not math.isfinite(item):
            raise InvalidRequestError(f"{what.capitalize()} contains {json.dumps(item)}, which JSON does not allow.")
        if isinstance(item, Mapping):
            return {clean_text(str(key)): clean(child, depth + 1) for key, child in item.items()}
        if isinstance(item, list):
            return [clean(child, depth + 1) for child in item]
        return item

    return clean(value, 0)


def _short(text: str | None, length: int = _SHORT_TEXT) -> str | None:
    return None if text is None else clean_text(text)[:length]


def _new_record_fields(client: ClientIds) -> dict[str, Any]:
    """Return what every new record gets: a new id, the time now, and ``client``'s ids, cleaned and cut."""
    return {
        "id": uuid.uuid4(),
        "created_at": utc_now(),
        "participant_id": _short(client.participant_id, MAX_CLIENT_ID_LENGTH),
        "session_id": _short(client.session_id, MAX_CLIENT_ID_LENGTH),
    }


def new_model_record(
    document: dict[str, Any],
    object_id: str,
    is_valid: bool,
    report: dict[str, Any],
    canonical_hash: str | None,
    client: ClientIds,
    cleaned: bool = False,
) -> ModelRecord:
    """Return an unsaved record of a submitted model (``cleaned``: ``document`` and ``report`` are cleaned already)."""
    return ModelRecord(
        **_new_record_fields(client),
        object_id=_short(object_id) or "",
        is_valid=is_valid,
        canonical_hash=canonical_hash,
        document=document if cleaned else clean_json(document),
        report=report if cleaned else clean_json(report),
    )


def new_trial_record(
    model_id: uuid.UUID,
    mapping: dict[str, Any],
    planner: str,
    verdict: dict[str, Any],
    cached: bool,
    seconds: float,
    client: ClientIds,
) -> TrialRecord:
    """Return an unsaved record of a transfer trial (``verdict`` is ``TransferVerdict.as_dict()``)."""
    return TrialRecord(
        **_new_record_fields(client),
        model_id=model_id,
        mapping=clean_json(mapping),
        training_object=_short(verdict.get("training_object")),
        test_object=_short(verdict.get("test_object")),
        planner=_short(planner, 64) or "",
        verdict=str(verdict["verdict"]),
        generalization=verdict.get("generalization"),
        decided_by=str(verdict["decided_by"]),
        cached=cached,
        seconds=seconds,
        result=clean_json(verdict),
    )


def save(engine: Engine, records: Sequence[ModelRecord | TrialRecord]) -> None:
    """Store new ``records`` (as ``new_model_record`` and ``new_trial_record`` make them) in one transaction.

    The records stay readable afterwards (they are not expired on commit).
    """
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        session.add_all(records)  # the unit of work inserts models before the trials that refer to them
        session.commit()


def get_model(session: Session, model_id: uuid.UUID) -> ModelRecord:
    """Return the stored model with this id; ModelNotFoundError when there is none."""
    with storage_errors(session):
        record = session.get(ModelRecord, model_id)
    if record is None:
        raise ModelNotFoundError(f"There is no stored model with id {model_id}.", details={"model_id": str(model_id)})
    return record


def list_trials(
    session: Session,
    offset: int,
    limit: int,
    participant_id: str | None = None,
    session_id: str | None = None,
) -> tuple[list[TrialRecord], int]:
    """Return a page of trials (newest first) and how many match the filters in all."""
    query = select(TrialRecord)
    if participant_id is not None:
        query = query.where(TrialRecord.participant_id == participant_id)
    if session_id is not None:
        query = query.where(TrialRecord.session_id == session_id)
    with storage_errors(session):
        count = session.scalar(select(func.count()).select_from(query.subquery())) or 0
        page = session.scalars(
            query.order_by(TrialRecord.created_at.desc(), TrialRecord.id).offset(offset).limit(limit)
        ).all()
    return list(page), count


def all_records(session: Session) -> tuple[list[ModelRecord], list[TrialRecord]]:
    """Return every stored model and trial, oldest first."""
    with storage_errors(session):
        models = session.scalars(select(ModelRecord).order_by(ModelRecord.created_at, ModelRecord.id)).all()
        trials = session.scalars(select(TrialRecord).order_by(TrialRecord.created_at, TrialRecord.id)).all()
    return list(models), list(trials)


def purge_invalid_models(session: Session, stored_before: datetime) -> int:
    """Delete the invalid models stored before ``stored_before`` that no trial or participant uses; return how many.

    A model that a trial was run with stays as long as its trial (it is a study's data).
    """
    used_by_trial = select(TrialRecord.id).where(TrialRecord.model_id == ModelRecord.id).exists()
    used_by_participant = select(ParticipantRecord.id).where(ParticipantRecord.model_id == ModelRecord.id).exists()
    with storage_errors(session):
        purged = session.execute(
            delete(ModelRecord).where(
                ModelRecord.is_valid.is_(False),
                ModelRecord.created_at < stored_before,
                ~used_by_trial,
                ~used_by_participant,
            )
        )
        session.commit()
    return int(purged.rowcount)  # type: ignore[attr-defined]  # a CursorResult for a DELETE
