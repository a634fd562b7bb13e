"""The 3D player's document of the robot's troubleshooting episode (``sim.robot_episode``).

The same format as an assembly's (``sim.robot.playback``, ``causalplan-playback/2``), with a
spare as a part of its own (id ``PART:spare``, name "... (spare)"): the player draws the
broken part set aside and its spare fetched from the table as two bodies.
"""

from __future__ import annotations

from causalplan.objects.model import AssemblyObject
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.robot.playback import player_document
from causalplan.sim.robot_episode_report import EpisodeInPhysics
from causalplan.sim.spares import SPARE


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

    bodies = [
        (body_id, solid(body_id).name + (" (spare)" if body_id.endswith(SPARE) else ""), solid(body_id), track)
        for body_id, track in result.tracks.items()
    ]
    return player_document(obj, commands, bodies, result.placed)
