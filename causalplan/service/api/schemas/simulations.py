"""Answers of POST /v1/simulations (and the result of its jobs): the plan, the simulator's report, the robot's run."""

from __future__ import annotations

import uuid
from typing import Literal

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel
from causalplan.service.api.schemas.plans import PlanResultOut


class CheckOut(OutputModel):
    """One physics check: its name, whether it passed, and the measured figure against its tolerance."""

    name: str
    passed: bool
    measured: float | None
    tolerance: float | None
    unit: str
    detail: str


class ReachOut(OutputModel):
    """Whether the robot arm reaches a step's grasp poses by inverse kinematics."""

    reachable: bool
    error_mm: float


class SimulatedStepOut(OutputModel):
    """One step of the plan as the simulator ran it (or skipped it, after a failed one)."""

    number: int
    action: str
    args: list[str] = Field(description="The moving part and the fixed part.")
    fit: str | None
    text: str
    status: Literal["passed", "failed", "not_run"]
    failure: str | None = Field(description="Why the step failed, e.g. 'falls', 'unreachable', 'collision'.")
    message: str
    checks: list[CheckOut]
    reach: ReachOut | None = Field(default=None, description="With an arm: whether it reaches the step's poses.")
    robot: list[str] | None = Field(
        default=None, description="With the robot: what it did in this step (transit, grasp, carry, ...)."
    )


class StabilityOut(OutputModel):
    checks: list[CheckOut]
    step: int | None = Field(description="The step after which the assembly did not hold still, if any.")


class RequirementCheckOut(OutputModel):
    """One requirement of the object's true mechanism, judged on the simulated assembly."""

    says: str
    met: bool
    fit: str | None
    detail: str


class TrackingOut(OutputModel):
    """How closely the joint motors followed the motor commands."""

    max_joint_error_rad: float
    joint: str = Field(description="The arm joint with the largest error, by its URDF name (empty: none moved).")
    max_end_effector_error_mm: float = Field(description="Between the gripper driven and the gripper commanded.")
    tolerance_rad: float
    tolerance_mm: float


class MotorRunOut(OutputModel):
    """The motor commands played through the Panda's joint motors in a fresh physics scene."""

    seconds: float
    tracking: TrackingOut
    slip_mm: dict[str, float] = Field(description="How far each held part moved in the gripper, by part.")
    slip_tolerance_mm: float
    grasp_slipped: bool
    failure: str | None = Field(description="E.g. tracking_error or grasp_slipped; null when the run went through.")
    step: int | None = Field(description="The step where it failed.")
    message: str
    produces_goal: bool
    mechanism: list[RequirementCheckOut]


class RobotRunOut(OutputModel):
    """What the robot did overall: how long its motor commands take, and how its motors did."""

    seconds: float
    unconstrained_seconds: float
    rate_hz: float | None
    motions: int
    points: int | None = None
    robot_model: str | None = None
    safety_factor: float | None = None
    motors: MotorRunOut | None = Field(
        default=None, description="Tracking errors, slip in the gripper and the mechanism, driven by the motors."
    )


class SimulationReportOut(OutputModel):
    """The simulator's report (``causalplan simulate --json``): every step's checks, stability, the mechanism."""

    object: str
    passed: bool
    produces_goal: bool
    stable: bool
    explanation: str
    steps: list[SimulatedStepOut]
    stability: StabilityOut
    mechanism: list[RequirementCheckOut]
    tolerances: dict[str, float]
    arm: bool
    timing_ms: dict[str, float]
    robot: RobotRunOut | None = Field(default=None, description="With the robot: its run as a whole.")


class RobotReasonOut(OutputModel):
    code: Literal["robot_cannot_execute"]
    message: str
    step: int | None
    failure: str | None


class RobotOutcomeOut(OutputModel):
    """Whether the robot carried out the plan and, when not, why."""

    carried_out: bool
    reason: RobotReasonOut | None


class VideoOut(OutputModel):
    """Where a video job's film is."""

    url: str = Field(description="GET it (/v1/jobs/{id}/video) until the job expires.")
    content_type: str
    bytes: int


class SimulationResultOut(OutputModel):
    """A simulation's answer: the plan, the simulator's report of it, and (with the robot) its run and film.

    Also the result of a ``simulation`` or ``video`` job.
    """

    planning: PlanResultOut
    simulation: SimulationReportOut | None = Field(description="Null when there is no plan to simulate.")
    image: str | None = Field(
        default=None, description="A PNG data URL of the final assembly, when 'picture' was asked."
    )
    model_id: uuid.UUID | None = Field(
        default=None, description="The stored model planned (inline models are stored too)."
    )
    robot: RobotOutcomeOut | None = Field(default=None, description="With the robot: whether it carried out the plan.")
    video: VideoOut | None = Field(default=None, description="A video job's result: where the film is.")


class SimulationOut(SimulationResultOut):
    """POST /v1/simulations' answer: the plan, the simulator's report of it and the picture (the robot: in a job)."""

    image: str | None = Field(description="A PNG data URL of the final assembly, when 'picture' was asked.")
    model_id: uuid.UUID = Field(description="The stored model planned (inline models are stored too).")
    cached: bool = Field(description="True when an identical request was answered before.")
