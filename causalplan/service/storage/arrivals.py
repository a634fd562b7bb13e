"""The public study link's records: arrivals, the places of each condition, consent, and exclusions.

An arrival is admitted (on consent) to the open condition with the fewest places held, and
numbered within it, which picks its object orders from the Latin squares: conditions and
orders stay balanced as people come. Places held are counted from the participants (finished,
or at work lately: ``studies.assignment.PlaceRules``); admissions are counted in
``study_places.taken`` by a compare-and-set update (``taken = n + 1 where taken = n``) in the
transaction that stores the participant. That update serialises the admissions of a condition,
so two arrivals, even on two replicas over PostgreSQL, never take the same number, and the
second counts the places held after the first is stored: never one over the bound.
"""

from __future__ import annotations

import uuid
from datetime import datetime

from sqlalchemy import and_, case, delete, exists, func, or_, select, text, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from causalplan.service.errors import ClientHoldsPlacesError, StorageError
from causalplan.service.storage import experiments as store
from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.records import (
    MAX_CLIENT_ADDRESS_LENGTH,
    ArrivalRecord,
    ExclusionRecord,
    ExperimentRecord,
    ParticipantRecord,
    StudyPlaceRecord,
    utc_now,
)
from causalplan.studies.assignment import Place, PlaceRules, choose
from causalplan.studies.design import Condition, Design
from causalplan.studies.recruitment import PlatformVisit
from causalplan.studies.steps import Stage

MAX_CLAIM_ATTEMPTS = 50
"""Tries to take a place while others take them at the same moment (each lost race means one was taken)."""
DEFAULT_RULES = PlaceRules()
_CLIENT_LOCK_SPACE = 0x63706C63  # any constant: the advisory locks of one client's admissions (with the key's hash)


def held_places(
    session: Session, experiment_id: uuid.UUID, rules: PlaceRules, now: datetime
) -> dict[str, tuple[int, int]]:
    """Return, per condition, the places held (finished or at work lately) and the participants who finished.

    An excluded participant (screened out, or flagged as too fast) holds no place and is no
    completion: bots that race through with well-formed ids cannot fill the quota.
    """
    participant = ParticipantRecord
    kept = ~exists().where(ExclusionRecord.participant_id == participant.id)
    finished = and_(participant.stage == Stage.DONE.value, kept)
    at_work = and_(
        kept,
        participant.finished_at.is_(None),
        or_(
            and_(participant.updated_at.is_(None), participant.created_at > now - rules.start),
            participant.updated_at > now - rules.hold,
        ),
    )
    query = (
        select(participant.condition, func.count(), func.sum(case((finished, 1), else_=0)))
        .where(participant.experiment_id == experiment_id, or_(finished, at_work))
        .group_by(participant.condition)
    )
    with storage_errors(session):
        return {condition: (int(held), int(done or 0)) for condition, held, done in session.execute(query)}


def places(session: Session, experiment: ExperimentRecord, rules: PlaceRules = DEFAULT_RULES) -> list[Place]:
    """Return each condition's places, in the design's order (rows made on first use)."""
    design = Design.from_dict(experiment.design)
    query = select(StudyPlaceRecord).where(StudyPlaceRecord.experiment_id == experiment.id)
    with storage_errors(session):
        rows = {row.condition: row for row in session.scalars(query.execution_options(populate_existing=True))}
        missing = [condition.name for condition in design.conditions if condition.name not in rows]
        if missing:
            counts = store.participants_per_condition(session, experiment.id)
            # Links made before the public link count as taken places, so numbering goes on from them.
            made = [StudyPlaceRecord(experiment_id=experiment.id, condition=n, taken=counts.get(n, 0)) for n in missing]
            try:
                session.add_all(made)
                session.commit()
            except IntegrityError:  # another arrival made them at the same moment: theirs are as good
                session.rollback()
            rows = {row.condition: row for row in session.scalars(query.execution_options(populate_existing=True))}
    held = held_places(session, experiment.id, rules, utc_now())
    found = []
    for condition in design.conditions:
        row = rows[condition.name]
        taken, finished = held.get(condition.name, (0, 0))
        extra = 0 if row.quota is None else rules.extra(row.quota)
        found.append(Place(condition.name, taken, row.quota, finished, extra, row.taken))
    return found


