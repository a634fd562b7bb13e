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
from datetime import UTC, datetime, timedelta
from typing import Any

from sqlalchemy import Engine, delete, func, select
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import Session

from causalplan.inputs import clean_text
from causalplan.service.errors import InvalidRequestError, ModelNotFoundError, StorageError, StorageFullError
from causalplan.service.storage.allowance import (
    Allowance,
    first_expiry,
    give_space_back,
    json_size,
    stored_bytes,
    take_write_lock,
)
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
MEGABYTE = 1_000_000
ROW_OVERHEAD_BYTES = 4096
"""What a stored row takes beyond its JSON, at most, about: its other columns, its index entries, and the
slack of the last page of its overflow chain (SQLite's pages are 4 KB). Measured near 2 KB a model row."""
TRY_LATER_SECONDS = 30
"""``Retry-After`` of a full allowance whose rows never expire (a key's): about when a job finishes."""


PAGE_SESSION_PREFIX = "experiment:"
"""The participant pages store a participant's records under the session ``experiment:<id>``."""


@dataclass(frozen=True)
class ClientIds:
    """Who sent a request: as the client says (``X-Participant-Id``, ``X-Session-Id``), or a participant's pages.

    ``allowance``: whose storage allowance the request's models and trials count in, and how
    long they are kept (a client without a key's rows belong to no experiment and expire);
    None for the pages' own rows (a study's data) and work no client asked for.
    """

    participant_id: str | None = None
    session_id: str | None = None
    allowance: Allowance | None = None

    def stored_fields(self, size: int) -> dict[str, Any]:
        """Return the owner, size and expiry of a new record whose JSON takes ``size`` bytes, as this client stores it.

        The size counted is the JSON's plus ``ROW_OVERHEAD_BYTES``, so an allowance bounds the
        database's growth, not only its documents'.
        """
        counted = size + ROW_OVERHEAD_BYTES
        allowance = self.allowance
        if allowance is None:
            return {"owner": None, "stored_bytes": counted, "expires_at": None}
        keep = allowance.keep_seconds
        expires = utc_now() + timedelta(seconds=keep) if keep is not None else None
        return {"owner": allowance.owner, "stored_bytes": counted, "expires_at": expires}


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
    document = document if cleaned else clean_json(document)
    report = report if cleaned else clean_json(report)
    return ModelRecord(
        **_new_record_fields(client),
        **client.stored_fields(json_size(document) + json_size(report)),
        object_id=_short(object_id) or "",
        is_valid=is_valid,
        canonical_hash=canonical_hash,
        document=document,
        report=report,
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
    mapping = clean_json(mapping)
    result = clean_json(verdict)
    return TrialRecord(
        **_new_record_fields(client),
        **client.stored_fields(json_size(mapping) + json_size(result)),
        model_id=model_id,
        mapping=mapping,
        training_object=_short(verdict.get("training_object")),
        test_object=_short(verdict.get("test_object")),
        planner=_short(planner, 64) or "",
        verdict=str(verdict["verdict"]),
        generalization=verdict.get("generalization"),
        decided_by=str(verdict["decided_by"]),
        cached=cached,
        seconds=seconds,
        result=result,
    )


def save(engine: Engine, records: Sequence[ModelRecord | TrialRecord], client: ClientIds | None = None) -> None:
    """Store new ``records`` (as ``new_model_record`` and ``new_trial_record`` make them) in one transaction.

    ``client``: whose records they are; with an allowance, they are counted against it first,
    with the owner's jobs, models and trials, under the write lock (``StorageFullError``, 429,
    when they would pass it: nothing is stored). The records stay readable afterwards.
    """
    with Session(engine, expire_on_commit=False) as session, storage_errors(session):
        allowance = client.allowance if client is not None else None
        if allowance is not None and allowance.limit_bytes is not None:
            take_write_lock(session)
            size = sum(record.stored_bytes for record in records)
            _check_allowance(session, allowance.owner, allowance.limit_bytes, size)
        session.add_all(records)  # the unit of work inserts models before the trials that refer to them
        session.commit()


def _check_allowance(session: Session, owner: str, allowance: int, size: int) -> None:
    now = utc_now()
    stored = stored_bytes(session, owner, now)
    if stored + size <= allowance:
        return
    first_to_go = first_expiry(session, owner, now)
    wait = TRY_LATER_SECONDS
    if first_to_go is not None:
        expires = first_to_go.replace(tzinfo=UTC) if first_to_go.tzinfo is None else first_to_go
        wait = max(1, math.ceil((expires - now).total_seconds()))
    raise StorageFullError(
        f"Your models, trials and jobs keep {stored / MEGABYTE:.2f} MB stored and this request adds "
        f"{size / MEGABYTE:.2f} MB; you may keep {allowance / MEGABYTE:.2f} MB. Stored rows of a client without a key "
        f"expire: try again in {wait} s.",
        wait,
    )


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


def purge_expired_records(engine: Engine, now: datetime) -> int:
    """Delete the expired trials, then the expired models no trial or participant uses; give the space back.

    Returns how many rows were deleted.
    """
    used_by_trial = select(TrialRecord.id).where(TrialRecord.model_id == ModelRecord.id).exists()
    used_by_participant = select(ParticipantRecord.id).where(ParticipantRecord.model_id == ModelRecord.id).exists()
    with Session(engine) as session, storage_errors(session):
        trials = session.execute(delete(TrialRecord).where(TrialRecord.expires_at <= now))
        models = session.execute(
            delete(ModelRecord).where(ModelRecord.expires_at <= now, ~used_by_trial, ~used_by_participant)
        )
        session.commit()
    deleted = int(trials.rowcount) + int(models.rowcount)  # type: ignore[attr-defined]  # CursorResults of DELETEs
    if deleted:
        with storage_errors():
            give_space_back(engine)
    return deleted
