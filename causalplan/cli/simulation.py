"""The simulate command: a plan checked in headless PyBullet, and drawn."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    EXIT_NO_PLAN,
    EXIT_OK,
    EXIT_UNDECIDED,
    FILE,
    catalog_from,
    catalog_option,
    dim,
    exit_on_error,
    exit_with,
    fail,
    json_option,
    load_task,
    mark,
    print_json,
    print_plan,
    progress_bar,
    say,
)

if TYPE_CHECKING:
    from causalplan.sim import SimulationReport
    from causalplan.sim.robot.checker import Violation


def _read_json(path: Path, what: str, invalid: str) -> object:
    """Return the JSON data of the ``what`` file ``path``; fail with ``invalid`` when it is not JSON."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        fail("input_file_error", f"Cannot read the {what} file {path}: {exc.strerror}.")
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        fail(invalid, f"{path} is not JSON: {exc}.")


def _print_simulation(report: SimulationReport) -> None:
    say(f"Simulated {len(report.steps)} step(s) on the {report.object_name} (headless PyBullet):")
    for step in report.steps:
        reach = ""
        if step.reach is not None:
            verb = "reaches" if step.reach.reachable else "cannot reach"
            reach = " " + dim(f"(arm {verb}: {step.reach.error_mm:.1f} mm)")
        if step.status.value == "passed":
            say(f"  {step.number}. {step.text} {mark(True, 'passed')}{reach}")
        elif step.status.value == "failed":
            failure = step.failure.value if step.failure else "failed"
            failed = click.style("FAILED", fg="red", bold=True)
            say(f"  {step.number}. {step.text} {failed}[{failure}]: {step.message}{reach}")
        else:
            say(f"  {step.number}. {step.text} {dim('not run')}")
        if step.motions:
            say("     " + dim("robot: " + ", ".join(step.motions)))
    drift = report.stability[0]
    say(f"Holds still while it settles: {mark(report.is_stable)} ({drift.detail}; tolerance {drift.tolerance:g} mm)")
    say("True mechanism on the simulated assembly:")
    for requirement in report.requirements:
        say(f"  {mark(requirement.met)} {requirement.says}: {requirement.detail}")
    say(f"Produces {report.goal}: {mark(report.produces_goal)}")
    commands = report.motor_commands
    if commands is not None:
        say(
            f"The robot moves for {commands.seconds:.1f} s ({len(commands.segments)} motions, "
            f"within {commands.safety_factor:g} x the {commands.limits.model}'s limits)."
        )
    if report.motors is not None:
        run = report.motors
        tracked = f"tracking within {run.joint_error:.4f} rad, {run.gripper_error_mm:.1f} mm at the gripper"
        outcome = "" if run.failure is None else f"; {run.failure.value} at step {run.step}: {run.message}"
        goal = f"produces {report.goal}" if run.produces_goal else f"no {report.goal}"
        say(f"Driven by its motors: {goal}, {tracked}{outcome}.")