def set_quotas(session: Session, experiment: ExperimentRecord, quotas: dict[str, int | None]) -> None:
    """Store each condition's quota (None: no limit); places already taken stay taken."""
    places(session, experiment)
    with storage_errors(session):
        for condition, quota in quotas.items():
            session.execute(
                update(StudyPlaceRecord)
                .where(StudyPlaceRecord.experiment_id == experiment.id, StudyPlaceRecord.condition == condition)
                .values(quota=quota)
            )
        session.commit()


def take_place(session: Session, experiment_id: uuid.UUID, place: Place) -> bool:
    """Take the next place of ``place``'s condition if nobody took one since ``place`` was read (no commit)."""
    taken = session.execute(
        update(StudyPlaceRecord)
        .where(
            StudyPlaceRecord.experiment_id == experiment_id,
            StudyPlaceRecord.condition == place.condition,
            StudyPlaceRecord.taken == place.number,
        )
        .values(taken=place.number + 1)
    )
    return bool(taken.rowcount == 1)  # type: ignore[attr-defined]  # a CursorResult for an UPDATE


def claim_place(
    session: Session, experiment: ExperimentRecord, rules: PlaceRules = DEFAULT_RULES
) -> tuple[Condition, int] | None:
    """Take a place (uncommitted, in the session's transaction): its condition and number; None when full."""
    design = Design.from_dict(experiment.design)
    for _ in range(MAX_CLAIM_ATTEMPTS):
        place = choose(places(session, experiment, rules))
        if place is None:
            return None
        with storage_errors(session):
            if take_place(session, experiment.id, place):
                return design.condition(place.condition), place.number
            session.rollback()
    raise StorageError("Too many people are starting the study at this moment; please reload the page.")


def is_full(session: Session, experiment: ExperimentRecord, rules: PlaceRules = DEFAULT_RULES) -> bool:
    """Return whether every condition has reached its quota."""
    return choose(places(session, experiment, rules)) is None


def find_arrival(session: Session, experiment_id: uuid.UUID, visit: PlatformVisit) -> ArrivalRecord | None:
    """Return the earlier arrival of the same platform session on this experiment (None: first time, or no ids).

    Both the platform id and its session must match: a platform id is easy to copy (it is in
    every link of that person), the session (Prolific's ``SESSION_ID``, MTurk's
    ``assignmentId``) only the platform's link to that person carries. So whoever arrives with
    another's platform id alone neither decides for them nor is sent to their record.
    """
    if visit.participant is None or visit.session is None:
        return None
    with storage_errors(session):
        return session.scalars(
            select(ArrivalRecord).where(
                ArrivalRecord.experiment_id == experiment_id,
                ArrivalRecord.platform == visit.platform,
                ArrivalRecord.platform_id == visit.participant,
                ArrivalRecord.platform_session == visit.session,
            )
        ).first()


def arrive(
    session: Session, experiment: ExperimentRecord, visit: PlatformVisit, client: str | None = None
) -> ArrivalRecord:
    """Return this visit's arrival: the one stored for its platform session, or a new one (before consent).

    ``client``: the address it came from (``deps.client_address``), kept for the places-per-client limit.
    """
    found = find_arrival(session, experiment.id, visit)
    if found is not None:
        return found
    record = ArrivalRecord(
        id=uuid.uuid4(),
        code=store.new_code(),
        experiment_id=experiment.id,
        created_at=utc_now(),
        platform=visit.platform,
        platform_id=visit.participant,
        platform_study=visit.study,
        platform_session=visit.session,
        submit_to=visit.submit_to,
        client_address=client[:MAX_CLIENT_ADDRESS_LENGTH] if client else None,
    )
    with storage_errors(session):
        try:
            session.add(record)
            session.commit()
        except IntegrityError:  # the same person opened the link twice at once: the first one counts
            session.rollback()
            found = find_arrival(session, experiment.id, visit)
            if found is None:
                raise
            return found
    return record


def arrival_by_code(session: Session, experiment_id: uuid.UUID, code: str) -> ArrivalRecord | None:
    """Return the arrival with the consent form's ``code`` on this experiment (None when it is not one)."""
    if not store.CODE_PATTERN.fullmatch(code):
        return None
    with storage_errors(session):
        return session.scalars(
            select(ArrivalRecord).where(ArrivalRecord.code == code, ArrivalRecord.experiment_id == experiment_id)
        ).first()


