"""Time the robot carrying out each paper object's plan, next to the physics check of the same plan.

    python benchmarks/robot.py [--repeat K] [--trials N] [--safety-factor F]

A robot run is ``simulate_plan(obj, steps, render=RenderMode.NONE, robot=True)``: the Panda
fetches, carries (OMPL when the straight joint path is not clear), drives home by IK and
lets go of every part, and the physics checks run as without it; no video. The reference,
measured in the same run, is the physics check alone (``robot=False``) of the same plan;
the table gives the ratio of the medians and splits the robot's time into inverse
kinematics, path planning (collision-checked) and the rest (execution: commanding the
joints, checking every position, the physics). A second table sets, for each plan, the
motor commands' duration (TOPP-RA within the datasheet limits times the safety factor)
against the unconstrained one (the planned waypoints at 50 a second, as before limits were
applied), and the cost of the time parameterization and of the motor-driven physics run
(``sim.robot.motors``) as ratios to the robot run without them (median times). Then ``estimate-fits``' trials per second
for each fit of the desk lamp, beside the time of the robot's nominal run of the fit. A
trial does not move the robot again (its commands do not depend on the noise it cannot
feel): it puts the part where those commands take it with the noisy grasp and measures the
seat, so trials are far cheaper than runs.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from importlib import metadata

from rich.console import Console
from rich.table import Table
from sim import PLANS  # benchmarks/sim.py, beside this script: the same plans as the physics benchmark

from causalplan.objects.catalog import load_catalog
from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.fit_estimates import estimate_fit
from causalplan.sim.plan_steps import check_steps
from causalplan.sim.robot.limits import DEFAULT_SAFETY_FACTOR
from causalplan.sim.robot.motors import drive_with_motors


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="timed runs per case, after one warm-up")
    parser.add_argument("--trials", type=int, default=2000, help="estimate-fits trials per fit")
    parser.add_argument("--safety-factor", type=float, default=DEFAULT_SAFETY_FACTOR, help="share of the limits used")
    options = parser.parse_args()
    catalog = load_catalog()
    console = Console(width=150)
    console.print(
        f"python {platform.python_version()}, pybullet {metadata.version('pybullet')}, "
        f"ompl {metadata.version('ompl')}, {platform.machine()}, repeat {options.repeat}"
    )
    table = Table(
        "object",
        "physics check ms",
        "robot run ms",
        "ratio",
        "IK ms",
        "planning ms",
        "execution ms",
        "robot s moved",
        "goal",
        title="The robot's run of each plan against the physics check of the same plan (medians)",
    )
    commands = Table(
        "object",
        "unconstrained s",
        "parameterized s",
        "duration ratio",
        "robot run ms",
        "parameterization ms",
        "parameterization / run",
        "motors ms",
        "motors / run",
        "motors: goal",
        "max joint error rad",
        "max gripper error mm",
        title=f"Motor commands within the Panda's limits x {options.safety_factor} (medians)",
    )
    factor = options.safety_factor
    for object_id, steps in PLANS.items():
        obj = catalog.get(object_id)
        simulate_plan(obj, steps, render=RenderMode.NONE)  # warm-up
        simulate_plan(obj, steps, render=RenderMode.NONE, robot=True, safety_factor=factor)
        checks, runs, ik, planning, execution, timing, motors = [], [], [], [], [], [], []
        for _ in range(options.repeat):
            started = time.perf_counter()
            simulate_plan(obj, steps, render=RenderMode.NONE)
            checks.append(time.perf_counter() - started)
            started = time.perf_counter()
            report = simulate_plan(obj, steps, render=RenderMode.NONE, robot=True, safety_factor=factor)
            timing.append(report.timing["robot_timing"])
            runs.append(time.perf_counter() - started - timing[-1])
            ik.append(report.timing["robot_ik"])
            planning.append(report.timing["robot_planning"])
            execution.append(runs[-1] - ik[-1] - planning[-1])
            assert report.motor_commands is not None
            started = time.perf_counter()
            motor_run = drive_with_motors(obj, check_steps(steps, obj), report.motor_commands)
            motors.append(time.perf_counter() - started)
        check, run = statistics.median(checks), statistics.median(runs)
        assert report.trajectory is not None and report.motor_commands is not None
        moved = report.motor_commands.seconds
        unconstrained = report.trajectory.seconds
        commands.add_row(
            object_id,
            f"{unconstrained:.1f}",
            f"{moved:.1f}",
            f"{moved / unconstrained:.2f}x",
            f"{run * 1000:.0f}",
            f"{statistics.median(timing) * 1000:.0f}",
            f"{statistics.median(timing) / run:.2f}x",
            f"{statistics.median(motors) * 1000:.0f}",
            f"{statistics.median(motors) / run:.2f}x",
            "yes" if motor_run.produces_goal and motor_run.failure is None else f"NO (!) {motor_run.message}",
            f"{motor_run.joint_error:.4f}",
            f"{motor_run.gripper_error_mm:.1f}",
        )
        table.add_row(
            object_id,
            f"{check * 1000:.1f}",
            f"{run * 1000:.1f}",
            f"{run / check:.1f}x",
            f"{statistics.median(ik) * 1000:.1f}",
            f"{statistics.median(planning) * 1000:.1f}",
            f"{statistics.median(execution) * 1000:.1f}",
            f"{moved:.1f}",
            "yes" if report.produces_goal else "NO (!)",
        )
    console.print(table)
    console.print(commands)
    fits = Table("fit", "trials", "trials / s", "nominal run ms", "probability", title="estimate-fits on the desk lamp")
    lamp = catalog.get("desk_lamp")
    for fit in lamp.fits:
        estimate_fit(lamp, fit, trials=1)  # warm-up (statsmodels' import, the scene)
        estimate = estimate_fit(lamp, fit, trials=options.trials)
        rate = options.trials / max(1e-9, estimate.timing["trials"])
        fits.add_row(
            fit.id,
            str(options.trials),
            f"{rate:,.0f}",
            f"{estimate.timing['robot'] * 1000:.0f}",
            f"{estimate.probability:.3f}",
        )
    console.print(fits)
    return 0


if __name__ == "__main__":
    sys.exit(main())
