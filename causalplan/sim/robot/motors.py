"""The robot driven by its motors: the motor commands played through PyBullet's joint motors, in physics.

The planning run (``sim.robot.robot``) moves a kinematic arm; this run checks that the
motors can follow what it wrote. In a fresh scene laid out as the plan lays it out, every
simulation step (240 a second) sends each arm joint the trajectory's position and velocity
there (position control, each joint's force capped at its datasheet torque) and each finger
the commanded width (capped at the gripper's force). A part is held by a fixed constraint
made only once both fingers touch it, whose force is capped at what the fingers' friction
can hold (a part that moved in the gripper between grasp and release slipped); when the
gripper opens the constraint goes, and the part stays where it is (welded to its mate for a
fastening primitive, resting on it for ``place``, as the simulator's own run does). The
part's collisions with the scene are off while it is held: the planning run has already
checked its path.

The run reports the tracking error (the largest joint error, and the largest distance
between the gripper and where the commands put it), how far each held part slipped in the
gripper, the first failure (``limit_violation``, ``tracking_error``, ``grasp_slipped``)
and whether the object, settled, produces its goal.

What the world does around the arm (a part joined to its mate when the gripper lets go of it,
a weld undone when a part is taken off, a spare swapped in between two motions) is the
``Effects``': ``AssemblyEffects`` for an assembly plan here, ``sim.robot_episode_motors`` for a
troubleshooting episode; the ``Driver`` and its measures are shared.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from causalplan.objects.model import AssemblyObject
from causalplan.sim import checks
from causalplan.sim.layout import ROBOT_ROW_GAP, catalog_fit, laid_out_scene, step_connectors
from causalplan.sim.mechanism import Joint, evaluate
from causalplan.sim.motions import MOTIONS
from causalplan.sim.outcomes import Failure, RequirementCheck
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose, distance
from causalplan.sim.robot.panda import ARM_JOINTS, FINGER_JOINTS, Panda
from causalplan.sim.robot.trajectory import Point, TimedSegment, Trajectory
from causalplan.sim.scene import TIME_STEP, Scene

TRACKING_TOLERANCE_RAD = 0.05
"""The largest joint error the run accepts (radians)."""
TRACKING_TOLERANCE_MM = 10.0
"""The largest gripper position error the run accepts (millimetres).

PyBullet's position-controlled motors follow their commands one simulation step behind, so
the gripper lags where the commands put it by what it travels in a step: the tolerance leaves
room for that lag at the commands' top speed, and fails an arm that does not keep up.
"""
SLIP_TOLERANCE_MM = 2.0
"""How far a held part may move in the gripper (millimetres)."""
TOUCH = 0.003
"""Metres within which a finger counts as touching a part (the arm follows a step behind its commands)."""
FRICTION = 0.8
"""Friction coefficient between the fingers and a part: the grasp holds 2 x FRICTION x the finger force."""
HAND_LINK = 8
"""``panda_hand``: the link a held part is fixed to."""
POSITION_GAIN, VELOCITY_GAIN = 1.0, 1.0
ERP = 0.8
"""How much of a held part's error its constraint corrects each simulation step."""
FK_EVERY = 4
"""Simulation steps between two measures of the gripper's error (forward kinematics of the commands)."""


@dataclass(frozen=True)
class MotorRun:
    """What happened when the motors carried out the trajectory."""

    seconds: float
    joint_error: float
    """The largest joint error (radians) over the run."""
    joint: str
    """The joint it was at."""
    gripper_error_mm: float
    slip_mm: dict[str, float]
    """For each part held, the most it had moved in the gripper when let go (millimetres)."""
    requirements: tuple[RequirementCheck, ...]
    produces_goal: bool
    failure: Failure | None = None
    step: int | None = None
    message: str = ""

    def as_dict(self) -> dict[str, object]:
        return {
            "seconds": round(self.seconds, 3),
            "tracking": {
                "max_joint_error_rad": round(self.joint_error, 5),
                "joint": self.joint,
                "max_end_effector_error_mm": round(self.gripper_error_mm, 3),
                "tolerance_rad": TRACKING_TOLERANCE_RAD,
                "tolerance_mm": TRACKING_TOLERANCE_MM,
            },
            "slip_mm": {part: round(slip, 3) for part, slip in self.slip_mm.items()},
            "slip_tolerance_mm": SLIP_TOLERANCE_MM,
            "grasp_slipped": any(slip > SLIP_TOLERANCE_MM for slip in self.slip_mm.values()),
            "failure": self.failure.value if self.failure else None,
            "step": self.step,
            "message": self.message,
            "produces_goal": self.produces_goal,
            "mechanism": [requirement.as_dict() for requirement in self.requirements],
        }


