"""What goes over the wire: request (``*In``) and response (``*Out``) models.

They are separate from the internal dataclasses on purpose: the API can stay stable while
those change. Model and mapping documents travel as plain JSON objects in the file schema
and are read by the same reader as files, so problems get the CLI's codes.
"""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, WithJsonSchema, model_validator

from causalplan.causal.model import DEFAULT_GOAL

_LABELS = {"type": "array", "items": {"type": "string"}, "description": "Function labels (free text)."}

MODEL_DOCUMENT_SCHEMA: dict[str, Any] = {
    "type": "object",
    "title": "ModelDocument",
    "description": "A causal model in the file schema (steps 1 and 2), as JSON.",
    "properties": {
        "object": {"type": "string", "description": "Catalog id of the training object.", "examples": ["desk_lamp"]},
        "goal": {"type": "string", "default": DEFAULT_GOAL, "description": "The effect the rules produce."},
        "functions": {
            "type": "object",
            "description": "Part id -> function labels (step 1).",
            "additionalProperties": _LABELS,
        },
        "rules": {
            "type": "array",
            "items": {"type": "string"},
            "description": "Keyword rules, e.g. 'provide electricity AND close the circuit CAUSES electricity flows'.",
        },
    },
    "required": ["object", "functions", "rules"],
    "additionalProperties": False,
    "examples": [
        {
            "object": "desk_lamp",
            "goal": "light",
            "functions": {
                "base_with_cables": ["provide electricity"],
                "light_bulb": ["turn electricity into light", "close the circuit"],
            },
            "rules": [
                "provide electricity AND close the circuit CAUSES electricity flows",
                "electricity flows AND turn electricity into light CAUSES light",
            ],
        }
    ],
}
MAPPING_DOCUMENT_SCHEMA: dict[str, Any] = {
    "type": "object",
    "title": "MappingDocument",
    "description": "A step-3 mapping: another object's parts given the model's functions.",
    "properties": {
        "object": {"type": "string", "description": "Catalog id of the new object.", "examples": ["flashlight"]},
        "functions": {"type": "object", "description": "Part id -> function labels.", "additionalProperties": _LABELS},
    },
    "required": ["object", "functions"],
    "additionalProperties": False,
    "examples": [
        {
            "object": "flashlight",
            "functions": {"batteries": ["provide electricity"], "head": ["turn electricity into light"]},
        }
    ],
}

ModelDocument = Annotated[dict[str, Any], WithJsonSchema(MODEL_DOCUMENT_SCHEMA)]
MappingDocument = Annotated[dict[str, Any], WithJsonSchema(MAPPING_DOCUMENT_SCHEMA)]


class InputModel(BaseModel):
    """The base of request bodies: an unknown field is an error, not silently dropped."""

    model_config = ConfigDict(extra="forbid")


class OutputModel(BaseModel):
    """The base of answers: built from records and dataclasses as well as dicts."""

    model_config = ConfigDict(from_attributes=True)


def _as_utc(value: datetime) -> datetime:
    # SQLite hands timestamps back without their zone; they were written in UTC.
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


UtcDatetime = Annotated[datetime, AfterValidator(_as_utc)]


class _Solve(InputModel):
    model: ModelDocument | None = Field(default=None, description="The model inline (or give model_id).")
    model_id: uuid.UUID | None = Field(default=None, description="A model stored by POST /v1/models.")
    planner: str = Field(
        default="auto",
        min_length=1,
        max_length=64,
        description="A planner name from GET /health ('planners'); 'auto' lets the service choose.",
    )
    time_limit: float | None = Field(
        default=None,
        gt=0,
        allow_inf_nan=False,
        description="Seconds the planner may run; at most the server's maximum (GET /health, 'limits').",
    )

    @model_validator(mode="after")
    def _one_model(self) -> _Solve:
        if (self.model is None) == (self.model_id is None):
            raise ValueError("give exactly one of 'model' (the model inline) and 'model_id' (a stored model)")
        return self


class PlanIn(_Solve):
    """POST /v1/plans: plan a model, on its own object or (with ``mapping``) on another."""

    mapping: MappingDocument | None = Field(default=None, description="A step-3 mapping: plan for that object.")
    include_pddl: bool = Field(default=False, description="Also return the PDDL domain and problem.")


class TransferIn(_Solve):
    """POST /v1/transfers: try a model on a new object through a step-3 mapping."""

    mapping: MappingDocument = Field(description="The step-3 mapping of the new object's parts.")


class LocationOut(OutputModel):
    file: str | None = None
    line: int | None = None
    rule: int | None = None
    part: str | None = None


class DiagnosticOut(OutputModel):
    """One finding of validation, with the same code as ``causalplan check``."""

    code: str
    severity: Literal["error", "warning"]
    message: str
    location: LocationOut
    hint: str | None = None


class ReportOut(OutputModel):
    """A validation report: ``causalplan check --json`` without the file name."""

    valid: bool
    errors: list[DiagnosticOut]
    warnings: list[DiagnosticOut]


class ModelLinks(OutputModel):
    self: str
    graph_svg: str
    graph_dot: str
    graph_json: str


