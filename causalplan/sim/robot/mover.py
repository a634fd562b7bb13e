"""The Panda moves the parts: the ``Mover`` (``sim.movers``) that has the robot fetch, drive and let go.

At the end of the run its planned waypoints are made into motor commands within the Panda's
datasheet limits times ``safety_factor`` (``sim.robot.timing``); with ``record_tracks``, every
part's pose over those commands is kept too (``sim.robot.tracks``: the run's own arm, posed at
the commands' times in the scene it built in, so no second scene is loaded for the player).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from causalplan.sim.movers import StepMove
from causalplan.sim.outcomes import Reach, RobotFailure
from causalplan.sim.poses import Pose
from causalplan.sim.robot.limits import DEFAULT_SAFETY_FACTOR, PANDA
from causalplan.sim.robot.panda import FINGER_OPEN, HOME
from causalplan.sim.robot.robot import Robot
from causalplan.sim.robot.steps import bring, drive, let_go, step_motions
from causalplan.sim.robot.timing import time_parameterize
from causalplan.sim.robot.tracks import PartTrack, run_tracks
from causalplan.sim.robot.trajectory import Trajectory, Waypoints
from causalplan.sim.scene import Scene


@dataclass
class PandaMovesThem:
    """The Panda carries each part from the table to its seat; ``observe`` hears every commanded position."""

    scene: Scene
    observe: Callable[[], None] | None = None
    safety_factor: float = DEFAULT_SAFETY_FACTOR
    """The share of the datasheet's velocity, acceleration and jerk limits the motor commands use."""
    record_tracks: bool = False
    """Whether to keep every part's pose over the motor commands (the browser's player draws them)."""
    robot: Robot = field(init=False)
    commands: Trajectory | None = None
    """The motor commands, once the run is finished."""
    tracks: dict[str, PartTrack] = field(default_factory=dict)
    """Every part's pose over the motor commands, once the run is finished."""
    homes: dict[str, Pose] = field(init=False)
    """Where each part rests when the run begins."""

    def __post_init__(self) -> None:
        self.robot = Robot(self.scene, observe=self.observe)
        self.homes = {part: self.scene.pose(part) for part in self.scene.bodies}

    def reach(self, move: StepMove) -> Reach | None:
        return None

    def bring(self, move: StepMove) -> RobotFailure | None:
        self.robot.step = move.number
        self.scene.place(move.part_id, move.home)
        return bring(self.robot, move.part_id, move.part, move.motion, move.path, move.start, move.mate)

    def drive(self, move: StepMove, stopped: float) -> RobotFailure | None:
        name = self.scene.solids[move.part_id].name
        return drive(self.robot, move.motion, move.path, move.start, stopped, name, move.mate)

    def let_go(self, move: StepMove) -> RobotFailure | None:
        name = self.scene.solids[move.part_id].name
        return let_go(self.robot, move.motion, move.path, move.start, move.home, name, move.mate)

    def finish(self, steps: int, carried_out: bool) -> dict[str, float]:
        self.robot.step = steps
        if carried_out:
            self.robot.go_home()
        started = time.perf_counter()
        self.commands = time_parameterize(self.robot.waypoints, HOME, 2 * FINGER_OPEN, PANDA, self.safety_factor)
        timing = {
            "robot_ik": self.robot.panda.ik_seconds,
            "robot_planning": self.robot.planning_seconds,
            "robot_timing": time.perf_counter() - started,
        }
        if self.record_tracks:
            started = time.perf_counter()
            self.tracks = run_tracks(self.robot.panda, self.robot.waypoints, self.commands, self.homes)
            timing["robot_tracks"] = time.perf_counter() - started
        return timing

    def motions(self, number: int) -> tuple[str, ...]:
        return step_motions(self.robot.waypoints, number)

    @property
    def trajectory(self) -> Waypoints | None:
        return self.robot.waypoints

    @property
    def placed(self) -> dict[str, Pose]:
        return dict(self.robot.released)
