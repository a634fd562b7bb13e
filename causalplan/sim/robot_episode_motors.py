"""A troubleshooting episode's motor commands played through the Panda's joint motors, in physics.

The robot's run of an episode (``sim.robot_episode``) poses a kinematic arm; this run checks
that the motors can follow what it wrote, as ``sim.robot.motors`` does for an assembly, with
the same ``Driver``, measures and tolerances. In a fresh scene built as the robot's run was
(``sim.robot_episode_scene``: the broken object built, the spares on the table), the world
changes around the arm as the robot's run recorded it (``Event``), each at the motion where
it happened there:

- a part taken off the object (``Unweld``): its weld to its mate is undone as the fingers take
  hold of it, and its joint leaves the mechanism;
- a part put on (``Join``): welded to its mate (a fastening primitive) where the gripper lets
  go of it, or, for a flame, the wick it touched is lit;
- a spare replacing a part (``Swap``, and ``Place`` for a base the gripper cannot hold, which
  the robot's run too puts where the broken one stood without the arm);
- a test (``LightsOut``): the last test's flame is out before the new one is struck.

Everything else is physics: a part set down on the table falls the last millimetres and rests
there, a part let go on its mate rests on it. At the end the scene settles and the object's
true mechanism is judged; the goal counts when the motors did not fail, the mechanism works,
and the robot's run replaced the broken part (physics cannot see a broken part).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject
from causalplan.sim import checks
from causalplan.sim.mechanism import Joint, evaluate
from causalplan.sim.poses import Pose
from causalplan.sim.robot.motors import Driver, MotorRun
from causalplan.sim.robot.trajectory import Segment, TimedSegment, Trajectory
from causalplan.sim.robot_episode_scene import EpisodeStage, built_object
from causalplan.sim.scene import Scene
from causalplan.sim.taking_off import collide_again, unweld


@dataclass(frozen=True)
class Unweld:
    """``part`` comes off ``fixed``: the grasp made in planned segments ``first``..``last - 1`` undoes the weld."""

    part: str
    fixed: str
    first: int
    last: int


@dataclass(frozen=True)
class Join:
    """``part`` is joined (``joint``; welded when it fastens) where it is let go in segments ``first``..``last - 1``."""

    part: str
    joint: Joint
    weld: bool
    first: int
    last: int


@dataclass(frozen=True)
class Swap:
    """The spare of ``part`` becomes the part before planned segment ``at``."""

    part: str
    at: int


@dataclass(frozen=True)
class Place:
    """``part`` is put at ``pose`` (with its mass, or none) before planned segment ``at``, without the arm."""

    part: str
    pose: Pose
    dynamic: bool
    at: int


@dataclass(frozen=True)
class LightsOut:
    """A test begins before planned segment ``at``: the flame of the last one is out."""

    at: int


Event = Unweld | Join | Swap | Place | LightsOut
"""A change the robot's run made to the world, at the planned segment (``Waypoints``) where it made it."""


def swap_spare(scene: Scene, part: str, spare: str) -> None:
    """Make the ``spare``'s body the part's and the part's the spare's (the names follow the bodies)."""
    scene.bodies[part], scene.bodies[spare] = scene.bodies[spare], scene.bodies[part]
    scene.names[scene.bodies[part]], scene.names[scene.bodies[spare]] = part, spare


@dataclass(frozen=True)
class _Timed:
    """An event at the trajectory's segments (planned segments without positions have no timed segment)."""

    event: Event
    first: int
    last: int


