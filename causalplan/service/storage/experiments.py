"""Reading and writing experiments, participants and their trials; database failures become ``StorageError``."""

from __future__ import annotations

import re
import secrets
import string
import uuid
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

from sqlalchemy import Select, func, select, update
from sqlalchemy.orm import Session, selectinload

from causalplan.service.errors import ExperimentNotFoundError, InvalidRequestError, ParticipantNotFoundError
from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.records import (
    ExperimentRecord,
    ParticipantRecord,
    ParticipantTrialRecord,
    TrialRecord,
    utc_now,
)
from causalplan.studies.assignment import Place, choose
from causalplan.studies.counterbalance import object_orders
from causalplan.studies.design import Condition, Design
from causalplan.studies.journey import Journey
from causalplan.studies.steps import Stage

CODE_ALPHABET = string.ascii_letters + string.digits
CODE_LENGTH = 22
"""A participant code: 22 random letters and digits (131 bits), so not guessable, not enumerable.

Letters and digits only, so a double click selects the whole code, and no spreadsheet
mistakes one starting with '-' for a formula.
"""
CODE_PATTERN = re.compile(r"[A-Za-z0-9_-]{16,64}")
MAX_LINKS_PER_REQUEST = 500

DEMO_NAME = "Try it yourself: desk lamp, then flashlight"


def new_code() -> str:
    """Return a fresh opaque participant code."""
    return "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_LENGTH))


def save(session: Session, *records: object) -> None:
    """Store (or update) ``records`` in one transaction."""
    with storage_errors(session):
        session.add_all(records)
        session.commit()


Changed = TypeVar("Changed")


def change_participant(session: Session, participant: ParticipantRecord, change: Callable[[], Changed]) -> Changed:
    """Apply ``change`` to the participant as stored now, holding their row, and store it; return its result.

    Two requests of one participant may be in flight at once (a slow plan beside a check): each
    read the record when it began, so storing that copy whole would undo what the other stored
    meanwhile. This ends the session's transaction, locks the row with an update that changes
    nothing (a row lock in PostgreSQL, the write lock in SQLite), reads the record again and
    only then lets ``change`` edit it, so every change lands on the latest one.
    """
    with storage_errors(session):
        session.rollback()
        session.execute(
            update(ParticipantRecord)
            .where(ParticipantRecord.id == participant.id)
            .values(position=ParticipantRecord.position)
            .execution_options(synchronize_session=False)  # the record is read again just below
        )
        session.refresh(participant)
        result = change()
        session.commit()
        return result


def create_experiment(
    session: Session, name: str, description: str, design: Design, is_demo: bool = False
) -> ExperimentRecord:
    """Store a new experiment and return it."""
    record = ExperimentRecord(
        id=uuid.uuid4(), name=name, description=description, design=design.as_dict(), is_demo=is_demo
    )
    save(session, record)
    return record


def get_experiment(session: Session, experiment_id: uuid.UUID) -> ExperimentRecord:
    """Return the experiment with this id; ExperimentNotFoundError when there is none."""
    with storage_errors(session):
        record = session.get(ExperimentRecord, experiment_id)
    if record is None:
        raise ExperimentNotFoundError(
            f"There is no experiment with id {experiment_id}.", details={"experiment_id": str(experiment_id)}
        )
    return record


def list_experiments(session: Session) -> list[tuple[ExperimentRecord, int]]:
    """Return every experiment (newest first) with its number of participants."""
    counts = (
        select(ParticipantRecord.experiment_id, func.count().label("participants"))
        .group_by(ParticipantRecord.experiment_id)
        .subquery()
    )
    query = (
        select(ExperimentRecord, func.coalesce(counts.c.participants, 0))
        .outerjoin(counts, counts.c.experiment_id == ExperimentRecord.id)
        .order_by(ExperimentRecord.created_at.desc(), ExperimentRecord.id)
    )
    with storage_errors(session):
        return [(experiment, int(count)) for experiment, count in session.execute(query).all()]


def demo_experiment(session: Session, design: Design) -> ExperimentRecord:
    """Return the built-in demo experiment (made on first use)."""
    with storage_errors(session):
        record = session.scalars(
            select(ExperimentRecord).where(ExperimentRecord.is_demo).order_by(ExperimentRecord.created_at).limit(1)
        ).first()
    if record is not None:
        return record
    description = "Made by the 'Try it yourself' button of the start page."
    return create_experiment(session, DEMO_NAME, description, design, is_demo=True)


def participants_per_condition(session: Session, experiment_id: uuid.UUID) -> Counter[str]:
    """Return how many participants each condition of an experiment has (made links and arrivals)."""
    with storage_errors(session):
        rows = session.execute(
            select(ParticipantRecord.condition, func.count())
            .where(ParticipantRecord.experiment_id == experiment_id)
            .group_by(ParticipantRecord.condition)
        ).all()
    return Counter({str(name): int(number) for name, number in rows})


