"""The pictures the pages show, kept once drawn: causal graphs (matplotlib, here) and simulator pictures (workers)."""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable
from typing import Any

from fastapi import Response

from causalplan.causal.diagram import diagram_svg
from causalplan.causal.model import CausalModel
from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject
from causalplan.service.api.routes.models import SVG_SECURITY_HEADERS
from causalplan.service.deps import Services
from causalplan.service.pages import pictures
from causalplan.service.work.pictures import AssemblyPictureArguments, PartPicturesArguments
from causalplan.service.work.registry import ASSEMBLY_PICTURE, PART_PICTURES

logger = logging.getLogger(__name__)

SVG_HEADERS = {**SVG_SECURITY_HEADERS, "X-Content-Type-Options": "nosniff"}


def fresh_svg(svg: bytes) -> Response:
    """Return a drawing made for this request (of data that changes) as an SVG response nobody keeps."""
    return Response(svg, media_type="image/svg+xml", headers={**SVG_HEADERS, "Cache-Control": "no-store"})


def document_key(document: dict[str, Any]) -> str:
    """Return a short hash of a model document (what its graph is cached under, and its URL's version)."""
    text = json.dumps(document, sort_keys=True, ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "replace")).hexdigest()[:16]


def graph_svg(services: Services, key: str, read: Callable[[], CausalModel | None]) -> bytes | None:
    """Return the causal graph of the model ``read`` gives as the pages' SVG (None when it gives none).

    Drawn once per ``key`` (see ``document_key``) and app: a graph kept already needs no reading.
    """

    def draw() -> dict[str, bytes]:
        model = read()
        return {key: diagram_svg(model)} if model is not None else {}

    return services.caches.page_graphs.get(key, draw)


def _picture_key(services: Services, *names: str) -> str:
    # The catalog's fingerprint first: a picture is of the catalog the server has now.
    return json.dumps([services.catalog_key, *names])


def part_picture(services: Services, obj: AssemblyObject, part_id: str) -> tuple[bytes, str]:
    """Return the simulator's picture of one part (PNG), or a plain drawing (SVG) when it cannot draw now."""

    def draw() -> dict[str, bytes]:
        drawn = services.work.run(PART_PICTURES, PartPicturesArguments(obj.id))
        return {_picture_key(services, obj.id, part): png for part, png in drawn.items()}

    try:
        png = services.caches.part_pictures.get(_picture_key(services, obj.id, part_id), draw)
    except CausalPlanError as exc:  # busy, crashed, or no simulator: a drawing now, the picture next time
        logger.info("no picture of %s.%s: %s", obj.id, part_id, exc.message)
        png = None
    if png is None:
        return pictures.drawing(obj.part(part_id).name), "image/svg+xml"
    return png, "image/png"


def is_plan_picture_kept(services: Services, obj: AssemblyObject, fit_ids: tuple[str, ...]) -> bool:
    """Return whether the picture of ``obj`` after the plan making ``fit_ids`` is drawn and kept already."""
    return services.caches.plan_pictures.has(_picture_key(services, obj.id, *fit_ids))


def plan_picture(services: Services, obj: AssemblyObject, fit_ids: tuple[str, ...]) -> bytes:
    """Return the simulator's picture of the object after the plan that makes ``fit_ids`` (PNG)."""
    key = _picture_key(services, obj.id, *fit_ids)

    def draw() -> dict[str, bytes]:
        return {key: services.work.run(ASSEMBLY_PICTURE, AssemblyPictureArguments(obj.id, fit_ids))}

    png = services.caches.plan_pictures.get(key, draw)
    assert png is not None
    return png
