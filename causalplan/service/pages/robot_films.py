"""'Watch the robot' on step 2: the robot's run for the page's 3D player, and its film as a job.

``POST /p/<code>/films/playback`` runs the robot (no film) in a planner worker and answers with
what the page's player (``static/robot_player.js``) draws at once: the timed motor commands and
each part's pose over time. The MP4 stays as a download:

``POST /p/<code>/films`` finds the film's job (one per object, plan, format and size, shared by
every participant while it is kept) or queues it, and answers at once; the page polls ``GET
/p/<code>/films/<key>`` for the frames drawn and fetches the film from ``GET
/p/<code>/films/<key>/video`` once it is ready. The job, its progress and the film live in the
database, so the replica that answers a poll, or serves the film, need not be the one filming
(``service.jobs.video``).

A film's job is the participant's who asked first (``owners.participant_owner``), under the
limits of a client with a key; the film shows the robot and a catalog object only, so every
participant's pages may follow and fetch it, and the API's ``/v1/jobs`` does not show it to them.
"""

from __future__ import annotations

import logging
import threading
import uuid
from collections.abc import Sequence
from typing import Annotated, Any

from fastapi import APIRouter, Path, Request, Response

from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject
from causalplan.service.api.schemas.experiments import FilmIn, FilmOut
from causalplan.service.deps import Services, ServicesDep, client_address
from causalplan.service.errors import FilmNotFoundError, InvalidRequestError, NotFoundError
from causalplan.service.jobs.video import FILM_KEY, FILM_KEY_PATTERN, film_key, fits_film_request
from causalplan.service.owners import admit_job, job_limits, participant_owner
from causalplan.service.pages.journeys import JourneyDep
from causalplan.service.responses import film_response
from causalplan.service.storage import jobs as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.service.storage.jobs import JobKind, JobStatus
from causalplan.service.storage.records import JobRecord, utc_now
from causalplan.service.work.registry import ROBOT_PLAYBACK
from causalplan.service.work.robot import CONTENT_TYPES, PlaybackArguments

logger = logging.getLogger(__name__)

router = APIRouter(prefix="/p/{code}/films", include_in_schema=False)

FILM_FORMAT = "mp4"
"""What the page plays: every browser's <video> plays H.264 MP4."""


def _seconds(job: JobRecord) -> float:
    began = store.aware(job.started_at or job.created_at)
    ended = store.aware(job.finished_at) if job.finished_at is not None else utc_now()
    return round(max(0.0, (ended - began).total_seconds()), 1)


def _out(code: str, job: JobRecord) -> FilmOut:
    result: dict[str, Any] = job.result or {}
    film: dict[str, Any] = result.get("video") or {}
    ready = job.status == JobStatus.SUCCEEDED and job.file_type is not None
    error = None
    if job.status == JobStatus.SUCCEEDED and not ready:
        error = {"code": "no_video", "message": "The robot made no film of this plan."}
    elif job.status not in store.UNFINISHED and not ready:
        failed = job.error or {"code": "job_cancelled", "message": "The film was cancelled."}
        error = {"code": str(failed["code"]), "message": str(failed["message"])}
    key = job.id.hex
    status_url = f"/p/{code}/films/{key}"
    return FilmOut.model_validate(
        {
            "key": key,
            "state": "filming" if job.status in store.UNFINISHED else "ready" if ready else "failed",
            "frames": job.done if job.total > 1 else 0,  # 1 of 1: nothing drawn yet, the robot is planning
            "expected_frames": job.total if job.total > 1 else None,
            "seconds": _seconds(job),
            "status_url": status_url,
            "video_url": f"{status_url}/video" if ready else None,
            "content_type": film.get("content_type") or CONTENT_TYPES[FILM_FORMAT],
            "bytes": int(film.get("bytes") or 0),
            "robot": result.get("robot"),
            "error": error,
        }
    )


def check_fits(obj: AssemblyObject, fits: list[str]) -> None:
    """Refuse (``InvalidRequestError``) a fit that is not one of ``obj``'s."""
    known = {fit.id for fit in obj.fits}
    unknown = [fit for fit in fits if fit not in known]
    if unknown:
        raise InvalidRequestError(
            f"The {obj.name} has no fit '{unknown[0]}'.", details={"fit": unknown[0], "fits": sorted(known)}
        )


def _training_object(body: FilmIn, journey: ParticipantJourney) -> AssemblyObject:
    """Return the training object ``body`` names, once its fits are the object's."""
    obj = next((o for o in journey.training if o.id == body.object), None)
    if obj is None:
        raise NotFoundError(f"'{body.object}' is not one of your objects in this step.")
    check_fits(obj, body.fits)
    return obj


def robot_run_key(services: Services, object_id: str, fits: Sequence[str]) -> str:
    """Return the key of the robot's run of ``fits`` on an object in ``caches.robot_runs``."""
    return f"{services.catalog_key}:{object_id}:{','.join(fits)}"


