"""/v1/jobs: post long work (a batch of trials, a simulation, a consensus), follow it, fetch its result, cancel it.

Any replica answers for any job: jobs live in the database, and whichever replica's runner
took a job does its work (see ``service.jobs``).
"""

from __future__ import annotations

import uuid
from typing import Any

import anyio.to_thread
from fastapi import APIRouter, Response

from causalplan.service.db.models import JobRecord
from causalplan.service.deps import ServicesDep
from causalplan.service.documents import StrictJSONRoute
from causalplan.service.jobs import store
from causalplan.service.jobs.kinds import KINDS, JobKind
from causalplan.service.schemas.common import ErrorOut, error_responses
from causalplan.service.schemas.jobs import JobIn, JobOut

router = APIRouter(prefix="/v1/jobs", tags=["jobs"], responses=error_responses(503), route_class=StrictJSONRoute)

_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job, or its result has expired."}
}


def job_url(job_id: uuid.UUID) -> str:
    """Return the path of a job's resource."""
    return f"/v1/jobs/{job_id}"


def job_out(record: JobRecord) -> JobOut:
    """Return the answer for a stored job."""
    return JobOut.model_validate(
        {
            "id": record.id,
            "kind": record.kind,
            "status": record.status,
            "url": job_url(record.id),
            "progress": {"done": record.done, "total": record.total},
            "attempts": record.attempts,
            "created_at": record.created_at,
            "started_at": record.started_at,
            "finished_at": record.finished_at,
            "expires_at": record.expires_at,
            "result": record.result,
            "error": record.error,
        }
    )


@router.post(
    "",
    status_code=202,
    response_model=JobOut,
    summary="Start a job",
    responses={
        **error_responses(404, 413, 422),
        429: {"model": ErrorOut, "description": "The service holds as many unfinished jobs as it takes."},
    },
)
async def create_job(body: JobIn, services: ServicesDep, response: Response) -> JobOut:
    """Check the request and queue the job; answer 202 with its URL (also in `Location`).

    `kind` says what to do: `batch` (trials uploaded as JSON Lines or CSV, judged as
    `causalplan batch`), `simulation` (POST /v1/simulations' body), `consensus` (participants
    as JSON Lines, as `causalplan consensus`). What is wrong with the upload (a model that
    cannot be read, a CSV without its columns, too many trials) is answered at once with 422;
    a batch's unreadable lines become `invalid` trials in the result, as in the CLI.
    """
    kind = JobKind(body.kind)
    request: dict[str, Any] = body.model_dump(mode="json", by_alias=True)  # stored as the API reads it

    def prepare_and_store() -> JobRecord:
        prepared = KINDS[kind].prepare(request, services)
        total = int(prepared.get("count", 1))
        return store.create_job(services.engine, kind.value, prepared, total, services.settings.max_queued_jobs)

    record = await anyio.to_thread.run_sync(prepare_and_store)
    response.headers["Location"] = job_url(record.id)
    return job_out(record)


@router.get("/{job_id}", response_model=JobOut, summary="A job's status, progress and result", responses=_NOT_FOUND)
async def read_job(job_id: uuid.UUID, services: ServicesDep) -> JobOut:
    """Return the job: `status` (queued, running, succeeded, failed, cancelled), `progress`, then `result`."""
    return job_out(await anyio.to_thread.run_sync(store.get_job, services.engine, job_id))


@router.delete(
    "/{job_id}",
    response_model=JobOut,
    summary="Cancel a job",
    responses={**_NOT_FOUND, 409: {"model": ErrorOut, "description": "The job has finished already."}},
)
async def cancel_job(job_id: uuid.UUID, services: ServicesDep) -> JobOut:
    """Cancel a queued or running job (a running one stops at its next step); answer the cancelled job."""
    keep = services.settings.job_result_seconds
    return job_out(await anyio.to_thread.run_sync(store.cancel_job, services.engine, job_id, keep))