def admit(
    session: Session,
    experiment: ExperimentRecord,
    arrival: ArrivalRecord,
    rules: PlaceRules = DEFAULT_RULES,
    places_per_client: int | None = None,
) -> ParticipantRecord | None:
    """Record consent and make the arrival a participant in the emptiest open condition; None when the study is full.

    ``places_per_client``: the places the arrival's client address may hold admitted but not
    started, this one included; one more raises ClientHoldsPlacesError and stores nothing.
    """
    if arrival.participant is not None:
        return arrival.participant
    claimed = claim_place(session, experiment, rules)
    if claimed is None:
        return None
    condition, ordinal = claimed
    participant = store.participant_record(experiment, Design.from_dict(experiment.design), condition, ordinal)
    participant.started_at = participant.created_at
    with storage_errors(session):  # the place, the participant and the consent: all or nothing
        session.add(participant)
        session.flush()
        arrival.consented = True
        arrival.decided_at = participant.created_at
        arrival.participant_id = participant.id
        session.add(arrival)
        session.flush()
        client = arrival.client_address
        if places_per_client is not None and client:
            held = unstarted_places_of(session, experiment.id, client, rules, participant.created_at)
            if held > places_per_client:
                session.rollback()  # the place goes back too: it was taken in this transaction
                raise ClientHoldsPlacesError(
                    "Many people have just joined this study from your network; please try again later.",
                    int(rules.start.total_seconds()),
                )
        session.commit()
    return participant


def unstarted_places_of(
    session: Session, experiment_id: uuid.UUID, client: str, rules: PlaceRules, now: datetime
) -> int:
    """Return the places ``client`` holds admitted but not started (this transaction's own admission included).

    On PostgreSQL the count waits for a lock of this experiment and client, held to the end of
    the transaction, so two consents from one address on two replicas are counted one after the
    other (each statement sees what the other committed). SQLite has one writer at a time anyway.
    """
    if session.get_bind().dialect.name == "postgresql":
        session.execute(
            text("SELECT pg_advisory_xact_lock(:space, hashtext(:key))"),
            {"space": _CLIENT_LOCK_SPACE, "key": f"{experiment_id}:{client}"},
        )
    participant = ParticipantRecord
    query = (
        select(func.count())
        .select_from(ArrivalRecord)
        .join(participant, participant.id == ArrivalRecord.participant_id)
        .where(
            ArrivalRecord.experiment_id == experiment_id,
            ArrivalRecord.client_address == client,
            participant.finished_at.is_(None),
            participant.updated_at.is_(None),
            participant.created_at > now - rules.start,
        )
    )
    return int(session.scalar(query) or 0)


def decline(session: Session, arrival: ArrivalRecord) -> None:
    """Record that the arrival declined consent (nothing else about them is stored)."""
    if arrival.consented is not None:
        return
    arrival.consented = False
    arrival.decided_at = utc_now()
    store.save(session, arrival)


def purge_undecided(session: Session, arrived_before: datetime) -> int:
    """Delete the arrivals that made no consent decision and came before ``arrived_before``; return how many.

    Nothing else was stored about them; one who comes back later simply arrives anew.
    """
    with storage_errors(session):
        purged = session.execute(
            delete(ArrivalRecord).where(
                ArrivalRecord.consented.is_(None),
                ArrivalRecord.participant_id.is_(None),
                ArrivalRecord.created_at < arrived_before,
            )
        )
        session.commit()
    return int(purged.rowcount)  # type: ignore[attr-defined]  # a CursorResult for a DELETE


def exclusion(participant: ParticipantRecord, reason: str, detail: str) -> ExclusionRecord:
    """Return a new exclusion of ``participant`` (the caller stores it with the participant's change)."""
    return ExclusionRecord(
        id=uuid.uuid4(), participant_id=participant.id, reason=reason, detail=detail[:500], created_at=utc_now()
    )


def exclude(session: Session, participant: ParticipantRecord, reason: str, detail: str) -> None:
    """Add an exclusion of ``participant`` to ``session`` (stored with the participant's change)."""
    session.add(exclusion(participant, reason, detail))


def arrival_counts(session: Session, experiment_id: uuid.UUID) -> dict[str, int]:
    """Return how many arrived on the public link, and how many of them consented, declined or have not decided."""
    with storage_errors(session):
        rows = session.execute(
            select(ArrivalRecord.consented, func.count())
            .where(ArrivalRecord.experiment_id == experiment_id)
            .group_by(ArrivalRecord.consented)
        ).all()
    found = {consented: int(number) for consented, number in rows}
    return {
        "arrived": sum(found.values()),
        "consented": found.get(True, 0),
        "declined": found.get(False, 0),
        "undecided": found.get(None, 0),
    }