def robot_run_document(obj: AssemblyObject, fits: Sequence[str], services: Services) -> bytes:
    """Return the robot's run of ``fits`` on ``obj`` for a page's 3D player (JSON), run in a planner worker.

    The robot's run alone (no film): ``sim.robot.playback``'s document, plus ``outcome``
    (whether it carried out the plan), as the worker encoded it. Kept by object and fits
    (``caches.robot_runs``); a request for a run under way waits for that run, never starts another.
    """
    key = robot_run_key(services, obj.id, fits)

    def run() -> dict[str, bytes]:
        return {key: services.work.run(ROBOT_PLAYBACK, PlaybackArguments(obj.id, tuple(fits)))}

    document = services.caches.robot_runs.get(key, run)
    assert document is not None, "run() makes the document of its key"
    return document


def playback_response(obj: AssemblyObject, fits: list[str], services: Services) -> Response:
    """Return the robot's run of ``fits`` on ``obj`` for a page's 3D player (see ``robot_run_document``)."""
    return Response(robot_run_document(obj, fits, services), media_type="application/json")


def run_ahead(services: Services, runs: Sequence[tuple[AssemblyObject, Sequence[str]]]) -> threading.Thread | None:
    """Start computing the robot's runs of plans just shown, in the background; return its thread (None: nothing to do).

    A participant reads the plan before clicking "Watch the robot": the run is computed
    meanwhile, so the click finds it ready (or joins the run under way). A run that cannot be
    made now (the workers busy or closing) is left to the click, which asks again.
    """
    wanted = [(obj, tuple(fits)) for obj, fits in runs if fits and all(fits)]
    if not wanted:
        return None

    def compute() -> None:
        for obj, fits in wanted:
            try:
                robot_run_document(obj, fits, services)
            except CausalPlanError as exc:
                logger.info("robot run not computed ahead: %s %s: %s", obj.id, ",".join(fits), exc.message)

    thread = threading.Thread(target=compute, name="causalplan-robot-ahead", daemon=True)
    thread.start()
    return thread


@router.post("/playback")
def robot_playback(body: FilmIn, code: str, journey: JourneyDep, services: ServicesDep) -> Response:
    """Return the robot's run of ``fits`` for the page's 3D player: motor commands and the parts' tracks."""
    del code
    return playback_response(_training_object(body, journey), body.fits, services)


@router.post("", response_model=FilmOut)
def start_film(body: FilmIn, code: str, journey: JourneyDep, services: ServicesDep, http: Request) -> FilmOut:
    """Start filming the robot making ``fits`` of one of the participant's training objects (kept once made)."""
    obj = _training_object(body, journey)
    settings = services.settings
    size = (settings.robot_video_width, settings.robot_video_height)
    fits = tuple(body.fits)
    key = film_key(services.catalog_key, obj.id, fits, FILM_FORMAT, size)
    kind = JobKind.VIDEO.value
    job = store.find_job(services.engine, kind, FILM_KEY, key)
    if job is None:  # two participants asking at once may each start one: harmless, and rare
        owner = participant_owner(journey.participant.id, client_address(http, settings))
        admit_job(services, owner)
        request = fits_film_request(obj.id, fits, FILM_FORMAT, key)
        limits = job_limits(owner, settings)
        job = store.create_job(
            services.engine, kind, request.stored(), 1, settings.max_queued_jobs, owner=owner.id, limits=limits
        )
    return _out(code, job)


def _film_job(key: str, services: Services) -> JobRecord:
    """Return the job of the participant pages' film ``key``; FilmNotFoundError for any other job."""
    job = store.get_job(services.engine, uuid.UUID(hex=key))
    if job.kind != JobKind.VIDEO or FILM_KEY not in job.request:
        raise FilmNotFoundError(f"No film is made under '{key}'.", details={"key": key})
    return job


@router.get("/{key}", response_model=FilmOut)
def film_status(
    code: str, key: Annotated[str, Path(pattern=FILM_KEY_PATTERN)], journey: JourneyDep, services: ServicesDep
) -> FilmOut:
    """Return how far the film is: filming (frames drawn of those expected), ready (where it is) or failed (why)."""
    del journey  # only participants may ask
    return _out(code, _film_job(key, services))


@router.get("/{key}/video")
def film_video(
    key: Annotated[str, Path(pattern=FILM_KEY_PATTERN)], journey: JourneyDep, services: ServicesDep
) -> Response:
    """Return the film ``key`` (MP4) once it is made; 404 ``video_not_found`` before, or for any other job."""
    del journey  # only participants may ask
    job = _film_job(key, services)
    found = store.get_job_file(services.engine, job.id)
    if found is None:
        raise FilmNotFoundError(f"The film '{key}' is not made (yet).", details={"key": key, "status": job.status})
    return film_response(*found)
