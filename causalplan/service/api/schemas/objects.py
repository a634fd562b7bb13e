"""Answers of /v1/objects: the catalog."""

from __future__ import annotations

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel


class ObjectPartOut(OutputModel):
    id: str
    name: str


class ObjectSummaryOut(OutputModel):
    """One catalog object in the list."""

    id: str
    name: str
    category: str
    goal: str
    description: str
    parts: list[ObjectPartOut]


class ConnectorOut(OutputModel):
    id: str
    kind: str
    spec: str


class PartOut(OutputModel):
    id: str
    name: str
    connectors: list[ConnectorOut]


class FitOut(OutputModel):
    id: str
    primitive: str
    moving: str = Field(description="part.connector of the part being attached")
    fixed: str = Field(description="part.connector of the part already assembled")
    probability: float
    blocks: list[str]
    text: str = Field(description="The step in words.")


class RequirementOut(OutputModel):
    any_of: list[str]
    says: str


class MechanismOut(OutputModel):
    explanation: str
    requires: list[RequirementOut]


class ObjectOut(ObjectSummaryOut):
    """A catalog object in full: parts, connectors, fits and true mechanism."""

    base: str
    parts: list[PartOut]  # type: ignore[assignment]  # the summary's parts, with their connectors
    fits: list[FitOut]
    mechanism: MechanismOut
