"""The experiment API, ``/v1/experiments``: define experiments, make participant links, read results and exports.

Protected by the research token (``Authorization: Bearer``), like ``/v1/trials`` and ``/v1/export``.
"""

from __future__ import annotations

import uuid
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request, Response
from pydantic import Field

from causalplan.service import experiments
from causalplan.service.api.schemas.common import BINARY, RESEARCH_ERROR_RESPONSES, error_responses
from causalplan.service.api.schemas.experiments import (
    ExperimentExportOut,
    ExperimentIn,
    ExperimentOut,
    LinksIn,
    ParticipantsOut,
    RecruitmentIn,
    RecruitmentOut,
    ResultsOut,
)
from causalplan.service.deps import CatalogDep, ResearchAccessDep, SessionDep
from causalplan.service.sharing import shareable_zip
from causalplan.service.storage import experiments as store
from causalplan.studies.sharing import DEFAULT_LICENSE

router = APIRouter(prefix="/v1/experiments", tags=["experiments"], responses=RESEARCH_ERROR_RESPONSES)


@router.post(
    "", status_code=201, response_model=ExperimentOut, summary="Define an experiment", responses=error_responses(422)
)
def create_experiment(
    body: ExperimentIn, _: ResearchAccessDep, session: SessionDep, catalog: CatalogDep
) -> ExperimentOut:
    """Store an experiment: its conditions (training objects, one or two, and test objects) and options.

    Every problem with the definition (unknown objects, a test object that is also a training
    object, objects with different goals in one condition, ...) is listed in `details.errors`.
    """
    record = experiments.create(session, catalog, body)
    return experiments.experiment_out(record, 0)


@router.get("", response_model=list[ExperimentOut], summary="List experiments")
def list_experiments(_: ResearchAccessDep, session: SessionDep) -> list[ExperimentOut]:
    """Return every experiment, newest first, with its number of participants."""
    return [experiments.experiment_out(record, count) for record, count in store.list_experiments(session)]


@router.get("/{experiment_id}", response_model=ExperimentOut, summary="One experiment", responses=error_responses(404))
def read_experiment(experiment_id: uuid.UUID, _: ResearchAccessDep, session: SessionDep) -> ExperimentOut:
    record = store.get_experiment(session, experiment_id)
    return experiments.experiment_out(record, len(store.participants_of(session, experiment_id)))


@router.post(
    "/{experiment_id}/participants",
    status_code=201,
    response_model=ParticipantsOut,
    summary="Make participant links",
    responses=error_responses(404, 422),
)
def create_participants(
    experiment_id: uuid.UUID,
    body: LinksIn,
    _: ResearchAccessDep,
    session: SessionDep,
    catalog: CatalogDep,
    request: Request,
) -> ParticipantsOut:
    """Make `count` participant links with opaque random codes, in one condition or spread evenly.

    Each participant's object orders come from balanced Latin squares, by their number in the condition.
    """
    experiment = store.get_experiment(session, experiment_id)
    made = store.add_participants(session, experiment, body.count, body.condition)
    return ParticipantsOut(data=[experiments.participant_out(p, catalog, request) for p in made])


@router.get(
    "/{experiment_id}/participants",
    response_model=ParticipantsOut,
    summary="Participants and their progress",
    responses=error_responses(404),
)
def list_participants(
    experiment_id: uuid.UUID, _: ResearchAccessDep, session: SessionDep, catalog: CatalogDep, request: Request
) -> ParticipantsOut:
    store.get_experiment(session, experiment_id)
    participants = store.participants_of(session, experiment_id)
    return ParticipantsOut(data=[experiments.participant_out(p, catalog, request) for p in participants])


