"""Requests and answers of /v1/jobs: long work (a batch of trials, a simulation, a consensus) as jobs."""

from __future__ import annotations

import uuid
from typing import Annotated, Any, Literal

from pydantic import Field

from causalplan.service.jobs.kinds import JobKind
from causalplan.service.jobs.store import JobStatus
from causalplan.service.schemas.common import ErrorDetailOut, InputModel, OutputModel, UtcDatetime
from causalplan.service.schemas.plans import SimulationIn

_PLANNER = Field(default="auto", min_length=1, max_length=64, description="A planner name from GET /health.")
_TIME_LIMIT = Field(default=None, gt=0, allow_inf_nan=False, description="Seconds per trial's solve.")
_SIMULATE = Field(default=True, description="Check each plan in the physics simulator (as `causalplan transfer`).")


class BatchJobIn(InputModel):
    """Judge many transfer trials, as `causalplan batch` does."""

    kind: Literal["batch"]
    trials: str = Field(
        min_length=1,
        description='The uploaded file\'s text: JSON Lines, one {"id", "model", "mapping"} a line; or CSV '
        "with the columns id, model, mapping (model and mapping cells hold JSON).",
    )
    format: Literal["jsonl", "csv"] = Field(default="jsonl", description="How `trials` is written.")
    planner: str = _PLANNER
    time_limit: float | None = _TIME_LIMIT
    simulate: bool = _SIMULATE


class SimulationJobIn(SimulationIn):
    """Plan a model and run the plan in the physics simulator, with the picture: POST /v1/simulations as a job."""

    kind: Literal["simulation"]


class ConsensusJobIn(InputModel):
    """Build the crowd's consensus model and judge it, as `causalplan consensus` does."""

    kind: Literal["consensus"]
    trials: str = Field(
        min_length=1,
        description='JSON Lines, one {"id", "model", "mapping"} a line (the mapping may be absent; lines '
        "with the same id are one person mapping several objects).",
    )
    min_support: float = Field(
        default=0.5, ge=0, le=1, description="Share of the crowd a rule needs to enter the consensus."
    )
    planner: str = _PLANNER
    time_limit: float | None = _TIME_LIMIT
    simulate: bool = _SIMULATE


JobIn = Annotated[BatchJobIn | SimulationJobIn | ConsensusJobIn, Field(discriminator="kind")]


class ProgressOut(OutputModel):
    done: int = Field(description="Units of work done (trials, for a batch).")
    total: int = Field(description="Units of work in all (0 until the job has started).")


class JobOut(OutputModel):
    """A job: its status and progress, then its result (or the error that ended it)."""

    id: uuid.UUID
    kind: JobKind
    status: JobStatus
    url: str = Field(description="Where to GET this job (and DELETE it to cancel).")
    progress: ProgressOut
    attempts: int = Field(description="Times a server started the job (more than 1: a server stopped mid-job).")
    created_at: UtcDatetime
    started_at: UtcDatetime | None
    finished_at: UtcDatetime | None
    expires_at: UtcDatetime | None = Field(description="When the finished job and its result are deleted.")
    result: dict[str, Any] | None = Field(
        description="When succeeded: batch {trials, verdicts, results}; simulation as POST /v1/simulations; "
        "consensus as `causalplan consensus`'s report.json."
    )
    error: ErrorDetailOut | None = Field(description="When failed: why, in the one error shape.")
