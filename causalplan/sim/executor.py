"""Run a plan in physics, step by step, and report what happened: ``simulate_plan``.

The base stands on the table at the origin; the other parts wait in a row behind it. Each
step checks, in order: the connectors fit, the part to attach to is in the assembly (and
the moving one is not), the approach path is clear, the part touches its mate at the seat,
the joined connectors are aligned, and nothing moves while the assembly settles. The robot
stops at the first failed step. After the plan the assembly settles once more, and the
object's true mechanism is judged on what was built.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from causalplan.objects.model import AssemblyObject
from causalplan.pddl.task import PlanningTask
from causalplan.planners.result import PlanStep
from causalplan.sim import checks
from causalplan.sim.layout import ROBOT_ROW_GAP, ROW_GAP, catalog_fit, laid_out_scene, step_connectors
from causalplan.sim.mechanism import Joint, evaluate, seat_error
from causalplan.sim.motions import MOTIONS, approach, approach_path, approach_start
from causalplan.sim.movers import Mover, PartsMoveThemselves, StepMove
from causalplan.sim.observers import Observer, Pictures
from causalplan.sim.outcomes import Check, Failure, Reach, RenderMode, RequirementCheck, StepReport, StepStatus
from causalplan.sim.plan_steps import StepRequest, check_steps
from causalplan.sim.poses import Pose, difference
from causalplan.sim.render import DEFAULT_SIZE, Camera
from causalplan.sim.report import SimulationReport
from causalplan.sim.robot.arm import Arm
from causalplan.sim.robot.limits import DEFAULT_SAFETY_FACTOR
from causalplan.sim.robot.motors import drive_with_motors
from causalplan.sim.robot.mover import PandaMovesThem
from causalplan.sim.scene import GROUND, Scene
from causalplan.sim.video import VIDEO_SIZE, VideoRecorder


@dataclass
class SimulationRun:
    """The state of one simulation as it goes."""

    obj: AssemblyObject
    scene: Scene
    homes: dict[str, Pose]
    assembled: set[str]
    mover: Mover
    joints: list[Joint] = field(default_factory=list)
    attached_at: dict[str, int] = field(default_factory=dict)

    def name(self, part_or_ground: str) -> str:
        return "table" if part_or_ground == GROUND else self.obj.part(part_or_ground).name


def settle(run: SimulationRun, seconds: float) -> tuple[tuple[Check, Check], str | None]:
    """Let the assembly settle; return the stability checks and the part that moved too much, if any."""
    parts = sorted(run.assembled)
    before = {part: run.scene.pose(part) for part in parts}
    run.scene.settle(seconds)
    moved = {part: difference(before[part], run.scene.pose(part)) for part in parts}
    drifted = max(parts, key=lambda part: moved[part][0])
    tilted = max(parts, key=lambda part: moved[part][1])
    drift, tilt = checks.stability_checks(
        moved[drifted][0] * 1000, math.degrees(moved[tilted][1]), run.name(drifted), seconds
    )
    culprit = drifted if not drift.passed else tilted if not tilt.passed else None
    return (drift, tilt), culprit


@dataclass
class _StepChecks:
    """The checks of one step as they are made; the first that fails ends the step."""

    run: SimulationRun
    number: int
    request: StepRequest
    made: list[Check] = field(default_factory=list)
    reach: Reach | None = None

    def passed(self, *found: Check) -> None:
        self.made.extend(found)

    def report(self, failure: Failure | None = None, message: str = "", not_run: bool = False) -> StepReport:
        """Return the step's report: passed, failed with ``failure``, or not run (an earlier step failed)."""
        request = self.request
        status = StepStatus.NOT_RUN if not_run else StepStatus.PASSED if failure is None else StepStatus.FAILED
        return StepReport(
            self.number,
            request.action,
            request.moving,
            request.fixed,
            request.fit,
            request.text(self.run.obj),
            status,
            tuple(self.made),
            failure,
            message,
            self.reach,
        )

    def fail(self, failure: Failure, check: Check, why: str = "") -> StepReport:
        """Return the report of a step that failed ``check`` (``why`` says more, in front)."""
        if why:
            check = replace(check, detail=f"{why}; {check.detail}")
        self.made.append(check)
        return self.report(failure, check.detail)


