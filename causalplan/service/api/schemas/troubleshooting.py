"""Request and answer of POST /v1/troubleshooting: repair a broken object with a model as the prior."""

from __future__ import annotations

import uuid
from typing import Literal

from pydantic import Field, StrictBool, model_validator

from causalplan.service.api.schemas.common import DiagnosticOut, InputModel, MappingDocument, ModelDocument, OutputModel
from causalplan.service.api.schemas.playback import PlaybackFileOut
from causalplan.service.api.schemas.simulations import MotorRunOut, RequirementCheckOut


class TroubleshootingIn(InputModel):
    """POST /v1/troubleshooting: the strategies' table on a broken object, and one episode if ``fault`` is given."""

    model: ModelDocument | None = Field(default=None, description="The model inline (or give model_id).")
    model_id: uuid.UUID | None = Field(default=None, description="A model stored by POST /v1/models.")
    mapping: MappingDocument | None = Field(default=None, description="A step-3 mapping: troubleshoot that object.")
    object: str | None = Field(
        default=None,
        min_length=1,
        max_length=64,
        description="The broken object (default: the mapping's, else the model's).",
    )
    fault: str | None = Field(
        default=None, min_length=1, max_length=64, description="The broken part: also run one episode ('episode')."
    )
    strategy: Literal["model", "uniform", "oracle"] = Field(
        default="model", description="Whose policy runs the episode."
    )
    robot: bool = Field(
        default=False,
        description="With `fault`: the Franka Panda carries out the episode in physics, action by action; "
        "a job (answered 202), whose result is `TroubleshootingRobotOut`.",
    )
    motors: StrictBool = Field(
        default=False,
        description="With `robot`: also play the motor commands through the Panda's joint motors in physics, "
        "as `causalplan troubleshoot --robot --motors` does; the result's robot.motors gives the tracking error, "
        "slip and the mechanism, and the episode counts as repaired only if the motors' run gives the goal too.",
    )

    @model_validator(mode="after")
    def _one_model(self) -> TroubleshootingIn:
        if (self.model is None) == (self.model_id is None):
            raise ValueError("give exactly one of 'model' (the model inline) and 'model_id' (a stored model)")
        if self.robot and self.fault is None:
            raise ValueError("'robot' carries out one episode: name the broken part ('fault')")
        if self.motors and not self.robot:
            raise ValueError("'motors' needs 'robot': true (it plays the robot's motor commands through its motors)")
        return self


class FaultResultOut(OutputModel):
    part: str
    probability: float = Field(description="The catalog's prior of this fault.")
    actions: int = Field(description="The actions this strategy takes when this part is broken.")
    fewest_actions: int = Field(description="The fewest actions of a robot that knows this part is broken.")
    reward_share: float = Field(description="(bonus - actions) / (bonus - fewest_actions).")


class StrategyOut(OutputModel):
    expected_actions: float = Field(description="Expected actions to the repair, under the catalog's priors.")
    worst_actions: int = Field(description="The most actions over the fault locations.")
    reward_share: float = Field(description="The reward as a share of the maximum, averaged over fault locations.")
    own_expected_actions: float = Field(description="Expected actions under the strategy's own prior.")
    faults: dict[str, FaultResultOut]


class StepOut(OutputModel):
    action: Literal["test", "inspect", "detach", "attach", "replace"]
    part: str | None = Field(description="The part acted on (null for a test).")
    observed: Literal["goal", "no goal", "broken", "works"] | None = Field(
        description="What a test or an inspection showed (null for the other actions)."
    )


class StrategyActionsOut(OutputModel):
    actions: int


class EpisodeOut(OutputModel):
    fault: str
    strategy: Literal["model", "uniform", "oracle"]
    actions: int
    steps: list[StepOut]
    strategies: dict[str, StrategyActionsOut] = Field(description="Each strategy's actions on the same fault.")


class _StrategiesTable(OutputModel):
    """The strategies' table on the broken object (`causalplan troubleshoot --all-faults --json`)."""

    status: str
    object: str
    fault_priors: str | None = Field(description="Where the catalog's priors come from: 'illustrative' or 'measured'.")
    repair_bonus: float = Field(description="The reward for the repair; each action costs 1.")
    faults: dict[str, float] = Field(description="The catalog's fault priors, by part.")
    strategies: dict[str, StrategyOut] = Field(description="model (with a model), uniform and oracle.")


class TroubleshootingOut(_StrategiesTable):
    """The same JSON as `causalplan troubleshoot --all-faults --json`, with the episode when a fault was given."""

    status: Literal["solved"]
    episode: EpisodeOut | None = None
    model_id: uuid.UUID
    warnings: list[DiagnosticOut]


class RobotActionOut(OutputModel):
    number: int
    action: Literal["test", "inspect", "detach", "attach", "replace"]
    part: str | None
    robot: list[str] = Field(
        description="The Panda's motions: transit, grasp, carry, approach, screw, push, ignite, release, retreat."
    )
    observed: Literal["goal", "no goal"] | None = Field(description="What a test showed in physics.")
    passed: bool
    failure: str | None = Field(description="Why the robot could not do it: a robot or simulator failure code.")
    message: str


class RobotEpisodeOut(OutputModel):
    """The Panda's run of the episode in physics (``causalplan troubleshoot --robot --json``'s ``robot``)."""

    produces_goal: bool = Field(description="Every action carried out, and the last test showed the goal.")
    carried_out: bool
    broken_part_replaced: bool
    actions: list[RobotActionOut]
    mechanism: list[RequirementCheckOut] = Field(description="The true mechanism at the robot's last test.")
    seconds: float = Field(description="How long the motor commands take.")
    timing: dict[str, float]
    motors: MotorRunOut | None = Field(
        default=None,
        description="With `motors`: the commands driven through the Panda's joint motors in a fresh scene "
        "(tracking error, slip in the gripper, the first failure, the mechanism); null without it.",
    )


class TroubleshootingRobotOut(_StrategiesTable):
    """A `troubleshooting` job's result: `TroubleshootingOut` with the robot's run of the episode."""

    status: Literal["repaired", "not_repaired_in_physics"]
    episode: EpisodeOut
    robot: RobotEpisodeOut
    model_id: uuid.UUID
    playback: PlaybackFileOut | None = Field(
        default=None,
        description="Where the 3D player's document of the robot's run is (`EpisodePlaybackOut`); "
        "null when the robot stopped before it moved (absent from a job run before the service served it).",
    )
