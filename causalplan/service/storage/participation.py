"""Storing what a participant's pages do: their submitted model (with their move to step 3), and a trial.

Each is one transaction: the model and the participant's new stage together, the trial and
its link to the participant (``participant_trials``) together. Database failures become
``StorageError``.
"""

from __future__ import annotations

import uuid

from sqlalchemy.orm import Session

from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.service.storage.records import ModelRecord, ParticipantTrialRecord, TrialRecord, utc_now
from causalplan.studies.steps import ParticipantModel


def store_submitted_model(
    session: Session, journey: ParticipantJourney, participant_model: ParticipantModel, record: ModelRecord
) -> None:
    """Store the model's ``record`` and freeze the participant's model (they begin step 3), in one transaction."""
    with storage_errors(session):
        session.add(record)
        session.flush()
        journey.finish_model(participant_model, record.id)
        session.add(journey.participant)
        session.commit()


def store_trial(
    session: Session, journey: ParticipantJourney, trial: TrialRecord, test_object: str, index: int
) -> None:
    """Store the participant's step-3 ``trial`` on test object number ``index``, with its link to them.

    The caller has checked that the participant has no trial on this object yet (a second one
    would break the link table's unique constraint).
    """
    link = ParticipantTrialRecord(
        id=uuid.uuid4(),
        participant_id=journey.participant.id,
        trial_id=trial.id,
        test_object=test_object,
        position=index,
        created_at=utc_now(),
    )
    # The trial first: the link's foreign key needs it, and the two are committed together.
    with storage_errors(session):
        session.add(trial)
        session.flush()
        session.add(link)
        session.commit()