def execute_step(run: SimulationRun, number: int, request: StepRequest) -> StepReport:
    """Execute one step and return its report (the scene is left as the step left it)."""
    obj, scene, step, mover = run.obj, run.scene, _StepChecks(run, number, request), run.mover
    motion = MOTIONS[request.action]
    moving_name, fixed_name = run.name(request.moving), run.name(request.fixed)

    pair = step_connectors(obj, request, run.joints)
    if pair is None:
        detail = (
            f"no connector of the {moving_name} ({_specs(obj, request.moving)}) fits one of the {fixed_name} "
            f"({_specs(obj, request.fixed)})"
        )
        return step.fail(Failure.INCOMPATIBLE_CONNECTORS, Check("connectors", False, detail))
    step.passed(checks.connectors_check(moving_name, pair[0], fixed_name, pair[1]))
    if request.fixed not in run.assembled:
        detail = f"the {fixed_name}: not in the assembly, still on the table"
        return step.fail(Failure.MISSING_PART, Check("parts", False, detail))
    if request.moving in run.assembled:
        detail = f"the {moving_name}: already in the assembly since step {run.attached_at[request.moving]}"
        return step.fail(Failure.ALREADY_ATTACHED, Check("parts", False, detail))
    step.passed(Check("parts", True, f"the {fixed_name} in the assembly, the {moving_name} free"))

    moving_frame = scene.solids[request.moving].frames[pair[0].id]
    fixed_frame = scene.solids[request.fixed].frames[pair[1].id]
    fixed_pose = scene.pose(request.fixed)
    path = approach_path(fixed_pose, moving_frame, fixed_frame, motion)
    scene.place(request.moving, path(0.0))
    direction = fixed_pose.turn(fixed_frame.axis)
    start = approach_start(scene.bounds([request.moving]), scene.bounds(run.assembled), direction)
    move = StepMove(
        number, request.moving, obj.part(request.moving), motion, path, start, request.fixed, run.homes[request.moving]
    )
    step.reach = mover.reach(move)
    failed = mover.bring(move)
    if failed is not None:
        return step.fail(failed.failure, failed.check)
    went = approach(scene, request.moving, path, start)
    failed = mover.drive(move, went.stopped)
    if failed is not None:
        return step.fail(failed.failure, failed.check)
    if went.hit is not None and went.hit != request.fixed:
        blocked = checks.path_check(went.hit_depth * 1000, moving_name, run.name(went.hit), went.stopped * 1000)
        return step.fail(Failure.BLOCKED_PATH, blocked)
    step.passed(checks.path_check(went.clear_depth * 1000, moving_name))

    contact = checks.contact_check(max(0.0, scene.gap(request.moving, request.fixed)) * 1000, moving_name, fixed_name)
    if not contact.passed:
        return step.fail(Failure.NO_CONTACT, contact)
    step.passed(contact)

    fit_id = catalog_fit(obj, request, pair)
    joint = Joint(number, fit_id, request.moving, pair[0].id, request.fixed, pair[1].id, motion.touches_only)
    if not motion.touches_only:
        scene.set_dynamic(request.moving, True)
        if motion.fastens:
            scene.weld(request.fixed, request.moving)  # where the part really is, so misalignment shows
        run.assembled.add(request.moving)
        run.attached_at[request.moving] = number
        run.joints.append(joint)  # joined, aligned or not: the mechanism judges the seat later
    offset, tilt = checks.alignment_check(*seat_error(scene, joint))
    for alignment in (offset, tilt):
        if not alignment.passed:
            short = f"stopped against the {fixed_name} {went.stopped * 1000:.1f} mm before the seat"
            return step.fail(Failure.MISALIGNED, alignment, short if went.hit else "")
        step.passed(alignment)
    failed = mover.let_go(move)
    if failed is not None:
        return step.fail(failed.failure, failed.check)
    if motion.touches_only:
        run.joints.append(joint)  # the flame touched the tip: lit
        scene.place(request.moving, run.homes[request.moving])  # and goes back to the table
        return step.report()

    stability, culprit = settle(run, checks.STEP_SETTLE_SECONDS)
    for check in stability:
        if not check.passed:
            assert culprit is not None
            return step.fail(Failure.FALLS, check, f"the {run.name(culprit)} fell")
        step.passed(check)
    return step.report()


def _specs(obj: AssemblyObject, part_id: str) -> str:
    """Return a part's connectors in words: 'screw base E27, ...'."""
    return ", ".join(f"{c.kind} {c.spec}" for c in obj.part(part_id).connectors) or "no connectors"


