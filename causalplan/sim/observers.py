"""What watches a simulation go: ``Observer``s hear of each step and of the end, and draw what they see.

``Pictures`` draws stills (the final assembly, or one per step); ``sim.video.VideoRecorder``
films the robot (it also hears every commanded position, from the robot's mover). Neither
changes what is simulated.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from causalplan.sim.render import Camera, draw
from causalplan.sim.report import Picture, RenderMode, StepReport
from causalplan.sim.scene import Scene


class Observer(Protocol):
    """Hears of a simulation's steps and its end."""

    def step_started(self, number: int, total: int, text: str) -> None:
        """Step ``number`` of ``total`` (``text`` says what it does) begins."""

    def step_ended(self, report: StepReport, total: int, lit: Callable[[], tuple[str, ...]]) -> None:
        """A step ended as ``report`` says; ``lit()`` returns the parts whose light shows now."""

    def finished(self, title: str, lit: tuple[str, ...], produces_goal: bool, goal: str) -> None:
        """The assembly settled and was judged: it produces ``goal`` or not, with ``lit`` parts lit."""


@dataclass
class Pictures:
    """Stills of a simulation: the parts first and one after each step (``FRAMES``), and the final assembly."""

    scene: Scene
    camera: Camera
    mode: RenderMode
    title: str
    frames: list[Picture] = field(default_factory=list)
    picture: Picture | None = None
    seconds: float = 0.0
    """Time spent drawing the final picture."""

    def __post_init__(self) -> None:
        if self.mode is RenderMode.FRAMES:
            self.frames.append(draw(self.scene, self.camera, (), f"{self.title}: the parts"))

    def step_started(self, number: int, total: int, text: str) -> None:
        return None

    def step_ended(self, report: StepReport, total: int, lit: Callable[[], tuple[str, ...]]) -> None:
        if self.mode is RenderMode.FRAMES:
            caption = f"{report.number}/{total} {report.text} {report.status.value}"
            self.frames.append(draw(self.scene, self.camera, lit(), caption))

    def finished(self, title: str, lit: tuple[str, ...], produces_goal: bool, goal: str) -> None:
        started = time.perf_counter()
        verdict = f"produces {goal}" if produces_goal else f"no {goal}"
        self.picture = draw(self.scene, self.camera, lit, f"{title}: {verdict}")
        if self.mode is RenderMode.FRAMES:
            self.frames.append(self.picture)
        self.seconds = time.perf_counter() - started
