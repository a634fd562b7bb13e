"""The 3D player's document of the robot's troubleshooting episode (``sim.robot_episode``).

The same format as an assembly's (``sim.robot.playback``, ``causalplan-playback/2``), with a
spare as a part of its own (id ``PART:spare``, name "... (spare)"): the player draws the
broken part set aside and its spare fetched from the table as two bodies.
"""

from __future__ import annotations

from causalplan.objects.model import AssemblyObject
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.robot.panda import BASE_POSITION
from causalplan.sim.robot.playback import DIGITS, FORMAT, _commands, _shape, pose_list
from causalplan.sim.robot_episode import SPARE, EpisodeInPhysics


def episode_playback(obj: AssemblyObject, result: EpisodeInPhysics) -> dict[str, object]:
    """Return the 3D player's document (``causalplan-playback/2``, ``sim.robot.playback``) of the robot's episode.

    A spare is a part of its own in the document (id ``PART:spare``, name "... (spare)").
    Needs a run made with ``tracks``.
    """
    commands = result.commands
    if commands is None or not commands.points or not result.tracks:
        raise ValueError("the episode's run has no motor commands or tracks (run it with tracks=True)")
    parts = solids(obj)

    def solid(body_id: str) -> Solid:
        return parts[body_id.removesuffix(SPARE)]

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
                "name": solid(body_id).name + (" (spare)" if body_id.endswith(SPARE) else ""),
                "shapes": [_shape(shape) for shape in solid(body_id).shapes],
                "light": [_shape(shape) for shape in solid(body_id).light],
                "track": {"times": [round(t, DIGITS) for t in track.times], "poses": list(map(pose_list, track.poses))},
            }
            for body_id, track in result.tracks.items()
        ],
        "assembled": {body_id: pose_list(pose) for body_id, pose in result.placed.items()},
    }