def simulate_plan(
    target: PlanningTask | AssemblyObject,
    steps: Sequence[StepRequest | PlanStep],
    *,
    render: RenderMode = RenderMode.FINAL,
    arm: bool = False,
    size: tuple[int, int] = DEFAULT_SIZE,
    robot: bool = False,
    safety_factor: float = DEFAULT_SAFETY_FACTOR,
    motors: bool = False,
    tracks: bool = False,
    video: bool = False,
    video_size: tuple[int, int] = VIDEO_SIZE,
    on_frame: Callable[[int], None] | None = None,
) -> SimulationReport:
    """Return the report of running ``steps`` on the target's object in a fresh headless PyBullet world.

    Raises PlanInputError when a step does not belong to the object, SimulatorUnavailableError
    when PyBullet cannot start. ``render`` picks the pictures (none, the final assembly, or a
    frame per step too); ``arm`` adds the Panda's reachability per step; ``robot`` has the
    Panda carry out every step (its planned waypoints are the report's ``trajectory``, its
    motor commands, within the datasheet's limits times ``safety_factor``, its
    ``motor_commands``); ``motors`` then plays them through the Panda's joint motors in a fresh
    scene (the report's ``motors``); ``tracks`` keeps every part's pose over the motor commands
    (the report's ``tracks``, which the browser's player draws); ``video`` films the robot (the
    report's ``video`` frames, ``video_size`` pixels; ``on_frame`` hears of every frame drawn). Raises
    LimitViolationError (``limit_violation``) when no motor commands keep within the limits.
    """
    obj = target.obj if isinstance(target, PlanningTask) else target
    requests = check_steps(steps, obj)
    timing: dict[str, float] = {}
    clock = time.perf_counter()
    video = video and robot
    drawn = render is not RenderMode.NONE or video
    with laid_out_scene(obj, requests, ROBOT_ROW_GAP if robot else ROW_GAP, drawn=drawn) as (scene, homes, design):
        recorder = VideoRecorder(scene, design, obj.name, video_size, on_frame) if video else None
        mover: Mover
        if robot:
            mover = PandaMovesThem(scene, recorder.observe if recorder else None, safety_factor, tracks)
        else:
            mover = PartsMoveThemselves(scene, Arm(scene) if arm else None)
        run = SimulationRun(obj, scene, homes, {obj.base}, mover)
        pictures = None
        if render is not RenderMode.NONE:
            pictures = Pictures(scene, Camera.around(scene, *design, size=size), render, obj.name)
        observers: list[Observer] = [o for o in (pictures, recorder) if o is not None]
        timing["scene"], clock = time.perf_counter() - clock, time.perf_counter()
        reports: list[StepReport] = []
        for number, request in enumerate(requests, start=1):
            if reports and reports[-1].status is not StepStatus.PASSED:
                reports.append(_StepChecks(run, number, request).report(not_run=True))
                continue
            for observer in observers:
                observer.step_started(number, len(requests), request.text(obj))
            reports.append(replace(execute_step(run, number, request), motions=mover.motions(number)))
            for observer in observers:
                observer.step_ended(
                    reports[-1], len(requests), lambda: _lit_parts(run, evaluate(obj, scene, run.joints))
                )
        carried_out = not reports or reports[-1].status is StepStatus.PASSED
        timing.update(mover.finish(len(requests), carried_out))
        timing["steps"], clock = time.perf_counter() - clock, time.perf_counter()
        stability, culprit = settle(run, checks.FINAL_SETTLE_SECONDS)
        timing["settle"], clock = time.perf_counter() - clock, time.perf_counter()
        requirements = evaluate(obj, scene, run.joints)
        produces_goal = all(requirement.met for requirement in requirements)
        timing["mechanism"], clock = time.perf_counter() - clock, time.perf_counter()
        for observer in observers:
            observer.finished(obj.name, _lit_parts(run, requirements), produces_goal, obj.goal)
        if pictures is not None:
            timing["render"] = pictures.seconds
    commands = mover.commands
    motor_run = None
    if motors and commands is not None:
        clock = time.perf_counter()
        motor_run = drive_with_motors(obj, requests, commands)
        timing["motors"] = time.perf_counter() - clock
    return SimulationReport(
        object_id=obj.id,
        object_name=obj.name,
        goal=obj.goal,
        steps=tuple(reports),
        stability=stability,
        unstable_step=run.attached_at.get(culprit) if culprit else None,
        requirements=requirements,
        produces_goal=produces_goal,
        tolerances=dict(checks.TOLERANCES),
        arm=arm,
        timing=timing,
        picture=pictures.picture if pictures else None,
        frames=tuple(pictures.frames) if pictures else (),
        robot=robot,
        trajectory=mover.trajectory,
        motor_commands=commands,
        motors=motor_run,
        placed=mover.placed,
        tracks=mover.tracks,
        video=tuple(recorder.frames) if recorder else (),
    )


def _lit_parts(run: SimulationRun, requirements: tuple[RequirementCheck, ...]) -> tuple[str, ...]:
    """Return the assembled parts whose light shows: all of them when every requirement is met."""
    if not all(requirement.met for requirement in requirements):
        return ()
    return tuple(sorted(run.assembled))
