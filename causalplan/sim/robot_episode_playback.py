"""The 3D player's document of the robot's troubleshooting episode (``sim.robot_episode``).

The same format as an assembly's (``sim.robot.playback``, ``causalplan-playback/2``), with a
spare as a part of its own (id ``PART:spare``, name "... (spare)"): the player draws the
broken part set aside and its spare fetched from the table as two bodies. It adds
``actions``, the episode's actions in order, each with when it starts and ends in the motor
commands, so the player shows which action is playing and what it observed::

    "actions": [{"number", "action", "part", "observed", "passed", "message", "start", "end"}]

An action without motion (inspect, replace, a test with nothing to light) starts and ends
where the action before it ended; the arm's way back to rest at the end is the last action's.
"""

from __future__ import annotations

from causalplan.objects.model import AssemblyObject
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.robot.playback import DIGITS, player_document
from causalplan.sim.robot.trajectory import Trajectory
from causalplan.sim.robot_episode_report import EpisodeInPhysics
from causalplan.sim.spares import SPARE
from causalplan.troubleshoot.episode import Episode
from causalplan.troubleshoot.solver import TEST


def _spans(commands: Trajectory) -> dict[int, tuple[float, float]]:
    """Return each action's (start, end) seconds in ``commands``, by number: its segments' first and last points."""
    spans: dict[int, tuple[float, float]] = {}
    for segment in commands.segments:
        start, end = commands.points[segment.first].time, commands.points[segment.last].time
        earlier = spans.get(segment.step)
        spans[segment.step] = (earlier[0], end) if earlier is not None else (start, end)
    return spans


def episode_actions(result: EpisodeInPhysics, episode: Episode | None = None) -> list[dict[str, object]]:
    """Return the robot's actions for the player: what each is, what it observed, when it plays.

    A test's ``observed`` is what physics showed; an inspection's is the episode's (looking is
    not simulated), when ``episode`` is given.
    """
    assert result.commands is not None
    spans = _spans(result.commands)
    planned = episode.steps if episode is not None else ()
    actions: list[dict[str, object]] = []
    ended = 0.0
    for action in result.actions:
        start, end = spans.get(action.number, (ended, ended))
        observed = action.observed
        if action.kind != TEST and action.number <= len(planned):
            observed = planned[action.number - 1].observed
        actions.append(
            {
                "number": action.number,
                "action": action.kind,
                "part": action.part,
                "observed": observed,
                "passed": action.passed,
                "message": action.message,
                "start": round(start, DIGITS),
                "end": round(end, DIGITS),
            }
        )
        ended = end
    return actions


def episode_playback(
    obj: AssemblyObject, result: EpisodeInPhysics, episode: Episode | None = None
) -> dict[str, object]:
    """Return the 3D player's document (``causalplan-playback/2``, ``sim.robot.playback``) of the robot's episode.

    A spare is a part of its own in the document (id ``PART:spare``, name "... (spare)");
    ``actions`` gives each action of the episode with its times (``episode_actions``).
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
    return {**player_document(obj, commands, bodies, result.placed), "actions": episode_actions(result, episode)}
