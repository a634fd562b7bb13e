"""The robot doing a step: fetch the part, carry it to its approach, follow the connector axis, let go.

``Robot`` moves a kinematic Panda (``sim.panda``) through one step's motions and writes them
into a ``Trajectory``: transit (a collision-free joint path from OMPL, then straight down to
the grasp), grasp, carry (lift, then a collision-free path to the approach pose, the part
riding on the gripper), approach and the primitive (straight Cartesian lines along the
connector axis by IK; a screw turns the wrist and regrasps when joint 7 runs out), release,
retreat. A held part is attached to the gripper kinematically, as PyBullet TAMP code does:
wherever the gripper goes, the part is put at the same pose relative to it. A motion that
cannot be done returns a ``RobotFailure`` naming the cause.
"""

from __future__ import annotations

import math
import random
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from causalplan.objects.model import Part
from causalplan.sim.checks import PENETRATION_TOLERANCE_MM
from causalplan.sim.outcomes import Check, Failure, RobotFailure
from causalplan.sim.poses import Pose, about_axis, scale
from causalplan.sim.robot.grasps import FINGER_REACH, finger_gap, grasp_of
from causalplan.sim.robot.motion_planning import plan_path
from causalplan.sim.robot.panda import ARM_JOINTS, FINGER_JOINTS, FINGER_OPEN, HOME, Configuration, Contact, Panda
from causalplan.sim.robot.trajectory import Gripper, Segment, Waypoints
from causalplan.sim.scene import GROUND, Scene

PREGRASP = 0.08
"""Metres the gripper stays back from a grasp before going straight in (and after letting go)."""
LIFT = 0.06
"""Metres a part is lifted off the table before it is carried."""
LINE_STEP = 0.002
"""Metres between two commanded poses of a straight line."""
SCREW_STEP = math.radians(10)
"""Largest wrist turn between two commanded poses of a screw."""
CLOSE_POSITIONS = 20
"""Commands (at the control rate) the fingers take to close or open."""
TOUCH = 0.0005
"""Metres at which a closing finger counts as touching the part."""
HELD = "held "
"""How a contact of the held part (rather than of the arm) is named."""
IK_SEEDS: tuple[Configuration, ...] = (
    HOME,
    (0.0, 0.2, 0.0, -1.8, 0.0, 2.0, 0.785),
    (0.8, -0.3, 0.0, -2.2, 0.0, 1.9, 0.8),
)
SHOULDER_AND_ELBOW = ARM_JOINTS[:6]
"""The arm's joints but the wrist's turn (joint 7)."""
RANDOM_SEEDS = 12
"""Further starting configurations for the IK (drawn once, from a fixed seed) when the first ones fail."""


@dataclass
class Held:
    """The part in the gripper, and the grasp: the gripper's pose in the part's frame."""

    part: str
    grasp: Pose


