"""The robot's motor commands: per step, segments of joint positions at a fixed control rate.

The JSON form (``simulate --robot --trajectory T.json``) is::

    {"robot": "franka_panda", "joints": [7 names], "rate_hz": R,
     "segments": [{"step": i, "kind": "transit|grasp|...", "gripper": "open|closed",
                   "positions": [[7 floats], ...]}]}

Position ``k`` of a segment is commanded ``k / rate_hz`` seconds after the segment starts;
``gripper`` is the gripper command held through the segment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, cast

from causalplan.errors import CausalPlanError
from causalplan.sim.robot.panda import JOINT_NAMES, ROBOT_NAME, Configuration

RATE_HZ = 50
"""Commands a second."""
SEGMENT_KINDS = ("transit", "grasp", "carry", "approach", "screw", "push", "ignite", "release", "retreat")
Gripper = Literal["open", "closed"]


class TrajectoryInputError(CausalPlanError):
    """A trajectory file is malformed."""

    code = "invalid_trajectory"


@dataclass
class Segment:
    """One stretch of motion with the gripper held open or closed."""

    step: int
    kind: str
    gripper: Gripper
    positions: list[Configuration] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return {
            "step": self.step,
            "kind": self.kind,
            "gripper": self.gripper,
            "positions": [[round(angle, 6) for angle in position] for position in self.positions],
        }


@dataclass
class Trajectory:
    """Everything the robot was commanded to do, segment by segment."""

    segments: list[Segment] = field(default_factory=list)
    rate_hz: int = RATE_HZ

    @property
    def seconds(self) -> float:
        """Return how long the commanded motion takes."""
        return sum(len(segment.positions) for segment in self.segments) / self.rate_hz

    def as_dict(self) -> dict[str, object]:
        """Return the JSON-ready form (positions rounded to a micro-radian)."""
        return {
            "robot": ROBOT_NAME,
            "joints": list(JOINT_NAMES),
            "rate_hz": self.rate_hz,
            "segments": [segment.as_dict() for segment in self.segments if segment.positions],
        }


def _position(value: object, where: str) -> Configuration:
    if not (isinstance(value, list) and len(value) == len(JOINT_NAMES)):
        raise TrajectoryInputError(f"{where}: a position is a list of {len(JOINT_NAMES)} joint angles (radians).")
    angles = []
    for angle in value:
        if isinstance(angle, bool) or not isinstance(angle, int | float) or not math.isfinite(angle):
            raise TrajectoryInputError(f"{where}: joint angles must be finite numbers, not {angle!r}.")
        angles.append(float(angle))
    return tuple(angles)


def read_trajectory(data: object) -> Trajectory:
    """Return the trajectory of a file's JSON data; TrajectoryInputError says what is wrong and where."""
    if not isinstance(data, dict):
        raise TrajectoryInputError("A trajectory is a JSON object with 'robot', 'joints', 'rate_hz' and 'segments'.")
    if data.get("robot") != ROBOT_NAME or data.get("joints") != list(JOINT_NAMES):
        raise TrajectoryInputError(f"The trajectory is not for the {ROBOT_NAME} with joints {', '.join(JOINT_NAMES)}.")
    rate = data.get("rate_hz")
    if isinstance(rate, bool) or not isinstance(rate, int) or not 1 <= rate <= 10_000:
        raise TrajectoryInputError("'rate_hz' must be a whole number of commands a second (1-10000).")
    segments = data.get("segments")
    if not isinstance(segments, list):
        raise TrajectoryInputError("'segments' must be a list.")
    read: list[Segment] = []
    for number, item in enumerate(segments, start=1):
        where = f"segment {number}"
        if not isinstance(item, dict) or set(item) != {"step", "kind", "gripper", "positions"}:
            raise TrajectoryInputError(f"{where}: needs exactly 'step', 'kind', 'gripper' and 'positions'.")
        step, kind, gripper, positions = item["step"], item["kind"], item["gripper"], item["positions"]
        if isinstance(step, bool) or not isinstance(step, int) or step < 1:
            raise TrajectoryInputError(f"{where}: 'step' must be a plan step number (1, 2, ...).")
        if kind not in SEGMENT_KINDS:
            raise TrajectoryInputError(f"{where}: unknown kind {kind!r}; use one of: {', '.join(SEGMENT_KINDS)}.")
        if gripper not in ("open", "closed"):
            raise TrajectoryInputError(f"{where}: 'gripper' must be 'open' or 'closed'.")
        if not isinstance(positions, list) or not positions:
            raise TrajectoryInputError(f"{where}: 'positions' must be a non-empty list.")
        read.append(
            Segment(
                step,
                kind,
                cast(Gripper, gripper),
                [_position(p, f"{where}, position {k + 1}") for k, p in enumerate(positions)],
            )
        )
    return Trajectory(read, rate)