@dataclass
class _Held:
    part: str
    step: int
    constraint: int
    relative: Pose  # the part's centre of mass in the hand's frame, when grasped


class Effects(Protocol):
    """What the world does around the arm as the commands play (indices are the trajectory's segments)."""

    def regrasps(self, segments: Sequence[TimedSegment]) -> set[int]:
        """Return the segments that open the gripper on a part it takes again (it stays there, unjoined)."""
        ...

    def entering(self, driver: Driver, index: int) -> None:
        """Change the world before segment ``index`` starts (``len(segments)``: after the last one)."""
        ...

    def intended(self, index: int) -> str | None:
        """Return the part the grasp of segment ``index`` takes (None: whichever both fingers touch)."""
        ...

    def grasped(self, driver: Driver, part: str, index: int) -> None:
        """Change the world as the fingers take hold of ``part`` in segment ``index``."""
        ...

    def released(self, driver: Driver, part: str, step: int, index: int) -> None:
        """Change the world as the gripper lets go of ``part`` (held since step ``step``) in segment ``index``."""
        ...


@dataclass
class Driver:
    """One motor-driven run as it goes: the arm, the part it holds, the joints made and the errors measured."""

    scene: Scene
    trajectory: Trajectory
    effects: Effects
    joints: list[Joint] = field(default_factory=list)
    """The object's joints (the mechanism's), as the run makes and undoes them."""
    panda: Panda = field(init=False)
    ghost: Panda = field(init=False)
    held: _Held | None = None
    slip: dict[str, float] = field(default_factory=dict)
    joint_error: float = 0.0
    joint: str = ""
    gripper_error: float = 0.0
    failure: tuple[Failure, int, str] | None = None

    def __post_init__(self) -> None:
        self.panda = Panda(self.scene)
        self.ghost = Panda(self.scene)  # the commands' arm, for the gripper's error: never stepped against
        start = self.trajectory.points[0]
        self.panda.set(start.positions, start.gripper_width / 2)
        pb, client = self.scene.pb, self.scene.client
        # The motors' loops replace PyBullet's default velocity motors.
        pb.setJointMotorControlArray(
            self.ghost.body, list(ARM_JOINTS), pb.VELOCITY_CONTROL, forces=[0.0] * 7, physicsClientId=client
        )

    def _fail(self, failure: Failure, step: int, message: str) -> None:
        if self.failure is None:
            self.failure = (failure, step, message)

    def _hand(self) -> Pose:
        state = self.scene.pb.getLinkState(self.panda.body, HAND_LINK, physicsClientId=self.scene.client)
        return Pose(tuple(state[0]), tuple(state[1]))

    def _command(self, point: Point) -> None:
        pb, client, limits = self.scene.pb, self.scene.client, self.trajectory.limits
        pb.setJointMotorControlArray(
            self.panda.body,
            list(ARM_JOINTS),
            pb.POSITION_CONTROL,
            targetPositions=list(point.positions),
            targetVelocities=list(point.velocities),
            forces=list(limits.torque),
            positionGains=[POSITION_GAIN] * 7,
            velocityGains=[VELOCITY_GAIN] * 7,
            physicsClientId=client,
        )
        pb.setJointMotorControlArray(
            self.panda.body,
            list(FINGER_JOINTS),
            pb.POSITION_CONTROL,
            targetPositions=[point.gripper_width / 2] * 2,
            forces=[limits.gripper_force] * 2,
            physicsClientId=client,
        )

    def _touched(self, intended: str | None) -> str | None:
        """Return the part both fingers touch, if any (only ``intended``, when given: a part inside another)."""
        pb, client = self.scene.pb, self.scene.client
        bodies = self.scene.bodies if intended is None else {intended: self.scene.bodies[intended]}
        for part, body in bodies.items():
            if all(
                pb.getClosestPoints(self.panda.body, body, TOUCH, linkIndexA=finger, physicsClientId=client)
                for finger in FINGER_JOINTS
            ):
                return part
        return None

    def _collide(self, part: str, on: bool) -> None:
        pb, client = self.scene.pb, self.scene.client
        body = self.scene.bodies[part]
        for other in [self.scene.ground, *self.scene.bodies.values()]:
            if other != body:
                pb.setCollisionFilterPair(body, other, -1, -1, int(on), physicsClientId=client)

    def _grasp(self, part: str, step: int, index: int) -> None:
        pb, client = self.scene.pb, self.scene.client
        self.effects.grasped(self, part, index)
        self.scene.set_dynamic(part, True)
        self._collide(part, False)
        relative = self._hand().inverse() * self.scene.body_pose(self.scene.bodies[part])
        constraint = self.scene.fix(self.panda.body, HAND_LINK, self.scene.bodies[part], relative)
        pb.changeConstraint(
            constraint, maxForce=2 * FRICTION * self.trajectory.limits.gripper_force, erp=ERP, physicsClientId=client
        )
        self.held = _Held(part, step, constraint, relative)
        self.slip.setdefault(part, 0.0)

    def _slipped(self, held: _Held, step: int) -> None:
        """Note how far the held part moved in the gripper since it was grasped (a constraint that gave way)."""
        now = self._hand().inverse() * self.scene.body_pose(self.scene.bodies[held.part])
        slip = distance(now.position, held.relative.position) * 1000
        self.slip[held.part] = max(self.slip[held.part], slip)
        if slip > SLIP_TOLERANCE_MM:
            name = self.scene.solids[held.part].name
            self._fail(Failure.GRASP_SLIPPED, step, f"the {name} slipped {slip:.1f} mm in the gripper")

    def _release(self, index: int, regrasp: bool) -> None:
        """Let go of the held part; for a ``regrasp`` (the gripper takes it again) it stays where it is, unjoined."""
        assert self.held is not None
        held, self.held = self.held, None
        self._slipped(held, held.step)
        self.scene.pb.removeConstraint(held.constraint, physicsClientId=self.scene.client)
        if regrasp:
            self.scene.set_dynamic(held.part, False)
            # A body without mass still moves at the velocity it had (PyBullet moves it kinematically).
            self.scene.pb.resetBaseVelocity(
                self.scene.bodies[held.part], [0, 0, 0], [0, 0, 0], physicsClientId=self.scene.client
            )
            return
        self._collide(held.part, True)
        self.effects.released(self, held.part, held.step, index)

    def _measure(self, point: Point, step: int, count: int) -> None:
        pb, client, limits = self.scene.pb, self.scene.client, self.trajectory.limits
        states = pb.getJointStates(self.panda.body, list(ARM_JOINTS), physicsClientId=client)
        for index, (state, wanted) in enumerate(zip(states, point.positions, strict=True)):
            error = abs(state[0] - wanted)
            if error > self.joint_error:
                self.joint_error, self.joint = error, limits.joints[index]
            if not limits.position_min[index] <= state[0] <= limits.position_max[index]:
                detail = f"{limits.joints[index]} at {state[0]:.4f} rad, beyond its limits"
                self._fail(Failure.LIMIT_VIOLATION, step, detail)
        if self.joint_error > TRACKING_TOLERANCE_RAD:
            detail = f"{self.joint} {self.joint_error:.3f} rad from its command (tolerance {TRACKING_TOLERANCE_RAD})"
            self._fail(Failure.TRACKING_ERROR, step, detail)
        if count % FK_EVERY == 0:
            self.ghost.set(point.positions)
            error = distance(self.ghost.gripper_pose().position, self.panda.gripper_pose().position) * 1000
            self.gripper_error = max(self.gripper_error, error)
            if error > TRACKING_TOLERANCE_MM:
                self._fail(Failure.TRACKING_ERROR, step, f"the gripper {error:.1f} mm from its command")

    def run(self) -> None:
        """Play every command through the motors, one simulation step each, until the end or the first failure."""
        points, segments = self.trajectory.points, self.trajectory.segments
        times = [point.time for point in points]
        ends = [points[segment.last].time for segment in segments]
        regrasps = self.effects.regrasps(segments)
        count, entered = 0, -1
        while (count + 1) * TIME_STEP <= points[-1].time + TIME_STEP and self.failure is None:
            count += 1
            now = count * TIME_STEP  # the command for the end of this simulation step, and what it is measured on
            index = min(len(segments) - 1, bisect.bisect_left(ends, now)) if segments else 0
            for later in range(entered + 1, index + 1):
                self.effects.entering(self, later)
            entered = max(entered, index)
            segment = segments[index] if segments else None
            point = _at(points, times, now)
            self._command(point)
            self.scene.pb.stepSimulation(physicsClientId=self.scene.client)
            step = segment.step if segment else 0
            closed = segment is not None and segment.gripper == "closed"
            if closed and self.held is None and segment is not None and segment.kind == "grasp":
                touched = self._touched(self.effects.intended(index))
                if touched is not None:
                    self._grasp(touched, step, index)
                elif now >= ends[index] - TIME_STEP:
                    self._fail(Failure.GRASP_SLIPPED, step, "the fingers closed and hold nothing")
            elif not closed and self.held is not None:
                self._release(index, regrasp=index in regrasps)
            self._measure(point, step, count)
        if self.held is not None and self.failure is None:
            self._release(len(segments), regrasp=False)
        if self.failure is None:
            for later in range(entered + 1, len(segments) + 1):
                self.effects.entering(self, later)

    def report(self, requirements: tuple[RequirementCheck, ...], goal: bool = True) -> MotorRun:
        """Return the run's report: the goal produced when the motors did not fail, ``goal`` and the mechanism works."""
        failure, step, message = self.failure or (None, None, "")
        works = failure is None and goal and all(requirement.met for requirement in requirements)
        return MotorRun(
            self.trajectory.seconds,
            self.joint_error,
            self.joint,
            self.gripper_error,
            self.slip,
            requirements,
            works,
            failure,
            step,
            message,
        )