def add_participants(
    session: Session, experiment: ExperimentRecord, count: int, condition_name: str | None
) -> list[ParticipantRecord]:
    """Make ``count`` participant links, in one condition or spread evenly over all; return them.

    Spread, each link joins the condition ``studies.assignment.choose`` picks (the rule arrivals
    on the public link follow), counting every participant made so far. Each participant is
    numbered within their condition, and that number picks their object orders from the Latin
    squares (``counterbalance.object_orders``).
    """
    design = Design.from_dict(experiment.design)
    if not 1 <= count <= MAX_LINKS_PER_REQUEST:
        raise InvalidRequestError(
            f"Make between 1 and {MAX_LINKS_PER_REQUEST} links at a time, not {count}.",
            details={"limit": MAX_LINKS_PER_REQUEST, "actual": count},
        )
    if condition_name is not None and condition_name not in [c.name for c in design.conditions]:
        names = ", ".join(c.name for c in design.conditions)
        raise InvalidRequestError(
            f"The experiment has no condition '{condition_name}'; its conditions are: {names}.",
            details={"condition": condition_name},
        )
    # Two researchers making links at the same moment may number a participant twice: that only
    # repeats an order, which counterbalancing tolerates; it never loses a participant.
    taken = participants_per_condition(session, experiment.id)
    made: list[ParticipantRecord] = []
    for _ in range(count):
        name = condition_name
        if name is None:  # the arrivals' rule: the emptiest (links have no quota, so every condition is open)
            place = choose([Place(c.name, taken[c.name], quota=None) for c in design.conditions])
            assert place is not None, "a condition without a quota is always open"
            name = place.condition
        condition = design.condition(name)
        made.append(participant_record(experiment, design, condition, taken[condition.name]))
        taken[condition.name] += 1
    save(session, *made)
    return made


def participant_record(
    experiment: ExperimentRecord, design: Design, condition: Condition, ordinal: int
) -> ParticipantRecord:
    """Return a new participant (not stored) of ``condition``, number ``ordinal`` in it, with its object orders."""
    training, tests = object_orders(
        ordinal, condition.training, condition.tests, design.counterbalance_training, design.counterbalance_tests
    )
    return ParticipantRecord(
        id=uuid.uuid4(),
        code=new_code(),
        experiment_id=experiment.id,
        condition=condition.name,
        ordinal=ordinal,
        training_order=training,
        test_order=tests,
        stage=(Stage.TUTORIAL if design.tutorial else Stage.STEP1).value,
        position=0,
        work={},
        created_at=utc_now(),
    )


def is_participant(session: Session, claimed: str) -> bool:
    """Return whether ``claimed`` (an id a client sent) is the id of a study participant."""
    try:
        participant_id = uuid.UUID(claimed)
    except ValueError:
        return False
    with storage_errors(session):
        return session.scalar(select(ParticipantRecord.id).where(ParticipantRecord.id == participant_id)) is not None


def participant_by_code(session: Session, code: str) -> ParticipantRecord:
    """Return the participant of a link code; ParticipantNotFoundError when the code is not one."""
    record = None
    if CODE_PATTERN.fullmatch(code):
        with storage_errors(session):
            record = session.scalars(select(ParticipantRecord).where(ParticipantRecord.code == code)).first()
    if record is None:
        raise ParticipantNotFoundError(
            "This participant link is not valid: check that it was copied whole, or ask the researcher for a new one."
        )
    return record


def participants_of(session: Session, experiment_id: uuid.UUID) -> list[ParticipantRecord]:
    """Return an experiment's participants in the order their links were made."""
    with storage_errors(session):
        return list(
            session.scalars(
                select(ParticipantRecord)
                .options(selectinload(ParticipantRecord.arrival), selectinload(ParticipantRecord.exclusions))
                .where(ParticipantRecord.experiment_id == experiment_id)
                .order_by(ParticipantRecord.created_at, ParticipantRecord.condition, ParticipantRecord.ordinal)
            ).all()
        )


@dataclass
class ParticipantJourney(Journey):
    """A stored participant's way through their experiment (the whole record, for storing it)."""

    participant: ParticipantRecord


@dataclass(frozen=True)
class StoredTrial:
    """One step-3 trial of an experiment, with its participant and the stored trial."""

    link: ParticipantTrialRecord
    participant: ParticipantRecord
    trial: TrialRecord


def _stored_trials() -> Select[ParticipantTrialRecord, ParticipantRecord, TrialRecord]:
    return (
        select(ParticipantTrialRecord, ParticipantRecord, TrialRecord)
        .join(ParticipantRecord, ParticipantTrialRecord.participant_id == ParticipantRecord.id)
        .join(TrialRecord, ParticipantTrialRecord.trial_id == TrialRecord.id)
    )


def trials_of(session: Session, experiment_id: uuid.UUID) -> list[StoredTrial]:
    """Return every step-3 trial of an experiment, oldest first."""
    query = (
        _stored_trials()
        .where(ParticipantRecord.experiment_id == experiment_id)
        .order_by(ParticipantTrialRecord.created_at, ParticipantTrialRecord.id)
    )
    with storage_errors(session):
        return [StoredTrial(*row) for row in session.execute(query).all()]


def trials_by_test(session: Session, participant: ParticipantRecord) -> dict[str, StoredTrial]:
    """Return the participant's trials by test object (one query for all of them)."""
    query = _stored_trials().where(ParticipantTrialRecord.participant_id == participant.id)
    with storage_errors(session):
        return {row[0].test_object: StoredTrial(*row) for row in session.execute(query).all()}


def trial_of(session: Session, participant: ParticipantRecord, test_object: str) -> StoredTrial | None:
    """Return the participant's trial on ``test_object`` (None before they submitted it)."""
    query = (
        _stored_trials()
        .where(ParticipantTrialRecord.participant_id == participant.id)
        .where(ParticipantTrialRecord.test_object == test_object)
    )
    with storage_errors(session):
        row = session.execute(query).first()
    return StoredTrial(*row) if row is not None else None
