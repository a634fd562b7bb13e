"""What a job stores as its request: one model per kind, written when it is posted, read back by a runner.

A kind's ``prepare`` turns the API's body into one of these (the model stored by id, the
planner and time limit resolved, the upload counted), and its ``run`` gets it back from the
job's row, whichever replica runs it. The JSON keys are those the rows have always had.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter


class JobRequest(BaseModel):
    """The base of stored requests: nothing unknown, nothing changed once stored."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True, protected_namespaces=())

    def units(self) -> int:
        """Return the units of work the job starts with (its progress's total)."""
        return 1

    def stored(self) -> dict[str, Any]:
        """Return the JSON stored in the job's row."""
        return self.model_dump(mode="json", by_alias=True)


class _Counted(JobRequest):
    count: int = Field(ge=0, description="Trials (or lines) the upload has: the job's total.")

    def units(self) -> int:
        return self.count


class BatchRequest(_Counted):
    """Trials to judge, as JSON Lines (a CSV upload is turned into them when it is posted)."""

    trials: str
    planner: str
    time_limit: float
    simulate: bool
    validate_plan: bool = Field(default=False, alias="validate")
    """VAL checks each plan; rows stored before VAL was asked for ran without it."""


class _StoredPlan(JobRequest):
    """A stored model, planned (on the mapping's object) with the planner and time limit resolved."""

    model_id: str
    mapping: dict[str, Any] | None
    planner: str
    time_limit: float


class SimulationRequest(_StoredPlan):
    """A stored model planned and simulated, or carried out by the robot."""

    picture: bool
    robot: bool
    validate_plan: bool = Field(default=False, alias="validate")
    """VAL checks the plan; jobs stored before VAL was asked for ran without it."""
    motors: bool = False
    """The robot's run is driven by its motors too; jobs stored before that ran without them."""


class ConsensusRequest(_Counted):
    """The crowd's models as JSON Lines, for ``causalplan consensus``."""

    trials: str
    min_support: float
    planner: str
    time_limit: float
    simulate: bool


class PlanFilmRequest(_StoredPlan):
    """The API's film: plan a stored model, then film the robot carrying out the plan."""

    validate_plan: bool = Field(alias="validate")
    video: str


class FitsFilmRequest(JobRequest):
    """The participant page's film: the robot making ``fits`` of ``object``, kept under ``film`` (its key)."""

    object: str
    fits: list[str]
    video: str
    film: str


VideoRequest = FitsFilmRequest | PlanFilmRequest
read_video_request = TypeAdapter(VideoRequest).validate_python
"""Return the stored request of a film: the participant page's (it names ``fits``) or the API's."""


class TroubleshootingRequest(JobRequest):
    """A stored model's troubleshooting episode on a broken object, carried out by the robot."""

    model_id: str
    mapping: dict[str, Any] | None
    object: str | None
    fault: str
    strategy: str
    motors: bool = False
    """The robot's run is driven by its motors too; jobs stored before that ran without them."""


class FitEstimationRequest(_Counted):
    """``causalplan estimate-fits`` of some fits of an object (``count``: trials times fits)."""

    object: str
    fits: list[str]
    trials: int
    seed: int
    noise_mm: float
    noise_deg: float
