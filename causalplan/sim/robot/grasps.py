"""Where the robot holds a part: from the catalog, or from the part's geometry; and whether it holds it.

A part without a catalog grasp is held from above: the fingertips' middle ``GRASP_DEPTH``
below its top (but the fingertips above the table), the fingers closing across its
narrower side. A part too wide for the open gripper needs a catalog grasp.
"""

from __future__ import annotations

from causalplan.objects.model import Grasp, Part, Vector
from causalplan.sim.geometry import Solid
from causalplan.sim.poses import Pose, about_axis, angle_between, cross, multiply, rotate, shortest_arc
from causalplan.sim.robot.panda import FINGER_BELOW_TARGET, FINGER_GAP_OPEN, FINGER_JOINTS
from causalplan.sim.scene import Scene

GRASP_DEPTH = 0.01
"""How far below a part's top the fingertips' middle holds it, by default."""
FINGER_REACH = 0.005
"""Metres a closed finger may be from the part and still hold it."""


def _arrange(approach: Vector, fingers: Vector) -> Pose:
    """Return the orientation that points the gripper along ``approach`` with fingers closing along ``fingers``."""
    turn = shortest_arc((0.0, 0.0, 1.0), approach)
    current = rotate(turn, (0.0, 1.0, 0.0))
    angle = angle_between(current, fingers)
    if sum(a * b for a, b in zip(cross(current, fingers), approach, strict=True)) < 0:
        angle = -angle
    return Pose(orientation=multiply(about_axis(approach, angle), turn))


def grasp_of(part: Part, solid: Solid) -> tuple[Pose, float] | str:
    """Return the gripper's pose in the part's frame and its closed finger gap, or why the part cannot be held."""
    if part.grasp is not None:
        grasp: Grasp = part.grasp
        width = grasp.width
        if width is None:
            index = max(range(3), key=lambda i: abs(grasp.fingers[i]))
            width = solid.upper[index] - solid.lower[index]
        if width > FINGER_GAP_OPEN:
            return f"its grasp is {width * 1000:.0f} mm across; the gripper opens {FINGER_GAP_OPEN * 1000:.0f} mm"
        return Pose(grasp.position, _arrange(grasp.approach, grasp.fingers).orientation), width
    (x0, y0, z0), (x1, y1, z1) = solid.lower, solid.upper
    along_y = (y1 - y0) <= (x1 - x0)
    width = (y1 - y0) if along_y else (x1 - x0)
    if width > FINGER_GAP_OPEN:
        return (
            f"it is {width * 1000:.0f} mm across at its narrowest and the gripper opens "
            f"{FINGER_GAP_OPEN * 1000:.0f} mm; give it a grasp in the catalog"
        )
    height = max(z1 - GRASP_DEPTH, z0 + FINGER_BELOW_TARGET + 0.001)
    fingers = (0.0, 1.0, 0.0) if along_y else (1.0, 0.0, 0.0)
    orientation = _arrange((0.0, 0.0, -1.0), fingers).orientation
    return Pose(((x0 + x1) / 2, (y0 + y1) / 2, height), orientation), width


def finger_gap(scene: Scene, robot: int, part_id: str) -> float:
    """Return how far (metres) the farther of the two fingers is from the part (0 when both touch it)."""
    pb, client = scene.pb, scene.client
    gaps = []
    for finger in FINGER_JOINTS:
        points = pb.getClosestPoints(robot, scene.bodies[part_id], 0.1, linkIndexA=finger, physicsClientId=client)
        gaps.append(max(0.0, min((point[8] for point in points), default=0.1)))
    return max(gaps)
