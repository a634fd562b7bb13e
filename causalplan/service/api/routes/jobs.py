"""/v1/jobs: post long work (trials, a simulation, a consensus, a film, fits, a repair), follow it, fetch its result.

A video job's film is served at ``/v1/jobs/{id}/video``, a troubleshooting job's 3D player
document at ``/v1/jobs/{id}/playback``; a job is cancelled with DELETE.

Any replica answers for any job: jobs live in the database, and whichever replica's runner
took a job does its work (see ``service.jobs``). Every job is its poster's (``service.owners``):
another client reading, cancelling or downloading it is answered 404, as for no job at all.
"""

from __future__ import annotations

import uuid
from functools import partial
from typing import Annotated, Any

import anyio.to_thread
from fastapi import APIRouter, Body, Response

from causalplan.service.api.schemas.common import (
    BINARY,
    JOB_CLIENT_RESPONSES,
    JOB_LIMIT_RESPONSE,
    ErrorOut,
    error_responses,
)
from causalplan.service.api.schemas.jobs import JOB_EXAMPLES, JobBody, JobIn, JobOut
from causalplan.service.api.schemas.playback import EpisodePlaybackOut
from causalplan.service.deps import Services, ServicesDep
from causalplan.service.documents import StrictJSONRoute
from causalplan.service.errors import FilmNotFoundError, JobNotFinishedError, PlaybackNotFoundError
from causalplan.service.jobs.kinds import KINDS
from causalplan.service.jobs.troubleshooting import PLAYBACK_TYPE, playback_url
from causalplan.service.jobs.video import video_url
from causalplan.service.owners import JobOwner, JobOwnerDep, admit_job, job_limits
from causalplan.service.responses import film_response
from causalplan.service.storage import jobs as store
from causalplan.service.storage.jobs import UNFINISHED, JobKind
from causalplan.service.storage.records import JobRecord
from causalplan.service.work.robot import CONTENT_TYPES

_RESPONSES = {**JOB_CLIENT_RESPONSES, **error_responses(503)}
router = APIRouter(prefix="/v1/jobs", tags=["jobs"], responses=_RESPONSES, route_class=StrictJSONRoute)

_JOB_ID = {"job_id": "$response.body#/id"}
_LINKS = {
    "ReadJob": {"operationId": "read_job", "parameters": _JOB_ID, "description": "Follow the job (its `url`)."},
    "CancelJob": {"operationId": "cancel_job", "parameters": _JOB_ID, "description": "Cancel it."},
    "ReadJobVideo": {"operationId": "read_job_video", "parameters": _JOB_ID, "description": "A video job's film."},
    "ReadJobPlayback": {
        "operationId": "read_job_playback",
        "parameters": _JOB_ID,
        "description": "A troubleshooting job's 3D player document.",
    },
}
"""OpenAPI links from a posted job to what can be done with it (clients and stateful tests follow them)."""
CANCEL_WAIT_SECONDS = 5.0
"""How long DELETE waits for this replica's worker of the job to be killed (it takes a moment)."""
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job, its result has expired, or it is another client's."}
}


def job_url(job_id: uuid.UUID) -> str:
    """Return the path of a job's resource."""
    return f"/v1/jobs/{job_id}"


def job_result(record: JobRecord) -> dict[str, Any] | None:
    """Return the job's stored result, with the URL of the film or player's document it made (served here)."""
    result = record.result
    if result is not None and record.file_type is not None and isinstance(result.get("video"), dict):
        result = {**result, "video": {**result["video"], "url": video_url(record.id)}}
    if result is not None and record.file_type is not None and isinstance(result.get("playback"), dict):
        result = {**result, "playback": {**result["playback"], "url": playback_url(record.id)}}
    return result


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
            "result": job_result(record),
            "error": record.error,
        }
    )


@router.post(
    "",
    status_code=202,
    response_model=JobOut,
    summary="Start a job",
    responses={
        202: {"description": "Queued: follow `url` (also in `Location`).", "links": _LINKS},
        **error_responses(404, 413, 422),
        429: JOB_LIMIT_RESPONSE,
    },
)
async def create_job(
    body: Annotated[JobIn, Body(openapi_examples=JOB_EXAMPLES)],
    services: ServicesDep,
    owner: JobOwnerDep,
    response: Response,
) -> JobOut:
    """Check the request and queue the job; answer 202 with its URL (also in `Location`).

    `kind` says what to do: `batch` (trials uploaded as JSON Lines or CSV, judged as
    `causalplan batch`), `simulation` (POST /v1/simulations' body), `consensus` (participants
    as JSON Lines, as `causalplan consensus`), `video` (a plan request: the robot carries the
    plan out on film, served at `/v1/jobs/{id}/video`), `fit_estimation` (as `causalplan
    estimate-fits`). What is wrong with the request (a model that cannot be read, a CSV
    without its columns, an unknown object or fit, too many trials) is answered at once with
    422 (404 for an unknown object) and nothing is queued; a batch's unreadable lines become
    `invalid` trials in the result, as in the CLI.

    The job is the client's: an API key's or the research token's (`Authorization: Bearer`),
    else its address's. Only it may follow, cancel or download the job. Each client has limits
    on jobs queued or running, megabytes its jobs keep stored (until they expire) and jobs a
    minute, smaller without a key (GET /health, `limits`): beyond one, 429 with `Retry-After`.
    """
    record = await anyio.to_thread.run_sync(queue_job, body, services, owner)
    response.headers["Location"] = job_url(record.id)
    return job_out(record)


