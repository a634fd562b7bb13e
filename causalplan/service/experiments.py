"""Experiments for the research pages and the API: create, describe, results and exports.

The pages and ``/v1/experiments`` call the same functions, so both show the same numbers.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, NamedTuple

from fastapi import Request, Response
from sqlalchemy.orm import Session

from causalplan.consensus.plausibility import MappingPlausibility
from causalplan.errors import InputFileError, UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.service.api.schemas.experiments import (
    ExperimentIn,
    ExperimentOut,
    ParticipantOut,
    RecruitmentIn,
    RecruitmentOut,
)
from causalplan.service.responses import SafeJSONResponse, csv_bytes
from causalplan.service.storage import arrivals
from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney, StoredTrial
from causalplan.service.storage.records import ExperimentRecord, ParticipantRecord
from causalplan.settings import Settings
from causalplan.studies.analysis import Analysis, analyse_export
from causalplan.studies.assignment import PlaceRules
from causalplan.studies.design import Design, read_design
from causalplan.studies.errors import InvalidExperimentError
from causalplan.studies.export import (
    PARTICIPANT_COLUMNS,
    TRIAL_COLUMNS,
    experiment_dict,
    participant_dict,
    trial_dict,
)
from causalplan.studies.far_generalization import DesignError, template_conditions
from causalplan.studies.rates import RateTable, rate_table
from causalplan.studies.recruitment import Recruitment, read_quotas, read_recruitment
from causalplan.studies.trials import ExportError, read_study
from causalplan.troubleshoot.study import troubleshooting_by_object


def create(session: Session, catalog: Catalog, body: ExperimentIn) -> ExperimentRecord:
    """Check a definition against the catalog and store the experiment (InvalidExperimentError lists problems)."""
    options = body.model_dump(
        include={"counterbalance_training", "counterbalance_tests", "show_verdict", "tutorial", "robot_verdict"}
    )
    conditions = [condition.model_dump() for condition in body.conditions]
    if body.template is not None:  # the paper's design: made from the catalog, or the given conditions checked
        try:
            conditions = template_conditions(body.template, catalog, conditions)
        except DesignError as exc:
            raise InvalidExperimentError(exc.message, details=exc.details) from None
    name, design = read_design(body.name, conditions, options, catalog)
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
        return ParticipantJourney.of(participant, catalog).progress()
    except UnknownObjectError:  # the catalog lost one of the experiment's objects
        return participant.stage


def participant_out(participant: ParticipantRecord, catalog: Catalog, request: Request) -> ParticipantOut:
    """Return the API view of a participant link: the record's own fields, and four worked out from it."""
    worked_out = {
        "url": participant_link(request, participant),
        "progress": progress(participant, catalog),
        "platform": participant.arrival.platform if participant.arrival is not None else None,
        "exclusion_reason": "; ".join(item.reason for item in participant.exclusions) or None,
    }
    stored = {name: getattr(participant, name) for name in ParticipantOut.model_fields if name not in worked_out}
    return ParticipantOut.model_validate({**stored, **worked_out})


def _export(
    catalog: Catalog,
    experiment: ExperimentRecord,
    request: Request,
    participants: Sequence[ParticipantRecord],
    trials: Sequence[StoredTrial],
    platform_ids: str,
) -> dict[str, Any]:
    return {
        "exported_at": datetime.now(UTC).isoformat(),
        "experiment": experiment_dict(experiment),
        "participants": [
            participant_dict(
                participant, progress(participant, catalog), participant_link(request, participant), platform_ids
            )
            for participant in participants
        ],
        "trials": [trial_dict(trial, catalog) for trial in trials],
    }


def export_data(
    session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request, platform_ids: str = "plain"
) -> dict[str, Any]:
    """Return every raw record of an experiment as the JSON export holds them (``causalplan analyze`` reads it)."""
    participants = store.participants_of(session, experiment.id)
    return _export(catalog, experiment, request, participants, store.trials_of(session, experiment.id), platform_ids)


def results(session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request) -> dict[str, Any]:
    """Return an experiment's participants, transfer rates and trials.

    The rates are ``causalplan analyze``'s of the experiment's export (``rates.rate_table``).
    """
    participants, data = _participants_and_export(session, catalog, experiment, request)
    return _results(catalog, experiment, request, participants, data, _rates(data, catalog))


class StudyView(NamedTuple):
    """What the research page shows of an experiment, from one read of its records."""

    results: dict[str, Any]
    """As ``results``."""
    analysis: Analysis | str
    """``causalplan analyze``'s analysis of the export, or why it cannot be made."""
    crowd_size: int
    """How many participants have written a model (the crowd of its consensus)."""
    troubleshooting: tuple[dict[str, object], ...] = ()
    """``causalplan analyze --troubleshooting``: per condition and test object, the models against the baselines."""


def study_view(session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request) -> StudyView:
    """Return the research page's view of an experiment: one export, analysed once."""
    participants, data = _participants_and_export(session, catalog, experiment, request)
    analysis = _analysis(data, catalog)
    table = analysis if isinstance(analysis, str) else analysis.table
    crowd = sum(1 for participant in participants if (participant.work or {}).get("model"))
    repairs = tuple(row.as_dict() for row in troubleshooting_by_object(data, catalog))
    return StudyView(_results(catalog, experiment, request, participants, data, table), analysis, crowd, repairs)


def _participants_and_export(
    session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request
) -> tuple[list[ParticipantRecord], dict[str, Any]]:
    participants = store.participants_of(session, experiment.id)
    data = _export(catalog, experiment, request, participants, store.trials_of(session, experiment.id), "omit")
    return participants, data


