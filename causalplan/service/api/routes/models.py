"""POST /v1/models, GET /v1/models/{id} and its causal graph (SVG, DOT or JSON)."""

from __future__ import annotations

import tempfile
import uuid
from pathlib import Path
from typing import Annotated, Literal

from fastapi import APIRouter, Body, Query, Request, Response

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel
from causalplan.causal.render import DRAW_LOCK
from causalplan.inputs import model_from_data
from causalplan.service.api.schemas.common import ErrorOut, ModelDocument, error_responses
from causalplan.service.api.schemas.models import GraphOut, ModelLinks, ModelOut, ModelView
from causalplan.service.deps import CatalogDep, ClientIdsDep, Services, ServicesDep, SessionDep, client_address
from causalplan.service.documents import StrictJSONRoute, first_errors, read_model
from causalplan.service.errors import InvalidModelError, TooManyModelsError
from causalplan.service.responses import SafeJSONResponse
from causalplan.service.storage import crud
from causalplan.service.storage.records import ModelRecord
from causalplan.service.storage.throttle import PerMinute

router = APIRouter(
    prefix="/v1/models", tags=["models"], responses=error_responses(403, 404, 503), route_class=StrictJSONRoute
)

SVG_SECURITY_HEADERS = {"Content-Security-Policy": "default-src 'none'; style-src 'unsafe-inline'"}


def model_out(record: ModelRecord, request: Request) -> ModelOut:
    """Return the API view of a stored model."""
    url = str(request.url_for("read_model", model_id=record.id).path)
    graph = str(request.url_for("read_model_graph", model_id=record.id).path)
    links = ModelLinks(self=url, graph_svg=graph, graph_dot=f"{graph}?format=dot", graph_json=f"{graph}?format=json")
    return ModelOut.model_validate({**dict(ModelView.model_validate(record, from_attributes=True)), "links": links})


@router.post(
    "",
    status_code=201,
    response_model=ModelOut,
    summary="Store and validate a model",
    responses={
        201: {"headers": {"Location": {"schema": {"type": "string"}, "description": "The model's URL."}}},
        429: {
            "model": ErrorOut,
            "description": "Too many models stored from this address this minute; see Retry-After.",
        },
    },
)
def create_model(
    document: Annotated[ModelDocument, Body(description="The model, in the same schema as model files.")],
    services: ServicesDep,
    client: ClientIdsDep,
    request: Request,
    response: Response,
) -> ModelOut:
    """Store a model (steps 1 and 2) and return its id, its validation report and links to its graph.

    An invalid model is answered with 422 and the report's codes (as `causalplan check`), and
    is kept all the same for research: `details.model_id` is its id. It is purged after
    `invalid_model_hours` unless a trial uses it. One client may store `models_per_minute`
    models a minute; beyond, 429 with `Retry-After`.
    """
    limit = PerMinute(services.engine, "model", services.settings.models_per_minute, TooManyModelsError)
    limit.admit(client_address(request, services.settings))
    submission = read_model(document, services, client)
    crud.save(services.engine, [submission.record], client)
    if not submission.is_valid:
        raise InvalidModelError(
            "The model is invalid: "
            + first_errors(submission.report)
            + (" (and more)" if len(submission.report.errors) > 3 else ""),
            details={"model": submission.report.as_dict(), "model_id": str(submission.record.id)},
        )
    out = model_out(submission.record, request)
    response.headers["Location"] = out.links.self
    return out


@router.get("/{model_id}", response_model=ModelOut, summary="A stored model", name="read_model")
def read_stored_model(model_id: uuid.UUID, session: SessionDep, request: Request) -> ModelOut:
    """Return a stored model as it was submitted, with its validation report."""
    return model_out(crud.get_model(session, model_id), request)


def _drawable(record: ModelRecord, catalog: CatalogDep) -> CausalModel:
    loaded = model_from_data(record.document, SourceMap(), catalog)
    if loaded.model is None:  # only when the document is not a mapping, which the API never stores
        raise InvalidModelError("The stored model cannot be read, so it cannot be drawn.")
    return loaded.model


def _svg(services: Services, model_id: uuid.UUID, model: CausalModel) -> bytes:
    """Return the model's drawing, kept by model id (a stored model never changes)."""
    import matplotlib

    from causalplan.causal.render import draw

    def drawn() -> bytes:
        with tempfile.TemporaryDirectory(prefix="causalplan-graph-") as folder:
            path = Path(folder) / "graph.svg"
            # Keep labels as text: searchable, selectable, readable by screen readers, and smaller.
            with matplotlib.rc_context({"svg.fonttype": "none"}):
                draw(model, path)
            return path.read_bytes()

    with DRAW_LOCK:
        return services.caches.model_graphs.get_or_make(str(model_id), drawn)


@router.get(
    "/{model_id}/graph",
    summary="A stored model's causal graph",
    # Three media types, the default (SVG) first: a generated client answers the text it can read
    # rather than parsing every answer as the JSON one.
    response_class=Response,
    responses={
        200: {
            "description": "SVG (default), Graphviz DOT (format=dot) or JSON nodes and edges (format=json).",
            "model": GraphOut,
            "content": {
                "image/svg+xml": {"schema": {"type": "string"}},
                "text/vnd.graphviz": {"schema": {"type": "string"}},
            },
        }
    },
)
def read_model_graph(
    model_id: uuid.UUID,
    session: SessionDep,
    catalog: CatalogDep,
    services: ServicesDep,
    format: Annotated[Literal["svg", "dot", "json"], Query(description="svg, dot or json.")] = "svg",
) -> Response:
    """Draw the model left to right, from the parts' functions to the goal (invalid models too)."""
    from causalplan.causal.render import to_dot, to_json

    model = _drawable(crud.get_model(session, model_id), catalog)
    if format == "dot":
        return Response(to_dot(model).encode("utf-8", "replace"), media_type="text/vnd.graphviz")
    if format == "json":
        return SafeJSONResponse(GraphOut.model_validate(to_json(model)).model_dump(mode="json"))
    return Response(_svg(services, model_id, model), media_type="image/svg+xml", headers=SVG_SECURITY_HEADERS)
