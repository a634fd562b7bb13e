"""The Franka Panda from ``pybullet_data`` as the robot that builds the object: joints, IK, collisions.

The arm is kinematic: its joints are set, not driven by motors, so the physics of the
assembly (welds, settling) runs exactly as without it, and every motion repeats exactly.
It never pushes anything in PyBullet's physics (its collision filter is off); whether it
touches what it must not is measured with ``getClosestPoints``, which ignores that filter.
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from causalplan.objects.model import Vector
from causalplan.sim.poses import Pose, difference
from causalplan.sim.robot.limits import PANDA, POSITION_MARGIN
from causalplan.sim.scene import Scene, SimulatorUnavailableError

PANDA_FILE = "franka_panda/panda.urdf"
ROBOT_NAME = "franka_panda"
JOINT_NAMES = PANDA.joints
ARM_JOINTS = tuple(range(7))
FINGER_JOINTS = (9, 10)
BASE_LINKS = frozenset({-1, 0})
"""The links that stand on the table."""
GRASP_LINK = 11
"""``panda_grasptarget``, between the fingertips."""
FINGER_OPEN = 0.04
"""Metres each finger opens: the fingers then leave a gap of about 72 mm."""
FINGER_GAP_OPEN = 0.072
FINGER_BELOW_TARGET = 0.0115
"""How far the fingertips reach below the grasp target (metres)."""
HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
BASE_POSITION: Vector = (-0.55, 0.0, 0.0)
"""Where the arm stands, beside the object (which stands at the origin)."""
IK_POSITION_TOLERANCE = 0.0005
IK_ANGLE_TOLERANCE = math.radians(0.5)
IK_ROUNDS = 40
NEAR_LIMIT = 0.1
"""Radians from a joint's limit within which the IK's second try holds that joint nearly still."""
STIFF_DAMPING = 100.0
"""The IK's damping of a joint at its limit on the second try (PyBullet's default is 0.1)."""

Configuration = tuple[float, ...]
"""The seven arm joint angles, in radians."""


@dataclass(frozen=True)
class Contact:
    """The deepest touch between the robot (or what it holds) and another body."""

    robot_part: str
    other: str
    depth: float  # metres


class Panda:
    """A kinematic Franka Panda standing beside the table of a scene."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        pb, client = scene.pb, scene.client
        try:
            data = importlib.import_module("pybullet_data")
        except ImportError as exc:
            raise SimulatorUnavailableError(f"The robot needs pybullet_data ({exc}).") from None
        pb.setAdditionalSearchPath(data.getDataPath(), physicsClientId=client)
        self.body: int = pb.loadURDF(PANDA_FILE, BASE_POSITION, useFixedBase=True, physicsClientId=client)
        self.links = tuple(range(-1, pb.getNumJoints(self.body, physicsClientId=client)))
        for link in self.links:
            pb.setCollisionFilterGroupMask(self.body, link, 0, 0, physicsClientId=client)
        # The datasheet's position limits, not the URDF's (which are wider), for OMPL's bounds and the IK's.
        self.lower = tuple(low + POSITION_MARGIN for low in PANDA.position_min)
        self.upper = tuple(high - POSITION_MARGIN for high in PANDA.position_max)
        self.fingers = FINGER_OPEN
        self.ik_seconds = 0.0
        """Time spent in inverse kinematics so far (the benchmark's breakdown)."""
        self.configuration: Configuration = HOME
        self.set(HOME)

    def set(self, configuration: Sequence[float], fingers: float | None = None) -> None:
        """Put the arm at ``configuration`` (and the fingers at ``fingers`` metres each, if given)."""
        pb, client = self.scene.pb, self.scene.client
        for joint, angle in zip(ARM_JOINTS, configuration, strict=True):
            pb.resetJointState(self.body, joint, angle, physicsClientId=client)
        if fingers is not None:
            self.fingers = fingers
        for joint in FINGER_JOINTS:
            pb.resetJointState(self.body, joint, self.fingers, physicsClientId=client)
        self.configuration = tuple(float(angle) for angle in configuration)

    def within_limits(self, configuration: Sequence[float]) -> bool:
        return all(low <= angle <= high for angle, low, high in zip(configuration, self.lower, self.upper, strict=True))

    def limit_margin(self, configuration: Sequence[float]) -> float:
        """Return how close ``configuration`` comes to a joint limit, as a fraction of that joint's range."""
        return min(
            float(min(angle - low, high - angle) / (high - low))
            for angle, low, high in zip(configuration, self.lower, self.upper, strict=True)
        )

    def gripper_pose(self) -> Pose:
        """Return the grasp target's pose in the world, at the current configuration."""
        state = self.scene.pb.getLinkState(
            self.body, GRASP_LINK, computeForwardKinematics=True, physicsClientId=self.scene.client
        )
        return Pose(tuple(state[4]), tuple(state[5]))

    def solve(self, target: Pose, seed: Sequence[float], hold: Sequence[int] = ()) -> Configuration | None:
        """Return joint angles that put the grasp target at ``target``, starting from ``seed``; None when none.

        ``hold``: the joints (indices) that, when the first answer leaves the limits, are held
        nearly still on a second try if they are near a limit (backing away needs no joint at
        its limit; a screw's turn should go to the wrist rather than drift the shoulder there).

        PyBullet's damped least squares runs from the current joints, so it is run in rounds
        from its own last answer until the pose is met within a fraction of a millimetre. The
        arm is left at ``seed`` either way.
        """
        started = time.perf_counter()
        answer = self._solve(target, seed)
        if hold and (answer is None or not self.within_limits(answer)):
            # PyBullet's IK lets a joint at its limit drift past it: try again with it held.
            answer = self._solve(target, seed, hold)
        self.ik_seconds += time.perf_counter() - started
        if answer is None or not self.within_limits(answer):
            return None
        return answer

    def _solve(self, target: Pose, seed: Sequence[float], hold: Sequence[int] = ()) -> Configuration | None:
        """Return IK's answer for ``target`` from ``seed`` if it converges (``hold``: those near a limit damped)."""
        pb, client = self.scene.pb, self.scene.client
        self.set(seed)
        limits: dict[str, object]
        if hold:
            near = [
                joint in hold and min(angle - low, high - angle) < NEAR_LIMIT
                for joint, (angle, low, high) in enumerate(zip(seed, self.lower, self.upper, strict=True))
            ]
            if not any(near):
                return None
            damping = [STIFF_DAMPING if is_near else 0.1 for is_near in near] + [0.1] * len(FINGER_JOINTS)
            limits = {"jointDamping": damping}
        else:
            ranges = [high - low for low, high in zip(self.lower, self.upper, strict=True)]
            limits = {"lowerLimits": list(self.lower), "upperLimits": list(self.upper), "jointRanges": ranges}
        answer: Configuration | None = None
        for _ in range(IK_ROUNDS):
            rest = {} if hold else {"restPoses": list(self.configuration)}
            angles = pb.calculateInverseKinematics(
                self.body,
                GRASP_LINK,
                target.position,
                target.orientation,
                **limits,
                **rest,
                maxNumIterations=100,
                residualThreshold=1e-6,
                physicsClientId=client,
            )
            self.set(tuple(angles[: len(ARM_JOINTS)]))
            moved, turned = difference(self.gripper_pose(), target)
            if moved <= IK_POSITION_TOLERANCE and turned <= IK_ANGLE_TOLERANCE:
                answer = self.configuration
                break
        self.set(seed)
        return answer

    def deepest_contact(
        self, others: Iterable[int], ignore: frozenset[tuple[int, int]] = frozenset()
    ) -> Contact | None:
        """Return the deepest overlap between the arm's links and ``others`` (``ignore``: (link, body) pairs)."""
        pb, client = self.scene.pb, self.scene.client
        deepest: Contact | None = None
        for other in others:
            for point in pb.getClosestPoints(self.body, other, 0.0, physicsClientId=client):
                link, depth = point[3], -point[8]
                if (link, other) in ignore or (link in BASE_LINKS and other == self.scene.ground):
                    continue
                if deepest is None or depth > deepest.depth:
                    name = pb.getJointInfo(self.body, max(link, 0), physicsClientId=client)[12].decode()
                    deepest = Contact(name if link >= 0 else "panda_link0", self.scene.names.get(other, "?"), depth)
        return deepest
