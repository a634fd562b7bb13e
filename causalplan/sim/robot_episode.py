"""The Panda carries out a troubleshooting episode in physics, action by action.

The broken object stands assembled at the origin (its parts put it together themselves: it
is handed to the robot that way), a working spare of every part the episode replaces waits
on the table, and the robot then does each action of the episode in the same scene:

- ``detach PART``: the assembly's motion in reverse. The robot grasps the part where it sits
  on the object, the weld to its mate is undone, the part goes back along its connector axis
  (a screw turns out its thread, regrasping as it goes in), and is carried to its place on
  the table and set down (``robot.fetch``, ``robot.screw``/``robot.follow``, ``robot.carry``,
  ``robot.release``: the motions, IK and OMPL paths the assembly uses). When the hand cannot
  reach the part for a neighbour that could come off now, the neighbour is lifted off first
  and put back after (and again when the part is put back on).
- ``replace PART``: the spare on the table becomes the part: the next ``attach`` (or the
  ``test``'s lighting, for a match or lighter) fetches it from the table; the broken one stays
  where it was set aside.
- ``attach PART``: an assembly step (``sim.executor``), with every physics check (blocked
  path, contact, alignment, stability).
- ``test``: a part to light is lit with the match or lighter (a part that covers its wick,
  such as a chimney, is lifted off first and put back after, as one does; these motions are
  not part of the episode's cost), and the true mechanism is judged on the object as it
  stands. Physics cannot see a broken part, so a test shows the goal when the mechanism works
  *and* a spare has replaced the broken part since the last test.
- ``inspect PART``: looking; the robot does not move.

All motions become one set of motor commands within the Panda's datasheet limits times the
safety factor (TOPP-RA, ``sim.robot.timing``), which ``check-trajectory`` accepts, and every
part's track for the 3D player (``sim.robot_episode_playback``). A broken base the gripper
can hold is carried off and its spare carried to where it stood. What is not simulated:
replacing a *base the gripper cannot hold* (wider than it opens, with no grasp in the
catalog: its spare is put where the broken one stood, not carried), and the object's
assembly before the episode (it is handed to the robot built). The run itself is kinematic
(the arm posed at its commands); with ``motors`` the commands are then played through the
Panda's joint motors in a fresh scene (``sim.robot_episode_motors``), as ``simulate --robot``
does for an assembly, the world changing around the arm as this run recorded it (``Event``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.sim import checks
from causalplan.sim.executor import SimulationRun, execute_step, settle
from causalplan.sim.mechanism import evaluate
from causalplan.sim.motions import ENGAGEMENT, MOTIONS, approach_path, approach_start
from causalplan.sim.outcomes import Failure, RequirementCheck, RobotFailure, StepStatus
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose
from causalplan.sim.robot.limits import DEFAULT_SAFETY_FACTOR
from causalplan.sim.robot.motors import MotorRun
from causalplan.sim.robot.mover import PandaMovesThem
from causalplan.sim.robot.robot import LIFT, LINE_STEP, Robot, line_poses
from causalplan.sim.robot.steps import (
    PUSH_DEPTH,
    SCREW_START_POSES,
    screw_spacing,
    spaced_distances,
    step_motions,
)
from causalplan.sim.robot_episode_motors import (
    Event,
    Join,
    LightsOut,
    Place,
    Swap,
    Unweld,
    drive_episode_with_motors,
    swap_spare,
)
from causalplan.sim.robot_episode_report import ActionInPhysics, EpisodeInPhysics
from causalplan.sim.robot_episode_scene import built_object, episode_stage
from causalplan.sim.scene import Scene
from causalplan.sim.spares import SPARE
from causalplan.sim.taking_off import along, collide_again, unweld
from causalplan.troubleshoot.assembly import ATTACH, DETACH
from causalplan.troubleshoot.episode import GOAL, NO_GOAL, Episode
from causalplan.troubleshoot.solver import INSPECT, REPLACE, TEST


@dataclass
class _Episode:
    """The state of the robot's run of an episode as it goes."""

    obj: AssemblyObject
    run: SimulationRun
    mover: PandaMovesThem
    fits: dict[str, Fit]
    """Each attached part's fit (the one the object was built with)."""
    bodies: dict[int, str]
    """Each body's id for the player: the part it started as, or its spare's id."""
    base_aside: Pose | None
    """The free place on the table where the broken base is set down, when the episode replaces the base."""
    swaps: list[tuple[str, int]] = field(default_factory=list)
    """Each part swapped for its spare, and the number of planned segments before the swap."""
    in_the_way: dict[str, list[str]] = field(default_factory=dict)
    """The parts the hand had to lift off to take each part off (they are lifted off to put it on, too)."""
    events: list[Event] = field(default_factory=list)
    """What the run changed in the world, at the planned segment where it did (the motors' run replays them)."""

    @property
    def scene(self) -> Scene:
        return self.run.scene

    @property
    def robot(self) -> Robot:
        return self.mover.robot

    @property
    def planned(self) -> int:
        """Return how many segments the robot has planned so far."""
        return len(self.robot.waypoints.segments)


