"""The kinematic Panda: IK within a fraction of a millimetre, limits, and contacts measured."""

from __future__ import annotations

import math

from causalplan.sim.geometry import solids
from causalplan.sim.poses import Pose, about_axis, difference
from causalplan.sim.robot.panda import HOME, IK_POSITION_TOLERANCE, Panda
from causalplan.sim.scene import Scene
from tests.conftest import builtin_catalog

DOWN = about_axis((1.0, 0.0, 0.0), math.pi)


def test_ik_puts_the_grasp_target_on_a_reachable_pose() -> None:
    with Scene({}, drawn=False) as scene:
        panda = Panda(scene)
        target = Pose((0.0, 0.1, 0.3), DOWN)
        answer = panda.solve(target, HOME)
        assert answer is not None and panda.within_limits(answer)
        assert panda.configuration == HOME  # left where it was
        panda.set(answer)
        moved, turned = difference(panda.gripper_pose(), target)
        assert moved <= IK_POSITION_TOLERANCE and turned <= math.radians(0.5)


def test_ik_finds_nothing_beyond_the_arms_reach() -> None:
    with Scene({}, drawn=False) as scene:
        assert Panda(scene).solve(Pose((1.0, 0.8, 0.1), DOWN), HOME) is None


def test_the_arm_touching_a_part_is_measured_but_the_table_under_its_base_is_not() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    with Scene(solids(lamp), drawn=False) as scene:
        panda = Panda(scene)
        assert panda.deepest_contact([scene.ground]) is None  # standing on the table is no collision
        scene.add_part("base_with_cables", Pose((-0.24, 0.0, 0.25)), dynamic=False)  # where the hand is at home
        touch = panda.deepest_contact([scene.bodies["base_with_cables"]])
        assert touch is not None and touch.other == "base_with_cables" and touch.depth > 0
