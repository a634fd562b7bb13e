"""Requests and answers of POST /v1/plans, /v1/transfers and /v1/simulations."""

from __future__ import annotations

import uuid
from typing import Literal

from pydantic import ConfigDict, Field, StrictBool, StrictFloat, model_validator

from causalplan.planners.result import MIN_TIME_LIMIT, PlanStatus
from causalplan.service.api.schemas.common import (
    DiagnosticOut,
    InputModel,
    MappingDocument,
    ModelDocument,
    OutputModel,
    PlanStepOut,
    ReportOut,
)
from causalplan.service.api.schemas.repairs import RepairsOut


class _Solve(InputModel):
    model: ModelDocument | None = Field(default=None, description="The model inline (or give model_id).")
    model_id: uuid.UUID | None = Field(default=None, description="A model stored by POST /v1/models.")
    planner: str = Field(
        default="auto",
        min_length=1,
        max_length=64,
        description="A planner name from GET /health ('planners'); 'auto' lets the service choose.",
    )
    time_limit: StrictFloat | None = Field(
        default=None,
        ge=MIN_TIME_LIMIT,
        allow_inf_nan=False,
        description=f"Seconds the planner may run: at least {MIN_TIME_LIMIT:g}, at most the server's maximum "
        "(GET /health, 'limits').",
    )
    validate_plan: StrictBool = Field(
        default=True,
        alias="validate",
        description="Check the plan with VAL on the readable PDDL too (the answer's 'validated_by'), as the CLI "
        "does by default; a plan VAL rejects is an error, never an answer. false: the replay alone.",
    )

    @model_validator(mode="after")
    def _one_model(self) -> _Solve:
        if (self.model is None) == (self.model_id is None):
            raise ValueError("give exactly one of 'model' (the model inline) and 'model_id' (a stored model)")
        return self


class PlanIn(_Solve):
    """POST /v1/plans: plan a model, on its own object or (with ``mapping``) on another."""

    mapping: MappingDocument | None = Field(default=None, description="A step-3 mapping: plan for that object.")
    include_pddl: StrictBool = Field(default=False, description="Also return the PDDL domain and problem.")


class TransferIn(_Solve):
    """POST /v1/transfers: try a model on a new object through a step-3 mapping."""

    mapping: MappingDocument = Field(description="The step-3 mapping of the new object's parts.")
    repair: bool = Field(
        default=False,
        description="When it fails: also the smallest sets of edits that make it transfer ('repairs'), "
        "each re-checked by a full verdict. For researchers: participants never see them.",
    )


class SimulationIn(PlanIn):
    """POST /v1/simulations: what POST /v1/plans takes, and whether to draw the final assembly."""

    picture: StrictBool = Field(
        default=True, description="Also return a PNG of the final assembly as a data URL (not with 'robot')."
    )
    robot: StrictBool = Field(
        default=False,
        description="Have the Franka Panda carry out the plan, as a job (answered 202 with the job): per step "
        "what it did ('robot' in each step), and in the result's 'robot' whether it could (else the reason "
        "robot_cannot_execute, its step and code).",
    )
    motors: StrictBool = Field(
        default=True,
        description="With 'robot': also drive the motor commands through the Panda's joint motors in physics, "
        "as `causalplan simulate --robot` does; the result's simulation.robot.motors gives the tracking error "
        "and slip, and a run the motors cannot follow is robot_cannot_execute (tracking_error, grasp_slipped). "
        "false: the kinematic run alone (faster).",
    )
    video: Literal["mp4", "gif"] | None = Field(
        default=None,
        description="With 'robot': also film it, as MP4 (H.264) or GIF, in a 'video' job; its result's 'video' "
        "says where to fetch the film (GET /v1/jobs/{id}/video). Filming takes tens of seconds.",
    )

    @model_validator(mode="after")
    def _video_needs_robot(self) -> SimulationIn:
        if self.video is not None and not self.robot:
            raise ValueError("'video' needs 'robot': true (the film is of the robot at work)")
        return self


class PddlOut(OutputModel):
    domain: str
    problem: str


