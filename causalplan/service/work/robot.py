"""What a worker process runs for the robot: carry out a plan for the 3D player, film it, film a model's plan.

Filming is slow, so a film writes its progress (frames drawn, frames expected) to a small JSON
file that the app reads while the worker works: the worker's socket carries only the work and
its answer. Functions take typed arguments and the worker's catalog, as ``planning``'s do.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject

if TYPE_CHECKING:
    from causalplan.planners.result import PlanStep
    from causalplan.sim import SimulationReport, StepRequest

FORMATS = {"mp4": ".mp4", "gif": ".gif"}
"""Video formats a request may ask for, by name, and the file suffix each is written with."""
CONTENT_TYPES = {"mp4": "video/mp4", "gif": "image/gif"}


@dataclass(frozen=True)
class PlaybackArguments:
    """The robot making ``fit_ids`` of the object, for the browser's player (no film)."""

    object_id: str
    fit_ids: tuple[str, ...]


@dataclass(frozen=True)
class FitsFilmArguments:
    """A film of the robot making ``fit_ids`` of the object; its progress goes to ``progress``."""

    object_id: str
    fit_ids: tuple[str, ...]
    video: str
    size: tuple[int, int]
    progress: Path | None


@dataclass(frozen=True)
class PlanFilmArguments:
    """A plan of ``model`` (on the mapping's object), then a film of the robot carrying it out."""

    model: CausalModel
    mapping: Labelling | None
    planner: str
    time_limit: float
    val: bool
    video: str
    size: tuple[int, int]
    progress: Path


def write_progress(path: Path | None, frames: int, expected: int | None) -> None:
    """Write the film's progress to ``path`` whole (a reader never sees half a file)."""
    if path is None:
        return
    draft = path.with_suffix(".part")
    draft.write_text(json.dumps({"frames": frames, "expected": expected}), encoding="utf-8")
    os.replace(draft, path)


def read_progress(path: Path) -> tuple[int, int | None]:
    """Return (frames drawn, frames expected) from a progress file; (0, None) before the first write."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return 0, None
    expected = data.get("expected")
    return int(data.get("frames", 0)), int(expected) if isinstance(expected, int) else None


def frames_expected(report: SimulationReport) -> int:
    """Return how many frames filming the run of ``report`` draws while the robot moves.

    The recorder draws one frame every ``FRAME_EVERY`` commanded positions, and the run is
    deterministic, so the run without a film (far cheaper than filming) says it.
    """
    from causalplan.sim.video import FRAME_EVERY

    positions = report.trajectory.positions if report.trajectory else 0
    return max(1, math.ceil(positions / FRAME_EVERY))


def steps_of(obj: AssemblyObject, fit_ids: Sequence[str]) -> list[StepRequest]:
    """Return the plan steps that make the fits ``fit_ids`` of ``obj``, in order."""
    from causalplan.sim import StepRequest

    return [StepRequest(fit.primitive, fit.moving_part, fit.fixed_part, fit.id) for fit in map(obj.fit, fit_ids)]


def robot_simulation(
    obj: AssemblyObject,
    steps: Sequence[StepRequest | PlanStep],
    video: str | None,
    size: tuple[int, int],
    progress: Path | None = None,
) -> tuple[SimulationReport, bytes | None]:
    """Return the robot's run of ``steps`` on ``obj`` and, when ``video`` names a format, its film.

    Without a film the run comes from the robot's cache (``robot_verdict.robot_run``). Filming
    writes its progress to ``progress``; a cancelled film's worker is killed by the app.
    """
    from causalplan.sim import RenderMode, simulate_plan
    from causalplan.sim.video import encode
    from causalplan.transfer.robot_verdict import robot_run

    report = robot_run(obj, tuple(steps))
    if video is None:
        return report, None
    expected = frames_expected(report)
    write_progress(progress, 0, expected)

    def on_frame(frames: int) -> None:
        write_progress(progress, min(frames, expected), expected)

    filmed = simulate_plan(
        obj, steps, render=RenderMode.NONE, robot=True, video=True, video_size=size, on_frame=on_frame
    )
    return filmed, encode(filmed.video, FORMATS[video])


def robot_outcome(report: SimulationReport) -> dict[str, object]:
    """Return whether the robot carried out the plan and, when not, why: the ``robot_cannot_execute`` reason."""
    from causalplan.transfer.robot_verdict import robot_reason

    reason = robot_reason(report)
    if reason is None:
        return {"carried_out": True, "reason": None}
    failed, motors = report.failed_step, report.motors
    step, failure = (failed.number, failed.failure) if failed is not None else (None, None)
    if failed is None and motors is not None:  # the steps passed; the motors did not
        step, failure = motors.step, motors.failure
    return {
        "carried_out": False,
        "reason": {
            "code": reason.code,
            "message": reason.message,
            "step": step,
            "failure": failure.value if failure is not None else None,
        },
    }


def film_of_fits(arguments: FitsFilmArguments, catalog: Catalog) -> dict[str, object]:
    """Film the robot making the fits; return ``{"video": bytes, "simulation": ..., "robot": robot_outcome}``."""
    obj = catalog.get(arguments.object_id)
    steps = steps_of(obj, arguments.fit_ids)
    report, film = robot_simulation(obj, steps, arguments.video, arguments.size, arguments.progress)
    return {"video": film, "simulation": report.as_dict(), "robot": robot_outcome(report)}


def film_of_plan(arguments: PlanFilmArguments, catalog: Catalog) -> dict[str, object]:
    """Plan the model and film the robot carrying the plan out.

    Returns ``planning`` (as ``causalplan plan --json``), ``simulation`` and ``robot`` (as POST
    /v1/simulations with ``robot``) and ``video``: the film's bytes, or None when there is no plan.
    """
    from causalplan.pddl.task import catalog_task
    from causalplan.planners import pipeline

    task = catalog_task(arguments.model, catalog, arguments.mapping)
    result = pipeline.plan_task(task, arguments.planner, arguments.time_limit, val=arguments.val)
    data: dict[str, object] = {"planning": result.as_dict(), "simulation": None, "robot": None, "video": None}
    if not result.has_plan:
        return data
    report, film = robot_simulation(task.obj, result.steps, arguments.video, arguments.size, arguments.progress)
    data.update(simulation=report.as_dict(), robot=robot_outcome(report), video=film)
    return data


def playback(arguments: PlaybackArguments, catalog: Catalog) -> bytes:
    """Return the browser player's document of the robot making the fits, as JSON.

    ``sim.robot.playback``'s document plus ``"outcome"``: whether the robot carried out the plan,
    or why not. The run records the parts' tracks as it goes (one scene, not a second for a
    replay). Encoded here: the app passes the bytes on, unlike a dict of thousands of lists.
    """
    from causalplan.sim import RenderMode, simulate_plan
    from causalplan.sim.robot.playback import playback as player_document

    obj = catalog.get(arguments.object_id)
    steps = steps_of(obj, arguments.fit_ids)
    report = simulate_plan(obj, steps, render=RenderMode.NONE, robot=True, tracks=True)
    document = {**player_document(obj, steps, report), "outcome": robot_outcome(report)}
    return json.dumps(document, separators=(",", ":")).encode()
