"""Experiments for the research pages and the API: create, describe, results and exports.

The pages and ``/v1/experiments`` call the same functions, so both show the same numbers.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from fastapi import Request, Response
from sqlalchemy.orm import Session

from causalplan.errors import UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.service.db.models import ExperimentRecord, ParticipantRecord
from causalplan.service.responses import SafeJSONResponse, csv_bytes
from causalplan.service.web import store
from causalplan.service.web.design import Design, read_design
from causalplan.service.web.journey import Journey
from causalplan.service.web.results import (
    PARTICIPANT_COLUMNS,
    TRIAL_COLUMNS,
    Rate,
    experiment_dict,
    participant_dict,
    transfer_rates,
    trial_dict,
)
from causalplan.service.web.schemas import ExperimentIn, ExperimentOut, ParticipantOut


def create(session: Session, catalog: Catalog, body: ExperimentIn) -> ExperimentRecord:
    """Check a definition against the catalog and store the experiment (InvalidExperimentError lists problems)."""
    options = body.model_dump(
        include={"counterbalance_training", "counterbalance_tests", "show_verdict", "tutorial", "robot_verdict"}
    )
    name, design = read_design(body.name, [condition.model_dump() for condition in body.conditions], options, catalog)
    return store.create_experiment(session, name, body.description.strip(), design)


def experiment_out(record: ExperimentRecord, participants: int) -> ExperimentOut:
    """Return the API view of an experiment."""
    api = f"/v1/experiments/{record.id}"
    return ExperimentOut.model_validate(
        {
            "id": record.id,
            "created_at": record.created_at,
            "name": record.name,
            "description": record.description,
            **Design.from_dict(record.design).as_dict(),  # the conditions and the options
            "is_demo": record.is_demo,
            "participants": participants,
            "links": {
                "page": f"/research/experiments/{record.id}",
                "results": f"{api}/results",
                "participants": f"{api}/participants",
                "export_json": f"{api}/export?format=json",
                "export_csv": f"{api}/export?format=csv",
            },
        }
    )


def participant_link(request: Request, participant: ParticipantRecord) -> str:
    """Return the participant's link: this server's address and their code."""
    return f"{request.base_url}p/{participant.code}"


def progress(participant: ParticipantRecord, catalog: Catalog) -> str:
    """Return how far a participant got, in words."""
    try:
        return Journey.of(participant, catalog).progress()
    except UnknownObjectError:  # the catalog lost one of the experiment's objects
        return participant.stage


def participant_out(participant: ParticipantRecord, catalog: Catalog, request: Request) -> ParticipantOut:
    """Return the API view of a participant link."""
    return ParticipantOut.model_validate(
        {
            "id": participant.id,
            "code": participant.code,
            "url": participant_link(request, participant),
            "condition": participant.condition,
            "ordinal": participant.ordinal,
            "training_order": participant.training_order,
            "test_order": participant.test_order,
            "stage": participant.stage,
            "progress": progress(participant, catalog),
            "created_at": participant.created_at,
            "started_at": participant.started_at,
            "updated_at": participant.updated_at,
            "finished_at": participant.finished_at,
        }
    )


def results(session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request) -> dict[str, Any]:
    """Return an experiment's participants, transfer rates and trials (what the results page shows)."""
    participants = store.participants_of(session, experiment.id)
    trials = store.trials_of(session, experiment.id)
    rates: list[Rate] = transfer_rates(Design.from_dict(experiment.design), trials, catalog)
    return {
        "experiment": experiment_out(experiment, len(participants)),
        "participants": [participant_out(participant, catalog, request) for participant in participants],
        "rates": [rate.as_dict() for rate in rates],
        "trials": [trial_dict(stored, catalog) for stored in trials],
    }


def export(
    session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request, format: str, table: str
) -> Response:
    """Return every raw record of an experiment as a JSON file, or one table as a CSV file."""
    stamp = datetime.now(UTC)
    name = f"causalplan-experiment-{str(experiment.id)[:8]}-{stamp:%Y%m%dT%H%M%SZ}"
    participants = [
        participant_dict(participant, progress(participant, catalog), participant_link(request, participant))
        for participant in store.participants_of(session, experiment.id)
    ]
    stored = store.trials_of(session, experiment.id)
    trials = [trial_dict(trial, catalog) for trial in stored]
    if format == "json":
        rates = transfer_rates(Design.from_dict(experiment.design), stored, catalog)
        data = {
            "exported_at": stamp.isoformat(),
            "experiment": experiment_dict(experiment),
            "rates": [rate.as_dict() for rate in rates],
            "participants": participants,
            "trials": trials,
        }
        return SafeJSONResponse(data, headers={"Content-Disposition": f'attachment; filename="{name}.json"'})
    body = csv_bytes(TRIAL_COLUMNS, trials) if table == "trials" else csv_bytes(PARTICIPANT_COLUMNS, participants)
    return Response(
        body,
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": f'attachment; filename="{name}-{table}.csv"'},
    )


def rates_of(session: Session, catalog: Catalog, experiment: ExperimentRecord) -> list[Rate]:
    """Return an experiment's transfer rates per condition and test object."""
    return transfer_rates(Design.from_dict(experiment.design), store.trials_of(session, experiment.id), catalog)
