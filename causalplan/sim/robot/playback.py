"""The robot's run as the browser's player reads it: the timed motor commands, the parts' shapes and tracks.

One JSON document (``playback(obj, steps, report)``)::

    {"format": "causalplan-playback/1", "object": id, "name": name, "seconds": s,
     "robot": {"model": "panda", "base_position": [x, y, z]},
     "trajectory": {... the motor commands as ``simulate --robot --trajectory`` writes them, but each
                    point without its velocities and accelerations (a third of the size; the
                    player needs the positions and the gripper's width at their times) ...},
     "parts": [{"id", "name", "shapes": [{"kind", "size", "position", "rotation", "color"}],
                "light": [shapes], "track": {"times": [s], "poses": [[x, y, z, qx, qy, qz, qw]]}}],
     "assembled": {part: [x, y, z, qx, qy, qz, qw]}}

Poses are a part's frame in the simulator's world (metres, z up; quaternions x, y, z, w);
shapes are in the part's frame, as the catalog gives them (``Shape``). ``assembled`` is where
the robot's run let each part go (``SimulationReport.placed``): the player's last frame must
put the parts there.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject, Shape
from causalplan.planners.result import PlanStep
from causalplan.sim.geometry import solids
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose
from causalplan.sim.report import SimulationReport
from causalplan.sim.robot.panda import BASE_POSITION
from causalplan.sim.robot.replay import part_tracks

FORMAT = "causalplan-playback/1"


class NoMotorCommandsError(CausalPlanError):
    """The report has no motor commands: it is not a robot's run, or the robot did not move."""

    code = "no_motor_commands"


def pose_list(pose: Pose) -> list[float]:
    """Return a pose as [x, y, z, qx, qy, qz, qw] (to a tenth of a millimetre, and of a micro-unit)."""
    return [round(value, 5) for value in pose.position] + [round(value, 6) for value in pose.orientation]


def _positions_only(trajectory: dict[str, Any]) -> dict[str, Any]:
    points = [
        {key: point[key] for key in ("time_from_start", "positions", "gripper_width")} for point in trajectory["points"]
    ]
    return {**trajectory, "points": points}


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
    """Return the browser player's document of the robot's run ``report`` of ``steps`` on ``obj``."""
    commands = report.motor_commands
    if commands is None or not commands.points:
        raise NoMotorCommandsError(f"The run of the {obj.name} has no motor commands to play.")
    tracks = part_tracks(obj, steps, commands)
    parts = solids(obj)
    return {
        "format": FORMAT,
        "object": obj.id,
        "name": obj.name,
        "seconds": round(commands.seconds, 6),
        "robot": {"model": commands.limits.model, "base_position": list(BASE_POSITION)},
        "trajectory": _positions_only(commands.as_dict()),
        "parts": [
            {
                "id": part,
                "name": parts[part].name,
                "shapes": [_shape(shape) for shape in parts[part].shapes],
                "light": [_shape(shape) for shape in parts[part].light],
                "track": {
                    "times": [round(time, 6) for time in track.times],
                    "poses": list(map(pose_list, track.poses)),
                },
            }
            for part, track in tracks.items()
        ],
        "assembled": {part: pose_list(pose) for part, pose in report.placed.items()},
    }
