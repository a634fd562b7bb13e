"""The optional robot arm: the Franka Panda from ``pybullet_data``, reaching grasp poses by inverse kinematics.

The arm does not carry the parts (the parts move on their own along their approach); it
answers, for every step, whether a real arm standing beside the table could put its gripper
where the part is grasped, at the start of the approach and at the seat. It never collides
with anything, so it cannot change the outcome of the other checks.
"""

from __future__ import annotations

import math

from causalplan.objects.model import Vector
from causalplan.sim.checks import REACH_TOLERANCE_MM
from causalplan.sim.geometry import corners
from causalplan.sim.poses import Pose, about_axis
from causalplan.sim.report import Reach
from causalplan.sim.robot.panda import ARM_JOINTS, GRASP_LINK, HOME, Panda
from causalplan.sim.scene import Scene

TOP_GRASP = about_axis((1.0, 0.0, 0.0), math.pi)
"""Gripper pointing straight down."""


class Arm:
    """The robot's Panda in a scene, used for reachability only."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.panda = Panda(scene)

    def go_home(self) -> None:
        """Put the arm in its resting pose."""
        self.panda.set(HOME)

    def reach(self, target: Vector) -> float:
        """Move the gripper as close as it gets to ``target`` (pointing down); return the miss in mm."""
        pb, client = self.scene.pb, self.scene.client
        self.go_home()
        angles = pb.calculateInverseKinematics(
            self.panda.body,
            GRASP_LINK,
            target,
            TOP_GRASP,
            maxNumIterations=200,
            residualThreshold=1e-5,
            physicsClientId=client,
        )
        self.panda.set(angles[: len(ARM_JOINTS)])
        return math.dist(self.panda.gripper_pose().position, target) * 1000


def grasp_point(scene: Scene, part_id: str, pose: Pose) -> Vector:
    """Return where the gripper holds a part at ``pose``: the middle of the part's top."""
    solid = scene.solids[part_id]
    placed = [pose.apply(corner) for corner in corners((solid.lower, solid.upper))]
    return (
        sum(corner[0] for corner in placed) / len(placed),
        sum(corner[1] for corner in placed) / len(placed),
        max(corner[2] for corner in placed),
    )


def reach_step(arm: Arm, scene: Scene, part_id: str, poses: tuple[Pose, ...]) -> Reach:
    """Return whether the arm reaches the part's grasp point at each pose (it stays at the last)."""
    misses = [arm.reach(grasp_point(scene, part_id, pose)) for pose in poses]
    worst = max(misses)
    return Reach(worst <= REACH_TOLERANCE_MM, worst)
