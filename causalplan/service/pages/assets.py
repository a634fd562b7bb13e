"""The start page, 'Try it yourself', the pages' scripts and styles, and the pictures of parts."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

from fastapi import APIRouter, Request, Response

from causalplan.service.deps import CatalogDep, ServicesDep, SessionDep, SettingsDep, client_address
from causalplan.service.errors import NotFoundError
from causalplan.service.pages.drawings import SVG_HEADERS, part_picture
from causalplan.service.pages.templating import PageRoute, redirect, render
from causalplan.service.storage import experiments as store
from causalplan.service.storage.demo import DemoStarts
from causalplan.studies.design import Condition, Design

router = APIRouter(include_in_schema=False)
pages = APIRouter(route_class=PageRoute, include_in_schema=False)

STATIC_TYPES = {".css": "text/css; charset=utf-8", ".js": "text/javascript; charset=utf-8"}
_STATIC_NAME = re.compile(r"[a-z0-9_-]+\.(css|js)")
DEMO_DESIGN = Design((Condition("near", ("desk_lamp",), ("flashlight",)),))
"""The paper's example: a model of the desk lamp, tried on the flashlight."""


@pages.get("/")
def start(request: Request, catalog: CatalogDep) -> Response:
    """The start page: what this is, 'Try it yourself', and the way to the research pages."""
    has_demo = all(object_id in catalog.objects for object_id in ("desk_lamp", "flashlight", "toy_car"))
    return render(request, "start.html", has_demo=has_demo)


@pages.post("/try")
def try_it(request: Request, session: SessionDep, catalog: CatalogDep, settings: SettingsDep) -> Response:
    """Make a participant of the demo experiment and go to their first page (a few a minute per client)."""
    demo_starts: DemoStarts = request.app.state.demo_starts
    demo_starts.admit(client_address(request, settings))
    for object_id in ("desk_lamp", "flashlight"):
        catalog.get(object_id)
    experiment = store.demo_experiment(session, DEMO_DESIGN)
    (participant,) = store.add_participants(session, experiment, 1, None)
    return redirect(f"/p/{participant.code}")


@router.get("/web/static/{name}")
def static(name: str) -> Response:
    """Return one of the pages' scripts or style sheets (shipped in the package)."""
    if not _STATIC_NAME.fullmatch(name):
        raise NotFoundError(f"There is no file '{name}'.")
    path = resources.files("causalplan.service.pages") / "static" / name
    if not path.is_file():
        raise NotFoundError(f"There is no file '{name}'.")
    media_type = STATIC_TYPES["." + name.rsplit(".", 1)[1]]
    return Response(
        path.read_bytes(),
        media_type=media_type,
        headers={"Cache-Control": "public, max-age=300", "X-Content-Type-Options": "nosniff"},
    )


@router.get("/web/pictures/{object_id}/{part_id}.png")
def part(object_id: str, part_id: str, services: ServicesDep, catalog: CatalogDep) -> Response:
    """Return the simulator's picture of one part of a catalog object (a plain drawing when it cannot draw)."""
    obj = catalog.get(object_id)
    if part_id not in obj.part_ids:
        raise NotFoundError(f"The {obj.name} has no part '{part_id}'.", details={"parts": list(obj.part_ids)})
    picture, media_type = part_picture(services, obj, part_id)
    cache = "public, max-age=86400" if media_type == "image/png" else "no-store"
    return Response(picture, media_type=media_type, headers={**SVG_HEADERS, "Cache-Control": cache})


VENDOR_TYPES = {
    ".js": "text/javascript; charset=utf-8",
    ".obj": "text/plain; charset=utf-8",
    ".urdf": "application/xml; charset=utf-8",
    ".txt": "text/plain; charset=utf-8",
    "": "text/plain; charset=utf-8",  # LICENSE
}
_VENDOR_PATH = re.compile(r"(?:[A-Za-z0-9_-]+/)*[A-Za-z0-9_-]+(?:\.[a-z0-9]+)*")
PANDA_FILES = re.compile(r"franka_panda/(?:panda\.urdf|LICENSE\.txt|meshes/collision/[a-z0-9]+\.obj)")
"""The Panda's files the player reads from pybullet_data: its URDF and light (collision) meshes."""
_VENDORED = resources.files("causalplan.service.pages") / "static" / "vendor"


@router.get("/web/vendor/{path:path}")
def vendor(path: str) -> Response:
    """Return a file of the robot player's libraries (``static/vendor``) or of the Panda (from ``pybullet_data``).

    Only the files shipped are served: the libraries unchanged from npm with their licences,
    the Panda's URDF and meshes from the installed ``pybullet_data`` (Apache-2.0) with its own.
    """
    if not _VENDOR_PATH.fullmatch(path) or Path(path).suffix not in VENDOR_TYPES:
        raise NotFoundError(f"There is no file '{path}'.")
    if path.startswith("franka_panda/") and not PANDA_FILES.fullmatch(path):
        raise NotFoundError(f"There is no file '{path}'.")
    # the Panda's files where the simulator reads them; the libraries from this package
    folder = resources.files("pybullet_data") if path.startswith("franka_panda/") else _VENDORED
    file = folder.joinpath(*path.split("/"))
    if not file.is_file():
        raise NotFoundError(f"There is no file '{path}'.")
    media_type = VENDOR_TYPES[Path(path).suffix]
    return Response(
        file.read_bytes(),
        media_type=media_type,
        headers={"Cache-Control": "public, max-age=86400", "X-Content-Type-Options": "nosniff"},
    )
