"""What every resource's schemas share: the document schemas, the bases, diagnostics, plan steps, errors.

Request (``*In``) and response (``*Out``) models are separate from the internal dataclasses on
purpose: the API can stay stable while those change. Model and mapping documents travel as
plain JSON objects in the file schema and are read by the same reader as files, so problems
get the CLI's codes.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, WithJsonSchema
from typing_extensions import TypeAliasType

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

# Named type aliases, so the OpenAPI document has one shared component of each (a `$ref`), not a copy
# inlined in every request body (which generated clients turn into PlanInModelDocument, TransferIn...).
ModelDocument = TypeAliasType("ModelDocument", Annotated[dict[str, Any], WithJsonSchema(MODEL_DOCUMENT_SCHEMA)])
MappingDocument = TypeAliasType("MappingDocument", Annotated[dict[str, Any], WithJsonSchema(MAPPING_DOCUMENT_SCHEMA)])


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


class PlanStepOut(OutputModel):
    action: str
    args: list[str]
    fit: str
    text: str


class ErrorDetailOut(BaseModel):
    code: str = Field(description="Stable, safe to match on.")
    message: str
    details: dict[str, Any]


class ErrorOut(BaseModel):
    """The one error shape of every route."""

    error: ErrorDetailOut


_ERROR_DESCRIPTIONS = {
    401: "No research token, or the wrong one.",
    403: "Forbidden: the research endpoints are disabled (no token configured), or X-Participant-Id or "
    "X-Session-Id names a study participant (participant_id_reserved).",
    404: "No such model or object.",
    413: "The request body is over the limit.",
    422: "Invalid request, model or mapping (codes as `causalplan check`), or over a limit.",
    429: "All planner workers are busy and the queue is full (`queue_full`), this client has as many planner "
    "requests running or waiting as it may (`too_many_requests_in_flight`), or its stored models, trials and jobs "
    "fill its allowance (`storage_full`); see Retry-After.",
    503: "A planner worker crashed (it has been replaced), or the database is unavailable.",
    504: "A planner worker overran its time limit and was stopped.",
}


def error_responses(*statuses: int) -> dict[int | str, dict[str, Any]]:
    """Return the OpenAPI ``responses`` entries for these error statuses (all in the one shape)."""
    return {status: {"model": ErrorOut, "description": _ERROR_DESCRIPTIONS[status]} for status in statuses}


BINARY: dict[str, Any] = {"schema": {"type": "string", "format": "binary"}}
"""An OpenAPI media type whose content is bytes (a film, a picture): generated clients answer it as bytes."""


RESEARCH_ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    **error_responses(401, 403, 503),
    429: {"model": ErrorOut, "description": "Too many wrong research tokens from this address; see Retry-After."},
}
"""The OpenAPI error responses of every route behind the research token."""

JOB_LIMIT_RESPONSE: dict[str, Any] = {
    "model": ErrorOut,
    "description": "Over a limit; see Retry-After. The service's unfinished jobs (`too_many_jobs`), or this "
    "client's: jobs queued or running (`too_many_jobs_in_flight`), megabytes its jobs keep stored "
    "(`job_storage_full`: its jobs, models and trials), jobs posted this minute (`too_many_job_starts`); its "
    "address's jobs (`too_many_jobs_in_flight`) or the share of clients without a key (`too_many_jobs`); or too "
    "many wrong bearer tokens from this address (`too_many_attempts`).",
}
"""The 429 of a route that queues a job: every limit a job passes, each with its own code."""
JOB_CLIENT_RESPONSES: dict[int | str, dict[str, Any]] = {
    401: {
        "model": ErrorOut,
        "description": "The bearer token is neither an API key nor the research token (`not_authenticated`).",
    },
    429: {
        "model": ErrorOut,
        "description": "Too many wrong bearer tokens from this address (`too_many_attempts`); see Retry-After.",
    },
}
"""The answers of every route that knows a job's client by its bearer token."""
