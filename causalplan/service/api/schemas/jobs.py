"""Requests and answers of /v1/jobs: long work (a batch of trials, a simulation, a consensus, a robot's
film, a fit estimation) as jobs."""

from __future__ import annotations

import uuid
from typing import Annotated, Any, Literal

from pydantic import Field, SerializeAsAny, SkipValidation, StrictBool, StrictFloat, StrictInt

from causalplan.planners.result import MIN_TIME_LIMIT
from causalplan.service.api.schemas.common import (
    ErrorDetailOut,
    InputModel,
    MappingDocument,
    OutputModel,
    UtcDatetime,
)
from causalplan.service.api.schemas.job_results import BatchResultOut, ConsensusResultOut, FitEstimationResultOut
from causalplan.service.api.schemas.plans import SimulationIn, _Solve
from causalplan.service.api.schemas.simulations import SimulationResultOut
from causalplan.service.api.schemas.troubleshooting import TroubleshootingIn, TroubleshootingRobotOut
from causalplan.service.storage.jobs import JobKind, JobStatus

_PLANNER = Field(default="auto", min_length=1, max_length=64, description="A planner name from GET /health.")
_TIME_LIMIT = Field(
    default=None,
    ge=MIN_TIME_LIMIT,
    allow_inf_nan=False,
    description=f"Seconds per trial's solve (at least {MIN_TIME_LIMIT:g}).",
)
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
    time_limit: StrictFloat | None = _TIME_LIMIT
    simulate: StrictBool = _SIMULATE
    validate_plan: StrictBool = Field(
        default=True,
        alias="validate",
        description="Check each distinct plan with VAL, as `causalplan batch` does by default (a trial whose plan "
        "VAL rejects is undecided); false: the replay alone.",
    )


class SimulationJobIn(SimulationIn):
    """Plan a model and run the plan in the physics simulator: POST /v1/simulations as a job (a film: `video`)."""

    kind: Literal["simulation"]


class ConsensusJobIn(InputModel):
    """Build the crowd's consensus model and judge it, as `causalplan consensus` does."""

    kind: Literal["consensus"]
    trials: str = Field(
        min_length=1,
        description='JSON Lines, one {"id", "model", "mapping"} a line (the mapping may be absent; lines '
        "with the same id are one person mapping several objects).",
    )
    min_support: StrictFloat = Field(
        default=0.5, ge=0, le=1, description="Share of the crowd a rule needs to enter the consensus."
    )
    planner: str = _PLANNER
    time_limit: StrictFloat | None = _TIME_LIMIT
    simulate: StrictBool = _SIMULATE


class VideoPlanIn(_Solve):
    """A plan to film: the model (inline or stored), on the mapping's object if given, and the film's format."""

    mapping: MappingDocument | None = Field(default=None, description="A step-3 mapping: plan for that object.")
    video: Literal["mp4", "gif"] = Field(default="mp4", description="The film's format: MP4 (H.264) or GIF.")


class VideoJobIn(VideoPlanIn):
    """Plan a model and film the Franka Panda carrying out the plan (tens of seconds).

    The result is POST /v1/simulations' answer with `robot`, and `video`: `{"url", "content_type",
    "bytes"}`; GET the film at `url` (`/v1/jobs/{id}/video`) from any replica until the job expires.
    Progress counts frames drawn of the frames expected.
    """

    kind: Literal["video"]


# The defaults are the CLI's, written out: the app does not import the simulator.
class FitEstimationJobIn(InputModel):
    """Measure each fit's success probability by noisy robot insertions, as `causalplan estimate-fits`.

    The result is what `causalplan estimate-fits --json` prints (the same numbers for the same
    seed), and `overlay`: the catalog overlay `--out` writes. Progress counts trials (a fit at a time,
    or a chunk at a time on a cluster).
    """

    kind: Literal["fit_estimation"]
    object: str = Field(min_length=1, max_length=200, description="A catalog object id (GET /v1/objects).")
    trials: StrictInt = Field(
        default=200,
        ge=1,
        le=100_000,
        description="Noisy insertions per fit; trials times fits at most the server's max_job_trials.",
    )
    seed: StrictInt = Field(
        default=0, ge=-(2**63), le=2**63 - 1, description="Seed of the grasp noise: the same seed, the same numbers."
    )
    noise_mm: StrictFloat = Field(
        default=1.0,
        ge=0,
        le=20,
        allow_inf_nan=False,
        description="Standard deviation of where the part sits in the gripper, per axis (millimetres).",
    )
    noise_deg: StrictFloat = Field(
        default=1.0,
        ge=0,
        le=30,
        allow_inf_nan=False,
        description="Standard deviation of how the part is turned in the gripper (degrees).",
    )
    fits: list[Annotated[str, Field(min_length=1, max_length=200)]] = Field(
        default_factory=list, max_length=64, description="Only these fits (ids from GET /v1/objects/{id}); [] all."
    )