@router.get("/{experiment_id}/results", response_model=ResultsOut, summary="Results", responses=error_responses(404))
def read_experiment_results(
    experiment_id: uuid.UUID, _: ResearchAccessDep, session: SessionDep, catalog: CatalogDep, request: Request
) -> ResultsOut:
    """Return participants and progress, transfer rates per condition and test object, and every trial."""
    experiment = store.get_experiment(session, experiment_id)
    return ResultsOut.model_validate(experiments.results(session, catalog, experiment, request))


@router.get(
    "/{experiment_id}/export",
    summary="Export the raw data",
    responses={
        200: {
            "model": ExperimentExportOut,
            "content": {"text/csv": {"schema": {"type": "string"}}},
            "description": "JSON (everything) or CSV (one table).",
        },
        **error_responses(404),
    },
)
def export_experiment(
    experiment_id: uuid.UUID,
    _: ResearchAccessDep,
    session: SessionDep,
    catalog: CatalogDep,
    request: Request,
    format: Annotated[Literal["json", "csv"], Query(description="json (everything) or csv (one table).")] = "json",
    table: Annotated[Literal["trials", "participants"], Query(description="For csv: which table.")] = "trials",
    platform_ids: Annotated[
        Literal["plain", "hashed", "omit"],
        Query(
            description="Crowd-platform ids (Prolific PID, MTurk workerId, ...): as stored, SHA-256 hashed, or omitted."
        ),
    ] = "plain",
) -> Response:
    """Export the experiment, every participant (with all saved work and exclusions) and every trial, as JSON or CSV."""
    experiment = store.get_experiment(session, experiment_id)
    return experiments.export(session, catalog, experiment, request, format, table, platform_ids)


@router.get(
    "/{experiment_id}/export/shareable",
    summary="Export the data to share (a Psych-DS dataset)",
    responses={
        200: {"content": {"application/zip": BINARY}, "description": "The dataset as a ZIP file (bytes)."},
        **error_responses(404),
    },
    response_class=Response,
)
def export_shareable(
    experiment_id: uuid.UUID,
    _: ResearchAccessDep,
    session: SessionDep,
    catalog: CatalogDep,
    request: Request,
    author: Annotated[
        list[Annotated[str, Field(min_length=1, max_length=200)]],
        Query(max_length=50, description="The dataset's authors (repeat the parameter for each), as they are cited."),
    ] = [],  # noqa: B006 - FastAPI copies a default per request
    license: Annotated[
        str, Query(min_length=1, max_length=300, description="The dataset's license (a URL or an SPDX id).")
    ] = DEFAULT_LICENSE,
) -> Response:
    """Return the experiment's data to share as a Psych-DS dataset (ZIP): no participant's link code, link or
    client address, the crowd-platform ids hashed (see `dataset_description.json`); the data dictionary
    describes every column. The export above is the researcher's own and keeps them all."""
    experiment = store.get_experiment(session, experiment_id)
    return shareable_zip(session, catalog, experiment, request, author, license)


@router.get(
    "/{experiment_id}/recruitment",
    response_model=RecruitmentOut,
    summary="Recruiting settings and places",
    responses=error_responses(404),
)
def read_recruitment(
    experiment_id: uuid.UUID, _: ResearchAccessDep, session: SessionDep, request: Request
) -> RecruitmentOut:
    """Return the consent text, completion codes, screening rules, demographics, the public link and its places."""
    experiment = store.get_experiment(session, experiment_id)
    return experiments.recruitment_out(session, experiment, request)


@router.put(
    "/{experiment_id}/recruitment",
    response_model=RecruitmentOut,
    summary="Set how the public link recruits",
    responses=error_responses(404, 422),
)
def set_recruitment(
    experiment_id: uuid.UUID, body: RecruitmentIn, _: ResearchAccessDep, session: SessionDep, request: Request
) -> RecruitmentOut:
    """Store the consent text, completion codes, comprehension rule, too-fast threshold, demographics and quotas."""
    experiment = store.get_experiment(session, experiment_id)
    experiments.set_recruitment(session, experiment, body)
    return experiments.recruitment_out(session, experiment, request)