def _results(
    catalog: Catalog,
    experiment: ExperimentRecord,
    request: Request,
    participants: Sequence[ParticipantRecord],
    data: dict[str, Any],
    table: RateTable | str,
) -> dict[str, Any]:
    return {
        "experiment": experiment_out(experiment, len(participants)),
        "participants": [participant_out(participant, catalog, request) for participant in participants],
        "rates": [] if isinstance(table, str) else [rate.as_dict() for rate in table.rates],
        "rates_problem": table if isinstance(table, str) else None,
        "trials": data["trials"],
    }


def _rates(data: dict[str, Any], catalog: Catalog) -> RateTable | str:
    try:
        return rate_table(read_study(data, catalog), catalog)
    except (ExportError, UnknownObjectError) as exc:
        return exc.message


def rates_of(session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request) -> RateTable | str:
    """Return the experiment's rates table (``causalplan analyze``'s of its export), or why it cannot be made."""
    return _rates(export_data(session, catalog, experiment, request, platform_ids="omit"), catalog)


def export(
    session: Session,
    catalog: Catalog,
    experiment: ExperimentRecord,
    request: Request,
    format: str,
    table: str,
    platform_ids: str = "plain",
) -> Response:
    """Return every raw record of an experiment as a JSON file, or one table as a CSV file.

    ``platform_ids``: the crowd platforms' ids as stored (``plain``), ``hashed`` or ``omit``-ted.
    """
    data = export_data(session, catalog, experiment, request, platform_ids)
    name = (
        f"causalplan-experiment-{str(experiment.id)[:8]}-{datetime.fromisoformat(data['exported_at']):%Y%m%dT%H%M%SZ}"
    )
    if format == "json":
        # No trial yet, or a problem the results name: no rate to export, [] (the field is always there).
        table_of_rates = _rates(data, catalog) if data["trials"] else "no trials"
        rates = [] if isinstance(table_of_rates, str) else [rate.as_dict() for rate in table_of_rates.rates]
        return SafeJSONResponse(
            {**data, "rates": rates}, headers={"Content-Disposition": f'attachment; filename="{name}.json"'}
        )
    body = (
        csv_bytes(TRIAL_COLUMNS, data["trials"])
        if table == "trials"
        else csv_bytes(PARTICIPANT_COLUMNS, data["participants"])
    )
    return Response(
        body,
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": f'attachment; filename="{name}-{table}.csv"'},
    )


def _analysis(data: dict[str, Any], catalog: Catalog) -> Analysis | str:
    """Return the study's analysis (``causalplan analyze`` on its export ``data``), or why it cannot be made."""
    try:
        return analyse_export(data, catalog, MappingPlausibility(catalog))
    except (ExportError, UnknownObjectError) as exc:
        return exc.message


def consensus_svg(session: Session, catalog: Catalog, experiment: ExperimentRecord, request: Request) -> bytes | str:
    """Return the crowd's consensus graph as SVG (``causalplan consensus`` on the export), or why there is none.

    The graph beside the first members' own models; an arrow's width is its rule's support.
    """
    import matplotlib

    from causalplan.consensus.build import NoCrowdError, build_consensus
    from causalplan.consensus.drawing import draw_consensus
    from causalplan.consensus.participants import participants_of_export

    data = export_data(session, catalog, experiment, request, platform_ids="omit")
    try:
        people = participants_of_export(data, f"experiment {experiment.id}")
        consensus = build_consensus(people, catalog)
    except (NoCrowdError, InputFileError) as exc:
        return exc.message
    # Each model is titled by the participant's place in the table, never by their link code (a secret).
    names = {person.id: f"participant {number}" for number, person in enumerate(people, start=1)}
    members = {names.get(person, "a participant"): model for person, model in consensus.models.items()}
    with tempfile.TemporaryDirectory() as folder, matplotlib.rc_context({"svg.fonttype": "none"}):
        paths = draw_consensus(consensus, members, Path(folder))  # matplotlib writes the files; the SVG is read back
        return next(path for path in paths if path.suffix == ".svg").read_bytes()


def public_link(request: Request, experiment: ExperimentRecord) -> str:
    """Return the experiment's public study link (Prolific or MTurk add their ids to it)."""
    return f"{request.base_url}s/{experiment.id}"


def place_rules(settings: Settings) -> PlaceRules:
    """Return how long an admitted participant holds a place, and the over-admission, as the settings say."""
    return PlaceRules(settings.place_start_minutes, settings.place_hold_hours, settings.over_admission)


def recruitment_out(session: Session, experiment: ExperimentRecord, request: Request) -> RecruitmentOut:
    """Return the recruiting settings with the public link and each condition's places.

    The places are counted by the rules admission uses (this server's ``place_start_minutes``,
    ``place_hold_hours`` and ``over_admission``), so what the page shows is what arrivals meet.
    """
    settings: Settings = request.app.state.services.settings
    return RecruitmentOut.model_validate(
        {
            **Recruitment.from_dict(experiment.recruitment).as_dict(),
            "public_link": public_link(request, experiment),
            "places": [vars(place) for place in arrivals.places(session, experiment, place_rules(settings))],
            "arrivals": arrivals.arrival_counts(session, experiment.id),
        }
    )


def set_recruitment(session: Session, experiment: ExperimentRecord, body: RecruitmentIn) -> None:
    """Check and store the recruiting settings and quotas (InvalidRequestError lists every problem)."""
    settings = read_recruitment(body.model_dump(exclude={"quotas"}))
    conditions = [condition.name for condition in Design.from_dict(experiment.design).conditions]
    quotas = read_quotas(body.quotas, conditions)
    experiment.recruitment = settings.as_dict()
    store.save(session, experiment)
    arrivals.set_quotas(session, experiment, quotas)