class ModelOut(OutputModel):
    """A stored model, its validation report, and where its graph is."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    object: str
    valid: bool
    report: ReportOut
    model: dict[str, Any] = Field(description="The model as it was submitted.")
    links: ModelLinks


class PlanStepOut(OutputModel):
    action: str
    args: list[str]
    fit: str
    text: str


class PddlOut(OutputModel):
    domain: str
    problem: str


class PlanOut(OutputModel):
    """A replayed plan (``causalplan plan --json``), and where the answer came from."""

    model_config = ConfigDict(extra="allow")  # planners may add fields, e.g. success_probability

    status: Literal["solved", "unsolvable", "timeout", "out_of_memory", "error"]
    planner_used: str
    object: str
    plan: list[PlanStepOut] | None
    plan_length: int | None
    valid_under_model: bool
    valid_under_true_mechanism: bool
    unmet_requirements: list[str]
    timing: dict[str, float]
    message: str
    pddl: PddlOut | None = None
    planner_requested: str = Field(description="The planner asked for ('auto' included).")
    cached: bool = Field(description="True when an identical request was answered before.")
    model_id: uuid.UUID | None = Field(description="The stored model planned (inline models are stored too).")
    warnings: list[DiagnosticOut] = Field(description="Validation warnings of the model and mapping.")


class ReasonOut(OutputModel):
    code: str
    severity: Literal["error", "warning"]
    message: str
    labels: list[str]


class TransferOut(OutputModel):
    """A transfer verdict (``causalplan transfer --json``), and the stored trial."""

    model_config = ConfigDict(extra="allow")

    verdict: Literal["transfers", "fails", "invalid", "undecided"]
    training_object: str | None
    test_object: str | None
    generalization: str | None
    decided_by: str
    reasons: list[ReasonOut]
    plan: list[PlanStepOut] | None
    planning: dict[str, Any] | None
    diagnostics: dict[str, Any]
    planner_requested: str
    cached: bool
    trial_id: uuid.UUID
    model_id: uuid.UUID


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


class ObjectOut(OutputModel):
    """A catalog object in full: parts, connectors, fits and true mechanism."""

    id: str
    name: str
    category: str
    goal: str
    description: str
    base: str
    parts: list[PartOut]
    fits: list[FitOut]
    mechanism: MechanismOut


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


class TrialOut(OutputModel):
    """One stored transfer trial."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    model_id: uuid.UUID
    training_object: str | None
    test_object: str | None
    planner: str
    verdict: str
    generalization: str | None
    decided_by: str
    cached: bool
    seconds: float
    mapping: dict[str, Any]
    result: dict[str, Any]


class TrialsOut(OutputModel):
    """A page of trials, newest first, and how many match in all."""

    data: list[TrialOut]
    count: int


class StoredModelOut(OutputModel):
    """One stored model in an export."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    object_id: str
    is_valid: bool
    canonical_hash: str | None
    document: dict[str, Any]
    report: dict[str, Any]


class ExportOut(OutputModel):
    """Everything stored: every model and every trial."""

    exported_at: datetime
    models: list[StoredModelOut]
    trials: list[TrialOut]


class DatabaseHealthOut(OutputModel):
    reachable: bool
    backend: str
    revision: str | None
    expected_revision: str
    problem: str | None = None


class FastDownwardHealthOut(OutputModel):
    search_binary: str | None
    search_binary_found: bool
    translator_found: bool
    versions: dict[str, str | None]
    problem: str | None = None


class PlannerHealthOut(OutputModel):
    name: str
    available: bool
    problem: str | None = Field(description="Why it cannot run here (null when it can).")


class HealthOut(OutputModel):
    """Whether the service can plan and store, and what it runs with."""

    status: Literal["ok", "degraded"]
    version: str
    planners: list[PlannerHealthOut] | None = Field(
        description="The planner registry as a worker sees it (null until the first probe has finished)."
    )
    default_planner: str = Field(description="What 'auto' (the default) runs as on this server.")
    fast_downward: FastDownwardHealthOut | None
    optional_backends_failed: dict[str, str] | None = Field(
        description="Optional modules that failed to import in a planner worker, with why (null: not probed yet)."
    )
    database: DatabaseHealthOut
    pool: dict[str, int]
    cache: dict[str, int]
    repeats: dict[str, int] = Field(
        description="Plan request bodies whose cached answers are kept by their exact bytes, and their hits."
    )
    limits: dict[str, int | float]


class ErrorDetailOut(BaseModel):
    code: str = Field(description="Stable, safe to match on.")
    message: str
    details: dict[str, Any]


class ErrorOut(BaseModel):
    """The one error shape of every route."""

    error: ErrorDetailOut


_ERROR_DESCRIPTIONS = {
    401: "No research token, or the wrong one.",
    403: "The research endpoints are disabled (no token configured).",
    404: "No such model or object.",
    413: "The request body is over the limit.",
    422: "Invalid request, model or mapping (codes as `causalplan check`), or over a limit.",
    429: "All planner workers are busy and the queue is full; see Retry-After.",
    503: "A planner worker crashed (it has been replaced), or the database is unavailable.",
    504: "A planner worker overran its time limit and was stopped.",
}


def error_responses(*statuses: int) -> dict[int | str, dict[str, Any]]:
    """Return the OpenAPI ``responses`` entries for these error statuses (all in the one shape)."""
    return {status: {"model": ErrorOut, "description": _ERROR_DESCRIPTIONS[status]} for status in statuses}


RESEARCH_ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    **error_responses(401, 403, 503),
    429: {"model": ErrorOut, "description": "Too many wrong research tokens from this address; see Retry-After."},
}
"""The OpenAPI error responses of every route behind the research token."""