def queue_job(body: JobBody, services: Services, owner: JobOwner) -> JobRecord:
    """Check ``body`` (its kind's ``prepare``: a clear error and nothing queued when wrong); queue it as ``owner``'s.

    The minute's count comes first, so a client over it costs no parsing of its upload's trials.
    """
    admit_job(services, owner)
    kind = JobKind(body.kind)
    prepared = KINDS[kind].prepare(body, services)
    settings = services.settings
    return store.create_job(
        services.engine,
        kind.value,
        prepared.stored(),
        prepared.units(),
        settings.max_queued_jobs,
        owner=owner.id,
        limits=job_limits(owner, settings),
    )


@router.get(
    "/{job_id}",
    response_model=JobOut,
    summary="A job's status, progress and result",
    responses=_NOT_FOUND,
)
async def read_job(job_id: uuid.UUID, services: ServicesDep, owner: JobOwnerDep) -> JobOut:
    """Return the job: `status` (queued, running, succeeded, failed, cancelled), `progress`, then `result`."""
    record = await anyio.to_thread.run_sync(partial(store.get_job, services.engine, job_id, owner=owner.visible_owner))
    return job_out(record)


@router.delete(
    "/{job_id}",
    response_model=JobOut,
    summary="Cancel a job",
    responses={**_NOT_FOUND, 409: {"model": ErrorOut, "description": "The job has finished already."}},
)
async def cancel_job(job_id: uuid.UUID, services: ServicesDep, owner: JobOwnerDep) -> JobOut:
    """Cancel a queued or running job; answer the cancelled job.

    A running job's worker is stopped at once: before the answer when this server runs the job,
    within `job_poll_seconds` when another replica does.
    """
    keep = services.settings.job_result_seconds
    cancel = partial(store.cancel_job, services.engine, job_id, keep, owner=owner.visible_owner)
    record = await anyio.to_thread.run_sync(cancel)
    if services.runner is not None:
        await anyio.to_thread.run_sync(services.runner.cancel, job_id, CANCEL_WAIT_SECONDS)
    return job_out(record)


@router.get(
    "/{job_id}/video",
    summary="The film a video job made (MP4 or GIF)",
    response_class=Response,
    responses={
        200: {"content": {"video/mp4": BINARY, "image/gif": BINARY}, "description": "The film (bytes)."},
        404: {"model": ErrorOut, "description": "No such job (or another client's), or it has made no film (yet)."},
    },
)
async def read_job_video(job_id: uuid.UUID, services: ServicesDep, owner: JobOwnerDep) -> Response:
    """Return the film of a finished `video` job, from whichever replica is asked, until the job expires."""
    seen_by = owner.visible_owner
    found = await anyio.to_thread.run_sync(partial(store.get_job_file, services.engine, job_id, owner=seen_by))
    if found is None or found[1] not in CONTENT_TYPES.values():  # a troubleshooting job's file is no film
        record = await anyio.to_thread.run_sync(partial(store.get_job, services.engine, job_id, owner=seen_by))
        raise FilmNotFoundError(
            f"Job {job_id} ({record.kind}, {record.status}) has no film: only a video job that has succeeded has one.",
            details={"job_id": str(job_id), "kind": record.kind, "status": record.status},
        )
    return film_response(*found)


@router.get(
    "/{job_id}/playback",
    summary="The 3D player's document of a troubleshooting job's robot run",
    response_model=None,  # the stored document is handed back as it is; its shape is declared below
    responses={
        200: {"model": EpisodePlaybackOut, "description": "The robot's run of the episode, for the 3D player."},
        404: {
            "model": ErrorOut,
            "description": "No such job (or another client's; `job_not_found`), or it has no player's document: "
            "not a troubleshooting job, or it failed, was cancelled or stopped before the robot moved "
            "(`playback_not_found`).",
        },
        409: {"model": ErrorOut, "description": "The job is queued or running (`job_not_finished`): ask again."},
    },
)
async def read_job_playback(job_id: uuid.UUID, services: ServicesDep, owner: JobOwnerDep) -> Response:
    """Return the 3D player's document (`causalplan-playback/2`) of a troubleshooting job that has succeeded.

    The robot's motor commands, every body's track (a spare as `PART:spare`) and each action of
    the episode with when it plays and what it observed (`EpisodePlaybackOut`); what the research
    page's player plays. From whichever replica is asked, until the job expires.
    """
    seen_by = owner.visible_owner
    found = await anyio.to_thread.run_sync(partial(store.get_job_file, services.engine, job_id, owner=seen_by))
    if found is not None and found[1] == PLAYBACK_TYPE:
        return film_response(*found)
    record = await anyio.to_thread.run_sync(partial(store.get_job, services.engine, job_id, owner=seen_by))
    details: dict[str, object] = {"job_id": str(job_id), "kind": record.kind, "status": record.status}
    if record.kind == JobKind.TROUBLESHOOTING and record.status in UNFINISHED:
        raise JobNotFinishedError(
            f"Job {job_id} is {record.status}: the robot's run can be played once the job has succeeded.",
            details=details,
        )
    raise PlaybackNotFoundError(
        f"Job {job_id} ({record.kind}, {record.status}) has no 3D player's document: only a troubleshooting job "
        "whose robot moved has one.",
        details=details,
    )