@click.command(short_help="Check a plan in a headless physics simulation, and draw it.")
@click.argument("model", type=FILE)
@click.option("--mapping", "-m", type=FILE, help="A step-3 mapping: simulate on that object instead.")
@click.option(
    "--plan",
    "plan_file",
    type=FILE,
    help="The plan to run: the JSON of `causalplan plan --json`, or its 'plan' list. Without it, plan first.",
)
@click.option("--png", type=FILE, help="Write a picture of the final assembly (PNG).")
@click.option("--frames", type=FILE, help="Write a picture per step to this folder, and strip.png.")
@click.option("--gif", type=FILE, help="Write the steps as an animated GIF.")
@click.option("--arm", is_flag=True, help="Add a Panda arm and report whether it reaches each step's grasp poses.")
@click.option(
    "--robot",
    is_flag=True,
    help="Have the Franka Panda build the object: grasp each part, carry it along a collision-free path "
    "(OMPL), drive it home along the connector axis, let go. A step it cannot do fails with "
    "unreachable, no_collision_free_path, collision or grasp_lost.",
)
@click.option(
    "--trajectory",
    type=FILE,
    help="With --robot: write the motor commands (time-stamped joint positions and gripper commands) as JSON.",
)
@click.option(
    "--safety-factor",
    type=click.FloatRange(0.0, 1.0, min_open=True),
    default=None,
    help="With --robot: the share of the Panda's datasheet velocity and acceleration limits its motor "
    "commands are timed to (jerk is checked against the datasheet)  "
    "[default: sim.robot.limits.DEFAULT_SAFETY_FACTOR, 0.5]",
)
@click.option(
    "--motors/--no-motors",
    default=True,
    help="With --robot: also play the motor commands through the Panda's joint motors in physics, and report "
    "the tracking error and slip (limit_violation, tracking_error, grasp_slipped).",
)
@click.option("--ros2-bag", type=FILE, help="With --robot: write the motor commands as a ROS 2 bag in this new folder.")
@click.option(
    "--joint-trajectory",
    type=FILE,
    help="With --robot: write the arm's control_msgs/action/FollowJointTrajectory goal as YAML.",
)
@click.option("--video", type=FILE, help="With --robot: film the robot at work, as V.mp4 or V.gif.")
@json_option
@catalog_option
def simulate(
    model: Path,
    mapping: Path | None,
    plan_file: Path | None,
    png: Path | None,
    frames: Path | None,
    gif: Path | None,
    arm: bool,
    robot: bool,
    trajectory: Path | None,
    safety_factor: float | None,
    motors: bool,
    ros2_bag: Path | None,
    joint_trajectory: Path | None,
    video: Path | None,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Run a plan in a headless physics simulation, check every step, and draw it.

    MODEL is the causal model file (YAML or JSON). Each step is checked (connectors fit, the
    path is clear, the joint is aligned, nothing falls), then the object's true mechanism is
    judged on the simulated assembly. Exit 0 when everything passes and the object produces
    its goal, 1 when not (or no plan is found), 2 for invalid input, 3 when the planner could
    not decide.

    With --robot the Panda does the work and the report says, per step, what it did (and
    which step it could not do: unreachable, no_collision_free_path, collision, grasp_lost):

    \b
        causalplan simulate examples/paper/desk_lamp.yaml --robot --video lamp.mp4 --trajectory t.json
        causalplan simulate examples/paper/desk_lamp.yaml --robot --ros2-bag lamp_bag --joint-trajectory goal.yaml

    The motor commands keep within the Panda's datasheet limits times --safety-factor; driven by
    its motors (--motors, the default) the run also reports the tracking error and slip.
    """
    from causalplan.planners.pipeline import plan_task
    from causalplan.sim import RenderMode, read_plan_steps, simulate_plan
    from causalplan.sim.render import animation, strip
    from causalplan.sim.robot.limits import DEFAULT_SAFETY_FACTOR

    if arm and robot:
        fail("invalid_option", "Use --robot (the Panda does the work) or --arm (it only checks its reach), not both.")
    if (trajectory or video or ros2_bag or joint_trajectory) and not robot:
        fail(
            "invalid_option",
            "--trajectory, --ros2-bag, --joint-trajectory and --video need --robot (the robot's motions are what "
            "they record).",
        )
    if video is not None and video.suffix.lower() not in (".mp4", ".gif"):
        fail("invalid_option", f"--video writes .mp4 or .gif, not '{video.suffix or video.name}'.")
    objects = catalog_from(catalog)
    task = load_task(model, mapping, objects, as_json)
    target = task.obj
    render = RenderMode.FRAMES if frames or gif else RenderMode.FINAL if png else RenderMode.NONE
    with exit_on_error():
        if plan_file is not None:
            steps = read_plan_steps(_read_json(plan_file, "plan", "invalid_plan"), target)
        else:
            result = plan_task(task)
            if not result.has_plan:
                if as_json:
                    print_json({"status": result.status.value, "message": result.message, "simulation": None})
                else:
                    print_plan(result)
                exit_with(EXIT_NO_PLAN if result.status.is_final() else EXIT_UNDECIDED)
            steps = read_plan_steps([step.as_dict() for step in result.steps], target)
        factor, motors = safety_factor or DEFAULT_SAFETY_FACTOR, motors and robot
        if video is None:
            report = simulate_plan(
                target, steps, render=render, arm=arm, robot=robot, safety_factor=factor, motors=motors
            )
        else:
            with progress_bar() as progress:
                filming = progress.add_task("filming the robot", total=None)

                def drawn(frames: int) -> None:
                    progress.update(filming, description=f"filming the robot: {frames} frames")

                report = simulate_plan(
                    target,
                    steps,
                    render=render,
                    arm=arm,
                    robot=True,
                    video=True,
                    on_frame=drawn,
                    safety_factor=factor,
                    motors=motors,
                )
    written: list[str] = []
    try:
        if png is not None and report.picture is not None:
            png.write_bytes(report.picture.png())
            written.append(str(png))
        if frames is not None:
            frames.mkdir(parents=True, exist_ok=True)
            for number, picture in enumerate(report.frames):
                (frames / f"step_{number:02d}.png").write_bytes(picture.png())
            (frames / "strip.png").write_bytes(strip(report.frames).png())
            written.append(str(frames))
        if gif is not None:
            gif.write_bytes(animation(report.frames))
            written.append(str(gif))
        if trajectory is not None and report.motor_commands is not None:
            trajectory.write_text(json.dumps(report.motor_commands.as_dict()), encoding="utf-8")
            written.append(str(trajectory))
        if joint_trajectory is not None and report.motor_commands is not None:
            from causalplan.sim.robot.ros import follow_joint_trajectory_goal

            joint_trajectory.write_text(follow_joint_trajectory_goal(report.motor_commands), encoding="utf-8")
            written.append(str(joint_trajectory))
        if ros2_bag is not None and report.motor_commands is not None:
            from causalplan.sim.robot.ros import write_bag

            with exit_on_error():
                write_bag(report.motor_commands, ros2_bag)
            written.append(str(ros2_bag))
        if video is not None:
            from causalplan.sim.video import encode

            video.write_bytes(encode(report.video, video.suffix))
            written.append(str(video))
    except OSError as exc:
        fail("output_not_writable", f"Cannot write {exc.filename}: {exc.strerror}.")
    if as_json:
        print_json({**report.as_dict(), "files": written})
    else:
        _print_simulation(report)
        for path in written:
            say(f"Wrote {path}")
    exit_with(EXIT_OK if report.passed else EXIT_NO_PLAN)


@click.command("check-trajectory", short_help="Check a robot trajectory file against the robot's limits.")
@click.argument("file", type=FILE)
@click.option(
    "--robot", "model", default=None, help="The robot model whose limits apply (default: the file's, else panda)."
)
@json_option
def check_trajectory(file: Path, model: str | None, as_json: bool) -> None:
    """Check FILE's motor commands against the robot's datasheet limits, independently of who wrote them.

    Velocity, acceleration and jerk are recomputed from the positions and times by finite
    differences (the velocities a file claims are not trusted); each value beyond a limit is
    reported with its joint, time and ratio to the limit. FILE is any of the three forms
    `simulate --robot` writes, told apart by what FILE is: a folder is a ROS 2 bag
    (--ros2-bag; the arm's JointTrajectory, and the gripper's when there), a .yaml/.yml file a
    FollowJointTrajectory goal (--joint-trajectory), anything else a trajectory JSON
    (--trajectory, or yours: 'joints' and 'points' with 'time_from_start' and 'positions').
    Exit 0 within the limits, 1 beyond them, 2 for invalid input.
    """
    from causalplan.sim.robot.checker import violations
    from causalplan.sim.robot.trajectory import read_trajectory

    with exit_on_error():
        trajectory = read_trajectory(_trajectory_data(file), model)
    found = violations(trajectory)
    if as_json:
        print_json(
            {
                "file": str(file),
                "robot": trajectory.limits.model,
                "points": len(trajectory.points),
                "seconds": round(trajectory.seconds, 4),
                "within_limits": not found,
                "violations": [violation.as_dict() for violation in found],
            }
        )
    else:
        _print_violations(file, trajectory.limits.model, len(trajectory.points), found)
    exit_with(EXIT_OK if not found else EXIT_NO_PLAN)


def _trajectory_data(file: Path) -> object:
    """Return the trajectory data of a ROS 2 bag folder, a FollowJointTrajectory goal (YAML) or a JSON file."""
    if file.is_dir():
        from causalplan.sim.robot.ros import bag_trajectory_data

        return bag_trajectory_data(file)
    if file.suffix.lower() in (".yaml", ".yml"):
        import yaml

        from causalplan.sim.robot.ros import goal_trajectory_data

        try:
            return goal_trajectory_data(yaml.safe_load(file.read_text(encoding="utf-8")))
        except OSError as exc:
            fail("input_file_error", f"Cannot read the trajectory file {file}: {exc.strerror}.")
        except (UnicodeDecodeError, yaml.YAMLError) as exc:
            fail("invalid_trajectory", f"{file} is not YAML: {exc}.")
    return _read_json(file, "trajectory", "invalid_trajectory")


def _print_violations(file: Path, model: str, points: int, found: list[Violation]) -> None:
    """Say whether the file keeps within the limits; else the worst value of each joint and quantity."""
    if not found:
        say(mark(True) + f" {file}: {points} points within the {model}'s limits.")
        return
    say(mark(False) + f" {file}: {len(found)} values beyond the {model}'s limits.")
    worst: dict[tuple[str, str], Violation] = {}
    for violation in found:
        key = (violation.joint, violation.quantity)
        if key not in worst or violation.ratio > worst[key].ratio:
            worst[key] = violation
    for violation in sorted(worst.values(), key=lambda v: -v.ratio):
        count = sum(1 for v in found if (v.joint, v.quantity) == (violation.joint, violation.quantity))
        say("   " + violation.text() + dim(f" (worst of {count})"))
