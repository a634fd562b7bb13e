"""The robot driven by its motors, for every object of the catalog and the two user objects of examples/catalog."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from causalplan.objects.catalog import load_catalog, parse_object
from causalplan.sim import simulate_plan
from causalplan.sim.outcomes import RenderMode
from causalplan.sim.plan_steps import StepRequest, check_steps
from causalplan.sim.robot.checker import violations
from causalplan.sim.robot.motors import drive_with_motors
from causalplan.sim.robot.trajectory import read_trajectory
from tests.conftest import EXAMPLES
from tests.sim.fixtures import goal_plans

DATA = Path(__file__).parents[2] / "data"
CATALOG = load_catalog([EXAMPLES / "catalog"])
"""The built-in catalog (whatever it holds) and the user objects of examples/catalog."""


@pytest.mark.slow
@pytest.mark.parametrize("object_id", sorted(CATALOG.objects))
def test_the_motor_commands_pass_the_checker_and_the_motors_build_the_object(object_id: str) -> None:
    obj = CATALOG.get(object_id)
    for plan in goal_plans(obj):  # the first order the robot can carry out
        report = simulate_plan(obj, plan, render=RenderMode.NONE, robot=True)
        if report.passed:
            break
    assert report.failed_step is None and report.produces_goal, report.explanation()
    assert report.motor_commands is not None
    report = replace(report, motors=drive_with_motors(obj, check_steps(plan, obj), report.motor_commands))
    assert report.motor_commands is not None and report.motors is not None
    written = read_trajectory(json.loads(json.dumps(report.motor_commands.as_dict())))
    assert violations(written) == []
    assert report.motors.failure is None, report.motors.message
    assert report.motors.produces_goal, report.explanation()
    motors = report.as_dict()["robot"]["motors"]  # type: ignore[index]
    assert motors["tracking"]["max_joint_error_rad"] <= motors["tracking"]["tolerance_rad"]
    assert not motors["grasp_slipped"]


@pytest.mark.slow
def test_a_part_moved_by_two_steps_makes_each_steps_own_joint() -> None:
    """The match lights one wick, then the other: letting go after step 4 makes step 4's joint, not step 3's."""
    obj = parse_object((DATA / "objects" / "twin_candle.yaml").read_text(), "twin_candle.yaml")
    plan = check_steps(
        [
            StepRequest(fit.primitive, fit.moving_part, fit.fixed_part, fit.id)
            for fit in map(
                obj.fit, ("wick_a_into_wax", "wick_b_into_wax", "match_lights_wick_a", "match_lights_wick_b")
            )
        ],
        obj,
    )
    report = simulate_plan(obj, plan, render=RenderMode.NONE, robot=True, motors=True)
    assert report.produces_goal, report.explanation()
    assert report.motors is not None and report.motors.failure is None, report.motors.message
    unmet = [requirement.says for requirement in report.motors.requirements if not requirement.met]
    assert unmet == [] and report.motors.produces_goal


@pytest.mark.slow
def test_the_motors_seat_the_oil_bottle_in_its_filling_hole() -> None:
    # The hole's mouth once stood 2 mm proud of where the neck seats: the motors left the bottle 1.8-2.0 mm up.
    obj = CATALOG.get("oil_lamp")
    plan = next(plan for plan in goal_plans(obj))
    report = simulate_plan(obj, plan, render=RenderMode.NONE, robot=True)
    assert report.passed and report.motor_commands is not None, report.explanation()
    driven = drive_with_motors(obj, check_steps(plan, obj), report.motor_commands)
    bottle = next(check for check in driven.requirements if check.fit == "bottle_into_filling_hole")
    found = re.search(r"\(([\d.]+) mm and", bottle.detail)
    assert bottle.met and found is not None, bottle.detail
    assert float(found.group(1)) <= 0.5, bottle.detail
