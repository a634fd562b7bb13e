"""The scene a troubleshooting episode starts in: the broken object built, its spares waiting on the table.

The robot's run of an episode (``sim.robot_episode``) and the same run driven by the Panda's
motors (``sim.robot_episode_motors``) each start from this scene, built the same way, so the
motors play their commands on the world the commands were planned in.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace

from causalplan.objects.model import AssemblyObject
from causalplan.sim import checks
from causalplan.sim.executor import SimulationRun, execute_step, settle
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.layout import ROBOT_ROW_GAP, layout
from causalplan.sim.motions import MOTIONS
from causalplan.sim.movers import PartsMoveThemselves
from causalplan.sim.outcomes import StepStatus
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose
from causalplan.sim.robot.grasps import grasp_of
from causalplan.sim.scene import Scene
from causalplan.sim.spares import ASIDE, SPARE, spare_homes
from causalplan.sim.troubleshooting import first_build_order, rebuild_steps
from causalplan.troubleshoot.episode import Episode
from causalplan.troubleshoot.solver import REPLACE


@dataclass(frozen=True)
class EpisodeStage:
    """Where everything starts: every part and spare's place on the table, and how the object is built."""

    parts: dict[str, Solid]
    """Each part's solid, and each spare's (by its ``:spare`` id)."""
    homes: dict[str, Pose]
    build: tuple[StepRequest, ...]
    """The steps that build the object before the episode (parts move themselves)."""
    base_aside: Pose | None
    """The free place where a broken base the gripper can hold is set down, when the episode replaces it."""


def episode_stage(obj: AssemblyObject, episode: Episode) -> EpisodeStage:
    """Return where the object's parts and the spares of the parts ``episode`` replaces start."""
    build = [step for step in rebuild_steps(obj, first_build_order(obj)) if not MOTIONS[step.action].touches_only]
    spares = sorted({step.part for step in episode.steps if step.kind == REPLACE and step.part is not None})
    parts: dict[str, Solid] = dict(solids(obj))  # a copy: solids() is cached
    homes, _design = layout(obj, parts, tuple(build), ROBOT_ROW_GAP)
    # The robot carries a base it can hold; one wider than the gripper opens is swapped without it.
    carried = obj.base in spares and not isinstance(grasp_of(obj.part(obj.base), parts[obj.base]), str)
    places = spare_homes(obj, parts, homes, spares, carried)
    aside = places.pop(obj.base + ASIDE, None)
    homes.update(places)
    parts.update({part + SPARE: parts[part] for part in spares})
    return EpisodeStage(parts, homes, tuple(build), aside)


@contextmanager
def built_object(obj: AssemblyObject, stage: EpisodeStage) -> Iterator[SimulationRun]:
    """Yield a run whose scene has the object built (its joints before every action) and the spares on the table.

    Raises RuntimeError when the object cannot be built in physics.
    """
    with Scene(stage.parts, drawn=False) as scene:
        for part, pose in stage.homes.items():
            scene.add_part(part, pose, dynamic=part == obj.base)
        run = SimulationRun(obj, scene, dict(stage.homes), {obj.base}, PartsMoveThemselves(scene))
        for number, request in enumerate(stage.build, start=1):
            report = execute_step(run, number, request)
            if report.status is not StepStatus.PASSED:
                raise RuntimeError(f"the {obj.name} cannot be built in physics: {report.message}")
        settle(run, checks.FINAL_SETTLE_SECONDS)
        # The object was handed over built: its joints come before every action of the episode
        # (the mechanism checks that a light comes after what it must follow by step number).
        run.joints[:] = [replace(joint, step=0) for joint in run.joints]
        run.attached_at = dict.fromkeys(run.attached_at, 0)
        yield run
