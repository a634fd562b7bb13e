"""The robot's run as the browser's player reads it: the timed motor commands, the parts' shapes and tracks.

One JSON document (``playback(obj, steps, report)``)::

    {"format": "causalplan-playback/2", "object": id, "name": name, "seconds": s,
     "robot": {"model": "panda", "base_position": [x, y, z]},
     "trajectory": {"robot": "panda", "joints": [7 names], "gripper_joints": [2 names],
                    "times": [s], "positions": [[7 angles]], "gripper_widths": [m],
                    "segments": [{"step", "kind", "gripper", "first", "last"}]},
     "parts": [{"id", "name", "shapes": [{"kind", "size", "position", "rotation", "color"}],
                "light": [shapes], "track": {"times": [s], "poses": [[x, y, z, qx, qy, qz, qw]]}}],
     "assembled": {part: [x, y, z, qx, qy, qz, qw]}}

``trajectory`` is the motor commands (every point of ``simulate --robot --trajectory``'s file)
by column, without the velocities and accelerations the player does not need: ``times[k]``,
``positions[k]`` and ``gripper_widths[k]`` are point ``k``. Poses are a part's frame in the
simulator's world (metres, z up; quaternions x, y, z, w); shapes are in the part's frame, as the
catalog gives them (``Shape``). ``assembled`` is where the robot's run let each part go
(``SimulationReport.placed``): the player's last frame must put the parts there.

Numbers keep ``DIGITS`` decimals: in the units above (radians, metres, seconds, unit
quaternions) that is finer than a pixel of the player's view and than the commands' spacing in
time, and it makes the document far smaller (sizes in benchmarks/RESULTS.md, `player.py`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject, Shape
from causalplan.planners.result import PlanStep
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose
from causalplan.sim.report import SimulationReport
from causalplan.sim.robot.panda import BASE_POSITION
from causalplan.sim.robot.replay import part_tracks
from causalplan.sim.robot.tracks import PartTrack
from causalplan.sim.robot.trajectory import Trajectory

FORMAT = "causalplan-playback/2"
DIGITS = 4
"""Decimals kept of every number the player reads (radians, metres, seconds, quaternion components)."""


class NoMotorCommandsError(CausalPlanError):
    """The report has no motor commands: it is not a robot's run, or the robot did not move."""

    code = "no_motor_commands"


def _rounded(values: Iterable[float]) -> list[float]:
    return [round(value, DIGITS) for value in values]


def pose_list(pose: Pose) -> list[float]:
    """Return a pose as [x, y, z, qx, qy, qz, qw], rounded as the player reads it (``DIGITS``)."""
    return _rounded((*pose.position, *pose.orientation))


def _commands(trajectory: Trajectory) -> dict[str, object]:
    points = trajectory.points
    return {
        "robot": trajectory.limits.model,
        "joints": list(trajectory.limits.joints),
        "gripper_joints": list(trajectory.limits.gripper_joints),
        "times": _rounded(point.time for point in points),
        "positions": [_rounded(point.positions) for point in points],
        "gripper_widths": _rounded(point.gripper_width for point in points),
        "segments": [segment.as_dict() for segment in trajectory.segments],
    }


def _shape(shape: Shape) -> dict[str, object]:
    return {
        "kind": shape.kind,
        "size": list(shape.size),
        "position": list(shape.position),
        "rotation": list(shape.rotation),
        "color": list(shape.color),
    }


def playback(
    obj: AssemblyObject, steps: Sequence[StepRequest | PlanStep], report: SimulationReport
) -> dict[str, object]:
    """Return the browser player's document of the robot's run ``report`` of ``steps`` on ``obj``.

    The parts' tracks are those the run recorded (``simulate_plan(..., tracks=True)``); a run
    made without them has them rebuilt from its motor commands in a fresh scene (``replay``).
    """
    commands = report.motor_commands
    if commands is None or not commands.points:
        raise NoMotorCommandsError(f"The run of the {obj.name} has no motor commands to play.")
    tracks = report.tracks or part_tracks(obj, steps, commands)
    parts = solids(obj)
    bodies = [(part, parts[part].name, parts[part], track) for part, track in tracks.items()]
    return player_document(obj, commands, bodies, report.placed)


def player_document(
    obj: AssemblyObject,
    commands: Trajectory,
    bodies: Iterable[tuple[str, str, Solid, PartTrack]],
    placed: Mapping[str, Pose],
) -> dict[str, object]:
    """Return the player's document of ``commands``: each body's id, name, solid and track; where each ends."""
    return {
        "format": FORMAT,
        "object": obj.id,
        "name": obj.name,
        "seconds": round(commands.seconds, DIGITS),
        "robot": {"model": commands.limits.model, "base_position": list(BASE_POSITION)},
        "trajectory": _commands(commands),
        "parts": [
            {
                "id": body_id,
                "name": name,
                "shapes": [_shape(shape) for shape in solid.shapes],
                "light": [_shape(shape) for shape in solid.light],
                "track": {"times": _rounded(track.times), "poses": list(map(pose_list, track.poses))},
            }
            for body_id, name, solid, track in bodies
        ],
        "assembled": {body_id: pose_list(pose) for body_id, pose in placed.items()},
    }