@dataclass
class Robot:
    """A Panda building in a scene, writing what it plans to do into ``waypoints``.

    ``observe`` is called after every commanded position (a video draws frames from it).
    """

    scene: Scene
    waypoints: Waypoints = field(default_factory=Waypoints)
    observe: Callable[[], None] | None = None
    panda: Panda = field(init=False)
    held: Held | None = None
    step: int = 0
    planning_seconds: float = 0.0
    """Time spent planning collision-free paths so far (the benchmark's breakdown)."""
    released: dict[str, Pose] = field(default_factory=dict)
    """Where the robot last let go of each part."""
    ignored: set[str] = field(default_factory=set)
    """Parts the arm may touch during the current motion (the one it is closing its fingers on)."""

    def __post_init__(self) -> None:
        self.panda = Panda(self.scene)

    # --- the world as the robot sees it -----------------------------------------------------

    def _others(self) -> list[int]:
        skip = {self.held.part} if self.held else set()
        skip |= self.ignored
        bodies = [body for part, body in self.scene.bodies.items() if part not in skip]
        return [self.scene.ground, *bodies]

    def _place_held(self) -> None:
        if self.held is not None:
            self.scene.place(self.held.part, self.panda.gripper_pose() * self.held.grasp.inverse())

    def _contact(self, allowed: frozenset[str] = frozenset(), with_held: bool = True) -> Contact | None:
        """Return the deepest touch of the arm (and its part) with anything else beyond tolerance, if any."""
        tolerance = PENETRATION_TOLERANCE_MM / 1000
        # Only the fingertips may brush the part being joined to (pushing a part home); the arm may not.
        brushed = frozenset(
            (finger, self.scene.bodies[part])
            for part in allowed
            if part in self.scene.bodies
            for finger in FINGER_JOINTS
        )
        touch = self.panda.deepest_contact(self._others(), brushed)
        if touch is not None and touch.depth > tolerance:
            return touch
        if self.held is not None and with_held:
            others = [body for body in self._others() if self.scene.names.get(body) not in allowed]
            depth, hit = self.scene.deepest_overlap(self.held.part, others)
            if depth > tolerance and hit is not None:
                return Contact(f"{HELD}{self.scene.solids[self.held.part].name}", hit, depth)
        return None

    def called(self, name: str) -> str:
        """Return what a contact's body is called in words: a part's name, or 'table'."""
        solid = self.scene.solids.get(name)
        return solid.name if solid is not None else "table" if name == GROUND else name

    def _is_clear(self, configuration: Configuration) -> bool:
        self.panda.set(configuration)
        self._place_held()
        return self._contact() is None

    # --- writing commands --------------------------------------------------------------------

    def _riding(self) -> tuple[str, Pose] | None:
        """Return the held part and its pose in the gripper's frame (what a segment carries), if any."""
        return None if self.held is None else (self.held.part, self.held.grasp.inverse())

    def _command(self, kind: str, gripper: Gripper, positions: Sequence[Configuration]) -> None:
        fingers = FINGER_OPEN if gripper == "open" else None
        segment = Segment(
            self.step, kind, gripper, 2 * (self.panda.fingers if fingers is None else fingers), held=self._riding()
        )
        self.waypoints.segments.append(segment)
        for position in positions:
            self.panda.set(position, fingers)
            self._place_held()
            segment.positions.append(position)
            if self.observe is not None:
                self.observe()

    def _fingers(self, kind: str, gripper: Gripper, width: float, on: str | None = None) -> None:
        """Open the fingers, or close them to ``width`` (on the part ``on``: until both touch it)."""
        start, end = self.panda.fingers, FINGER_OPEN if gripper == "open" else max(0.0, width / 2)
        if on is not None:
            end = 0.0
        segment = Segment(self.step, kind, gripper, 2 * end, held=self._riding())
        self.waypoints.segments.append(segment)
        for k in range(1, CLOSE_POSITIONS + 1):
            self.panda.set(self.panda.configuration, start + (end - start) * k / CLOSE_POSITIONS)
            segment.positions.append(self.panda.configuration)
            if self.observe is not None:
                self.observe()
            if on is not None and finger_gap(self.scene, self.panda.body, on) <= TOUCH:
                break
        segment.width = 2 * self.panda.fingers

    # --- motions -----------------------------------------------------------------------------

    def _unreachable(self, what: str) -> RobotFailure:
        detail = f"no arm pose puts the gripper {what} (inverse kinematics)"
        return RobotFailure(Failure.UNREACHABLE, Check("robot", False, detail))

    def _collision(self, what: str, touch: Contact) -> RobotFailure:
        detail = (
            f"{what}: the {touch.robot_part} touched the {self.called(touch.other)} ({touch.depth * 1000:.1f} mm deep)"
        )
        return RobotFailure(
            Failure.COLLISION,
            Check("robot", False, detail, round(touch.depth * 1000, 2), PENETRATION_TOLERANCE_MM, "mm"),
        )

    def _go(
        self,
        kind: str,
        gripper: Gripper,
        target: Pose,
        what: str,
        then: Sequence[Pose] = (),
        allowed: frozenset[str] = frozenset(),
        fingers_then: Sequence[float | None] = (),
    ) -> RobotFailure | None:
        """Move along a collision-free joint path (OMPL) to a configuration reaching ``target``.

        Of the arm poses that reach it, the first from which the gripper can then follow the
        poses ``then`` (a straight line) by IK without touching anything but ``allowed`` is
        taken; when the line can be followed only by touching something, there is no path.
        ``fingers_then`` gives each pose of ``then`` its finger opening (metres each; None or
        missing: as they are now), so a line after the grasp is checked with the fingers closed.
        """
        start = self.panda.configuration
        if not self._is_clear(start):
            touch = self._contact()
            assert touch is not None
            return self._collision(f"before moving {what}", touch)
        reaching: list[Configuration] = []
        clear: list[Configuration] = []
        for seeds in ((start, *IK_SEEDS), self._random_seeds()):
            solutions = [self.panda.solve(target, seed) for seed in seeds]
            reaching += [solution for solution in solutions if solution is not None]
            # The clear pose farthest from the joint limits leaves the most room for the line that follows.
            clear = sorted((s for s in reaching if self._is_clear(s)), key=lambda s: -self.panda.limit_margin(s))
            if clear:
                break
        if not reaching:
            self.panda.set(start)
            self._place_held()
            return self._unreachable(what)
        goal, touched = (clear[0] if clear else None), None
        for candidate in clear:
            outcome = self._can_follow(candidate, then, allowed, fingers_then)
            if outcome is True:
                goal, touched = candidate, None
                break
            if isinstance(outcome, Contact) and touched is None:
                touched = outcome
        self.panda.set(start)
        self._place_held()
        if touched is not None:
            detail = (
                f"no arm pose {what} lets the gripper go on along the connector axis without the "
                f"{touched.robot_part} touching the {self.called(touched.other)} ({touched.depth * 1000:.1f} mm deep)"
            )
            return RobotFailure(Failure.NO_COLLISION_FREE_PATH, Check("robot", False, detail), touched.other)
        if goal is None:
            detail = f"every arm pose that puts the gripper {what} touches the {self._contact_at(reaching[0])}"
            return RobotFailure(Failure.NO_COLLISION_FREE_PATH, Check("robot", False, detail))
        planned = time.perf_counter()
        path = plan_path(start, goal, self._is_clear, self.panda.lower, self.panda.upper)
        self.planning_seconds += time.perf_counter() - planned
        self.panda.set(start)
        self._place_held()
        if path is None:
            detail = f"the motion planner (OMPL RRTConnect) found no collision-free path {what}"
            return RobotFailure(Failure.NO_COLLISION_FREE_PATH, Check("robot", False, detail))
        self._command(kind, gripper, path[1:])
        return None

    def _can_follow(
        self,
        configuration: Configuration,
        targets: Sequence[Pose],
        allowed: frozenset[str],
        fingers: Sequence[float | None] = (),
    ) -> bool | Contact:
        """Return whether IK follows ``targets`` from ``configuration`` without a jump (or what the arm touches).

        ``fingers``: each target's finger opening (metres each; None or missing: as they are).
        """
        saved, saved_fingers = self.panda.configuration, self.panda.fingers
        try:
            for index, target in enumerate(targets):
                solution = self.panda.solve(target, configuration)
                if solution is None or max(abs(a - b) for a, b in zip(solution, configuration, strict=True)) > 0.5:
                    return False
                configuration = solution
                self.panda.set(configuration, fingers[index] if index < len(fingers) else None)
                self._place_held()
                touch = self._contact(allowed)
                if touch is not None and touch.robot_part.startswith(HELD):
                    return True  # the part stops here, and the simulator's path check says why
                if touch is not None:
                    return touch
            return True
        finally:
            self.panda.set(saved, saved_fingers)
            self._place_held()

    def _random_seeds(self) -> list[Configuration]:
        chance = random.Random(RANDOM_SEEDS)
        return [
            tuple(chance.uniform(low, high) for low, high in zip(self.panda.lower, self.panda.upper, strict=True))
            for _ in range(RANDOM_SEEDS)
        ]

    def _contact_at(self, configuration: Configuration) -> str:
        self.panda.set(configuration)
        self._place_held()
        touch = self._contact()
        return self.called(touch.other) if touch else "scene"

    def _line(
        self,
        kind: str,
        gripper: Gripper,
        targets: Sequence[Pose],
        what: str,
        allowed: frozenset[str] = frozenset(),
        with_held: bool = True,
        hold: Sequence[int] = (),
    ) -> tuple[RobotFailure | None, int]:
        """Follow gripper poses one by one by IK (a straight line); return the failure, if any, and the poses reached.

        ``with_held``: whether the held part's touches count too (not along the connector axis,
        where the simulator's own path check judges the part). ``hold``: see ``Panda.solve``.
        """
        positions: list[Configuration] = []
        configuration = self.panda.configuration
        for target in targets:
            solution = self.panda.solve(target, configuration, hold)
            if solution is None or max(abs(a - b) for a, b in zip(solution, configuration, strict=True)) > 0.5:
                self._command(kind, gripper, positions)
                return self._unreachable(what), len(positions)
            configuration = solution
            self.panda.set(configuration)
            self._place_held()
            touch = self._contact(allowed, with_held)
            if touch is not None:
                self._command(kind, gripper, [*positions, configuration])
                return self._collision(what, touch), len(positions)
            positions.append(configuration)
        self._command(kind, gripper, positions)
        return None, len(positions)

    def fetch(
        self, part_id: str, part: Part, then: Sequence[Pose] = (), allowed: frozenset[str] = frozenset()
    ) -> RobotFailure | None:
        """Transit to the part, go straight to its grasp, and close the fingers on it.

        ``then``: the part's poses after the grasp (taking it off an assembly along its
        connector axis, where its gripper may brush ``allowed``), which choose the arm pose.
        """
        name = self.scene.solids[part_id].name
        found = grasp_of(part, self.scene.solids[part_id])
        if isinstance(found, str):
            return RobotFailure(Failure.UNREACHABLE, Check("robot", False, f"the {name} cannot be grasped: {found}"))
        grasp_pose, width = found
        grasp = self.scene.pose(part_id) * grasp_pose
        backed = grasp.translated(scale(grasp.turn((0.0, 0.0, 1.0)), -PREGRASP))
        self.ignored = {part_id}
        try:
            # The arm pose above the part must also go straight down to the grasp (fingers open)
            # and take the part out along ``then`` (fingers closed on it).
            way_in = line_poses(backed, grasp)
            way = [*way_in, *(pose * grasp_pose for pose in then)]
            fingers = [*([None] * len(way_in)), *([width / 2] * len(then))]
            failure = self._go("transit", "open", backed, f"above the {name}", way, allowed, fingers)
            if failure is None:
                failure, _ = self._line("transit", "open", line_poses(backed, grasp), f"at the {name}'s grasp")
        finally:
            self.ignored = set()
        if failure is not None:
            return failure
        self._fingers("grasp", "closed", width, on=part_id)
        gap = finger_gap(self.scene, self.panda.body, part_id)
        if gap > FINGER_REACH:
            detail = f"the fingers closed {gap * 1000:.1f} mm from the {name}: the grasp holds nothing"
            return RobotFailure(
                Failure.GRASP_LOST, Check("grasp", False, detail, round(gap * 1000, 2), FINGER_REACH * 1000, "mm")
            )
        self.held = Held(part_id, grasp_pose)
        self._place_held()
        return None

    def carry(
        self, part_pose: Pose, what: str, then: Sequence[Pose] = (), mate: str | None = None
    ) -> RobotFailure | None:
        """Lift the held part and carry it along a collision-free path until it is at ``part_pose``.

        ``then`` are the part's poses after it (a line to follow, on which it may touch ``mate``),
        which choose the arm pose.
        """
        assert self.held is not None
        held = self.held
        here = self.panda.gripper_pose()
        lifted = here.translated((0.0, 0.0, LIFT))
        failure, _ = self._line("carry", "closed", line_poses(here, lifted), "lifting the part")
        if failure is None:
            targets = [pose * held.grasp for pose in then]
            allowed = frozenset({mate}) if mate else frozenset()
            failure = self._go("carry", "closed", part_pose * held.grasp, what, targets, allowed)
        return failure

    def follow(self, kind: str, part_poses: Sequence[Pose], what: str, mate: str) -> RobotFailure | None:
        """Move the held part through ``part_poses`` (a straight line along the connector axis) by IK.

        The part may touch ``mate`` (it is being joined to it: the simulator's own path check judges that).
        """
        assert self.held is not None
        targets = [pose * self.held.grasp for pose in part_poses]
        return self._line(kind, "closed", targets, what, frozenset({mate}), with_held=False)[0]

    def screw(self, part_poses: Sequence[Pose], what: str, mate: str) -> RobotFailure | None:
        """Turn the held part down its thread, regrasping (a half turn back) whenever joint 7 runs out."""
        index, regrasped = 0, False
        while index < len(part_poses):
            assert self.held is not None
            targets = [pose * self.held.grasp for pose in part_poses[index:]]
            # The turn goes to the wrist (which regrasps when it runs out), not to a shoulder at its limit.
            failure, done = self._line("screw", "closed", targets, what, frozenset({mate}), False, SHOULDER_AND_ELBOW)
            index += done
            if failure is None:
                return None
            if failure.failure is not Failure.UNREACHABLE or (regrasped and done == 0):
                return failure
            failure = self._regrasp(what)
            if failure is not None:
                return failure
            regrasped = True
        return None

    def _regrasp(self, what: str) -> RobotFailure | None:
        """Let go, turn the wrist half a turn back, and take hold again (the gripper is symmetric)."""
        assert self.held is not None
        held = self.held
        lower, upper = self.panda.lower[6], self.panda.upper[6]
        wrist = self.panda.configuration[6]
        back = math.pi if wrist - math.pi < lower else -math.pi
        if not lower <= wrist + back <= upper:
            return self._unreachable(f"{what}: the wrist cannot turn back to regrasp")
        self.held = None
        width = 2 * self.panda.fingers
        self._fingers("release", "open", width)
        start = self.panda.configuration
        turned = (*start[:6], wrist + back)
        count = max(1, math.ceil(abs(back) / SCREW_STEP))
        self.ignored = {held.part}
        try:
            path = [(*start[:6], wrist + back * k / count) for k in range(1, count + 1)]
            self._command("transit", "open", path)
        finally:
            self.ignored = set()
        self.panda.set(turned)
        self._fingers("grasp", "closed", width)
        spin = Pose(orientation=about_axis((0.0, 0.0, 1.0), back))
        self.held = Held(held.part, held.grasp * spin)
        return None

    def release(self, retreat: bool = True, mate: str | None = None) -> RobotFailure | None:
        """Open the fingers and back away along the gripper's axis (the fingers may brush ``mate`` as they leave)."""
        held, self.held = self.held, None
        if held is not None:
            self.released[held.part] = self.scene.pose(held.part)
        self._fingers("release", "open", 0.0)
        if not retreat or held is None:
            return None
        here = self.panda.gripper_pose()
        backed = here.translated(scale(here.turn((0.0, 0.0, 1.0)), -PREGRASP))
        self.ignored = {held.part}
        try:
            allowed = frozenset({mate}) if mate else frozenset()
            # Backing away needs no joint at its limit (a wrist left there by a screw stays there).
            return self._line("retreat", "open", line_poses(here, backed), "backing away", allowed, True, ARM_JOINTS)[0]
        finally:
            self.ignored = set()

    def go_home(self) -> RobotFailure | None:
        """Return to the resting pose along a collision-free path."""
        planned = time.perf_counter()
        path = plan_path(self.panda.configuration, HOME, self._is_clear, self.panda.lower, self.panda.upper)
        self.planning_seconds += time.perf_counter() - planned
        if path is None:
            return RobotFailure(Failure.NO_COLLISION_FREE_PATH, Check("robot", False, "no collision-free path home"))
        self._command("retreat", "open", path[1:])
        return None


def line_poses(start: Pose, end: Pose) -> list[Pose]:
    """Return poses every ``LINE_STEP`` on the straight line from ``start`` to ``end`` (same orientation as end)."""
    length = math.dist(start.position, end.position)
    count = max(1, math.ceil(length / LINE_STEP))
    return [
        Pose(tuple(a + (b - a) * k / count for a, b in zip(start.position, end.position, strict=True)), end.orientation)  # type: ignore[arg-type]
        for k in range(1, count + 1)
    ]
