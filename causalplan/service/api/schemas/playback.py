"""The 3D player's document (``causalplan-playback/2``, ``sim.robot.playback``) as the API serves it.

``GET /v1/jobs/{id}/playback`` answers a troubleshooting job's (``EpisodePlaybackOut``: the
robot's run of the episode, with its actions). These models declare the document's shape for
clients and for the tests that check real answers against it; the route hands the stored
document back as it is.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel


class PlaybackFileOut(OutputModel):
    """Where a troubleshooting job's 3D player document is."""

    url: str = Field(description="GET it (/v1/jobs/{id}/playback) until the job expires.")
    content_type: Literal["application/json"]
    bytes: int


class PlaybackRobotOut(OutputModel):
    model: str = Field(description="The robot's model: panda.")
    base_position: list[float] = Field(description="Where its base stands: x, y, z in metres.")


class PlaybackSegmentOut(OutputModel):
    """The points ``first``..``last`` of the commands: one motion of one step (an action of an episode)."""

    step: int
    kind: str = Field(description="transit, grasp, carry, approach, screw, push, ignite, release, retreat.")
    gripper: Literal["open", "closed"]
    first: int
    last: int


class PlaybackCommandsOut(OutputModel):
    """The motor commands by column: point k is ``times[k]``, ``positions[k]``, ``gripper_widths[k]``."""

    robot: str
    joints: list[str]
    gripper_joints: list[str]
    times: list[float] = Field(description="Seconds from the start.")
    positions: list[list[float]] = Field(description="Joint angles (radians), one list a point.")
    gripper_widths: list[float] = Field(description="Metres between the fingers.")
    segments: list[PlaybackSegmentOut]


class PlaybackShapeOut(OutputModel):
    """A part's shape in the part's frame, as the catalog gives it."""

    kind: str = Field(description="box, cylinder or sphere.")
    size: list[float]
    position: list[float]
    rotation: list[float] = Field(description="Roll, pitch, yaw (radians).")
    color: list[float] = Field(description="Red, green, blue, alpha in 0..1.")


class PlaybackTrackOut(OutputModel):
    times: list[float]
    poses: list[list[float]] = Field(description="x, y, z (metres, z up), qx, qy, qz, qw.")


class PlaybackPartOut(OutputModel):
    id: str = Field(description="The part's id; a spare's is `PART:spare`.")
    name: str
    shapes: list[PlaybackShapeOut]
    light: list[PlaybackShapeOut] = Field(description="What shows when the object gives its goal.")
    track: PlaybackTrackOut


class PlaybackActionOut(OutputModel):
    """One action of the episode, with when it plays in the commands."""

    number: int
    action: Literal["test", "inspect", "detach", "attach", "replace"]
    part: str | None
    observed: Literal["goal", "no goal", "broken", "works"] | None = Field(
        description="A test's outcome in physics; an inspection's in the episode; null otherwise."
    )
    passed: bool = Field(description="False: the robot could not do it, and the run stops there.")
    message: str
    start: float = Field(description="Seconds from the start; an action without motion starts where the last ended.")
    end: float


class EpisodePlaybackOut(OutputModel):
    """The 3D player's document of the robot's troubleshooting episode (``causalplan-playback/2``)."""

    format: Literal["causalplan-playback/2"]
    object: str
    name: str
    seconds: float = Field(description="How long the motor commands take.")
    robot: PlaybackRobotOut
    trajectory: PlaybackCommandsOut
    parts: list[PlaybackPartOut]
    assembled: dict[str, list[float]] = Field(description="Where each body is at the end: x, y, z, qx, qy, qz, qw.")
    actions: list[PlaybackActionOut]
