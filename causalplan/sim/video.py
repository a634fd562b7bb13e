"""A film of the robot at work: frames drawn while it moves, written as MP4 (imageio + ffmpeg) or GIF.

``VideoRecorder`` is an observer of the simulation (``sim.observers``): it captions the
frames with the step being done. Its ``observe`` is called after every commanded position
and draws one frame in ``FRAME_EVERY``; ``finish`` adds the finished object, lit when it
produces its goal, held for a moment. ``encode`` writes the frames with imageio: MP4 through the ffmpeg binary that
``imageio-ffmpeg`` ships, or an animated GIF.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from causalplan.errors import CausalPlanError
from causalplan.sim.geometry import Box
from causalplan.sim.render import Camera, draw
from causalplan.sim.report import Picture, StepReport
from causalplan.sim.robot.trajectory import RATE_HZ
from causalplan.sim.scene import Scene

VIDEO_SIZE = (480, 360)
FRAME_EVERY = 5
"""Commanded positions per frame: at 50 commands a second, 10 frames a second."""
FRAMES_PER_SECOND = RATE_HZ // FRAME_EVERY
HOLD_SECONDS = 2.0
"""How long the finished object stays on screen at the end."""
ROBOT_BOX: Box = ((-0.45, -0.1, 0.0), (-0.3, 0.1, 0.45))
"""Part of the arm the camera shows too (its upper reaches may leave the picture)."""
VIDEO_FORMATS = (".mp4", ".gif")


class VideoError(CausalPlanError):
    """A video cannot be written in the format asked for."""

    code = "invalid_video_format"


@dataclass
class VideoRecorder:
    """Draws frames of a scene while the robot moves."""

    scene: Scene
    design: Box
    title: str
    size: tuple[int, int] = VIDEO_SIZE
    on_frame: Callable[[int], None] | None = None
    """Called with the number of frames drawn so far, after each (a progress display)."""
    frames: list[Picture] = field(default_factory=list)
    count: int = 0
    caption: str = ""
    """What the frames say at the top now (the step being done); the title when empty."""

    def __post_init__(self) -> None:
        table = self.scene.bounds(self.scene.bodies)
        lower = tuple(min(a, b, c) for a, b, c in zip(self.design[0], table[0], ROBOT_BOX[0], strict=True))
        upper = tuple(max(a, b, c) for a, b, c in zip(self.design[1], table[1], ROBOT_BOX[1], strict=True))
        self.camera = Camera.around(self.scene, lower, upper, size=self.size)  # type: ignore[arg-type]

    def observe(self) -> None:
        """Draw a frame when it is time for one."""
        if self.count % FRAME_EVERY == 0:
            self.frames.append(draw(self.scene, self.camera, (), self.caption or self.title))
            if self.on_frame is not None:
                self.on_frame(len(self.frames))
        self.count += 1

    def step_started(self, number: int, total: int, text: str) -> None:
        """Caption the frames with the step being done."""
        self.caption = f"{number}/{total} {text}"

    def step_ended(self, report: StepReport, total: int, lit: Callable[[], tuple[str, ...]]) -> None:
        return None

    def finished(self, title: str, lit: tuple[str, ...], produces_goal: bool, goal: str) -> None:
        """End the film on the finished object."""
        self.finish(lit, f"{title}: " + ("light" if produces_goal else "no goal"))

    def finish(self, lit_parts: Sequence[str], caption: str) -> None:
        """Add the finished object (lit when it produces its goal), held for ``HOLD_SECONDS``."""
        final = draw(self.scene, self.camera, lit_parts, caption)
        self.frames.extend([final] * round(HOLD_SECONDS * FRAMES_PER_SECOND))


def encode(frames: Sequence[Picture], suffix: str) -> bytes:
    """Return the frames as a video file's bytes: ``suffix`` ".mp4" (H.264) or ".gif"."""
    import imageio.v3 as iio
    import numpy as np

    suffix = suffix.lower()
    if suffix not in VIDEO_FORMATS:
        raise VideoError(f"A video is written as {' or '.join(VIDEO_FORMATS)}, not '{suffix}'.")
    if not frames:
        raise VideoError("There are no frames to write: the robot did not move.")
    stack = np.stack([np.frombuffer(f.rgb, dtype=np.uint8).reshape(f.height, f.width, 3) for f in frames])
    if suffix == ".gif":
        data: bytes = iio.imwrite("<bytes>", stack, extension=".gif", duration=1000 // FRAMES_PER_SECOND, loop=0)
        return data
    video: bytes = iio.imwrite(
        "<bytes>", stack, extension=".mp4", fps=FRAMES_PER_SECOND, codec="libx264", macro_block_size=8
    )
    return video
