"""Replay a robot trajectory file in a fresh scene: the motor commands' joint positions alone rebuild the assembly.

Nothing of the original run is used but the object, the plan (which lays the parts out on
the table) and the motor commands: when the gripper closes, the part between its fingers
rides along; when it opens, the part stays where it is. The poses where parts were let go
are what the replay returns, to compare with the run's ``SimulationReport.placed``; every
part's pose over time (``part_tracks``) is what the run itself records for the browser's
player (``sim.robot.tracks``), rebuilt here from the file alone.
"""

from __future__ import annotations

from collections.abc import Sequence

from causalplan.objects.model import AssemblyObject
from causalplan.planners.result import PlanStep
from causalplan.sim.layout import ROBOT_ROW_GAP, laid_out_scene
from causalplan.sim.plan_steps import StepRequest, check_steps
from causalplan.sim.poses import Pose
from causalplan.sim.robot.panda import FINGER_JOINTS, FINGER_OPEN, Panda
from causalplan.sim.robot.tracks import Keyframes, PartTrack, carried_indexes
from causalplan.sim.robot.trajectory import Trajectory
from causalplan.sim.scene import Scene

GRASP_REACH = 0.02
"""Metres from each finger within which a part counts as between the fingers."""


def _part_between_fingers(scene: Scene, panda: Panda) -> str | None:
    """Return the part both fingers are nearest to (each within ``GRASP_REACH``), if any."""
    pb, client = scene.pb, scene.client
    nearest: tuple[float, str] | None = None
    for part, body in scene.bodies.items():
        gaps = []
        for finger in FINGER_JOINTS:
            points = pb.getClosestPoints(panda.body, body, GRASP_REACH, linkIndexA=finger, physicsClientId=client)
            gaps.append(min((point[8] for point in points), default=None))
        if None in gaps:
            continue
        total = sum(gap for gap in gaps if gap is not None)
        if nearest is None or total < nearest[0]:
            nearest = (total, part)
    return nearest[1] if nearest else None


def part_tracks(
    obj: AssemblyObject, steps: Sequence[StepRequest | PlanStep], trajectory: Trajectory
) -> dict[str, PartTrack]:
    """Return every part's track when ``trajectory`` is played in a fresh scene (parts laid out as the plan's run)."""
    with laid_out_scene(obj, check_steps(steps, obj), ROBOT_ROW_GAP, still=True) as (scene, homes, _):
        frames = Keyframes.at_rest(homes)
        panda = Panda(scene)
        held: tuple[str, Pose] | None = None
        for segment in trajectory.segments:
            first = trajectory.points[segment.first]
            panda.set(first.positions, FINGER_OPEN if segment.gripper == "open" else 0.0)
            if segment.gripper == "closed" and held is None:
                between = _part_between_fingers(scene, panda)
                if between is not None:
                    held = (between, panda.gripper_pose().inverse() * scene.pose(between))
                    frames.keep(between, first.time, scene.pose(between))
            elif segment.gripper == "open" and held is not None:
                frames.released.add(held[0])
                held = None
            if held is None:
                continue  # nothing rides along: the next segment's first point is all that matters
            part, offset = held
            for index in carried_indexes(segment.first, segment.last):
                point = trajectory.points[index]
                panda.set(point.positions)
                pose = panda.gripper_pose() * offset
                scene.place(part, pose)
                frames.keep(part, point.time, pose)
    return frames.tracks()


def replay(obj: AssemblyObject, steps: Sequence[StepRequest | PlanStep], trajectory: Trajectory) -> dict[str, Pose]:
    """Return where each part was last let go when ``trajectory`` is played in a fresh scene."""
    return {part: track.poses[-1] for part, track in part_tracks(obj, steps, trajectory).items() if track.released}