def _detach(state: _Episode, number: int, part: str) -> tuple[str, str] | None:
    """Take ``part`` off the object and set it down; return the failure code and message, if any.

    A part the hand cannot reach for one beside it that could come off now (the gas lantern's
    knob beside its globe) is reached as one would: that part is lifted off first and put back after.
    """
    aside: list[str] = []
    failed = _take_off(state, number, part, aside)
    if failed is not None:
        return failed
    if aside:
        state.in_the_way[part] = aside
    return _put_back(state, number, aside)


def _code(failure: RobotFailure | None) -> tuple[str, str] | None:
    """Return a robot failure's code and message (None for none)."""
    return None if failure is None else (failure.failure.value, failure.check.detail)


def _in_the_way(state: _Episode, part: str, failure: RobotFailure, aside: list[str]) -> str | None:
    """Return the assembled part the hand met reaching ``part``, if it can come off now (nothing stands on it)."""
    other = failure.obstacle
    run = state.run
    if failure.failure is not Failure.NO_COLLISION_FREE_PATH or other is None or other in aside:
        return None
    if other == part or other == state.obj.base or other not in run.assembled:
        return None
    standing_on = any(joint.fixed == other for joint in run.joints if not joint.touch_only)
    return None if standing_on else other


def _put_back(state: _Episode, number: int, aside: list[str]) -> tuple[str, str] | None:
    """Put the parts lifted off out of the hand's way back on the object, the last lifted first."""
    for part in reversed(aside):
        fit = state.fits[part]
        failed = _step_failure(state, number, StepRequest(fit.primitive, part, fit.fixed_part, fit.id))
        if failed is not None:
            return failed
    return None


def _take_off(state: _Episode, number: int, part: str, aside: list[str]) -> tuple[str, str] | None:
    """Take ``part`` off the object as its assembly step put it on, backwards, and set it down at its table place.

    A part in the hand's way is taken off first (and added to ``aside``). Returns the failure
    code and message, if any.
    """
    obj, scene, run, robot = state.obj, state.scene, state.run, state.robot
    fit = state.fits[part]
    joint = next(joint for joint in run.joints if joint.moving == part and not joint.touch_only)
    motion = MOTIONS[fit.primitive]
    name = obj.part(part).name
    moving_frame = scene.solids[part].frames[joint.moving_connector]
    fixed_frame = scene.solids[joint.fixed].frames[joint.fixed_connector]
    fixed_pose = scene.pose(joint.fixed)
    path = approach_path(fixed_pose, moving_frame, fixed_frame, motion)
    others = run.assembled - {part}
    start = approach_start(scene.bounds([part]), scene.bounds(others), fixed_pose.turn(fixed_frame.axis))
    here = along(path, scene.pose(part), start)
    if motion.turns > 0:
        thread = max(here, min(start, ENGAGEMENT))
        out = spaced_distances(here, thread, screw_spacing(motion))
    else:
        thread = max(here, min(start, PUSH_DEPTH))
        out = spaced_distances(here, thread, LINE_STEP)
    # A screw's way out turns the wrist further than it can go (it regrasps): the arm pose is
    # chosen for the first quarter turn; a push's, for the whole line out.
    first = out[:SCREW_START_POSES] if motion.turns > 0 else [*out, *spaced_distances(thread, start, LINE_STEP)]
    way_out = [path(d) for d in first]
    # An arm pose from which the gripper can also take the part out along its axis.
    fetched = state.planned
    failure = robot.fetch(part, obj.part(part), way_out, frozenset({joint.fixed}))
    while failure is not None and (blocking := _in_the_way(state, part, failure, aside)) is not None:
        # The fetch failed before moving: lift the part in the way off, and try again.
        failed = _detach(state, number, blocking)
        if failed is not None:
            return failed
        aside.append(blocking)
        fetched = state.planned
        failure = robot.fetch(part, obj.part(part), way_out, frozenset({joint.fixed}))
    if failure is not None:
        return _code(failure)
    state.events.append(Unweld(part, joint.fixed, fetched, state.planned))
    unweld(scene, joint.fixed, part)
    scene.set_dynamic(part, False)
    run.joints.remove(joint)
    run.assembled.discard(part)
    what = f"taking the {name} off"
    if motion.turns > 0:
        failure = robot.screw([path(d) for d in out], what, joint.fixed)
    else:
        failure = robot.follow("push", [path(d) for d in out], what, joint.fixed)
    if failure is None and thread < start:
        failure = robot.follow(
            "approach", [path(d) for d in spaced_distances(thread, start, LINE_STEP)], what, joint.fixed
        )
    if failure is not None:
        return _code(failure)
    collide_again(scene, joint.fixed, part)
    return _code(_set_down(state, part, run.homes[part]))


