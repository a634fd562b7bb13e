"""'Watch the robot' on step 2: film the robot carrying out the plan, in the background, and say how far it is.

``POST /p/<code>/films`` starts filming (or finds the film kept: one per object, plan and
size) and answers at once; the page polls ``GET /p/<code>/films/<key>`` for the frames drawn
and plays the MP4 from ``/v1/simulations/videos/<key>`` once it is ready.
"""

from __future__ import annotations

from pathlib import Path as FilePath
from typing import Annotated, Any

from fastapi import APIRouter, Path

from causalplan.service.deps import ServicesDep
from causalplan.service.errors import InvalidRequestError, NotFoundError
from causalplan.service.films import Film, film_key, video_url
from causalplan.service.pool.robot_jobs import robot_film_job
from causalplan.service.routes.simulations import VIDEO_KEY
from causalplan.service.web.routes.journeys import JourneyDep
from causalplan.service.web.schemas import FilmIn, FilmOut

router = APIRouter(prefix="/p/{code}/films", include_in_schema=False)

FILM_FORMAT = "mp4"
"""What the page plays: every browser's <video> plays H.264 MP4."""


def _out(code: str, film: Film) -> FilmOut:
    status = film.status()
    ready = film.state == "ready"
    return FilmOut.model_validate(
        {
            **status,
            "key": film.key,
            "status_url": f"/p/{code}/films/{film.key}",
            "video_url": video_url(film.key) if ready else None,
        }
    )


@router.post("", response_model=FilmOut)
def start_film(body: FilmIn, code: str, journey: JourneyDep, services: ServicesDep) -> FilmOut:
    """Start filming the robot making ``fits`` of one of the participant's training objects (kept once made)."""
    obj = next((o for o in journey.training if o.id == body.object), None)
    if obj is None:
        raise NotFoundError(f"'{body.object}' is not one of your objects in this step.")
    known = {fit.id for fit in obj.fits}
    unknown = [fit for fit in body.fits if fit not in known]
    if unknown:
        raise InvalidRequestError(
            f"The {obj.name} has no fit '{unknown[0]}'.", details={"fit": unknown[0], "fits": sorted(known)}
        )
    settings = services.settings
    size = (settings.robot_video_width, settings.robot_video_height)
    fits = tuple(body.fits)
    key = film_key(services.catalog_key, obj.id, fits, FILM_FORMAT, size)
    folders = tuple(settings.catalog_folders)

    def make(progress: FilePath) -> dict[str, Any]:
        args = (obj.id, fits, folders, FILM_FORMAT, size, progress)
        made: dict[str, Any] = services.pool.run(robot_film_job, args, settings.robot_seconds)
        return made

    return _out(code, services.films.start(key, FILM_FORMAT, make))


@router.get("/{key}", response_model=FilmOut)
def film_status(
    code: str, key: Annotated[str, Path(pattern=VIDEO_KEY)], journey: JourneyDep, services: ServicesDep
) -> FilmOut:
    """Return how far the film is: filming (frames drawn of those expected), ready (where it is) or failed (why)."""
    del journey  # only participants may ask
    return _out(code, services.films.get(key))
