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


class FaultOut(OutputModel):
    part: str
    probability: float = Field(description="The prior that this part is the broken one (an object's sum to 1).")
    looks: str = Field(description="What the fault is like.")
    visible: bool = Field(description="Whether inspecting the part shows the fault.")


class ObjectOut(ObjectSummaryOut):
    """A catalog object in full: parts, connectors, fits and true mechanism."""

    base: str
    parts: list[PartOut]  # type: ignore[assignment]  # the summary's parts, with their connectors
    fits: list[FitOut]
    mechanism: MechanismOut
    faults: list[FaultOut] = Field(description="The parts whose failure stops the goal (empty: none listed).")
    fault_priors: str | None = Field(description="Where the faults' priors come from: 'illustrative' or 'measured'.")
