"""The robot's motions: planned waypoints, and the motor commands made of them (a timed trajectory).

``Waypoints`` is what the robot plans, segment by segment: joint positions along a
collision-checked path (transit, grasp, carry, ...), the gripper held open or closed. The
film draws them as they are planned, ``rate_hz`` a second. ``Trajectory`` is what a robot
runs: those paths time-parameterized within the robot's limits (``sim.robot.timing``),
sampled as points with positions, velocities, accelerations and a time from the start. Its
JSON form (``simulate --robot --trajectory T.json``, read back by ``read_trajectory``)::

    {"format": "causalplan-trajectory/2", "robot": "panda", "joints": [7 names],
     "gripper_joints": [2 names], "units": {...}, "limits": {... the limits used ...},
     "points": [{"time_from_start": s, "positions": [7], "velocities": [7],
                 "accelerations": [7], "gripper_width": m}, ...],
     "segments": [{"step": i, "kind": "transit|grasp|...", "gripper": "open|closed",
                   "first": k, "last": n}]}

Angles in radians, times in seconds, the gripper's width (between the fingers) in metres.
A segment's points are ``first``..``last`` (indexes into ``points``; consecutive segments
share their joining point). A user's file needs only ``joints`` and, per point,
``time_from_start`` and ``positions``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, cast

from causalplan.errors import CausalPlanError
from causalplan.sim.poses import Pose
from causalplan.sim.robot.limits import RobotLimits, robot_limits
from causalplan.sim.robot.panda import Configuration

RATE_HZ = 50
"""Waypoints a second as the film shows them (the planned motion, before time parameterization)."""
FORMAT = "causalplan-trajectory/2"
SEGMENT_KINDS = ("transit", "grasp", "carry", "approach", "screw", "push", "ignite", "release", "retreat")
UNITS = {"position": "rad", "velocity": "rad/s", "acceleration": "rad/s^2", "time": "s", "gripper_width": "m"}
Gripper = Literal["open", "closed"]


class TrajectoryInputError(CausalPlanError):
    """A trajectory file is malformed."""

    code = "invalid_trajectory"


@dataclass
class Segment:
    """One planned stretch of motion with the gripper held open or closed, ending ``width`` metres open."""

    step: int
    kind: str
    gripper: Gripper
    width: float
    positions: list[Configuration] = field(default_factory=list)
    held: tuple[str, Pose] | None = None
    """The part riding in the gripper all along, and its pose in the gripper's frame (the player's tracks)."""


@dataclass
class Waypoints:
    """Everything the robot planned to do, segment by segment (untimed: the film shows ``rate_hz`` a second)."""

    segments: list[Segment] = field(default_factory=list)
    rate_hz: int = RATE_HZ

    @property
    def positions(self) -> int:
        """Return how many positions the robot planned, over every segment."""
        return sum(len(segment.positions) for segment in self.segments)

    @property
    def seconds(self) -> float:
        """Return how long the planned positions last at ``rate_hz`` (the film's pace, before any limit)."""
        return self.positions / self.rate_hz


@dataclass(frozen=True)
class Point:
    """One motor command: where the joints are, how fast they move, at ``time`` seconds from the start."""

    time: float
    positions: Configuration
    velocities: Configuration
    accelerations: Configuration
    gripper_width: float

    def as_dict(self) -> dict[str, object]:
        return {
            "time_from_start": round(self.time, 6),
            "positions": [round(value, 6) for value in self.positions],
            "velocities": [round(value, 6) for value in self.velocities],
            "accelerations": [round(value, 5) for value in self.accelerations],
            "gripper_width": round(self.gripper_width, 6),
        }


@dataclass(frozen=True)
class TimedSegment:
    """The points ``first``..``last`` of a trajectory: one motion of a plan step."""

    step: int
    kind: str
    gripper: Gripper
    first: int
    last: int

    def as_dict(self) -> dict[str, object]:
        return {"step": self.step, "kind": self.kind, "gripper": self.gripper, "first": self.first, "last": self.last}


@dataclass(frozen=True)
class Trajectory:
    """Motor commands for a robot model, made within its limits times ``safety_factor``."""

    limits: RobotLimits
    safety_factor: float
    points: tuple[Point, ...]
    segments: tuple[TimedSegment, ...] = ()

    @property
    def seconds(self) -> float:
        """Return how long the motion takes."""
        return self.points[-1].time if self.points else 0.0

    def as_dict(self) -> dict[str, object]:
        """Return the JSON form (positions to a micro-radian, times to a microsecond)."""
        return {
            "format": FORMAT,
            "robot": self.limits.model,
            "joints": list(self.limits.joints),
            "gripper_joints": list(self.limits.gripper_joints),
            "units": UNITS,
            "limits": self.limits.as_dict(self.safety_factor),
            "points": [point.as_dict() for point in self.points],
            "segments": [segment.as_dict() for segment in self.segments],
        }


def _numbers(value: object, count: int, where: str, what: str) -> Configuration:
    if not (isinstance(value, list) and len(value) == count):
        raise TrajectoryInputError(f"{where}: '{what}' must be a list of {count} numbers.")
    numbers = []
    for number in value:
        if isinstance(number, bool) or not isinstance(number, int | float) or not math.isfinite(number):
            raise TrajectoryInputError(f"{where}: '{what}' must hold finite numbers, not {number!r}.")
        numbers.append(float(number))
    return tuple(numbers)


def _number(value: object, where: str, what: str) -> float:
    return _numbers([value], 1, where, what)[0]


def _point(item: object, count: int, where: str, before: float | None) -> Point:
    if not isinstance(item, dict):
        raise TrajectoryInputError(f"{where}: a point is an object with 'time_from_start' and 'positions'.")
    if "time_from_start" not in item or "positions" not in item:
        raise TrajectoryInputError(f"{where}: needs 'time_from_start' (seconds) and 'positions' (radians).")
    time = _number(item["time_from_start"], where, "time_from_start")
    if time < 0 or (before is not None and time <= before):
        raise TrajectoryInputError(f"{where}: 'time_from_start' must grow from point to point (here {time} s).")
    positions = _numbers(item["positions"], count, where, "positions")
    zeros = (0.0,) * count
    velocities = _numbers(item["velocities"], count, where, "velocities") if "velocities" in item else zeros
    accelerations = _numbers(item["accelerations"], count, where, "accelerations") if "accelerations" in item else zeros
    width = _number(item.get("gripper_width", 0.0), where, "gripper_width")
    return Point(time, positions, velocities, accelerations, width)


def _segment(item: object, points: int, where: str) -> TimedSegment:
    if not isinstance(item, dict) or not {"step", "kind", "gripper", "first", "last"} <= set(item):
        raise TrajectoryInputError(f"{where}: needs 'step', 'kind', 'gripper', 'first' and 'last'.")
    step, kind, gripper, first, last = (item[key] for key in ("step", "kind", "gripper", "first", "last"))
    for name, value in (("step", step), ("first", first), ("last", last)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise TrajectoryInputError(f"{where}: '{name}' must be a whole number, not {value!r}.")
    if not first <= last < points:
        raise TrajectoryInputError(f"{where}: points {first}..{last} are not among the {points} points.")
    if kind not in SEGMENT_KINDS:
        raise TrajectoryInputError(f"{where}: unknown kind {kind!r}; use one of: {', '.join(SEGMENT_KINDS)}.")
    if gripper not in ("open", "closed"):
        raise TrajectoryInputError(f"{where}: 'gripper' must be 'open' or 'closed'.")
    return TimedSegment(step, kind, cast(Gripper, gripper), first, last)


def read_trajectory(data: object, robot: str | None = None) -> Trajectory:
    """Return the trajectory of a file's JSON data, for ``robot`` (default: the file's, else the Panda).

    TrajectoryInputError says what is wrong and where. Files of the first format (positions
    at a fixed ``rate_hz``, no times or velocities) are refused: run the simulation again.
    """
    if not isinstance(data, dict):
        raise TrajectoryInputError("A trajectory is a JSON object with 'joints' and 'points'.")
    if "rate_hz" in data and "points" not in data:
        raise TrajectoryInputError(
            "This is a trajectory of the first format (positions at 'rate_hz', no times, velocities or "
            "limits), which is no longer read: write it again with 'causalplan simulate ... --robot --trajectory'."
        )
    named = data.get("robot")
    if robot is None and named is not None and not isinstance(named, str):
        raise TrajectoryInputError("'robot' must be a robot model's name, e.g. 'panda'.")
    limits = robot_limits(robot or cast(str | None, named) or "panda")
    if data.get("joints") != list(limits.joints):
        raise TrajectoryInputError(f"'joints' must be the {limits.model}'s: {', '.join(limits.joints)}.")
    items = data.get("points")
    if not isinstance(items, list) or not items:
        raise TrajectoryInputError("'points' must be a non-empty list.")
    points: list[Point] = []
    for number, item in enumerate(items):
        points.append(_point(item, len(limits.joints), f"point {number}", points[-1].time if points else None))
    segments = data.get("segments", [])
    if not isinstance(segments, list):
        raise TrajectoryInputError("'segments' must be a list.")
    read = tuple(_segment(item, len(points), f"segment {k + 1}") for k, item in enumerate(segments))
    factor = data.get("limits", {}).get("safety_factor", 1.0) if isinstance(data.get("limits"), dict) else 1.0
    return Trajectory(limits, _number(factor, "limits", "safety_factor"), tuple(points), read)