def _set_down(state: _Episode, part: str, home: Pose) -> RobotFailure | None:
    """Carry the held part above ``home`` on the table, lower it there and let go."""
    robot, name = state.robot, state.obj.part(part).name
    above = home.translated((0.0, 0.0, LIFT))
    failure = robot.carry(above, f"setting the {name} aside")
    if failure is None:
        failure = robot.follow("carry", line_poses(above, home), f"putting the {name} down", "ground")
    if failure is None:
        failure = robot.release()
    state.scene.place(part, home)
    return failure


def _swap(state: _Episode, part: str) -> None:
    """Make the spare on the table the part (the broken one stays where it lies, as the spare's id)."""
    scene, run = state.scene, state.run
    spare = part + SPARE
    state.swaps.append((part, state.planned))
    state.events.append(Swap(part, state.planned))
    swap_spare(scene, part, spare)
    run.homes[part], run.homes[spare] = run.homes[spare], run.homes[part]


def _replace_base(state: _Episode, part: str) -> tuple[str, str] | None:
    """Carry the broken base (everything is off it) to a free place and the spare to where it stood.

    A base the gripper cannot hold (wider than it opens, and no grasp in the catalog: no free
    place was kept for it) is swapped without the robot: the spare is put where the broken
    one stood, the broken one where the spare waited.
    """
    scene, run = state.scene, state.run
    here, aside = scene.pose(part), state.base_aside
    if aside is None:
        table = run.homes[part + SPARE]
        _swap(state, part)
        for placed, pose, dynamic in ((part + SPARE, table, False), (part, here, True)):
            state.events.append(Place(placed, pose, dynamic, state.planned))
            scene.place(placed, pose)
            scene.set_dynamic(placed, dynamic)
        run.homes[part] = here
        return None
    failed = _carry_base(state, part, aside)
    if failed is not None:
        return failed
    _swap(state, part)
    failed = _carry_base(state, part, here)
    scene.set_dynamic(part, True)  # the object's base again: it stands on the table in physics
    run.homes[part], run.homes[part + SPARE] = here, aside
    return failed


def _carry_base(state: _Episode, part: str, to: Pose) -> tuple[str, str] | None:
    """Pick the base up where it stands, carry it to ``to`` on the table and set it down there."""
    state.scene.set_dynamic(part, False)
    failure = state.robot.fetch(part, state.obj.part(part))
    if failure is None:
        failure = _set_down(state, part, to)
    return _code(failure)


def _attach(state: _Episode, number: int, part: str) -> tuple[str, str] | None:
    """Put ``part`` on the object, lifting off first what was in the hand's way to take it off (and back after)."""
    run = state.run
    aside: list[str] = []
    for other in state.in_the_way.get(part, []):
        if other in run.assembled and not any(joint.fixed == other for joint in run.joints if not joint.touch_only):
            failed = _detach(state, number, other)
            if failed is not None:
                return failed
            aside.append(other)
    fit = state.fits[part]
    failed = _step_failure(state, number, StepRequest(fit.primitive, part, fit.fixed_part, fit.id))
    return failed if failed is not None else _put_back(state, number, aside)


def _step_failure(state: _Episode, number: int, request: StepRequest) -> tuple[str, str] | None:
    """Make one assembly step (attach or light) by the robot; return its failure code and message, if any."""
    first, joints = state.planned, list(state.run.joints)
    report = execute_step(state.run, number, request)
    if report.status is StepStatus.PASSED:
        motion = MOTIONS[request.action]
        for joint in state.run.joints:
            if joint not in joints:  # the joint this step made: made again where the motors let go of the part
                state.events.append(Join(request.moving, joint, motion.fastens, first, state.planned))
        return None
    code = report.failure.value if report.failure is not None else "failed"
    return code, report.message