class PolicyEntryOut(OutputModel):
    """One entry of the MDP's policy: in this state (fits made, fits failed), attempt this fit."""

    made: list[str]
    failed: list[str]
    attempt: str = Field(description="The fit to attempt.")
    text: str
    success_probability: float = Field(description="The chance of reaching the goal from this state.")


class PlanResultOut(OutputModel):
    """A replayed plan as ``causalplan plan --json`` prints it (also a transfer's and a simulation's ``planning``)."""

    model_config = ConfigDict(extra="allow")  # a newer planner's figures pass through (as additional properties)

    status: PlanStatus = Field(description="Every outcome a planner has, e.g. 'too_large' from the exact MDP.")
    planner_used: str
    object: str
    plan: list[PlanStepOut] | None
    plan_length: int | None
    valid_under_model: bool
    valid_under_true_mechanism: bool
    unmet_requirements: list[str]
    success_probability: float | None = Field(
        description="The chance the plan assembles the object, from the fits' success probabilities."
    )
    expected_actions: float | None = Field(description="Attempts expected, failed ones included.")
    fallback_reason: str | None = Field(description="Why 'auto' fell back from its first planner (else null).")
    validated_by_up: bool | None = Field(description="unified-planning's validator's verdict, when it was asked.")
    validated_by: dict[str, str] | None = Field(
        description="Each validator's verdict on the plan, e.g. {'replay': 'valid', 'val': 'valid'} "
        "(VAL only when the request asked for 'validate'); null without a plan."
    )
    timing: dict[str, float] = Field(description="Seconds per stage.")
    message: str
    pddl: PddlOut | None = Field(default=None, description="The PDDL domain and problem, when asked.")
    # The MDP's own figures, null (or absent, as in the CLI's JSON) unless the MDP gave the answer.
    objective: Literal["probability", "attempts"] | None = Field(default=None, description="What the MDP optimised.")
    required_success: float | None = Field(default=None, description="The success probability the MDP had to reach.")
    optimality: Literal["optimal", "bounded"] | None = Field(
        default=None, description="'optimal' (proved) or 'bounded' (the time limit came first)."
    )
    states: int | None = Field(default=None, description="States the MDP solver stored.")
    fewest_attempts: bool | None = Field(
        default=None,
        description="Whether the expected attempts are proved the fewest among the most reliable policies "
        "(false: they are the returned policy's, exact, but another equally reliable policy may need fewer).",
    )
    success_probability_bounds: list[float] | None = Field(
        default=None, min_length=2, max_length=2, description="Lower and upper bound on the success probability."
    )
    bound_gap: float | None = Field(default=None, description="Upper bound minus lower bound.")
    policy: list[PolicyEntryOut] | None = Field(default=None, description="The MDP's policy, state by state.")


class PlanOut(PlanResultOut):
    """POST /v1/plans' answer: the replayed plan (``causalplan plan --json``), and where the answer came from."""

    planner_requested: str = Field(description="The planner asked for ('auto' included).")
    cached: bool = Field(description="True when an identical request was answered before.")
    model_id: uuid.UUID | None = Field(description="The stored model planned (inline models are stored too).")
    warnings: list[DiagnosticOut] = Field(description="Validation warnings of the model and mapping.")


class SimulationSummaryOut(OutputModel):
    """The short form of a simulation report that a transfer verdict carries."""

    passed: bool
    produces_goal: bool
    stable: bool
    failed_step: int | None
    failure: str | None = Field(description="The failed step's failure code, e.g. 'falls'.")
    unmet_requirements: list[str]
    explanation: str = Field(description="In one sentence, what went wrong (empty when the simulation passed).")


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
    planning: PlanResultOut | None = Field(description="The plan's full answer, as POST /v1/plans has it.")
    diagnostics: dict[str, ReportOut] = Field(
        description="An invalid verdict's checks of its inputs, by input ('model', 'mapping'). Empty here: "
        "invalid inputs are a 422, whose details carry the verdict; stored trials and batch verdicts keep them."
    )
    simulation: SimulationSummaryOut | None = Field(description="The plan run in physics, when it was.")
    planner_requested: str
    cached: bool
    trial_id: uuid.UUID
    model_id: uuid.UUID
    repairs: RepairsOut | None = Field(default=None, description="Asked with 'repair' and the transfer fails.")
