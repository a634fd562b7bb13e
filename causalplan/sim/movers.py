"""Who moves a step's part: the part itself along its approach, or the Panda (``sim.robot.mover``).

The executor (``sim.executor``) makes every physics check of a step the same way whoever
moves the part; a ``Mover`` is asked at four moments of the step: before the approach
(``reach``, then ``bring``), once the approach found how far the part gets (``drive``), and
once the joint is made (``let_go``). ``PartsMoveThemselves`` does nothing at those moments
(with an ``Arm`` it answers whether a Panda could reach the part's grasp); the Panda's
mover makes the robot do the motions and writes its motor commands.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from causalplan.objects.model import Part
from causalplan.sim.motions import Motion
from causalplan.sim.outcomes import Reach, RobotFailure
from causalplan.sim.poses import Pose
from causalplan.sim.robot.arm import Arm, reach_step
from causalplan.sim.scene import Scene

if TYPE_CHECKING:
    from causalplan.sim.robot.tracks import PartTrack
    from causalplan.sim.robot.trajectory import Trajectory, Waypoints


@dataclass(frozen=True)
class StepMove:
    """What a step asks of its mover: which part goes along which path to which mate."""

    number: int
    part_id: str
    part: Part
    motion: Motion
    path: Callable[[float], Pose]
    """The part's pose as a function of its distance (metres) from the seat."""
    start: float
    """Where the approach begins (metres from the seat)."""
    mate: str
    home: Pose
    """Where the part waits on the table."""


class Mover(Protocol):
    """Who moves the parts: asked at each moment of a step; a failure ends the step."""

    def reach(self, move: StepMove) -> Reach | None:
        """Return whether an arm reaches the part's grasp at the approach and the seat (None: not asked)."""

    def bring(self, move: StepMove) -> RobotFailure | None:
        """Bring the part from the table to the start of its approach."""

    def drive(self, move: StepMove, stopped: float) -> RobotFailure | None:
        """Drive the part along its approach to ``stopped`` metres from the seat (where physics stopped it)."""

    def let_go(self, move: StepMove) -> RobotFailure | None:
        """Let go of the joined part (or take a touching one back to the table)."""

    def finish(self, steps: int, carried_out: bool) -> dict[str, float]:
        """End the run after ``steps`` steps (``carried_out``: all passed); return the mover's timing (seconds)."""

    def motions(self, number: int) -> tuple[str, ...]:
        """Return what the mover did in step ``number`` (transit, grasp, ...), for the step's report."""

    @property
    def trajectory(self) -> Waypoints | None:
        """The waypoints the robot planned, when a robot moved the parts."""

    @property
    def placed(self) -> dict[str, Pose]:
        """Where each part was let go, when a robot moved the parts."""

    @property
    def commands(self) -> Trajectory | None:
        """The motor commands (the waypoints time-parameterized), once a robot's run is finished."""

    @property
    def tracks(self) -> dict[str, PartTrack]:
        """Every part's pose over the motor commands, when a robot's run was asked to keep them."""


@dataclass
class PartsMoveThemselves:
    """Parts move along their approach on their own; with ``arm``, a Panda checks it could reach each grasp."""

    scene: Scene
    arm: Arm | None = None
    placed: dict[str, Pose] = field(default_factory=dict)

    def reach(self, move: StepMove) -> Reach | None:
        if self.arm is None:
            return None
        return reach_step(self.arm, self.scene, move.part_id, (move.path(move.start), move.path(0.0)))

    def bring(self, move: StepMove) -> RobotFailure | None:
        return None

    def drive(self, move: StepMove, stopped: float) -> RobotFailure | None:
        return None

    def let_go(self, move: StepMove) -> RobotFailure | None:
        return None

    def finish(self, steps: int, carried_out: bool) -> dict[str, float]:
        if self.arm is not None:
            self.arm.go_home()
        return {}

    def motions(self, number: int) -> tuple[str, ...]:
        return ()

    @property
    def trajectory(self) -> Waypoints | None:
        return None

    @property
    def commands(self) -> Trajectory | None:
        return None

    @property
    def tracks(self) -> dict[str, PartTrack]:
        return {}