class TroubleshootingJobIn(TroubleshootingIn):
    """The Panda carries out a troubleshooting episode in physics: POST /v1/troubleshooting with `robot` as a job.

    The result is `TroubleshootingRobotOut`: the strategies' table, the episode, and `robot`.
    """

    kind: Literal["troubleshooting"]


JobBody = BatchJobIn | SimulationJobIn | ConsensusJobIn | VideoJobIn | FitEstimationJobIn | TroubleshootingJobIn
JobIn = Annotated[JobBody, Field(discriminator="kind")]


JobResult = SimulationResultOut | BatchResultOut | ConsensusResultOut | FitEstimationResultOut | TroubleshootingRobotOut
"""A succeeded job's result: a simulation's (kinds simulation and video), a batch's, a consensus's, fit estimates,
a troubleshooting episode carried out by the robot."""


class ProgressOut(OutputModel):
    done: int = Field(description="Units of work done: trials (batch, fit_estimation), frames (video).")
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
    # Stored results are handed back as they are (no validation, nothing dropped); the union declares their shapes.
    result: SkipValidation[SerializeAsAny[JobResult | None]] = Field(
        description="When succeeded: batch {trials, verdicts, results}; simulation as POST /v1/simulations; "
        "consensus as `causalplan consensus`'s report.json; video as POST /v1/simulations with robot, its "
        "`video.url` where the film is; fit_estimation as `causalplan estimate-fits --json`, with `overlay`; "
        "troubleshooting as `causalplan troubleshoot --robot --json` (`TroubleshootingRobotOut`), its "
        "`playback.url` where the 3D player's document is."
    )
    error: ErrorDetailOut | None = Field(description="When failed: why, in the one error shape.")


def _examples() -> dict[str, dict[str, Any]]:
    """Return a valid request of each kind, for the OpenAPI document (and the tests that post them)."""
    import json

    from causalplan.service.api.schemas.common import MAPPING_DOCUMENT_SCHEMA, MODEL_DOCUMENT_SCHEMA

    model = MODEL_DOCUMENT_SCHEMA["examples"][0]
    # The paper's flashlight mapping (examples/paper): the desk lamp's model transfers, so there is a plan to film.
    mapping = {**MAPPING_DOCUMENT_SCHEMA["examples"][0]}
    mapping["functions"] = {
        "batteries": ["provide electricity"],
        "head": ["turn electricity into light", "close the circuit"],
    }
    trial = json.dumps({"id": "t1", "model": model, "mapping": mapping})
    crowd = "\n".join(json.dumps({"id": person, "model": model, "mapping": mapping}) for person in ("a", "b", "c"))
    values: dict[JobKind, tuple[str, dict[str, Any]]] = {
        JobKind.BATCH: ("Transfer trials, one JSON object a line", {"trials": trial, "simulate": False}),
        JobKind.SIMULATION: ("The desk lamp's model on the flashlight", {"model": model, "mapping": mapping}),
        JobKind.CONSENSUS: ("Three people's models and mappings", {"trials": crowd, "simulate": False}),
        JobKind.VIDEO: ("Film the robot assembling the flashlight", {"model": model, "mapping": mapping}),
        JobKind.FIT_ESTIMATION: ("The flashlight's fits, 50 trials each", {"object": "flashlight", "trials": 50}),
        JobKind.TROUBLESHOOTING: (
            "The robot repairs a flashlight with flat batteries",
            {"model": model, "mapping": mapping, "fault": "batteries", "strategy": "model"},
        ),
    }
    return {
        kind.value: {"summary": summary, "value": {"kind": kind.value, **value}}
        for kind, (summary, value) in values.items()
    }


JOB_EXAMPLES = _examples()
"""A valid ``POST /v1/jobs`` body of each kind, by kind (OpenAPI ``examples``)."""
