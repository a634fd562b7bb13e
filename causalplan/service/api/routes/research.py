"""GET /v1/trials and GET /v1/export: everything stored, for researchers with the token."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query
from fastapi.responses import Response

from causalplan.service.api.schemas.common import RESEARCH_ERROR_RESPONSES
from causalplan.service.api.schemas.research import ExportOut, StoredModelOut, TrialOut, TrialsOut
from causalplan.service.deps import ResearchAccessDep, SessionDep
from causalplan.service.responses import SafeJSONResponse, csv_bytes
from causalplan.service.storage import crud
from causalplan.service.storage.records import MAX_CLIENT_ID_LENGTH, ModelRecord, TrialRecord

router = APIRouter(prefix="/v1", tags=["research"], responses=RESEARCH_ERROR_RESPONSES)

MAX_PAGE = 1000


@router.get("/trials", response_model=TrialsOut, summary="List transfer trials")
def list_trials(
    _: ResearchAccessDep,
    session: SessionDep,
    offset: Annotated[int, Query(ge=0, le=1_000_000_000)] = 0,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
    participant_id: Annotated[str | None, Query(max_length=MAX_CLIENT_ID_LENGTH)] = None,
    session_id: Annotated[str | None, Query(max_length=MAX_CLIENT_ID_LENGTH)] = None,
) -> TrialsOut:
    """Return stored trials, newest first, optionally of one participant or session."""
    trials, count = crud.list_trials(session, offset, limit, participant_id, session_id)
    return TrialsOut(data=[TrialOut.model_validate(trial) for trial in trials], count=count)


def _trial_row(trial: TrialRecord) -> dict[str, Any]:
    return TrialOut.model_validate(trial).model_dump(mode="json")


def _model_row(model: ModelRecord) -> dict[str, Any]:
    return StoredModelOut.model_validate(model).model_dump(mode="json")


@router.get(
    "/export",
    response_model=ExportOut,
    summary="Export everything stored",
    responses={200: {"content": {"text/csv": {"schema": {"type": "string"}}}, "description": "JSON or CSV."}},
)
def export_everything(
    _: ResearchAccessDep,
    session: SessionDep,
    format: Annotated[Literal["json", "csv"], Query(description="json (models and trials) or csv.")] = "json",
    table: Annotated[Literal["trials", "models"], Query(description="For csv: which table.")] = "trials",
) -> Response:
    """Export every stored model and trial as JSON, or one table as CSV (JSON values in cells)."""
    models, trials = crud.all_records(session)
    stamp = datetime.now(UTC)
    if format == "json":
        data = {
            "exported_at": stamp.isoformat(),
            "models": [_model_row(model) for model in models],
            "trials": [_trial_row(trial) for trial in trials],
        }
        return SafeJSONResponse(
            data, headers={"Content-Disposition": f'attachment; filename="causalplan-{stamp:%Y%m%dT%H%M%SZ}.json"'}
        )
    if table == "trials":
        body = csv_bytes(list(TrialOut.model_fields), [_trial_row(trial) for trial in trials])
    else:
        body = csv_bytes(list(StoredModelOut.model_fields), [_model_row(model) for model in models])
    return Response(
        body,
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": f'attachment; filename="causalplan-{table}-{stamp:%Y%m%dT%H%M%SZ}.csv"'},
    )