def _at(points: Sequence[Point], times: list[float], now: float) -> Point:
    """Return the command at ``now``: linear between the two points around it."""
    after = bisect.bisect_right(times, now)
    if after >= len(points):
        return points[-1]
    before = points[after - 1]
    nxt = points[after]
    share = (now - before.time) / (nxt.time - before.time)

    def mix(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(x + (y - x) * share for x, y in zip(a, b, strict=True))

    width = before.gripper_width + (nxt.gripper_width - before.gripper_width) * share
    return Point(now, mix(before.positions, nxt.positions), mix(before.velocities, nxt.velocities), (0.0,) * 7, width)


@dataclass(frozen=True)
class AssemblyEffects:
    """An assembly plan's world: each step's part, let go at its seat, is joined to its mate."""

    obj: AssemblyObject
    requests: tuple[StepRequest, ...]

    def regrasps(self, segments: Sequence[TimedSegment]) -> set[int]:
        # One part per step: a segment that opens the gripper before the same step grasps again.
        return {
            k
            for k, segment in enumerate(segments)
            if any(later.step == segment.step and later.kind == "grasp" for later in segments[k + 1 :])
        }

    def entering(self, driver: Driver, index: int) -> None:
        return None

    def intended(self, index: int) -> str | None:
        return None  # one part per step, fetched from the table: the fingers touch only it

    def grasped(self, driver: Driver, part: str, index: int) -> None:
        return None

    def released(self, driver: Driver, part: str, step: int, index: int) -> None:
        # The step that held it, not the first to move it: a match may light one wick, then another.
        request = self.requests[step - 1] if 0 < step <= len(self.requests) else None
        if request is None or request.moving != part:
            return
        motion = MOTIONS[request.action]
        pair = step_connectors(self.obj, request, driver.joints)
        if pair is None:
            return
        fit = catalog_fit(self.obj, request, pair)
        joint = Joint(step, fit, request.moving, pair[0].id, request.fixed, pair[1].id, motion.touches_only)
        if motion.touches_only:
            driver.joints.append(joint)  # the flame touched the wick on its way: lit
            return
        if motion.fastens:
            driver.scene.weld(request.fixed, request.moving)
        driver.joints.append(joint)


def drive_with_motors(obj: AssemblyObject, requests: tuple[StepRequest, ...], trajectory: Trajectory) -> MotorRun:
    """Return how the motors carried out ``trajectory`` (the plan ``requests`` on ``obj``) in a fresh scene."""
    with laid_out_scene(obj, requests, ROBOT_ROW_GAP) as (scene, _, _):
        driver = Driver(scene, trajectory, AssemblyEffects(obj, requests))
        driver.run()
        scene.settle(checks.FINAL_SETTLE_SECONDS)
        return driver.report(evaluate(obj, scene, driver.joints))