class EpisodeEffects:
    """What the world does around the arm as an episode's commands play: its recorded events, in order."""

    def __init__(self, events: Sequence[Event], planned: Sequence[Segment], spare_suffix: str) -> None:
        # Each planned segment's index among the timed ones (time_parameterize drops empty segments).
        timed = [0]
        for segment in planned:
            timed.append(timed[-1] + (1 if segment.positions else 0))
        self._events: list[_Timed] = []
        for event in events:
            if isinstance(event, Unweld | Join):
                self._events.append(_Timed(event, timed[event.first], timed[event.last]))
            else:
                self._events.append(_Timed(event, timed[event.at], timed[event.at]))
        self._regrasps = {timed[k] for k in _planned_regrasps(planned)}
        self._spare = spare_suffix
        # What each grasp takes, by the part held after it. A spare swapped in is the part by then
        # in the scene, though the planned segments call it by its ``:spare`` id (the player's).
        self._intended: dict[int, str] = {}
        for k, segment in enumerate(planned):
            if segment.kind != "grasp" or segment.gripper != "closed":
                continue
            after = next((later.held for later in planned[k + 1 :] if later.held is not None), None)
            if after is not None:
                self._intended[timed[k]] = after[0].removesuffix(spare_suffix)

    def regrasps(self, segments: Sequence[TimedSegment]) -> set[int]:
        return self._regrasps

    def intended(self, index: int) -> str | None:
        return self._intended.get(index)

    def entering(self, driver: Driver, index: int) -> None:
        scene = driver.scene
        for timed in self._events:
            event = timed.event
            if timed.first != index or isinstance(event, Unweld | Join):
                continue
            if isinstance(event, Swap):
                swap_spare(scene, event.part, event.part + self._spare)
            elif isinstance(event, Place):
                scene.place(event.part, event.pose)
                scene.set_dynamic(event.part, event.dynamic)
            else:
                driver.joints[:] = [joint for joint in driver.joints if not joint.touch_only]

    def grasped(self, driver: Driver, part: str, index: int) -> None:
        for timed in self._events:
            event = timed.event
            if isinstance(event, Unweld) and event.part == part and timed.first <= index < timed.last:
                unweld(driver.scene, event.fixed, part)
                collide_again(driver.scene, event.fixed, part)
                driver.joints[:] = [
                    joint
                    for joint in driver.joints
                    if joint.touch_only or joint.moving != part or joint.fixed != event.fixed
                ]

    def released(self, driver: Driver, part: str, step: int, index: int) -> None:
        for timed in self._events:
            event = timed.event
            if isinstance(event, Join) and event.part == part and timed.first <= index < timed.last:
                if event.weld:
                    driver.scene.weld(event.joint.fixed, part)
                driver.joints.append(event.joint)


def _planned_regrasps(planned: Sequence[Segment]) -> list[int]:
    """Return the planned segments that let go of a part only to take it again (a screw turned in or out).

    One action may set a part down and take another, so the part must be the same, and no
    retreat (what follows a real release) comes between.
    """
    found = []
    for k, segment in enumerate(planned):
        before = planned[k - 1].held if k > 0 else None
        if segment.kind != "release" or before is None:
            continue
        after = next((j for j in range(k + 1, len(planned)) if planned[j].held is not None), None)
        if after is None or planned[after].held[0] != before[0]:  # type: ignore[index]
            continue
        if all(later.kind != "retreat" for later in planned[k + 1 : after]):
            found.append(k)
    return found


def drive_episode_with_motors(
    obj: AssemblyObject,
    stage: EpisodeStage,
    planned: Sequence[Segment],
    trajectory: Trajectory,
    events: Sequence[Event],
    spare_suffix: str,
    replaced: bool,
) -> MotorRun:
    """Return how the motors carried out an episode's ``trajectory`` in a fresh scene built from ``stage``.

    ``planned`` are the robot's planned segments (the trajectory's, with the parts held),
    ``events`` what its run changed in the world, and ``replaced`` whether it replaced the
    broken part before its last test.
    """
    with built_object(obj, stage) as run:
        effects = EpisodeEffects(events, planned, spare_suffix)
        driver = Driver(run.scene, trajectory, effects, list(run.joints))
        driver.run()
        run.scene.settle(checks.FINAL_SETTLE_SECONDS)
        return driver.report(evaluate(obj, run.scene, driver.joints), replaced)
