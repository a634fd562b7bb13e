"""The ``video`` kind of job: the robot carrying out a plan, filmed; the film is stored with the job.

Two requests make a film. The API's (``POST /v1/jobs`` with ``kind: video``, or POST
/v1/simulations with ``robot`` and ``video``) is a plan request: the model is planned (on the
mapping's object), then the Panda carries out the plan on camera. The participant page's
("Watch the robot") names the object and the fits of a plan it has shown already. Either way
a job worker films and writes its progress (frames drawn, frames expected) to a file that
this replica's runner reads and reports; a cancel kills the worker. The film's bytes go into
the job's row, so any replica serves them (``GET /v1/jobs/{id}/video``) until the job expires.
"""

from __future__ import annotations

import hashlib
import json
import logging
import tempfile
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from causalplan.service.jobs.requests import FitsFilmRequest, PlanFilmRequest, VideoRequest
from causalplan.service.jobs.work import JobCancelledError, JobFile, Outcome, Progress, in_pool_retried
from causalplan.service.work.registry import FILM_OF_FITS, FILM_OF_PLAN
from causalplan.service.work.robot import CONTENT_TYPES, FitsFilmArguments, PlanFilmArguments, read_progress

if TYPE_CHECKING:
    from causalplan.service.api.schemas.jobs import VideoJobIn
    from causalplan.service.deps import Services
    from causalplan.service.documents import PlanInputs

logger = logging.getLogger(__name__)

WATCH_SECONDS = 1.0
"""How often the runner reads the film's progress and reports it."""
FILM_KEY = "film"
"""The participant page's film's key (``film_key``) in its stored request: one job per film, reused."""
FILM_KEY_PATTERN = r"^[0-9a-f]{32}$"
"""What a film's key looks like (``film_key``, and a job's id as hex)."""


def film_key(catalog_key: str, object_id: str, fit_ids: Sequence[str], video: str, size: tuple[int, int]) -> str:
    """Return the key of the film of the plan making ``fit_ids`` of the object, in ``video`` format and ``size``.

    The robot is deterministic, so one film per object, plan, format, size and catalog is enough.
    """
    text = json.dumps([catalog_key, object_id, list(fit_ids), video, list(size)], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:32]


def video_url(job_id: object) -> str:
    """Return where the API serves the film of job ``job_id``."""
    return f"/v1/jobs/{job_id}/video"


def _plan_inputs(fields: dict[str, Any], services: Services) -> PlanInputs:
    """Return the plan inputs of a film's request (its JSON), read as POST /v1/plans reads its body."""
    from causalplan.service.api.schemas.plans import PlanIn
    from causalplan.service.documents import plan_inputs
    from causalplan.service.storage.crud import ClientIds

    plan = PlanIn.model_validate({key: value for key, value in fields.items() if key not in ("video", "kind")})
    return plan_inputs(plan, services, ClientIds())


def prepare_video(body: VideoJobIn, services: Services) -> PlanFilmRequest:
    inputs = _plan_inputs(body.model_dump(mode="json", by_alias=True), services)
    inputs.store(services)
    return PlanFilmRequest(
        model_id=str(inputs.submission.record.id),
        mapping=body.mapping,
        planner=inputs.planner,
        time_limit=inputs.time_limit,
        validate=body.validate_plan,
        video=body.video,
    )


def fits_film_request(object_id: str, fit_ids: tuple[str, ...], video: str, key: str) -> FitsFilmRequest:
    """Return the stored request of the film ``key`` of ``fit_ids`` of the object (the participant page's)."""
    return FitsFilmRequest(object=object_id, fits=list(fit_ids), video=video, film=key)


def _film_in_worker(
    request: VideoRequest, services: Services, progress: Progress, progress_file: Path
) -> dict[str, Any]:
    settings = services.settings
    size = (settings.robot_video_width, settings.robot_video_height)
    video = request.video
    if isinstance(request, FitsFilmRequest):
        fits = FitsFilmArguments(request.object, tuple(request.fits), video, size, progress_file)
        return in_pool_retried(services, progress, FILM_OF_FITS, fits)
    inputs = _plan_inputs(request.stored(), services)
    plan = PlanFilmArguments(
        inputs.model,
        inputs.mapping,
        inputs.planner,
        inputs.time_limit,
        request.validate_plan,
        video,
        size,
        progress_file,
    )
    data = in_pool_retried(services, progress, FILM_OF_PLAN, plan)
    return {**data, "model_id": request.model_id}


def run_video_job(request: VideoRequest, services: Services, progress: Progress) -> Outcome:
    """Film the plan, reporting frames drawn of frames expected; a cancel kills the worker (``in_pool``).

    A worker that dies while filming is replaced and the film made once more (``in_pool_retried``).
    """
    progress(0, 1)
    with tempfile.TemporaryDirectory(prefix="causalplan-film-job-") as folder:
        progress_file = Path(folder) / "progress.json"
        finished = threading.Event()

        def watch() -> None:
            while not finished.wait(WATCH_SECONDS):
                frames, expected = read_progress(progress_file)
                try:  # before the first frame the robot is still planning: 0 of 1
                    progress(frames, expected or 1)
                except JobCancelledError:  # the job's stop event is set: its worker is being killed
                    return

        watcher = threading.Thread(target=watch, name="causalplan-film-watch", daemon=True)
        watcher.start()
        try:
            data = _film_in_worker(request, services, progress, progress_file)
        finally:
            finished.set()
            watcher.join()
    film = data.pop("video", None)
    content_type = CONTENT_TYPES[request.video]
    if not isinstance(film, bytes):
        return Outcome({**data, "video": None})
    # The URL is the route's to say (``video_url``, filled in when the job is read).
    described = {"url": None, "content_type": content_type, "bytes": len(film)}
    return Outcome({**data, "video": described}, JobFile(film, content_type))
