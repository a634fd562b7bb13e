"""The optional robot arm: a Panda reaching each step's grasp poses by inverse kinematics."""

from __future__ import annotations

from causalplan.objects.catalog import Catalog
from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.checks import REACH_TOLERANCE_MM
from causalplan.sim.geometry import solids
from causalplan.sim.robot.arm import Arm
from causalplan.sim.scene import Scene
from tests.sim.fixtures import CORRECT_PLANS


def test_the_arm_reaches_every_step_of_the_desk_lamp_without_changing_the_outcome(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    with_arm = simulate_plan(lamp, CORRECT_PLANS["desk_lamp"], render=RenderMode.NONE, arm=True)
    without = simulate_plan(lamp, CORRECT_PLANS["desk_lamp"], render=RenderMode.NONE)
    assert with_arm.arm and with_arm.passed
    for step in with_arm.steps:
        assert step.reach is not None and step.reach.reachable
        assert step.reach.error_mm <= REACH_TOLERANCE_MM
    assert [step.checks for step in with_arm.steps] == [step.checks for step in without.steps]
    assert without.steps[0].reach is None


def test_a_point_out_of_reach_is_missed_by_more_than_the_tolerance(catalog: Catalog) -> None:
    with Scene(solids(catalog.get("candle")), drawn=False) as scene:
        arm = Arm(scene)
        assert arm.reach((0.0, 0.0, 0.3)) <= REACH_TOLERANCE_MM
        assert arm.reach((2.0, 0.0, 0.3)) > 1000  # 2.55 m from the arm's base; it reaches about 0.85 m
