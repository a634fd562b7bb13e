"""The optional robot arm: the Franka Panda from ``pybullet_data``, reaching grasp poses by inverse kinematics.

The arm does not carry the parts (the parts move on their own along their approach); it
answers, for every step, whether a real arm standing beside the table could put its gripper
where the part is grasped, at the start of the approach and at the seat. It never collides
with anything, so it cannot change the outcome of the other checks.
"""

from __future__ import annotations

import importlib
import math

from causalplan.objects.model import Vector
from causalplan.sim.checks import REACH_TOLERANCE_MM
from causalplan.sim.geometry import corners
from causalplan.sim.poses import Pose, about_axis
from causalplan.sim.report import Reach
from causalplan.sim.scene import Scene, SimulatorUnavailableError

PANDA_FILE = "franka_panda/panda.urdf"
GRASP_LINK = 11
"""The Panda's ``panda_grasptarget`` link, between the fingertips."""
ARM_JOINTS = tuple(range(7))
FINGER_JOINTS = (9, 10)
HOME_ANGLES = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
ARM_BASE: Vector = (-0.55, 0.0, 0.0)
"""Where the arm stands, beside the object (which stands at the origin)."""
TOP_GRASP = about_axis((1.0, 0.0, 0.0), math.pi)
"""Gripper pointing straight down."""


class Arm:
    """A Panda arm in a scene, used for reachability only."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        pb = scene.pb
        try:
            data = importlib.import_module("pybullet_data")
        except ImportError as exc:
            raise SimulatorUnavailableError(f"The robot arm needs pybullet_data ({exc}).") from None
        pb.setAdditionalSearchPath(data.getDataPath(), physicsClientId=scene.client)
        self.body: int = pb.loadURDF(PANDA_FILE, ARM_BASE, useFixedBase=True, physicsClientId=scene.client)
        for link in range(-1, pb.getNumJoints(self.body, physicsClientId=scene.client)):
            pb.setCollisionFilterGroupMask(self.body, link, 0, 0, physicsClientId=scene.client)
        self.go_home()

    def _set(self, angles: tuple[float, ...] | list[float]) -> None:
        for joint, angle in zip(ARM_JOINTS, angles, strict=False):
            self.scene.pb.resetJointState(self.body, joint, angle, physicsClientId=self.scene.client)
        for joint in FINGER_JOINTS:
            self.scene.pb.resetJointState(self.body, joint, 0.04, physicsClientId=self.scene.client)

    def go_home(self) -> None:
        """Put the arm in its resting pose."""
        self._set(HOME_ANGLES)

    def reach(self, target: Vector) -> float:
        """Move the gripper as close as it gets to ``target`` (pointing down); return the miss in mm."""
        pb, client = self.scene.pb, self.scene.client
        self.go_home()
        angles = pb.calculateInverseKinematics(
            self.body,
            GRASP_LINK,
            target,
            TOP_GRASP,
            maxNumIterations=200,
            residualThreshold=1e-5,
            physicsClientId=client,
        )
        self._set(list(angles)[: len(ARM_JOINTS)])
        reached = pb.getLinkState(self.body, GRASP_LINK, computeForwardKinematics=True, physicsClientId=client)[4]
        return math.dist(reached, target) * 1000


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