def _test(state: _Episode, number: int, lights: list[Fit]) -> tuple[str, str] | None:
    """Light what the object lights (lifting off what covers it, and putting it back), then let it settle."""
    run = state.run
    state.events.append(LightsOut(state.planned))
    run.joints[:] = [joint for joint in run.joints if not joint.touch_only]  # a failed test's flame is out
    for light in lights:
        if light.fixed_part not in run.assembled:
            continue
        covering = [
            part
            for part in sorted(run.assembled - {state.obj.base}, key=lambda p: -run.attached_at.get(p, 0))
            if (light.fixed_part, light.fixed_connector) in state.fits[part].blocks
        ]
        for part in covering:
            failed = _detach(state, number, part)
            if failed is not None:
                return failed
        request = StepRequest(light.primitive, light.moving_part, light.fixed_part, light.id)
        failed = _step_failure(state, number, request)
        if failed is not None:
            return failed
        for part in reversed(covering):
            fit = state.fits[part]
            failed = _step_failure(state, number, StepRequest(fit.primitive, part, fit.fixed_part, fit.id))
            if failed is not None:
                return failed
    settle(run, checks.STEP_SETTLE_SECONDS)
    return None


def _rename_spares(state: _Episode) -> None:
    """Name each planned segment's held part by its body's id (a spare by its ``:spare`` id), for the tracks.

    After a swap the part's id names its spare; segments before it held the part itself.
    """
    segments = state.robot.waypoints.segments
    for part, first in state.swaps:
        for segment in segments[first:]:
            if segment.held is not None and segment.held[0] == part:
                segment.held = (part + SPARE, segment.held[1])


def robot_episode(
    obj: AssemblyObject,
    episode: Episode,
    safety_factor: float = DEFAULT_SAFETY_FACTOR,
    tracks: bool = False,
    on_action: Callable[[int, int], None] | None = None,
    motors: bool = False,
) -> EpisodeInPhysics:
    """Have the Panda carry out ``episode`` on ``obj`` in physics, action by action, and judge its last test.

    ``tracks`` keeps every body's pose over the motor commands (``sim.robot_episode_playback``);
    ``on_action(done, total)`` hears of each action done; ``motors`` then plays the commands
    through the Panda's joint motors in a fresh scene (``motors`` in the answer). Raises
    LimitViolationError when no motor commands keep within the limits,
    SimulatorUnavailableError when PyBullet cannot start.
    """
    clock = time.perf_counter()
    lights = [fit for fit in obj.fits if MOTIONS[fit.primitive].touches_only]
    stage = episode_stage(obj, episode)
    actions: list[ActionInPhysics] = []
    requirements: tuple[RequirementCheck, ...] = ()
    replaced = broken_replaced = False
    with built_object(obj, stage) as run:
        scene = run.scene
        fits = {request.moving: obj.fit(request.fit) for request in stage.build if request.fit is not None}
        mover = PandaMovesThem(scene, None, safety_factor, tracks)
        run.mover = mover
        bodies = {body: part for part, body in scene.bodies.items()}
        state = _Episode(obj, run, mover, fits, bodies, stage.base_aside)
        timing = {"build": time.perf_counter() - clock}
        clock = time.perf_counter()
        for number, step in enumerate(episode.steps, start=1):
            mover.robot.step = number
            failed: tuple[str, str] | None = None
            observed = None
            if step.kind == DETACH and step.part is not None:
                failed = _detach(state, number, step.part)
            elif step.kind == ATTACH and step.part is not None:
                failed = _attach(state, number, step.part)
            elif step.kind == REPLACE and step.part is not None:
                if step.part == obj.base:
                    failed = _replace_base(state, step.part)
                else:
                    _swap(state, step.part)
                replaced = replaced or step.part == episode.fault
            elif step.kind == TEST:
                failed = _test(state, number, lights)
                if failed is None:
                    requirements = evaluate(obj, scene, run.joints)
                    works = all(requirement.met for requirement in requirements)
                    observed = GOAL if works and replaced else NO_GOAL
                    broken_replaced = replaced
                    replaced = False
            else:
                assert step.kind == INSPECT
            motions = step_motions(mover.robot.waypoints, number)
            code, message = failed if failed is not None else (None, "")
            actions.append(ActionInPhysics(number, step.kind, step.part, motions, observed, code, message))
            if on_action is not None:
                on_action(number, len(episode.steps))
            if failed is not None:
                break
        timing["episode"] = time.perf_counter() - clock
        _rename_spares(state)
        carried_out = all(action.passed for action in actions)
        timing.update(mover.finish(len(episode.steps), carried_out))
        placed = {state.bodies[body]: scene.pose(part) for part, body in scene.bodies.items()}
    motor_run: MotorRun | None = None
    if motors and carried_out and mover.commands is not None and mover.commands.points:
        clock = time.perf_counter()
        planned = mover.robot.waypoints.segments
        replaced_last = broken_replaced
        motor_run = drive_episode_with_motors(obj, stage, planned, mover.commands, state.events, SPARE, replaced_last)
        timing["motors"] = time.perf_counter() - clock
    return EpisodeInPhysics(
        obj.id,
        tuple(actions),
        requirements,
        broken_replaced,
        mover.commands,
        dict(mover.tracks),
        placed,
        timing,
        motor_run,
    )
