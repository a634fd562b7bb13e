"""Where each part is while the motor commands play: keyframes of its pose, for the browser's player.

A part rests where it is until the gripper holds it; while held it rides on the gripper at the
grasp the robot made; once let go it stays where it was let go. ``run_tracks`` takes what the
robot's run itself recorded (which part each planned segment held, and where in the gripper)
and poses the run's own Panda at the motor commands' times (forward kinematics in the scene
already loaded), so the tracks match the arm the player draws from those commands, point for
point. ``sim.robot.replay`` rebuilds the same tracks from a trajectory file alone.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from causalplan.sim.poses import Pose
from causalplan.sim.robot.panda import Panda
from causalplan.sim.robot.trajectory import Trajectory, Waypoints

TRACK_EVERY = 4
"""A held part's pose is kept at every 4th motor command (25 a second) and at each segment's end."""


@dataclass(frozen=True)
class PartTrack:
    """Where a part's frame is while the motor commands play: ``poses[k]`` from ``times[k]`` seconds on.

    Between two keyframes the part moves smoothly (the gripper's points are 100 a second);
    after the last one it stays put. ``released`` says whether the robot ever let it go.
    """

    part_id: str
    times: tuple[float, ...]
    poses: tuple[Pose, ...]
    released: bool


@dataclass
class Keyframes:
    """Tracks as they are written, part by part, from where each part rests at the start."""

    keys: dict[str, list[tuple[float, Pose]]]
    released: set[str] = field(default_factory=set)

    @classmethod
    def at_rest(cls, homes: Mapping[str, Pose]) -> Keyframes:
        return cls({part: [(0.0, pose)] for part, pose in homes.items()})

    def keep(self, part: str, time: float, pose: Pose) -> None:
        """Keep the part's pose at ``time`` (consecutive segments share their joining point: the later one wins)."""
        track = self.keys[part]
        if track[-1][0] >= time:
            track.pop()
        track.append((time, pose))

    def tracks(self) -> dict[str, PartTrack]:
        return {
            part: PartTrack(part, tuple(t for t, _ in track), tuple(pose for _, pose in track), part in self.released)
            for part, track in self.keys.items()
        }


def carried_indexes(first: int, last: int) -> tuple[int, ...]:
    """Return the motor commands of a segment ``first``..``last`` at which a held part's pose is kept."""
    return (*range(first, last, TRACK_EVERY), last)


def run_tracks(
    panda: Panda, waypoints: Waypoints, commands: Trajectory, homes: Mapping[str, Pose]
) -> dict[str, PartTrack]:
    """Return every part's track over ``commands``, the motor commands made of the run's ``waypoints``.

    Each planned segment with positions became one timed segment (``time_parameterize``); a
    segment's ``held`` says which part rode in the gripper and where. ``panda`` is posed at the
    held segments' commands and put back as it was.
    """
    planned = [segment for segment in waypoints.segments if segment.positions]  # as time_parameterize skips
    assert len(planned) == len(commands.segments), "each planned segment with positions is one timed segment"
    frames = Keyframes.at_rest(homes)
    saved, fingers = panda.configuration, panda.fingers
    holding: str | None = None
    for segment, timed in zip(planned, commands.segments, strict=True):
        if segment.held is None:
            if holding is not None and segment.gripper == "open":
                frames.released.add(holding)
            holding = None
            continue
        holding, offset = segment.held
        for index in carried_indexes(timed.first, timed.last):
            point = commands.points[index]
            panda.set(point.positions)
            frames.keep(holding, point.time, panda.gripper_pose() * offset)
    panda.set(saved, fingers)
    return frames.tracks()
