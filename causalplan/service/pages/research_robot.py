"""'Watch the robot' on the research pages: the robot's run of a trial's plan, for the 3D player.

``POST /research/playback`` (the research token: a bearer header or the signed-in cookie)
takes an object of the catalog and the fits of a plan, as a trial stores them, and answers
as a participant's ``POST /p/<code>/films/playback`` does (``robot_films.playback_response``):
the page's player (``static/robot_player.js``, started by ``static/research.js``) plays it.
"""

from __future__ import annotations

from fastapi import APIRouter, Response

from causalplan.service.api.schemas.experiments import FilmIn
from causalplan.service.deps import CatalogDep, ServicesDep
from causalplan.service.pages.auth import ResearchPageDep
from causalplan.service.pages.robot_films import check_fits, playback_response

router = APIRouter(prefix="/research", include_in_schema=False)


@router.post("/playback")
def research_playback(body: FilmIn, _: ResearchPageDep, catalog: CatalogDep, services: ServicesDep) -> Response:
    """Return the robot's run of ``fits`` on any object of the catalog (a trial's test object), for the player."""
    obj = catalog.get(body.object)
    check_fits(obj, body.fits)
    return playback_response(obj, body.fits, services)
