"""'Watch the robot repair it' on the research pages: the 3D player on a robot troubleshooting episode.

``GET /research/troubleshooting`` (the research token: a bearer header or the signed-in
cookie) offers every broken part of the catalog's objects and the three strategies. The page's
script (``static/research_troubleshooting.js``) posts the choice to the API as any client
does (``POST /v1/troubleshooting`` with ``robot``: a job, its owner the browser's address),
follows the job, and opens the player (``static/robot_player.js``) on the job's document
(``GET /v1/jobs/{id}/playback``), which lists each action as it plays. The model is the
object's reference model (its true mechanism as a causal model, ``objects.reference``): the
page needs no person's model to show the robot at work.
"""

from __future__ import annotations

from dataclasses import dataclass

import markupsafe
from fastapi import APIRouter, Request, Response

from causalplan.objects.model import AssemblyObject
from causalplan.objects.reference import reference_model
from causalplan.service.deps import CatalogDep
from causalplan.service.pages.auth import ResearchPageDep
from causalplan.service.pages.templating import PageRoute, render
from causalplan.service.responses import render_json

router = APIRouter(prefix="/research", route_class=PageRoute, include_in_schema=False)

STRATEGIES = {
    "model": "The expert's model (the object's true mechanism as rules)",
    "uniform": "No model: every part equally suspect",
    "oracle": "The catalog's fault priors: the best a robot can do",
}
"""The strategies the page offers, with how it names them (``troubleshoot``'s three)."""


@dataclass(frozen=True)
class BrokenPart:
    """One choice of the page: an object with one part broken."""

    object_id: str
    part: str
    label: str


def broken_parts(obj: AssemblyObject) -> list[BrokenPart]:
    """Return the object's faults as the page offers them: the part's name, what the fault is like, its prior."""
    names = {part.id: part.name for part in obj.parts}
    return [
        BrokenPart(obj.id, fault.part, f"{names[fault.part]}: {fault.looks} (prior {fault.probability:g})")
        for fault in obj.faults
    ]


def json_for_script(value: object) -> markupsafe.Markup:
    """Return ``value`` as JSON safe inside a ``<script type="application/json">`` block."""
    text = render_json(value).decode("utf-8").replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
    return markupsafe.Markup(text)


@router.get("/troubleshooting")
def troubleshooting_page(request: Request, _: ResearchPageDep, catalog: CatalogDep) -> Response:
    """Return the page that has the robot repair a broken object and plays its run in 3D."""
    objects = sorted((obj for obj in catalog.objects.values() if obj.faults), key=lambda obj: (obj.category, obj.name))
    return render(
        request,
        "research_troubleshooting.html",
        objects=[(obj, broken_parts(obj)) for obj in objects],
        strategies=STRATEGIES,
        models=json_for_script({obj.id: reference_model(obj) for obj in objects}),
    )
