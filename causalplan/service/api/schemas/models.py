"""Answers of /v1/models: a stored model and its causal graph."""

from __future__ import annotations

import uuid
from typing import Any, Literal

from pydantic import AliasChoices, Field

from causalplan.service.api.schemas.common import OutputModel, ReportOut, UtcDatetime


class ModelLinks(OutputModel):
    self: str
    graph_svg: str
    graph_dot: str
    graph_json: str


class ModelView(OutputModel):
    """A stored model and its validation report, read from its record (``from_attributes``)."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    object: str = Field(validation_alias=AliasChoices("object_id", "object"))
    valid: bool = Field(validation_alias=AliasChoices("is_valid", "valid"))
    report: ReportOut
    model: dict[str, Any] = Field(
        validation_alias=AliasChoices("document", "model"), description="The model as it was submitted."
    )


class ModelOut(ModelView):
    """A stored model, its validation report, and where its graph is."""

    links: ModelLinks


class GraphNodeOut(OutputModel):
    id: str
    label: str
    kind: Literal["function", "effect", "goal", "unknown", "rule"]
    column: int


class GraphEdgeOut(OutputModel):
    source: str
    target: str


class GraphOut(OutputModel):
    nodes: list[GraphNodeOut]
    edges: list[GraphEdgeOut]
